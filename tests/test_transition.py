"""toppra transitions: analytic trapezoid, multi-axis limits when sampled, park/unpark."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import motioncue
from motioncue import LimitError
from motioncue.trajectory import (
    ActuatorLimits,
    RealtimeLimiter,
    check_trajectory,
    limit_pose,
    park_path,
    resume_path,
    transition,
    transition_q,
    transition_through,
    unpark_path,
)


def _trapezoid_time(d, v, a):
    return d / v + v / a if d >= v * v / a else 2.0 * np.sqrt(d / a)


@pytest.mark.parametrize(
    ("d", "v", "a"), [(0.15, 0.25, 3.0), (0.01, 0.25, 3.0), (0.3, 0.1, 10.0), (0.05, 0.5, 1.0)]
)
def test_single_axis_matches_bang_coast_bang(d, v, a):
    lim = ActuatorLimits([-0.2], [0.2], [v], [a])
    tr = transition_q([-0.15], [-0.15 + d], lim, 100.0)
    t_ref = _trapezoid_time(d, v, a)
    assert tr.duration_s == pytest.approx(t_ref, rel=0.01)
    assert tr.check.ok
    assert tr.q[0, 0] == -0.15
    assert tr.q[-1, 0] == pytest.approx(-0.15 + d, abs=1e-12)
    assert tr.n_frames == int(np.ceil(tr.duration_s * 100 - 1e-9)) + 1


@pytest.fixture(scope="module")
def hexapod():
    return motioncue.load_platform("stewart6-linear")


@pytest.fixture(scope="module")
def hex_limits(hexapod):
    v = np.array([0.25, 0.2, 0.25, 0.15, 0.25, 0.3])
    a = np.array([3.0, 2.0, 4.0, 3.0, 2.5, 5.0])
    return ActuatorLimits(hexapod.q_min, hexapod.q_max, v, a)


POSES = [
    ([0.02, 0, 0, 0.05, 0, 0.1], [0, -0.02, 0.01, 0, 0.05, 0]),
    ([0, 0, 0, 0, 0, 0], [0.03, 0.03, -0.02, 0.05, -0.05, 0.1]),
    ([-0.03, 0.01, 0.02, -0.04, 0.02, -0.1], [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
]


@pytest.mark.parametrize(("a", "b"), POSES)
@pytest.mark.parametrize("rate", [60.0, 100.0, 250.0])
def test_multi_axis_transition_respects_every_limit_when_sampled(hexapod, hex_limits, a, b, rate):
    tr = transition(hexapod, a, b, hex_limits, rate)
    dt = 1.0 / rate
    # independent check: rest before, rest after, finite differences of the frames
    padded = np.concatenate([tr.q, tr.q[-1:], tr.q[-1:]])
    chk = check_trajectory(padded, dt, hex_limits, history=np.stack([tr.q[0], tr.q[0]]))
    assert chk.ok, chk
    np.testing.assert_allclose(tr.poses[0], a, atol=1e-12)
    np.testing.assert_allclose(tr.poses[-1], b, atol=1e-12)
    np.testing.assert_allclose(tr.q, hexapod.inverse(tr.poses), atol=1e-12)
    # the poses lie on the straight line between a and b, in order
    d = np.asarray(b) - np.asarray(a)
    s = (tr.poses - a) @ d / (d @ d)
    np.testing.assert_allclose(tr.poses, np.asarray(a) + s[:, None] * d, atol=1e-12)
    assert np.all(np.diff(s) >= -1e-12)
    # time-optimal: at least one actuator reaches a speed or acceleration limit
    v = np.abs(np.diff(tr.q, axis=0)) / dt / hex_limits.v_max
    acc = np.abs(np.diff(tr.q, 2, axis=0)) / dt**2 / hex_limits.a_max
    assert max(v.max(), acc.max()) > 0.9


def test_keyframes_with_free_timing(hexapod, hex_limits):
    keys = np.array([[0, 0, 0, 0, 0, 0], POSES[0][0], POSES[0][1], [0, 0, 0.01, 0, 0, 0]])
    tr = transition_through(hexapod, keys, hex_limits, 100.0)
    assert tr.check.ok
    # passes near every keyframe (frames are time samples, so within one frame's travel)
    step = np.max(np.linalg.norm(np.diff(tr.poses, axis=0), axis=1))
    for k in keys:
        assert np.min(np.linalg.norm(tr.poses - k, axis=1)) <= step
    np.testing.assert_allclose(tr.poses[-1], keys[-1], atol=1e-12)


def test_unpark_park_and_resume(hexapod, hex_limits):
    up = unpark_path(hexapod, hex_limits, 100.0)
    assert up.check.ok
    np.testing.assert_allclose(up.q[0], hexapod.q_park, atol=1e-9)
    np.testing.assert_allclose(up.poses[-1], np.zeros(6), atol=1e-12)
    down = park_path(hexapod, hex_limits, 100.0, pose_from=np.zeros(6))
    assert down.check.ok
    np.testing.assert_allclose(down.q[-1], hexapod.q_park, atol=1e-9)
    res = resume_path(hexapod, POSES[0][0], POSES[0][1], hex_limits, 100.0)
    assert res.check.ok


def test_park_while_moving_brakes_first_then_parks(hexapod, hex_limits):
    q_from = np.full(6, 0.02)
    v_from = np.array([0.2, -0.15, 0.1, 0.1, -0.2, 0.25])
    rt = RealtimeLimiter(hex_limits, 0.01)
    assert rt.is_admissible(q_from, v_from)
    tr = park_path(hexapod, hex_limits, 100.0, q_from=q_from, v_from=v_from)
    assert tr.check.ok, tr.check
    hist = np.stack([q_from - v_from * 0.01, q_from])
    chk = check_trajectory(tr.q, 0.01, hex_limits, history=hist)
    assert chk.ok
    np.testing.assert_allclose(tr.q[-1], hexapod.q_park, atol=1e-9)
    # the first frame continues the motion (no jump): its speed is within one accel step
    v1 = (tr.q[0] - q_from) / 0.01
    assert np.all(np.abs(v1 - v_from) <= hex_limits.a_max * 0.01 + 1e-9)


def test_path_outside_the_stroke_is_refused(hexapod, hex_limits):
    with pytest.raises(LimitError):
        transition(hexapod, np.zeros(6), [0, 0, 0.2, 0, 0, 0], hex_limits, 100.0)


def test_zero_length_transition_is_one_frame(hexapod, hex_limits):
    tr = transition(hexapod, POSES[0][0], POSES[0][0], hex_limits, 100.0)
    assert tr.n_frames == 1 and tr.duration_s == 0.0


@settings(max_examples=25, deadline=None)
@given(
    st.sampled_from(["stewart6-linear", "stewart6-rotary", "seat3", "seat2-yaw"]),
    st.integers(0, 2**32 - 1),
    st.sampled_from([50.0, 100.0, 200.0]),
)
def test_random_transitions_respect_every_limit_when_sampled(name, seed, rate):
    p = motioncue.load_platform(name)
    rng = np.random.default_rng(seed)
    kind_scale = np.where(np.array(p.actuator_kinds) == "rotary", 10.0, 1.0)
    lim = ActuatorLimits(
        p.q_min, p.q_max, rng.uniform(0.05, 0.4, p.n_actuators) * kind_scale,
        rng.uniform(0.5, 8.0, p.n_actuators) * kind_scale,
    )  # fmt: skip
    ends = limit_pose(p, rng.normal(0.0, [0.03, 0.03, 0.02, 0.1, 0.1, 0.3], (2, 6))).pose
    try:
        tr = transition(p, ends[0], ends[1], lim, rate)
    except LimitError:
        # only allowed when the straight line leaves the workspace
        s = np.linspace(0, 1, 201)[:, None]
        assert not np.all(p.check(ends[0] + s * (ends[1] - ends[0])).ok)
        return
    dt = 1.0 / rate
    padded = np.concatenate([tr.q, tr.q[-1:], tr.q[-1:]])
    chk = check_trajectory(padded, dt, lim, history=np.stack([tr.q[0], tr.q[0]]))
    assert chk.ok, chk
    np.testing.assert_allclose(tr.poses[-1], ends[1], atol=1e-12)


def test_unsupported_pose_components_are_zeroed():
    p = motioncue.load_platform("seat3")  # heave, roll, pitch only
    lim = ActuatorLimits(p.q_min, p.q_max, np.full(3, 0.2), np.full(3, 3.0))
    tr = transition(p, np.zeros(6), [0.05, 0.05, 0.01, 0.05, 0.0, 0.3], lim, 100.0)
    assert np.all(tr.poses[:, ~p.dof_mask] == 0.0)
    np.testing.assert_allclose(tr.q, p.inverse(tr.poses), atol=1e-12)
    assert tr.check.ok


def test_jerk_limited_transitions_and_park(hexapod):
    lim = ActuatorLimits.from_platform(hexapod, v_max=0.25, a_max=4.0, j_max=60.0)
    dt = 0.01
    for tr in (
        unpark_path(hexapod, lim, 100.0),
        transition(hexapod, POSES[0][0], POSES[0][1], lim, 100.0),
        transition_q(np.zeros(6), np.full(6, 0.05), lim, 100.0),
    ):
        padded = np.concatenate([tr.q, np.repeat(tr.q[-1:], 3, axis=0)])
        chk = check_trajectory(padded, dt, lim, history=np.repeat(tr.q[:1], 3, axis=0))
        assert chk.ok and chk.jerk <= 1e-9, chk
        assert tr.duration_s == pytest.approx((tr.n_frames - 1) * dt)
        if not np.isnan(tr.poses).any():
            np.testing.assert_allclose(hexapod.inverse(tr.poses), tr.q, atol=1e-9)
    # without the jerk limit the same move is faster (toppra's bang-coast-bang)
    fast = transition_q(np.zeros(6), np.full(6, 0.05), lim.without_jerk(), 100.0)
    assert fast.n_frames < tr.n_frames
    # park from a moving state: brake (jerk-limited), then transition, all within limits
    q_from = np.full(6, 0.01)
    v_from = np.array([0.1, -0.1, 0.05, 0.0, 0.2, -0.2])
    a_from = np.array([1.0, 0.0, -1.0, 0.5, 0.0, 0.0])
    park = park_path(hexapod, lim, 100.0, q_from=q_from, v_from=v_from, a_from=a_from)
    assert park.check.ok and park.check.jerk <= 1e-9
    np.testing.assert_allclose(park.q[-1], hexapod.q_park, atol=1e-9)


# ------------------------------------------------------------- from and to motion (s25)
_ACC = np.array([0.17, 0.17, 0.28, 0.34, 0.34, 0.34])


def test_quintic_meets_its_ends_by_finite_differences():
    from motioncue.trajectory._transition import quintic_poses

    rng = np.random.default_rng(5)
    p0, p1, v0, v1 = (rng.normal(size=6) * s for s in (0.05, 0.05, 0.1, 0.1))
    T, h = 1.3, 1e-4
    t = np.array([0.0, h, 2 * h, T - 2 * h, T - h, T])
    p, acc = quintic_poses(p0, v0, p1, v1, T, t)
    np.testing.assert_allclose(p[0], p0, atol=1e-12)
    np.testing.assert_allclose(p[-1], p1, atol=1e-12)
    np.testing.assert_allclose((p[1] - p[0]) / h, v0, atol=1e-3)  # forward differences
    np.testing.assert_allclose((p[-1] - p[-2]) / h, v1, atol=1e-3)
    np.testing.assert_allclose(acc[[0, -1]], 0.0, atol=1e-12)
    np.testing.assert_allclose((p[2] - 2 * p[1] + p[0]) / h**2, 0.0, atol=0.05)
    # the acceleration returned is the second derivative of the position
    tt = np.linspace(0.0, T, 2001)
    pp, aa = quintic_poses(p0, v0, p1, v1, T, tt)
    d2 = np.diff(pp, 2, axis=0) / (tt[1] - tt[0]) ** 2
    np.testing.assert_allclose(d2, aa[1:-1], atol=1e-4)


@pytest.mark.parametrize("end", ["from", "to"])
def test_a_move_from_or_to_motion_has_no_velocity_step_and_keeps_its_targets(
    hexapod: motioncue.kinematics.Platform, hex_limits: ActuatorLimits, end: str
) -> None:
    lim = hex_limits
    cue = np.array([0.03, -0.02, 0.01, 0.02, -0.03, 0.05])
    v = np.array([0.08, -0.05, 0.02, 0.05, 0.0, -0.04])
    park = np.asarray(hexapod.pose_park, dtype=float)
    if end == "from":
        tr = transition(hexapod, cue, park, lim, 100.0, v_from=v, accel_max=_ACC)
        start, stop, v0, v1 = cue, park, v, np.zeros(6)
    else:
        tr = transition(hexapod, park, cue, lim, 100.0, v_to=v, accel_max=_ACC)
        start, stop, v0, v1 = park, cue, np.zeros(6), v
    dt = 0.01
    p = tr.poses
    np.testing.assert_allclose(p[0], start, atol=1e-12)
    np.testing.assert_allclose(p[-1], stop, atol=1e-12)
    assert tr.check.ok and not tr.shortened and not tr.fallback
    # no velocity step: the first (last) frame's difference is the motion's, to O(a dt)
    np.testing.assert_allclose((p[1] - p[0]) / dt, v0, atol=_ACC.max() * dt)
    np.testing.assert_allclose((p[-1] - p[-2]) / dt, v1, atol=_ACC.max() * dt)
    # every component's acceleration within its target (finite differences of the frames),
    # and the time is the shortest that allows it (within a frame and the grid's rounding)
    a = np.abs(np.diff(p, 2, axis=0)) / dt**2
    assert np.all(a <= _ACC * 1.001), (a.max(axis=0), _ACC)
    assert np.max(a / _ACC) > 0.9
    # the actuators from the motion, through the move, into the motion: within the limits
    before = hexapod.inverse(start - np.outer([2, 1], v0) * dt)
    after = hexapod.inverse(stop + np.outer([1, 2], v1) * dt)
    q = np.concatenate([before, hexapod.inverse(p), after])
    assert check_trajectory(q[2:], dt, lim.without_jerk(), history=q[:2]).ok


def test_a_move_from_motion_the_workspace_cuts_short_says_so(
    hexapod: motioncue.kinematics.Platform, hex_limits: ActuatorLimits
) -> None:
    lim = hex_limits
    cue = np.array([0.05, 0.0, 0.0, 0.0, 0.0, 0.0])
    v = np.array([0.1, 0.0, 0.0, 0.0, 0.0, 0.0])  # heading away from park
    park = np.asarray(hexapod.pose_park, dtype=float)
    free = transition(hexapod, cue, park, lim, 100.0, v_from=v, accel_max=_ACC)
    reach = float(free.poses[:, 0].max())
    assert reach > 0.06 and not free.shortened  # it overshoots the cue by ~v^2 / (2 a)

    edge = 0.05 + 0.6 * (reach - 0.05)  # a workspace that ends before the free overshoot

    def box(poses: np.ndarray) -> bool:
        return bool(poses[:, 0].max() <= edge)

    tr = transition(hexapod, cue, park, lim, 100.0, v_from=v, accel_max=_ACC, accept=box)
    assert box(tr.poses) and tr.check.ok
    assert tr.duration_s < free.duration_s
    assert "shortened by the workspace" in tr.shortened, tr.shortened
    peak = np.abs(np.diff(tr.poses[:, 0], 2)).max() * 1e4
    assert peak > _ACC[0]  # faster than the target: that is what is reported
    said = float(tr.shortened.split("peak acceleration ")[1].split(" ")[0])
    assert said == pytest.approx(peak, rel=0.05) and " on x," in tr.shortened


def test_a_move_from_motion_needs_its_acceleration_targets(
    hexapod: motioncue.kinematics.Platform, hex_limits: ActuatorLimits
) -> None:
    lim = hex_limits
    with pytest.raises(motioncue.ConfigError, match="accel_max"):
        transition(hexapod, np.zeros(6), hexapod.pose_park, lim, 100.0, v_from=np.ones(6) * 0.01)
    with pytest.raises(motioncue.ConfigError, match="accel_max"):
        transition(hexapod, np.zeros(6), hexapod.pose_park, lim, 100.0,
                   v_from=np.ones(6) * 0.01, accel_max=[0.1, 0, 1, 1, 1, 1])  # fmt: skip
