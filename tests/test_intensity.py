"""``--intensity PCT`` (issue 20, Build item 5): a point of the preset's tuned range.

On an excerpt of the bundled lap (never tuned on), ``racing-hexapod-strong`` (the preset
with a tuned intensity range) at 0, 50 and 100 % gives monotonically stronger rides (the
tuner's strength, the geometric mean of the rendered shares of fx and fy, and the shares of
fx and fy each; definitions of ``motioncue.cueing._metrics``; measured 0.028 / 0.088,
0.038 / 0.123 and 0.046 / 0.135),
each a complete washout between the two tuned ends (not a
plain gain), and ``generate --intensity`` publishes each ride only after the checks ``play``
makes (every frame within the limits on the controller's clock). Bad intensities and
presets without a range are refused with one line.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from motioncue.analysis._compare import run_chain
from motioncue.cli import main
from motioncue.cueing import at_intensity, load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import Recording, read_recording_csv, write_recording_csv
from motioncue.trajectory import ActuatorLimits

PLATFORM, CONTROLLER, PRESET, RATE = "stewart6-linear", "mbox6", "racing-hexapod-strong", 100.0


@pytest.fixture(scope="module")
def lap_excerpt(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rec = read_recording_csv(sample_drives("demo")[0])
    a, b = 1000, 4000  # 10 s to 40 s: braking, corners, a crest
    out = tmp_path_factory.mktemp("intensity") / "lap-10-40.csv"
    write_recording_csv(out, Recording(rec.t_s[a:b] - rec.t_s[a], rec.f[a:b], rec.w[a:b]))
    return out


def test_intensity_points_are_tuned_designs_between_the_ends() -> None:
    strong = load_cueing(PRESET)
    assert strong.intensity_gentle is not None
    assert at_intensity(strong, 100.0) is strong
    gentle = at_intensity(strong, 0.0)
    mid = at_intensity(strong, 50.0)
    # geometric midpoint of every tuned value, e.g. the tilt gains and the tilt rate
    for name, i in (("tilt_scale", 0), ("tilt_scale", 1), ("f_scale", 1)):
        lo, hi, m = getattr(gentle, name)[i], getattr(strong, name)[i], getattr(mid, name)[i]
        assert m == pytest.approx(math.sqrt(lo * hi), rel=1e-9)
    assert mid.tilt_rate_limit_rad_s == pytest.approx(
        math.sqrt(gentle.tilt_rate_limit_rad_s * strong.tilt_rate_limit_rad_s), rel=1e-9
    )
    # not a plain gain: more than the scales differ between the ends
    assert gentle.tilt_wn_rad_s != pytest.approx(strong.tilt_wn_rad_s, rel=1e-3) or (
        gentle.tilt_reach_use != pytest.approx(strong.tilt_reach_use, rel=1e-3)
    )


def test_intensity_0_50_100_is_monotonically_stronger_within_the_limits(
    lap_excerpt: Path, tmp_path: Path
) -> None:
    platform = load_platform(PLATFORM)
    limits = ActuatorLimits.from_platform(platform, load_controller(CONTROLLER), rate_hz=RATE)
    rec = read_recording_csv(lap_excerpt)
    strong = load_cueing(PRESET)
    shares = []
    for pct in (0.0, 50.0, 100.0):
        run = run_chain(rec.f, rec.w, at_intensity(strong, pct), platform, limits, RATE)
        ev = run.evaluation
        m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds)
        shares.append(m.rendered_share[:2])
        assert run.poses_clamped <= 0.01 * len(run.poses)
        # and the ride generate makes at this intensity passes play's checks
        out = tmp_path / f"i{pct:g}.ride"
        import contextlib
        import io

        buf = io.StringIO()
        with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
            rc = main([
                "generate", "--input", str(lap_excerpt), "--platform", PLATFORM,
                "--controller", CONTROLLER, "--preset", PRESET, "--intensity", f"{pct:g}",
                "--out", str(out),
                "--quiet", "--json",
            ])  # fmt: skip
        assert rc == 0
        summary = json.loads(buf.getvalue())
        assert "OK" in summary["frame_check"], summary["frame_check"]
        assert out.exists()
    s = np.array(shares)
    strength = np.sqrt(s[:, 0] * s[:, 1])  # the tuner's strength: geometric mean of fx, fy
    print("shares fx, fy at 0/50/100 %:", s.round(4).tolist())
    assert np.all(np.diff(strength) > 0.0), s
    assert np.all(np.diff(s[:, 1]) > 0.0), s  # fy grows 0 -> 50 -> 100
    assert np.all(np.diff(s[:, 0]) > 0.0), s  # and so does fx
    assert strength[2] >= 1.1 * strength[0], s  # and the range is more than a nudge


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--intensity", "120"], "intensity 120.0 % is invalid"),
        (["--intensity", "nan"], "intensity nan % is invalid"),
        (["--intensity", "50", "--preset", "racing"], "has no tuned intensity range"),
        # the platform's default (with or without a range): test_intensity_play.py
    ],
)
def test_bad_intensity_is_one_line(
    lap_excerpt: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str], args: list[str],
    message: str,
) -> None:  # fmt: skip
    out = tmp_path / "x.ride"
    rc = main([
        "generate", "--input", str(lap_excerpt), "--platform", PLATFORM, "--controller",
        CONTROLLER, "--out", str(out), "--quiet", *args,
    ])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 2
    assert message in err and "Traceback" not in err
    assert err.strip().splitlines()[-1].startswith("motioncue generate: error:")
    assert not out.exists()


def test_profile_intensity_is_read_and_checked(tmp_path: Path) -> None:
    from motioncue._errors import ConfigError
    from motioncue.pipeline._profile import load_profile

    good = tmp_path / "p.toml"
    good.write_text('source = "f1"\npreset = "racing-hexapod-strong"\nintensity = 40\n')
    assert load_profile(good).intensity == 40.0
    bad = tmp_path / "q.toml"
    bad.write_text('source = "f1"\nintensity = 140\n')
    with pytest.raises(ConfigError, match="intensity"):
        load_profile(bad)
