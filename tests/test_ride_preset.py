"""The ride-file default and the plan's highest rate (issue 20: the strongest ride a ride
file can have by default).

A platform file's ``ride_preset`` is what ``generate`` and ``cue`` use when no ``--preset`` is
given (the whole recording is known: ``stewart6-linear`` names the plan
``optimal-hexapod-auto``); ``bridge`` keeps ``default_preset`` (tests/test_cueing_interface.py
checks both messages). The plan declares a highest rate (``max_rate_hz`` 100 Hz, the rate its
presets are tuned at): a faster ride is cued at the frame rate over a whole divisor and the
frames follow a cubic spline through the plan's poses. Checked here: the divisor rule in
closed form; at the spline's knots the frames' cue poses are the plan's at 100 Hz exactly; the
rider's rendered share at 500 Hz is the 100 Hz ride's within 2 %; the frames pass the
independent limits check.
"""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cli import main
from motioncue.cueing import Rig, cueing_entry, load_cueing, make_cueing, register_cueing
from motioncue.cueing._classical import ClassicalWashout
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline import generate_ride, load_ride
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import (
    Recording,
    read_recording_csv,
    resample,
    write_recording_csv,
)
from motioncue.trajectory import ActuatorLimits
from motioncue.viewer import load_view_input, rendered_shares

PLATFORM, CONTROLLER, PRESET = "stewart6-linear", "mbox6", "optimal-hexapod-auto"


@pytest.mark.parametrize(
    ("frame_hz", "cue_hz"),
    [(1000.0, 100.0), (500.0, 100.0), (250.0, 250.0 / 3.0), (200.0, 100.0), (120.0, 60.0),
     (100.0, 100.0), (60.0, 60.0), (100.0000001, 100.0000001 / 2.0), (300.0, 100.0)],
)  # fmt: skip
def test_the_cue_rate_is_the_frame_rate_over_the_smallest_divisor(
    frame_hz: float, cue_hz: float
) -> None:
    assert cueing_entry("optimal").cue_rate_hz(frame_hz) == pytest.approx(cue_hz, rel=1e-12)
    assert cueing_entry("classical").cue_rate_hz(frame_hz) == frame_hz  # no cap: as before


def test_a_bad_highest_rate_is_refused_at_registration() -> None:
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(ConfigError, match="max_rate_hz"):
            register_cueing("capped-copy", ClassicalWashout, max_rate_hz=bad)


def test_the_bundled_hexapod_names_the_plan_for_ride_files() -> None:
    platform = load_platform(PLATFORM)
    assert platform.ride_preset == PRESET and platform.default_preset == "racing-hexapod-auto"
    assert not cueing_entry(load_cueing(PRESET).algorithm).streaming  # never for the bridge
    assert cueing_entry(load_cueing(platform.default_preset).algorithm).streaming


@pytest.fixture(scope="module")
def excerpt(tmp_path_factory: pytest.TempPathFactory) -> Path:
    lap = read_recording_csv(sample_drives("demo")[0])
    a, b = 1000, 2500  # 10 s to 25 s: braking and corners
    out = tmp_path_factory.mktemp("ride-preset") / "lap-10-25.csv"
    write_recording_csv(out, Recording(lap.t_s[a:b] - lap.t_s[a], lap.f[a:b], lap.w[a:b]))
    return out


def test_a_fast_ride_follows_the_plan_at_its_rate(excerpt: Path) -> None:
    platform, controller = load_platform(PLATFORM), load_controller(CONTROLLER)
    params = load_cueing(PRESET)
    rec = read_recording_csv(excerpt)
    ride, report = generate_ride(rec, platform, controller, params, rate_hz=500.0)
    assert report.cue_rate_hz == 100.0
    assert report.frame_check.ok and ride.rate_hz == 500.0
    # the plan at 100 Hz, run here on its own: the frames' cue poses pass through its poses
    at100 = resample(rec, 100.0)
    limits = ActuatorLimits.from_platform(platform, controller, rate_hz=500.0)
    design = make_cueing(params, 100.0, Rig(platform, limits, controller.name))
    plan = np.asarray(design.run(at100.f, at100.w).poses, dtype=float)
    at500 = resample(rec, 500.0)
    knots = np.searchsorted(at500.t_s, at100.t_s)
    ok = knots < len(at500.t_s)
    assert np.all(np.abs(at500.t_s[knots[ok]] - at100.t_s[ok]) < 1e-9)  # the knots are frames
    np.testing.assert_allclose(report.poses_cue[knots[ok]], plan[ok], rtol=0.0, atol=1e-12)
    # between the knots a smooth path: no frame beyond the plan's range on any DOF
    lo, hi = plan.min(axis=0), plan.max(axis=0)
    span = hi - lo
    assert np.all(report.poses_cue >= lo - 0.02 * span - 1e-12)
    assert np.all(report.poses_cue <= hi + 0.02 * span + 1e-12)


def test_the_rider_gets_the_same_ride_at_100_and_500_hz(excerpt: Path, tmp_path: Path) -> None:
    shares = []
    for rate in (100.0, 500.0):
        out = tmp_path / f"r{rate:g}.ride"
        err = io.StringIO()
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
            rc = main(["generate", "--input", str(excerpt), "--platform", PLATFORM,
                       "--controller", CONTROLLER, "--rate", f"{rate:g}",
                       "--out", str(out)])  # fmt: skip
        said = err.getvalue()
        assert rc == 0, said
        assert f"preset {PRESET} (ride-file default of platform {PLATFORM})" in said
        plans_line = "cueing: optimal plans at 100 Hz (its highest rate)"
        assert (plans_line in said) == (rate == 500.0), said
        assert load_ride(out).notes["cueing"]["preset"] == PRESET
        shares.append(rendered_shares(load_view_input(out, recording=excerpt)))
    s = np.array(shares)
    assert np.all(np.isfinite(s)) and np.all(s > 0.05), s
    print("rendered share fx, fy at 100 / 500 Hz:", s.round(4).tolist())
    np.testing.assert_allclose(s[1], s[0], rtol=0.02)


def test_cue_at_a_fast_rate_runs_the_plan_at_its_own(
    excerpt: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    tables = {}
    for rate in (100.0, 500.0):
        out = tmp_path / f"p{rate:g}.csv"
        rc = main(["cue", "--input", str(excerpt), "--platform", PLATFORM, "--rate",
                   f"{rate:g}", "--out", str(out)])  # fmt: skip
        said = capsys.readouterr()
        assert rc == 0, said.err
        assert f"preset {PRESET} (ride-file default of platform {PLATFORM})" in said.out
        assert ("optimal plans at 100 Hz" in said.err) == (rate == 500.0), said.err
        tables[rate] = np.loadtxt(out, delimiter=",", skiprows=1)
    slow, fast = tables[100.0], tables[500.0]
    np.testing.assert_allclose(np.diff(fast[:, 0]), 0.002, atol=1e-9)
    # every fifth 500 Hz row is a 100 Hz sample: the same pose (the spline's knots)
    n = min(len(slow), len(fast[::5]))
    np.testing.assert_allclose(fast[::5][:n, 0], slow[:n, 0], atol=1e-9)
    np.testing.assert_allclose(fast[::5][:n, 1:], slow[:n, 1:], rtol=0.0, atol=1e-12)
