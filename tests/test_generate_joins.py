"""The joins between a generated ride's cue and its ramps from and to park.

A cue still moving at its first or last sample (an MPC washing back at the end of a
recording, a recording that begins in motion) used to meet a ramp that starts and ends at
rest: a velocity step of the cue's whole speed in one frame (8 m/s^2 for 0.08 m/s at 100 Hz,
felt as a jolt though within the actuator limits). The cue below is synthetic (a surge
velocity of 0.08 m/s and a pitch rate of 0.05 rad/s from its first sample to its last, put in
place of the cueing stage's output), and the figures are the ride's own: whole pulses ->
forward kinematics -> finite differences, sharing nothing with the planner's numbers.
Measured: peak translational acceleration within 0.3 s of the joins 8.16 / 8.20 m/s^2 before,
0.173 / 0.166 after; pitch 5.10 / 5.12 rad/s^2 before, 0.205 / 0.202 after.

Session 25: the ramps themselves start (end) at the cue's motion: one move between the
moving cue and park whose every pose component's acceleration stays within the perception
thresholds, instead of the cue brought to rest and then the ramp's own ~0.9 m/s^2 (measured
over both ramps, joins included, per DOF: x 0.571, z 0.701 m/s^2, pitch 0.301 rad/s^2 with
stop-then-ramp; x 0.179, z 0.088, pitch 0.122 with the moves from motion; the ride 5.93 s
-> 5.84 s).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from motioncue.cueing import load_cueing
from motioncue.kinematics import Platform, load_platform
from motioncue.output import load_controller
from motioncue.pipeline import _chain, generate_ride
from motioncue.pipeline._chain import Cued
from motioncue.telemetry._recording import Recording
from motioncue.trajectory import ActuatorLimits

RATE_HZ = 100.0
SPEED_M_S = 0.08
"""The synthetic cue's surge speed at (and between) its first and last sample."""
PITCH_RATE_RAD_S = 0.05
"""... and its pitch rate."""
THRESHOLD_M_S2 = 0.17
"""Surge specific-force perception threshold (Reid & Nahon 1985)."""
HEAD_M = 0.5
"""A seated rider's head above the rotation centre: a pitch acceleration ``a`` swings it
with ``a * HEAD_M`` (m/s^2)."""
JOIN_WINDOW_S = 0.3
"""Frames this close to the cue's first or last frame are the join."""


THRESHOLDS_DOF = np.array([0.17, 0.17, 0.28, 0.34, 0.34, 0.34])
"""Perception thresholds per pose DOF: x y z (m/s^2, Reid & Nahon 1985) and, for rotations,
the angular acceleration (rad/s^2) that swings the head (HEAD_M) at the surge threshold."""
ROUNDING = 1.1
"""Allowance for the whole pulses' rounding on second differences (about 5 %)."""


def _ride(
    monkeypatch: pytest.MonkeyPatch, notes: dict | None = None, x_end_m: float = 0.04
) -> tuple[np.ndarray, np.ndarray, int, int, Platform]:
    """Generate the ride of the synthetic cue; return (poses from FK (N, 6), pulses, first
    and one-past-last cue frame, platform); the ride's notes go into ``notes``."""
    platform = load_platform("stewart6-linear")
    n = int(RATE_HZ)  # 1 s of cue: x from -0.04 to +0.04 m (by default)
    poses = np.zeros((n, 6))
    poses[:, 0] = SPEED_M_S * (np.arange(n) / RATE_HZ - 0.5) + x_end_m - 0.04
    poses[:, 4] = PITCH_RATE_RAD_S * (np.arange(n) / RATE_HZ - 0.5)

    def fake_cueing(design: object, f: np.ndarray, w: np.ndarray) -> Cued:
        assert len(f) == n
        return Cued(None, poses.copy(), np.asarray(f), np.asarray(w), 0)  # type: ignore[arg-type]

    monkeypatch.setattr(_chain, "run_cueing", fake_cueing)  # generate's cueing stage
    t = np.arange(n) / RATE_HZ
    f = np.tile([0.0, 0.0, 9.80665], (n, 1))
    ride, _ = generate_ride(
        Recording(t, f, np.zeros((n, 3))),
        platform,
        load_controller("mbox6"),
        load_cueing("racing-hexapod"),
        rate_hz=RATE_HZ,
    )
    q = platform.drives.from_pulses(ride.pulses)
    out = np.empty((len(q), 6))
    guess = None
    for i, qi in enumerate(q):
        res = platform.forward(qi, guess)
        assert res.ok, i
        out[i] = guess = res.pose
    a, b = ride.notes["cue_frames"]
    if notes is not None:
        notes.update(ride.notes)
    return out, np.asarray(ride.pulses), int(a), int(b), platform


def test_the_cue_meets_its_ramps_without_a_velocity_step(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    poses, _, a, b, _ = _ride(monkeypatch)
    dt = 1.0 / RATE_HZ
    # the cue itself is delivered (its surge speed between the joins)
    v = np.diff(poses[:, [0, 4]], axis=0) / dt
    assert np.allclose(v[a + 5 : b - 5], [SPEED_M_S, PITCH_RATE_RAD_S], atol=2e-3)
    acc = np.linalg.norm(np.diff(poses[:, :3], 2, axis=0) / dt**2, axis=1)  # frame k+1
    ang = np.linalg.norm(np.diff(poses[:, 3:], 2, axis=0) / dt**2, axis=1)  # rad/s^2
    k = np.arange(len(acc)) + 1
    w = int(JOIN_WINDOW_S * RATE_HZ)
    join_in = (k >= a - w) & (k <= a + w)
    join_out = (k >= b - 1 - w) & (k <= b - 1 + w)
    # the old joins: the whole 0.08 m/s in one frame, 8 m/s^2; now the cue is brought to rest
    # (and out of it) at about the perception threshold, the pulse rounding's noise aside
    bound = 1.5 * THRESHOLD_M_S2
    assert np.max(acc[join_in]) < bound, np.max(acc[join_in])
    assert np.max(acc[join_out]) < bound, np.max(acc[join_out])
    # the pitch rate too (the old joins: 0.05 rad/s in a frame, 5 rad/s^2): within twice
    # the threshold where the head swings
    bound_rad_s2 = 2.0 * THRESHOLD_M_S2 / HEAD_M
    assert np.max(ang[join_in]) < bound_rad_s2, np.max(ang[join_in])
    assert np.max(ang[join_out]) < bound_rad_s2, np.max(ang[join_out])


def test_the_ride_still_starts_and_ends_parked_at_rest_within_the_limits(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _, pulses, _, _, platform = _ride(monkeypatch)
    park = platform.drives.to_pulses(np.asarray(platform.q_park, dtype=float))
    assert np.array_equal(pulses[0], park)
    assert np.array_equal(pulses[-1], park) and np.array_equal(pulses[-2], park)
    # every frame within the platform's limits, by finite differences of the pulses
    lim = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE_HZ)
    table = lim.to_pulses_table(platform)
    p = pulses.astype(float)
    vel = np.diff(np.vstack([p[:1], p]), axis=0) * RATE_HZ  # from rest at park
    acc = np.diff(np.vstack([np.zeros((1, p.shape[1])), vel]), axis=0) * RATE_HZ
    for j, row in enumerate(table):
        lo, hi = row["stroke_pulses"]
        assert lo <= p[:, j].min() and p[:, j].max() <= hi, row["name"]
        # one pulse of rounding per frame allowed on top of the limits
        assert np.max(np.abs(vel[:, j])) <= row["max_speed_pulses_s"] + RATE_HZ, row["name"]
        assert np.max(np.abs(acc[:, j])) <= row["max_accel_pulses_s2"] + 2 * RATE_HZ**2, row["name"]


def test_the_way_to_and_from_park_is_one_motion_below_the_thresholds(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Both ramps whole, joins included (every frame outside the cue): each pose DOF's
    acceleration within its perception threshold (the whole pulses' rounding aside), and the
    ride's notes say each end was met from motion, not shortened."""
    notes: dict = {}
    poses, _, a, b, _ = _ride(monkeypatch, notes)
    dt = 1.0 / RATE_HZ
    acc = np.abs(np.diff(poses, 2, axis=0)) / dt**2  # frame k + 1
    k = np.arange(len(acc)) + 1
    outside = (k < a) | (k >= b)
    peak = acc[outside].max(axis=0)
    assert np.all(peak <= ROUNDING * THRESHOLDS_DOF), peak
    assert [j["end"] for j in notes["joins"]] == ["start", "end"]
    for j in notes["joins"]:
        assert j["kind"] == "from motion" and j["shortened"] == "", j
        assert 0.5 < j["duration_s"] < 5.0


def test_a_join_the_workspace_cuts_short_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    """The cue ends 5 mm inside the surge workspace (about 0.115 m on this rig), still heading
    out at 0.08 m/s: the move to park cannot overshoot as far as the thresholds would need, so
    it is shorter (its deceleration above the threshold) and the ride's notes say so."""
    notes: dict = {}
    poses, _, _, b, _ = _ride(monkeypatch, notes, x_end_m=0.11)
    start, end = notes["joins"]
    assert start["kind"] == "from motion" and start["shortened"] == ""
    assert end["kind"] in ("from motion", "stop then ramp")
    assert "shortened" in end["shortened"] and "workspace" in end["shortened"], end
    # the frames after the cue: within the workspace the chain allows, and faster than the
    # threshold (what the note reports)
    dt = 1.0 / RATE_HZ
    acc = np.abs(np.diff(poses[b - 1 :, 0], 2)) / dt**2
    assert acc.max() > THRESHOLDS_DOF[0] * ROUNDING
    assert poses[b - 1 :, 0].max() < 0.125


@pytest.mark.parametrize("x_end_m", [0.04, 0.11])
def test_generate_prints_its_joins(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    x_end_m: float,
) -> None:
    """``motioncue generate --json`` lists how the cue met each ramp, and a join the workspace
    cut short is said on stderr as a ``note:`` (a rider may feel it); a join within the
    thresholds is not."""
    import json

    from motioncue.cli import main
    from motioncue.telemetry._recording import write_recording_csv

    notes: dict = {}
    _ride(monkeypatch, notes, x_end_m=x_end_m)  # the same synthetic cue, patched in place
    n = int(RATE_HZ)
    t = np.arange(n) / RATE_HZ
    folder = tmp_path
    write_recording_csv(
        folder / "in.csv",
        Recording(t, np.tile([0.0, 0.0, 9.80665], (n, 1)), np.zeros((n, 3))),
    )
    code = main([
        "generate", "--input", str(folder / "in.csv"), "--platform", "stewart6-linear",
        "--controller", "mbox6", "--preset", "racing-hexapod", "--rate", f"{RATE_HZ:g}",
        "--out", str(folder / "out.ride"), "--json",
    ])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, err
    joins = json.loads(out)["joins"]
    assert joins == notes["joins"]
    shortened = [j for j in joins if j["shortened"]]
    assert len(shortened) == (1 if x_end_m > 0.1 else 0), joins
    said = [line for line in err.splitlines() if line.startswith("note: the cue's")]
    assert len(said) == len(shortened), err
    for line in said:
        assert "end met the ramp" in line and "workspace" in line, line
