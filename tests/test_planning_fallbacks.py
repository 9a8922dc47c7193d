"""Planning makes a ride from inputs a ride should survive (issue 23 item 9).

Each failure of the report is reproduced with a generated input: square-wave keyframes
(surge +-20 mm) on stewart6-rotary, where toppra finds no time parametrisation of a plain
straight pose line; square-wave telemetry on stewart6-rotary, whose ramp back to park left
the actuator stroke; a legal MBOX stroke limit (Fn0C0 = 1000, 100 mm from the homed origin)
that puts park on the stroke end. Where the time-optimal pose path cannot be used the move
goes in a straight line in actuator space (rest to rest, timed by the discrete limiter on the
path parameter), and the ride says so. Every ride is judged by ``pipeline._verify``, which
shares no code with the planner (numpy only), on the frames in pulses against the
controller's own limits table; jerk by a finite difference written here.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from motioncue.cli import main
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline import generate_ride
from motioncue.pipeline._generate import generate_keyframe_ride, pulse_rounding_limits
from motioncue.pipeline._inputs import Keyframes
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry._recording import Recording
from motioncue.trajectory import ActuatorLimits, transition

G = 9.80665


def _judge(ride, platform, limits) -> None:  # type: ignore[no-untyped-def]
    """The independent check: frames in pulses, the real limits table, from rest."""
    chk = check_frames(ride.t_s, ride.pulses, limits.to_pulses_table(platform), start_at_rest=True)
    assert chk.ok, chk.summary()
    park = platform.drives.to_pulses(platform.q_park)
    np.testing.assert_array_equal(ride.pulses[0], park)  # starts parked
    np.testing.assert_array_equal(ride.pulses[-1], park)  # ends parked ...
    np.testing.assert_array_equal(ride.pulses[-2], park)  # ... at rest


def _square_keyframes(amp_m: float, axis: int, n: int, period_s: float) -> Keyframes:
    poses = np.zeros((n, 6))
    poses[:, axis] = amp_m * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    return Keyframes(poses, np.arange(n) * period_s, np.zeros(n, int), np.zeros((n, 2), int))


def test_a_line_toppra_cannot_time_moves_in_actuator_space_within_the_limits() -> None:
    """-20 mm to +20 mm surge on stewart6-rotary: toppra (seidel) returns no parametrisation
    (the reverse move it times); the fallback moves and keeps every limit."""
    p = load_platform("stewart6-rotary")
    ctrl = load_controller("mbox6")
    lim = pulse_rounding_limits(ActuatorLimits.from_platform(p, ctrl, rate_hz=100.0), p, 0.01)
    a, b = np.array([0.02, 0, 0, 0, 0, 0.0]), np.array([-0.02, 0, 0, 0, 0, 0.0])
    assert transition(p, a, b, lim, 100.0).fallback == ""  # this way toppra times it
    tr = transition(p, b, a, lim, 100.0)
    assert tr.fallback.startswith("toppra found no time-optimal timing on the pose path: moved")
    np.testing.assert_allclose(tr.q[0], p.inverse(b), rtol=0, atol=1e-12)
    np.testing.assert_allclose(tr.q[-1], p.inverse(a), rtol=0, atol=1e-12)
    v = np.diff(tr.q, axis=0, prepend=tr.q[:1], append=tr.q[-1:]) * 100.0
    acc = np.diff(v, axis=0) * 100.0
    assert np.all(np.abs(v) <= lim.v_max * (1 + 1e-9))
    assert np.all(np.abs(acc) <= lim.a_max * (1 + 1e-9))
    # not crawling: the fallback is limited by the limits, not by a guess
    assert np.abs(v).max() > 0.5 * lim.v_max.max() or np.abs(acc).max() > 0.9 * lim.a_max.max()
    # the poses of the frames: forward kinematics, from b to a
    np.testing.assert_allclose(tr.poses[0], b, atol=1e-9)
    np.testing.assert_allclose(tr.poses[-1], a, atol=1e-9)


@pytest.mark.parametrize("rate_hz", [100.0, 200.0])
def test_square_wave_keyframes_on_the_rotary_hexapod_make_a_ride(rate_hz: float) -> None:
    p = load_platform("stewart6-rotary")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(p, ctrl, rate_hz=rate_hz)
    kf = _square_keyframes(0.02, 0, 6, 0.5)
    ride, info = generate_keyframe_ride(kf, p, ctrl, rate_hz=rate_hz, limits=lim)
    _judge(ride, p, lim)
    assert info["transition_fallbacks"], info  # counted and said
    assert all("straight line in actuator space" in f for f in info["transition_fallbacks"])
    assert ride.notes["transition_fallbacks"] == info["transition_fallbacks"]
    # every keyframe reached, at rest, within a pulse
    want = p.drives.to_pulses(p.inverse(kf.poses))
    got = ride.pulses[info["keyframe_frames"]]
    assert np.max(np.abs(got - want)) <= 1, got - want


def _square_telemetry(
    amp: float, freq_hz: float, seconds: float = 6.0, rotation: bool = False
) -> Recording:
    """A square wave on all three axes of the specific force (m/s^2) or of the angular
    velocity (rad/s), 100 Hz."""
    t = np.arange(int(seconds * 100)) / 100.0
    f = np.zeros((t.size, 3))
    f[:, 2] = G
    w = np.zeros((t.size, 3))
    wave = amp * np.sign(np.sin(2 * np.pi * freq_hz * t) + 1e-12)[:, None]
    if rotation:
        w += wave
    else:
        f += wave
    return Recording(t, f, w)


@pytest.mark.parametrize(
    ("platform", "preset", "amp", "freq_hz", "rotation"),
    [
        # the rotary rig's default was the generic racing preset when this failed; its own
        # racing-rotary (issue 20) stays clear of the stroke here, so the case names racing
        ("stewart6-rotary", "racing", 2 * G, 1.0, False),
        ("stewart6-linear", "racing-hexapod", 0.5, 0.25, True),
    ],
)
def test_square_wave_telemetry_makes_a_ride(
    platform: str, preset: str, amp: float, freq_hz: float, rotation: bool
) -> None:
    """8 s of square waves whose ramp back to park along the pose line left the stroke
    ("the transition path leaves the actuator stroke" before)."""
    p = load_platform(platform)
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(p, ctrl, rate_hz=100.0)
    ride, rep = generate_ride(
        _square_telemetry(amp, freq_hz, 8.0, rotation), p, ctrl, load_cueing(preset),
        rate_hz=100.0, limits=lim,
    )  # fmt: skip
    _judge(ride, p, lim)
    assert len(rep.transition_fallbacks) == 1, rep.transition_fallbacks
    assert rep.transition_fallbacks[0].startswith(
        "ramp back to park: the pose path leaves the actuator stroke: moved in a straight "
        "line in actuator space instead (rest to rest, "
    )
    assert ride.notes["transition_fallbacks"] == list(rep.transition_fallbacks)


def test_a_100_mm_mbox_stroke_from_the_homed_origin_makes_a_ride(tmp_path: Path) -> None:
    """Fn0C0 = 1000 (100 mm from pulse 0, the homed park position): park lies on the stroke
    end, half a pulse outside the stroke tightened for rounding; was "the transition path
    leaves the actuator stroke"."""
    src = Path(__file__).resolve().parents[1] / "configs" / "controllers" / "mbox6.toml"
    text = src.read_text()
    assert "\nFn0C0 = 0\n" in text
    path = tmp_path / "mbox6-100mm.toml"
    path.write_text(text.replace("\nFn0C0 = 0\n", "\nFn0C0 = 1000\n"))
    p = load_platform("stewart6-linear")
    ctrl = load_controller(str(path))
    lim = ActuatorLimits.from_platform(p, ctrl, rate_hz=100.0)
    table = lim.to_pulses_table(p)
    assert all(row["stroke_pulses"] == [0, 200_000] for row in table)  # 100 mm from the origin
    rec = _square_telemetry(0.5 * G, 0.5, 4.0)
    ride, _ = generate_ride(rec, p, ctrl, load_cueing(p.default_preset), rate_hz=100.0, limits=lim)
    _judge(ride, p, lim)
    assert ride.pulses.min() == 0  # park, pulse 0, on the stroke end


def test_generate_cli_says_what_the_fallback_changed(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    rows = ["t,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg"]
    rows += [f"{0.5 * k:g},{20 if k % 2 == 0 else -20},0,0,0,0,0" for k in range(4)]
    csv = tmp_path / "square.csv"
    csv.write_text("\n".join(rows) + "\n")
    out = tmp_path / "square.ride"
    args = ["generate", "--input", str(csv), "--platform", "stewart6-rotary", "--controller",
            "mbox6", "--rate", "100", "--out", str(out), "--quiet"]  # fmt: skip
    assert main(args) == 0
    err = capsys.readouterr().err
    # -20 -> +20 mm is the move toppra cannot time (keyframes 2 to 3); +20 -> -20 it can
    assert "note: keyframe 2 to 3: toppra found no time-optimal timing on the pose path: moved " \
           "in a straight line in actuator space instead (rest to rest," in err, err  # fmt: skip
    assert "note: keyframe 1 to 2" not in err
    assert "Traceback" not in err
    assert main([*args, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["transition_fallbacks"] >= 1


@pytest.mark.parametrize("jerk", [False, True])
def test_the_line_fallback_keeps_the_limits_on_random_moves(jerk: bool) -> None:
    """The fallback itself, on random moves through random knots with random limits:
    stroke, speed, acceleration (and jerk) by finite differences written here, from and to
    rest; ends exact."""
    from motioncue.trajectory._transition import _line_fallback

    rng = np.random.default_rng(3 + jerk)
    for _ in range(10):
        n = int(rng.integers(1, 7))
        lim = ActuatorLimits(
            -rng.uniform(0.05, 0.1, n), rng.uniform(0.05, 0.1, n), rng.uniform(0.05, 0.5, n),
            rng.uniform(0.5, 20.0, n), rng.uniform(50.0, 2000.0, n) if jerk else None,
        )  # fmt: skip
        knots = rng.uniform(lim.q_min, lim.q_max, (int(rng.integers(2, 5)), n))
        rate = float(rng.choice([50.0, 100.0, 250.0]))
        tr = _line_fallback(knots, lim, rate, None, "test")
        q = np.concatenate([tr.q[:1]] * 3 + [tr.q] + [tr.q[-1:]] * 3)
        assert np.all(q >= lim.q_min) and np.all(q <= lim.q_max)
        v = np.diff(q, axis=0) * rate
        a = np.diff(v, axis=0) * rate
        assert np.all(np.abs(v) <= lim.v_max * (1 + 1e-9))
        assert np.all(np.abs(a) <= lim.a_max * (1 + 1e-9))
        if jerk:
            assert np.all(np.abs(np.diff(a, axis=0) * rate) <= lim.j_max * (1 + 1e-9))
        np.testing.assert_allclose(tr.q[0], knots[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(tr.q[-1], knots[-1], rtol=0, atol=1e-12)
        for kq in knots[1:-1]:  # through every knot, at rest there
            assert np.min(np.max(np.abs(tr.q - kq), axis=1)) < 1e-12


@pytest.mark.parametrize(("platform", "ctrl"), [("seat3", "imax3"), ("corner4", "mbox6")])
def test_free_time_keyframes_a_platform_cannot_produce_make_a_ride(
    platform: str, ctrl: str
) -> None:
    """Surge square-wave keyframes without times on a machine without surge: held at zero,
    they coincide; the move passes there once (was "keyframes must differ from their
    neighbours", though the file's keyframes do differ)."""
    p = load_platform(platform)
    c = load_controller(ctrl)
    lim = ActuatorLimits.from_platform(p, c, rate_hz=100.0)
    kf = _square_keyframes(0.02, 0, 6, 0.0)
    kf = Keyframes(kf.poses, np.full(6, np.nan), kf.dout, kf.dacs)
    ride, info = generate_keyframe_ride(kf, p, c, rate_hz=100.0, limits=lim)
    _judge(ride, p, lim)
    # the move passes neutral (without stopping: free timing) within one frame's travel
    neutral = p.drives.to_pulses(p.inverse(np.zeros(6)))
    step = np.array([r["max_speed_pulses_s"] for r in lim.to_pulses_table(p)]) / 100.0
    assert np.all(np.abs(ride.pulses[info["keyframe_frames"]] - neutral) <= step + 1)
    assert np.ptp(ride.pulses, axis=0).max() > 10 * step.max()  # it did move there
