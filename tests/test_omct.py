"""The Objective Motion Cueing Test: the measured chain against the linear washout, limits
that are reached lower the gain, and the ``motioncue omct`` verb."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest

from motioncue.analysis._omct import (
    OMCT_FREQUENCIES_RAD_S,
    OMCT_PATHS,
    _first_harmonic,
    linear_response,
    omct_amplitude,
    platform_motion,
    run_omct,
)
from motioncue.cli import main
from motioncue.cueing import GRAVITY_M_S2, ClassicalWashout, load_cueing
from motioncue.kinematics import load_platform
from motioncue.output._controllers import load_controller
from motioncue.trajectory import ActuatorLimits

RATE_HZ = 100.0


@pytest.fixture(scope="module")
def chain():
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE_HZ)
    return platform, limits


def test_test_frequencies_are_the_omcts():
    expected = (0.100, 0.158, 0.251, 0.398, 0.631, 1.000, 1.585, 2.512, 3.981, 6.310, 10.000,
                15.849)  # fmt: skip
    assert len(OMCT_FREQUENCIES_RAD_S) == 12
    assert np.allclose(OMCT_FREQUENCIES_RAD_S, expected, atol=6e-4)


def test_linear_response_by_hand():
    """Pin the analytic formulas at points computed by hand (independent of python-control).

    At its natural frequency a damped high-pass s^2/(s^2 + 2 z w s + w^2) is j/(2 z): the
    yaw path of the hand-written racing preset (w_scale 0.4, wn 1, zeta 1) is 0.2 at +90 deg
    at 1 rad/s. At low frequency tilt coordination gives q = -k_f s f / g: 0.4 * 0.1 / g,
    lagging -90.
    """
    design = ClassicalWashout(load_cueing("racing"), RATE_HZ)
    h = linear_response(design, "r->r", [1.0])[0]
    assert abs(h - 0.2j) < 1e-12
    h = linear_response(design, "ax->q", [0.1])[0]
    assert abs(abs(h) - 0.4 * 0.1 / GRAVITY_M_S2) < 1e-5
    assert -95.0 < math.degrees(np.angle(h)) < -90.0
    h = linear_response(design, "ay->ay", [1e-3])[0]  # tilt supplies sustained force: k_f
    assert abs(h / 0.4 - 1.0) < 5e-4  # relative, as 1e-4 was on the former k_f 0.2


def test_first_harmonic_and_platform_motion():
    t = np.arange(2000) * 0.01
    w = 2.0 * math.pi / 5.0  # four whole periods
    y = 0.3 + 1.5 * np.sin(w * t + 0.4) + 0.2 * np.sin(3.0 * w * t)
    ph = _first_harmonic(y, t, w)
    assert abs(abs(ph) - 1.5) < 1e-9 and abs(np.angle(ph) - 0.4) < 1e-9
    # constant roll: gravity seen in the tilted frame; pure yaw rate: body rate r
    n = 50
    poses = np.zeros((n, 6))
    poses[:, 3] = 0.1
    poses[:, 5] = 0.25 * np.arange(n) * 0.01
    f, wb = platform_motion(poses, 0.01)
    g = GRAVITY_M_S2
    assert np.allclose(f, [0.0, g * math.sin(0.1), g * math.cos(0.1)], atol=1e-9)
    assert np.allclose(wb, [0.0, 0.25 * math.sin(0.1), 0.25 * math.cos(0.1)], atol=1e-12)
    # a sinusoidal surge: specific force = acceleration, to the 5-point stencil's accuracy
    poses = np.zeros((400, 6))
    tt = np.arange(400) * 0.01
    poses[:, 0] = 0.01 * np.sin(15.849 * tt)
    f, _ = platform_motion(poses, 0.01)
    assert np.allclose(f[:, 0], -0.01 * 15.849**2 * np.sin(15.849 * tt[4:-4]), atol=2e-4)
    # a head 0.5 m forward of the origin on a platform turning at 0.25 rad/s (yaw, level):
    # centripetal -r^2 h_x towards the axis, nothing tangential at a constant rate
    poses = np.zeros((50, 6))
    poses[:, 5] = 0.25 * np.arange(50) * 0.01
    f, _ = platform_motion(poses, 0.01, (0.5, 0.0, 0.0))
    assert np.allclose(f, [-(0.25**2) * 0.5, 0.0, g], atol=1e-9)


def test_no_limit_reached_matches_linear_washout(chain):
    """Acceptance: every path at every test frequency within 1 % in gain and 1 deg in phase
    of the analytic linear washout, with no limit reached anywhere in the chain."""
    platform, limits = chain
    design = ClassicalWashout(load_cueing("racing-hexapod"), RATE_HZ)
    res = run_omct(design, platform, limits, amplitude_scale=0.2)
    assert len(res.points) == len(OMCT_PATHS) * 12
    for pt in res.points:
        where = f"{pt.path} at {pt.frequency_rad_s:.3f} rad/s"
        assert pt.workspace_clamped == 0 and pt.actuator_limited == 0, where
        assert pt.linear_gain > 0.0, where
        assert abs(pt.gain / pt.linear_gain - 1.0) < 0.01, (where, pt.gain, pt.linear_gain)
        assert abs(pt.phase_error_deg) < 1.0, (where, pt.phase_deg, pt.linear_phase_deg)
    worst = max(abs(pt.gain_error) for pt in res.points)
    assert worst > 0.0  # measured, not copied from the oracle


def test_tilt_gain_and_head_offset_match_linear_washout():
    """With a separate tilt gain the linear match holds at 100 Hz; with a head offset the
    force is measured at the head, and the match holds at 1000 Hz (the washout forms the
    head's angular acceleration by backward differences: a one-frame lag of that term,
    up to 11 % / 5 deg at 15.8 rad/s and 100 Hz, 1.2 % at 1000 Hz). The hand-written racing
    preset: no tilt acceleration limit, so no limit inside the washout is reached either
    (the tuned racing-hexapod's 396 deg/s^2 is, at 15.8 rad/s with a 0.35 tilt gain)."""
    platform = load_platform("stewart6-linear")
    base = load_cueing("racing")
    for rate, kw, paths, freqs in (
        (100.0, {"tilt_scale": (0.35, 0.3)}, ["ax->ax", "ay->p"], OMCT_FREQUENCIES_RAD_S),
        (1000.0, {"head_offset_m": (0.1, -0.05, 0.6)}, ["ax->ax", "p->ay"], [1.0, 3.981, 10.0]),
    ):
        limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=rate)
        design = ClassicalWashout(dataclasses.replace(base, **kw), rate)
        plain = ClassicalWashout(base, rate)
        res = run_omct(design, platform, limits, paths=paths, frequencies_rad_s=freqs,
                       amplitude_scale=0.1)  # fmt: skip
        for pt in res.points:
            where = f"{kw} {pt.path} at {pt.frequency_rad_s:.3f} rad/s"
            assert pt.workspace_clamped == 0 and pt.actuator_limited == 0, where
            assert abs(pt.gain_error) < 0.01 and abs(pt.phase_error_deg) < 1.0, (where, pt)
            # the feature changes the response: the oracle is not the plain washout's
            h0 = linear_response(plain, pt.path, [pt.frequency_rad_s])[0]
            assert abs(pt.gain / abs(h0) - 1.0) > 0.02 or pt.frequency_rad_s > 5.0, where


def test_reached_workspace_lowers_the_gain(chain):
    """A roll cue beyond the hexapod's workspace: the washout itself stays linear (its rate
    limit far away), the workspace limiting scales the poses back, the gain drops."""
    platform, limits = chain
    p = dataclasses.replace(
        load_cueing("racing-hexapod"), w_scale=(1.0, 1.0, 1.0), w_limit_rad_s=(20.0, 20.0, 20.0)
    )
    design = ClassicalWashout(p, RATE_HZ)
    assert omct_amplitude("p->p", 1.0) * 10.0 < 0.7 * 20.0  # below the washout's knee
    small = run_omct(design, platform, limits, paths=["p->p"], frequencies_rad_s=[1.0],
                     amplitude_scale=0.5)  # fmt: skip
    big = run_omct(design, platform, limits, paths=["p->p"], frequencies_rad_s=[1.0],
                   amplitude_scale=10.0)  # fmt: skip
    (s,), (b,) = small.points, big.points
    assert s.workspace_clamped == 0 and abs(s.gain_error) < 0.01
    assert b.workspace_clamped > 0
    assert b.gain < 0.9 * b.linear_gain


def test_reached_actuator_limit_lowers_the_gain(chain):
    """Slow actuators (5 % of the speed limit): the actuator limiter, not the workspace,
    cuts a heave cue the washout passes linearly (the hand-written racing preset: its heave
    high-pass passes more at 10 rad/s than the tuned one's)."""
    platform, limits = chain
    slow = limits.scaled(speed=0.05)
    design = ClassicalWashout(load_cueing("racing"), RATE_HZ)
    fast = run_omct(design, platform, limits, paths=["az->az"], frequencies_rad_s=[10.0])
    cut = run_omct(design, platform, slow, paths=["az->az"], frequencies_rad_s=[10.0])
    (a,), (b,) = fast.points, cut.points
    assert a.actuator_limited == 0 and abs(a.gain_error) < 0.01
    assert b.workspace_clamped == 0 and b.actuator_limited > 0
    assert b.gain < 0.9 * b.linear_gain


def test_bad_arguments_are_config_errors(chain):
    from motioncue import ConfigError

    platform, limits = chain
    design = ClassicalWashout(load_cueing("racing-hexapod"), RATE_HZ)
    with pytest.raises(ConfigError, match="unknown"):
        run_omct(design, platform, limits, paths=["x->y"])
    with pytest.raises(ConfigError, match="amplitude_scale"):
        run_omct(design, platform, limits, amplitude_scale=0.0)
    with pytest.raises(ConfigError, match="frequency"):
        run_omct(design, platform, limits, frequencies_rad_s=[200.0])
    with pytest.raises(ConfigError, match="frequency"):
        run_omct(design, platform, limits, frequencies_rad_s=[math.nan])


# ------------------------------------------------------------------------------------ CLI
_BASE = ["omct", "--preset", "racing-hexapod", "--platform", "stewart6-linear",
         "--controller", "mbox6"]  # fmt: skip


def test_cli_json_table(capsys):
    assert main([*_BASE, "--paths", "r->r", "ay-p", "--json"]) == 0  # ay-p: shell-safe
    data = json.loads(capsys.readouterr().out)
    assert data["preset"] == "racing-hexapod" and data["rate_hz"] == 100.0
    assert {p["path"] for p in data["paths"]} == {"r->r", "ay->p"}
    assert len(data["points"]) == 24
    units = {p["path"]: p["gain_unit"] for p in data["paths"]}
    assert units["ay->p"] == "(rad/s)/(m/s^2)" and units["r->r"] == "-"
    for pt in data["points"]:
        assert abs(pt["gain_error"]) < 0.01 and abs(pt["phase_error_deg"]) < 1.0


def test_cli_text_table_and_plot(tmp_path, capsys):
    out = tmp_path / "omct.png"
    assert main([*_BASE, "--paths", "q->q", "--plot", str(out)]) == 0
    text = capsys.readouterr().out
    assert "columns:" in text and "rad/s" in text and "deg/s" in text and "dgain" in text
    assert "q->q: pitch rate to pitch rate" in text
    rows = [ln for ln in text.splitlines() if ln.split()[:1] and ln.split()[0][:1].isdigit()]
    assert len(rows) == 12
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize(
    ("args", "needle"),
    [
        (["--preset", "nope", "--platform", "stewart6-linear", "--controller", "mbox6"],
         "nope"),
        (["--preset", "racing", "--platform", "nope", "--controller", "mbox6"], "nope"),
        (["--preset", "racing", "--platform", "stewart6-linear", "--controller", "nope"],
         "nope"),
        ([*_BASE[1:], "--paths", "x->y"], "x->y"),
        ([*_BASE[1:], "--paths", "ax-"], "quote"),
        ([*_BASE[1:], "--amplitude-scale", "0"], "--amplitude-scale"),
        ([*_BASE[1:], "--rate", "nan"], "--rate"),
        ([*_BASE[1:], "--rate", "333.3"], "333.3"),
    ],
)  # fmt: skip
def test_cli_errors_are_one_line(args, needle, capsys):
    assert main(["omct", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("motioncue omct: error:") and needle in err
    assert len(err.splitlines()) == 1
