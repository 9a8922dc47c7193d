"""Real-time limiter: safety from any admissible state, exact pass-through, braking oracle."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError
from motioncue.trajectory import (
    ActuatorLimits,
    RealtimeLimiter,
    braking_distance,
    braking_speed_cap,
    check_trajectory,
)

TOL = 1e-9


# ----------------------------------------------------------------------------- strategies
# The strategies the composites below draw from, built once: a composite that builds its
# strategies at each draw spends a good part of its time on that (st.floats looks its
# arguments up in Hypothesis' cache each time), and the same strategies draw the same values.
_N_AXES, _Q_MIN, _SPAN = st.integers(1, 6), st.floats(-0.5, 0.5), st.floats(0.01, 1.0)
_V_MAX, _A_MAX = st.floats(0.01, 2.0), st.floats(0.1, 60.0)
_DT = st.sampled_from([0.001, 0.002, 0.004, 0.01, 0.0166667, 0.02, 0.05])
_AT_END = st.sampled_from([0.0, 1.0, None])
_KIND = st.sampled_from(["step", "spike", "impulse", "chatter", "nan", "inf", "far", "noise"])
_LEVEL, _SPIKE = st.floats(-0.5, 1.5), st.sampled_from([1e3, -1e3, 1e300, -1e300, 1.7e308])
_IMPULSE, _CHATTER = st.floats(-3, 3), st.floats(0.0, 2.0)
_INF = st.sampled_from([np.inf, -np.inf])
_FAR = st.sampled_from([-1e6, 1e6, 1e12, -1e12, 1.7e308, -1.7e308])
_SEED, _PART, _PARTS = st.integers(0, 2**32 - 1), st.integers(1, 60), st.integers(1, 5)


@st.composite
def limits_and_dt(draw, n=None):
    n = n or draw(_N_AXES)
    q_min = np.array([draw(_Q_MIN) for _ in range(n)])
    span = np.array([draw(_SPAN) for _ in range(n)])
    v_max = np.array([draw(_V_MAX) for _ in range(n)])
    a_max = np.array([draw(_A_MAX) for _ in range(n)])
    dt = draw(_DT)
    return ActuatorLimits(q_min, q_min + span, v_max, a_max), dt


_LIMITS_AND_DT = limits_and_dt()


@st.composite
def admissible_state(draw, lim, dt):
    """Any admissible (q, v): speed first, then a position from which it can still stop."""
    q, v = [], []
    for i in range(lim.n_actuators):
        lo, hi = float(lim.q_min[i]), float(lim.q_max[i])
        vmax, amax = float(lim.v_max[i]), float(lim.a_max[i])
        # largest admissible |v| from mid-stroke is bounded by the braking cap
        cap = min(vmax, braking_speed_cap((hi - lo), amax, dt))
        vi = draw(st.floats(-cap, cap))
        d = braking_distance(vi, amax, dt)
        qlo = lo + (d if vi < 0 else 0.0)
        qhi = hi - (d if vi > 0 else 0.0)
        assume(qlo <= qhi)
        frac = draw(_AT_END)
        qi = (qlo if frac == 0.0 else qhi) if frac is not None else draw(st.floats(qlo, qhi))
        q.append(qi)
        v.append(vi)
    return np.array(q), np.array(v)


def _segment(draw, n, lim, length):
    """One adversarial piece of target stream (length, n)."""
    kind = draw(_KIND)
    lo, hi = lim.q_min, lim.q_max
    span = hi - lo
    level = lo + span * draw(_LEVEL)
    seg = np.repeat(level[None, :], length, axis=0)
    if kind == "spike":
        k = draw(st.integers(0, length - 1))
        seg[k] = draw(_SPIKE) * np.ones(n)
    elif kind == "impulse":
        seg[::3] += span * draw(_IMPULSE)
    elif kind == "chatter":
        amp = draw(_CHATTER) * span
        seg += amp * (2 * (np.arange(length) % 2) - 1)[:, None]
    elif kind == "nan":
        seg[draw(st.integers(0, length - 1)) :] = np.nan
    elif kind == "inf":
        seg[:: max(1, length // 3)] = draw(_INF)
    elif kind == "far":
        seg[:] = draw(_FAR)
    elif kind == "noise":
        seed = draw(_SEED)
        seg = lo + span * np.random.default_rng(seed).uniform(-1, 2, (length, n))
    return seg


@st.composite
def scenario(draw):
    lim, dt = draw(_LIMITS_AND_DT)
    q0, v0 = draw(admissible_state(lim, dt))
    parts = [_segment(draw, lim.n_actuators, lim, draw(_PART)) for _ in range(draw(_PARTS))]
    return lim, dt, q0, v0, np.concatenate(parts)


def _check_safe(lim, dt, q0, v0, out):
    history = np.stack([q0 - v0 * dt, q0])
    chk = check_trajectory(out, dt, lim, history=history)
    assert chk.finite
    assert chk.stroke <= TOL, chk
    assert chk.speed <= TOL, chk
    assert chk.accel <= TOL, chk
    return chk


# ----------------------------------------------------------------------------- safety
@settings(max_examples=300)
@given(scenario())
def test_adversarial_streams_stay_within_every_limit(case):
    lim, dt, q0, v0, targets = case
    rt = RealtimeLimiter(lim, dt)
    state = rt.initial_state(q0, v0)
    out = rt.run(state, targets)
    _check_safe(lim, dt, q0, v0, out)
    # the state after the stream is admissible again, so the stream could go on safely
    assert rt.is_admissible(state.q, state.v)
    assert state.n_frames == len(targets)
    assert state.n_nonfinite == int(np.sum(~np.isfinite(targets)))


@settings(max_examples=150)
@given(limits_and_dt(), st.integers(0, 2**32 - 1))
def test_full_speed_into_the_stroke_end_brakes_in_time(case, seed):
    """Start at full admissible speed towards an end, target far beyond it."""
    lim, dt = case
    rng = np.random.default_rng(seed)
    rt = RealtimeLimiter(lim, dt)
    sign = rng.choice([-1.0, 1.0], lim.n_actuators)
    q0, v0 = [], []
    for i in range(lim.n_actuators):
        lo, hi = float(lim.q_min[i]), float(lim.q_max[i])
        a = float(lim.a_max[i])
        v = min(float(lim.v_max[i]), braking_speed_cap(hi - lo, a, dt))
        d = braking_distance(v, a, dt)
        q0.append(hi - d if sign[i] > 0 else lo + d)  # right at the braking boundary
        v0.append(sign[i] * v)
    q0, v0 = np.array(q0), np.array(v0)
    assert rt.is_admissible(q0, v0)
    n_stop = lim.braking_steps(dt) + 2
    assume(n_stop < 4000)
    targets = np.repeat((sign * 1e3)[None, :], n_stop, axis=0)
    out = rt.run(rt.initial_state(q0, v0), targets)
    _check_safe(lim, dt, q0, v0, out)
    # it ends at rest against the stroke end it was heading to
    end = np.where(sign > 0, lim.q_max, lim.q_min)
    np.testing.assert_allclose(out[-1], end, atol=1e-9)
    np.testing.assert_allclose(out[-1], out[-2], atol=1e-12)


# ----------------------------------------------------------------------------- pass-through
@settings(max_examples=150)
@given(scenario(), st.floats(0.3, 0.99))
def test_feasible_streams_pass_through_exactly(case, shrink):
    """A stream made feasible by a tighter limiter goes through the real one bit for bit."""
    lim, dt, q0, _v0, targets = case
    mid = 0.5 * (lim.q_min + lim.q_max)
    half = 0.5 * (lim.q_max - lim.q_min) * shrink
    tight = ActuatorLimits(mid - half, mid + half, lim.v_max * shrink, lim.a_max * shrink)
    rt_tight = RealtimeLimiter(tight, dt)
    q_start = np.clip(q0, tight.q_min, tight.q_max)
    feasible = rt_tight.run(rt_tight.initial_state(q_start), targets)
    rt = RealtimeLimiter(lim, dt)
    state = rt.initial_state(q_start)
    out = rt.run(state, feasible)
    assert np.array_equal(out, feasible)
    assert state.n_clamped == 0


@settings(max_examples=150)
@given(scenario())
def test_its_own_output_passes_through_again(case):
    """Idempotence: what the limiter sent, fed back from the same state, is sent again to
    1e-12 m. Its frames reach the bounds exactly, and the differences recomputed from them
    miss by rounding (~1e-15 m/s); the landing test's slack absorbs that, where without it
    a hexapod ride was limited again on a quarter of its frames by up to 7 mm. (A frame
    that braked onto a stroke end may lie beyond it by rounding, ~1e-14 m: the limiter
    then decides it again, and sends the same frame.)"""
    lim, dt, q0, v0, targets = case
    rt = RealtimeLimiter(lim, dt)
    out = rt.run(rt.initial_state(q0, v0), targets)
    state = rt.initial_state(q0, v0)
    again = rt.run(state, out)
    np.testing.assert_allclose(again, out, rtol=0, atol=1e-12)
    assert state.max_deviation <= 1e-12


def hexapod_sines(n_frames: int) -> np.ndarray:
    """A 6-axis ride at 100 Hz, (n_frames, 6) m: four random sines per axis, 30 mm each."""
    rng = np.random.default_rng(3)
    t = np.arange(n_frames)[:, None] * 0.01
    return sum(0.03 * np.sin(2 * np.pi * rng.uniform(0.1, 1.5, 6) * t + rng.uniform(0, 6, 6))
               for _ in range(4))  # fmt: skip


def test_a_hexapod_ride_it_sent_passes_through_untouched():
    """The case that showed the defect: a 6-axis ride at 100 Hz limited once, then fed back,
    is not limited again on any frame (before the landing slack: on 529 of 2000 frames)."""
    lim = ActuatorLimits(np.full(6, -0.1), np.full(6, 0.1), np.full(6, 0.25), np.full(6, 4.0))
    rt = RealtimeLimiter(lim, 0.01)
    out = rt.run(rt.initial_state(np.zeros(6)), hexapod_sines(1000))
    state = rt.initial_state(np.zeros(6))
    again = rt.run(state, out)
    assert state.n_clamped == 0
    np.testing.assert_allclose(again, out, rtol=0, atol=1e-12)


@settings(max_examples=100)
@given(limits_and_dt(), st.floats(0.05, 0.95), st.floats(0.0, 6.28))
def test_feasible_sinusoid_passes_through_exactly(case, frac, phase):
    """Independent feasible stream: a sinusoid within speed, acceleration and stroke."""
    lim, dt = case
    mid = 0.5 * (lim.q_min + lim.q_max)
    amp = 0.5 * (lim.q_max - lim.q_min) * frac
    # continuous peak speed A w and peak accel A w^2 kept below the limits; discrete
    # differences are averages of the continuous ones, so they stay below too
    w = 0.9 * np.min(np.minimum(lim.v_max / amp, np.sqrt(lim.a_max / amp)))
    t = np.arange(300) * dt
    q = mid + amp * np.sin(w * t[:, None] + phase)
    rt = RealtimeLimiter(lim, dt)
    # start from the state the stream itself is in after its first two frames
    state = rt.initial_state(q[1], (q[1] - q[0]) / dt)
    out = rt.run(state, q[2:])
    assert np.array_equal(out, q[2:])
    assert state.n_clamped == 0


def test_step_target_is_reached_without_overshoot():
    lim = ActuatorLimits([0.0], [0.3], [0.4], [6.0])
    rt = RealtimeLimiter(lim, 0.01)
    out = rt.run(rt.initial_state([0.05]), np.full((200, 1), 0.25))[:, 0]
    assert np.all(np.diff(out) >= -1e-12)  # monotone (to rounding): no overshoot, no ringing
    assert out.max() <= 0.25 + 1e-12
    assert out[-1] == 0.25
    # time to arrive is close to the continuous bang-coast-bang time (0.2/0.4 + 0.4/6 s)
    t_arrive = (np.argmax(out == 0.25) + 1) * 0.01
    assert abs(t_arrive - (0.2 / 0.4 + 0.4 / 6.0)) < 0.03


def test_nonfinite_targets_hold_the_last_finite_target_and_are_counted():
    lim = ActuatorLimits([0.0, 0.0], [0.3, 0.3], [0.4, 0.4], [6.0, 6.0])
    rt = RealtimeLimiter(lim, 0.01)
    state = rt.initial_state([0.1, 0.1])
    assert rt.step(state, [0.1005, 0.1]) == [0.1005, 0.1]
    out = rt.step(state, [math.nan, math.inf])
    assert out == [0.1005, 0.1]
    assert state.n_nonfinite == 2


def test_batch_equals_streaming():
    rng = np.random.default_rng(3)
    lim = ActuatorLimits(np.zeros(6), np.full(6, 0.25), np.full(6, 0.3), np.full(6, 4.0))
    rt = RealtimeLimiter(lim, 0.01)
    targets = 0.125 + 0.2 * rng.standard_normal((500, 6))
    batch = rt.run(rt.initial_state(np.full(6, 0.1)), targets)
    state = rt.initial_state(np.full(6, 0.1))
    streamed = np.array([rt.step(state, row) for row in targets])
    assert np.array_equal(batch, streamed)


# ----------------------------------------------------------------------------- braking oracle
@given(st.floats(0.0, 5.0), st.floats(0.1, 50.0), st.sampled_from([0.001, 0.01, 0.05]))
def test_braking_distance_matches_simulation(v, a, dt):
    dist, speed = 0.0, v
    while speed - a * dt > 0:
        speed -= a * dt
        dist += speed * dt
    assert braking_distance(v, a, dt) == pytest.approx(dist, rel=1e-9, abs=1e-15)
    assert braking_distance(-v, a, dt) == braking_distance(v, a, dt)
    assert braking_distance(v, a, dt) <= v * v / (2 * a) + 1e-15


@given(st.floats(0.0, 1.0), st.floats(0.1, 50.0), st.sampled_from([0.001, 0.01, 0.05]))
def test_braking_speed_cap_is_the_largest_admissible_speed(budget, a, dt):
    def f(v):
        return v * dt + braking_distance(v, a, dt)

    cap = braking_speed_cap(budget, a, dt)
    assert f(cap) <= budget * (1 + 1e-12) + 1e-15
    # bisection oracle for the supremum of {v : f(v) <= budget}
    lo, hi = 0.0, budget / dt + 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) <= budget else (lo, mid)
    assert cap == pytest.approx(lo, rel=1e-9, abs=1e-12)


# ----------------------------------------------------------------------------- validation
def test_inadmissible_initial_state_is_refused():
    lim = ActuatorLimits([0.0], [0.3], [0.4], [6.0])
    rt = RealtimeLimiter(lim, 0.01)
    with pytest.raises(LimitError):
        rt.initial_state([0.31])
    with pytest.raises(LimitError):
        rt.initial_state([0.1], [0.5])  # faster than v_max
    with pytest.raises(LimitError):
        rt.initial_state([0.299], [0.4])  # cannot stop before q_max
    assert rt.is_admissible([0.2], [0.4])


def test_construction_is_validated():
    with pytest.raises(ConfigError, match="q_min < q_max"):
        ActuatorLimits([0.3], [0.3], [0.4], [6.0])
    with pytest.raises(ConfigError, match="v_max"):
        ActuatorLimits([0.0], [0.3], [0.0], [6.0])
    with pytest.raises(ConfigError, match="finite"):
        ActuatorLimits([0.0], [math.nan], [0.4], [6.0])
    with pytest.raises(ConfigError, match="dt_s"):
        RealtimeLimiter(ActuatorLimits([0.0], [0.3], [0.4], [6.0]), 0.0)
    with pytest.raises(ConfigError, match="jerk"):
        RealtimeLimiter(ActuatorLimits([0.0], [0.3], [0.4], [6.0], [100.0]), 0.01)


def test_wrong_target_length_is_refused():
    lim = ActuatorLimits([0.0, 0.0], [0.3, 0.3], [0.4, 0.4], [6.0, 6.0])
    rt = RealtimeLimiter(lim, 0.01)
    state = rt.initial_state([0.1, 0.1])
    with pytest.raises(ConfigError, match="expected 2"):
        rt.step(state, [0.1])
    assert state.n_frames == 0


def test_scalar_initial_speed_is_broadcast():
    lim = ActuatorLimits([0.0, 0.0], [0.3, 0.3], [0.4, 0.4], [6.0, 6.0])
    rt = RealtimeLimiter(lim, 0.01)
    assert rt.initial_state([0.1, 0.1], 0).v == [0.0, 0.0]
    assert rt.initial_state([0.1, 0.1], 0.1).v == [0.1, 0.1]


def test_check_trajectory_measures_violations_by_the_definitions():
    """The checker itself can fail: closed-form differences of a hand-made sequence."""
    lim = ActuatorLimits([0.0], [1.0], [1.0], [10.0], [1000.0])
    dt = 0.1
    q = np.array([[0.0], [0.0], [0.2], [0.2], [1.05]])
    chk = check_trajectory(q, dt, lim, relative=False)
    # speeds 0, 2, 0, 8.5 -> 7.5 over; accels 20, -20, 85 -> 75 over; stroke 0.05 over
    assert chk.speed == pytest.approx(7.5)
    assert chk.accel == pytest.approx(75.0)
    # jerks (q3-3q2+3q1-q0)/dt^3: (0.2-0.6+0)/1e-3 = -400, (1.05-0.6+0.6-0)/1e-3 = 1050
    assert chk.jerk == pytest.approx(50.0)
    assert chk.stroke == pytest.approx(0.05)
    assert not chk.ok
    rel = check_trajectory(q, dt, lim)
    assert rel.speed == pytest.approx(7.5) and rel.accel == pytest.approx(7.5)
    assert check_trajectory(q[:2], dt, lim).ok
