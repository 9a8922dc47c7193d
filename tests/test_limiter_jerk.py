"""Jerk-limited real-time limiter: every limit from any admissible state, pass-through."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError
from motioncue.trajectory import ActuatorLimits, JerkLimiter, check_trajectory
from test_limiter import hexapod_sines

TOL = 1e-9


# The strategies the composites below draw from, built once: a composite that builds its
# strategies at each draw spends about a third of its time on that (st.floats looks its
# arguments up in Hypothesis' cache each time), and the same strategies draw the same values.
_N_AXES = st.integers(1, 4)
_Q_MIN, _SPAN, _V = st.floats(-0.3, 0.3), st.floats(0.02, 0.6), st.floats(0.05, 1.0)
_A, _J = st.floats(1.0, 30.0), st.floats(20.0, 1000.0)
_DT = st.sampled_from([0.004, 0.01, 0.0166667, 0.02])
_KIND = st.sampled_from(["step", "spike", "chatter", "nan", "inf", "far", "noise"])
_LEVEL, _SPIKE = st.floats(-0.5, 1.5), st.sampled_from([1e3, -1e300, 1.7e308, -1.7e308])
_CHATTER, _FAR = st.floats(0, 2), st.sampled_from([-1e9, 1e9, 1.7e308, -1.7e308])
_SEED, _UNIT = st.integers(0, 2**32 - 1), st.floats(0, 1)
_WARM, _PART, _PARTS = st.integers(1, 40), st.integers(1, 50), st.integers(1, 4)
_SOFT_A, _SOFT_J = st.floats(0.5, 8.0), st.floats(40.0, 1000.0)
_REVERSAL = st.floats(-1.0, 1.0)


@st.composite
def jerk_limits(draw):
    n = draw(_N_AXES)
    q_min = np.array([draw(_Q_MIN) for _ in range(n)])
    span = np.array([draw(_SPAN) for _ in range(n)])
    v = np.array([draw(_V) for _ in range(n)])
    a = np.array([draw(_A) for _ in range(n)])
    j = np.array([draw(_J) for _ in range(n)])
    dt = draw(_DT)
    return ActuatorLimits(q_min, q_min + span, v, a, j), dt


_JERK_LIMITS = jerk_limits()


def _targets(draw, lim, length):
    kind = draw(_KIND)
    lo, hi = lim.q_min, lim.q_max
    span = hi - lo
    seg = np.repeat((lo + span * draw(_LEVEL))[None, :], length, axis=0)
    if kind == "spike":
        seg[draw(st.integers(0, length - 1))] = draw(_SPIKE)
    elif kind == "chatter":
        seg += draw(_CHATTER) * span * (2 * (np.arange(length) % 2) - 1)[:, None]
    elif kind == "nan":
        seg[draw(st.integers(0, length - 1)) :] = np.nan
    elif kind == "inf":
        seg[::3] = np.inf
    elif kind == "far":
        seg[:] = draw(_FAR)
    elif kind == "noise":
        rng = np.random.default_rng(draw(_SEED))
        seg = lo + span * rng.uniform(-1, 2, (length, lim.n_actuators))
    return seg


@st.composite
def scenario(draw):
    lim, dt = draw(_JERK_LIMITS)
    jl = JerkLimiter(lim, dt)
    # an admissible start: either at rest anywhere in stroke, or a state the limiter itself
    # reached (reachable states are admissible by induction) after a random warm-up
    frac = np.array([draw(_UNIT) for _ in range(lim.n_actuators)])
    q0 = lim.q_min + frac * (lim.q_max - lim.q_min)
    state = jl.initial_state(q0)
    hist = [q0, q0, q0]
    if draw(st.booleans()):
        warm = _targets(draw, lim, draw(_WARM))
        out = jl.run(state, warm)
        hist = [*list(np.concatenate([np.stack(hist), out])[-3:])]
    parts = [_targets(draw, lim, draw(_PART)) for _ in range(draw(_PARTS))]
    return jl, state, np.stack(hist), np.concatenate(parts)


@settings(max_examples=150)
@given(scenario())
def test_adversarial_streams_keep_every_limit_including_jerk(case):
    jl, state, hist, targets = case
    lim, dt = jl.limits, jl.dt_s
    q_start = np.array(state.q)
    np.testing.assert_allclose(hist[-1], q_start, atol=0)
    assert jl.is_admissible(state.q, state.v, state.a)
    out = jl.run(state, targets)
    chk = check_trajectory(out, dt, lim, history=hist)
    assert chk.finite
    assert chk.stroke <= TOL and chk.speed <= TOL and chk.accel <= TOL, chk
    assert chk.jerk <= TOL, chk
    assert jl.is_admissible(state.q, state.v, state.a)


@settings(max_examples=80)
@given(scenario(), st.floats(0.3, 0.95))
def test_streams_of_a_tighter_limiter_pass_through_exactly(case, shrink):
    jl, state, _hist, targets = case
    lim, dt = jl.limits, jl.dt_s
    assume(all(v == 0.0 for v in state.v) and all(a == 0.0 for a in state.a))
    mid = 0.5 * (lim.q_min + lim.q_max)
    half = 0.5 * (lim.q_max - lim.q_min) * shrink
    tight = ActuatorLimits(
        mid - half, mid + half, lim.v_max * shrink, lim.a_max * shrink, lim.j_max * shrink
    )
    q0 = np.clip(np.array(state.q), tight.q_min, tight.q_max)
    jt = JerkLimiter(tight, dt)
    feasible = jt.run(jt.initial_state(q0), targets)
    st2 = jl.initial_state(q0)
    out = jl.run(st2, feasible)
    assert np.array_equal(out, feasible)
    assert st2.n_clamped == 0


@settings(max_examples=80)
@given(scenario())
def test_its_own_output_passes_through_again(case):
    """Idempotence: the frames the limiter sent, fed back from the same state, are sent
    again to 1e-12 m (its frames reach the jerk bound exactly and the recomputed
    differences miss it by rounding, ~2e-15 m/s^2 a frame: the landing test's slack absorbs
    it; without it the benchmark's hexapod ride was limited again on 1120 of 2000 frames,
    by up to 16 mm)."""
    jl, state, _hist, targets = case
    out = jl.run(jl.initial_state(state.q, state.v, state.a), targets)
    again_state = jl.initial_state(state.q, state.v, state.a)
    again = jl.run(again_state, out)
    np.testing.assert_allclose(again, out, rtol=0, atol=1e-12)
    assert again_state.max_deviation <= 1e-12


def test_a_hexapod_ride_it_sent_passes_through_untouched():
    """The benchmark's case: a 6-axis ride at 100 Hz made jerk-feasible by the limiter, fed
    back, is not limited again on any frame (before the landing slack: most frames)."""
    lim = ActuatorLimits(
        np.full(6, -0.1), np.full(6, 0.1), np.full(6, 0.25), np.full(6, 4.0), np.full(6, 80.0)
    )
    jl = JerkLimiter(lim, 0.01)
    out = jl.run(jl.initial_state(np.zeros(6)), hexapod_sines(600))
    state = jl.initial_state(np.zeros(6))
    again = jl.run(state, out)
    assert state.n_clamped == 0
    np.testing.assert_allclose(again, out, rtol=0, atol=1e-12)


@settings(max_examples=100)
@given(jerk_limits(), st.floats(-1, 1), st.floats(-1, 1))
def test_stopping_bound_covers_the_simulated_braking(case, fv, fa):
    lim, dt = case
    jl = JerkLimiter(lim, dt)
    for i in range(lim.n_actuators):
        v = fv * float(lim.v_max[i])
        a = fa * float(lim.a_max[i])
        ext = jl.stopping_offset(i, v, a)
        if ext is None:
            continue
        assert ext[0] <= 0.0 <= ext[1]
        assert max(-ext[0], ext[1]) <= jl._bound(i, v, a)


def test_step_target_is_approached_without_overshoot_at_full_speed():
    lim = ActuatorLimits([0.0], [0.3], [0.4], [6.0], [100.0])
    jl = JerkLimiter(lim, 0.01)
    out = jl.run(jl.initial_state([0.05]), np.full((150, 1), 0.25))[:, 0]
    assert np.all(np.diff(out) >= -1e-12)
    assert out.max() <= 0.25 + 1e-12 and out[-1] == 0.25
    assert np.max(np.diff(out)) / 0.01 == pytest.approx(0.4, rel=1e-6)  # reaches v_max
    chk = check_trajectory(out[:, None], 0.01, lim, history=np.full((3, 1), 0.05))
    assert chk.ok


def test_full_speed_towards_a_stroke_end_stops_in_time():
    lim = ActuatorLimits([0.0], [0.3], [0.4], [6.0], [100.0])
    jl = JerkLimiter(lim, 0.01)
    # reach full speed upwards from the bottom, then keep asking for far beyond the top
    state = jl.initial_state([0.0])
    out = jl.run(state, np.full((200, 1), 1e6))[:, 0]
    chk = check_trajectory(out[:, None], 0.01, lim, history=np.zeros((3, 1)))
    assert chk.ok, chk
    assert out[-1] == pytest.approx(0.3, abs=1e-9)
    assert state.v[0] == 0.0 and state.a[0] == 0.0


def test_validation():
    with pytest.raises(ConfigError, match="j_max"):
        JerkLimiter(ActuatorLimits([0.0], [0.3], [0.4], [6.0]), 0.01)
    jl = JerkLimiter(ActuatorLimits([0.0], [0.3], [0.4], [6.0], [100.0]), 0.01)
    with pytest.raises(LimitError):
        jl.initial_state([0.29], [0.4], [0.0])  # cannot stop before 0.3
    with pytest.raises(LimitError):
        jl.initial_state([0.1], [0.0], [7.0])  # beyond a_max
    assert not jl.is_admissible([0.1], [math.nan], [0.0])
    with pytest.raises(ConfigError, match="expected 1"):
        jl.step(jl.initial_state([0.1]), [0.1, 0.2])


@st.composite
def soft_jerk_limits(draw):
    """Limits whose braking never meets the +-v_max caps (a^2/(2j) + a dt <= v_max), as
    real cylinders: the braking simulation then also takes its closed-form staircase exit."""
    lim, dt = draw(_JERK_LIMITS)
    amax = np.array([draw(_SOFT_A) for _ in range(lim.n_actuators)])
    jmax = np.array([draw(_SOFT_J) for _ in range(lim.n_actuators)])
    vmax = np.maximum(lim.v_max, amax * amax / (2.0 * jmax) + amax * dt)
    return ActuatorLimits(lim.q_min, lim.q_max, vmax, amax, jmax), dt


_ANY_LIMITS = st.one_of(jerk_limits(), soft_jerk_limits())


@st.composite
def braking_states(draw):
    """Limits, an axis and a velocity-level-admissible (v, a), with the simulated extent."""
    lim, dt = draw(_ANY_LIMITS)
    jl = JerkLimiter(lim, dt)
    i = draw(st.integers(0, lim.n_actuators - 1))
    vmax, amax, jmax = float(lim.v_max[i]), float(lim.a_max[i]), float(lim.j_max[i])
    a = draw(st.one_of(st.floats(-amax, amax), st.sampled_from([-amax, 0.0, amax])))
    v = draw(
        st.one_of(
            st.floats(-vmax, vmax),
            _REVERSAL.map(lambda f: f * a * a / (2.0 * jmax)),  # reversal zone
        )
    )
    vs, acc = [0.0] * lim.n_actuators, [0.0] * lim.n_actuators
    zeros = [0.0] * lim.n_actuators
    # a drawn state that could not brake inside the stroke is halved (towards rest) until it
    # can, rather than thrown away: rejecting most draws trips Hypothesis' filter health check
    for _ in range(60):
        vs[i], acc[i] = v, a
        if jl.is_admissible(zeros, vs, acc):
            break
        v, a = 0.5 * v, 0.5 * a
    assume(jl.is_admissible(zeros, vs, acc))
    return jl, i, v, a, dt


@settings(max_examples=300)
@given(braking_states())
def test_one_sided_braking_bounds_cover_the_simulated_extent(case):
    from motioncue.trajectory._brake import brake_bound

    jl, i, v, a, dt = case
    lim = jl.limits
    ext = jl.stopping_offset(i, v, a)
    assert ext is not None
    down, up = brake_bound(v, a, float(lim.a_max[i]), float(lim.j_max[i]), dt)
    assert down >= 0.0 and up >= 0.0
    assert -ext[0] <= down and ext[1] <= up


@settings(max_examples=300)
@given(braking_states())
def test_closed_form_stopping_distance_is_the_simulated_one(case):
    """forward_stop (ramp and hold summed, staircase in closed form) against the brute-force
    frame-by-frame simulation of P (stopping_offset), on limits whose braking never meets
    the +-v_max caps: where it answers, P moves one way and stops at that distance, to
    1e-12 m (the two sum the same speeds in a different order: rounding, ~1e-17 m)."""
    from motioncue.trajectory._brake import forward_stop

    jl, i, v, a, dt = case
    lim = jl.limits
    vmax, amax, jmax = float(lim.v_max[i]), float(lim.a_max[i]), float(lim.j_max[i])
    dist = forward_stop(v, a, amax, jmax * dt, dt)
    ext = jl.stopping_offset(i, v, a)
    assert ext is not None
    if amax * amax / (2.0 * jmax) + amax * dt > vmax:
        return  # outside its stated domain (the caps may bind): stops_within simulates
    opposes = (v > 0.0 and a < 0.0) or (v < 0.0 and a > 0.0)
    if dist is None:
        assert opposes  # only a state braking harder than P would is left to the simulation
        return
    if dist >= 0.0:
        assert ext[0] >= -1e-12  # never goes back
        assert dist == pytest.approx(ext[1], rel=0, abs=1e-12)
    else:
        assert ext[1] <= 1e-12
        assert dist == pytest.approx(ext[0], rel=0, abs=1e-12)


@settings(max_examples=200)
@given(
    braking_states(),
    st.one_of(st.floats(-1.0, 1.0), st.sampled_from([0.0, 1e-10, -1e-10, 2e-9, -2e-9, 3e-9])),
)
def test_early_no_and_forward_side_give_the_closed_forms_answers(case, frac):
    """JerkLimiter.step decides with forward_within (forward_stop's answer, or an early no
    once the ramp alone passes the band by 1e-9 more than the tolerance) and brake_ahead
    (brake_bound's forward side alone). Against forward_stop and brake_bound themselves, on
    bands that end just before, at and just beyond P's stop (both directions), each early
    no checked against the simulated extent too (it is the simulation's answer also where
    forward_stop has none)."""
    from motioncue.trajectory._brake import (
        brake_ahead,
        brake_bound,
        forward_stop,
        forward_within,
    )

    jl, i, v, a, dt = case
    lim = jl.limits
    amax, jmax = float(lim.a_max[i]), float(lim.j_max[i])
    down, up = brake_bound(v, a, amax, jmax, dt)
    flip = v < 0.0 or (v == 0.0 and a < 0.0)
    ahead = brake_ahead(-v, -a, amax, jmax, dt) if flip else brake_ahead(v, a, amax, jmax, dt)
    assert ahead == pytest.approx(down if flip else up, rel=1e-15, abs=0.0)
    dist = forward_stop(v, a, amax, jmax * dt, dt)
    ext = jl.stopping_offset(i, v, a)
    assert ext is not None
    q = 0.01
    scale = (abs(v) + abs(a) * dt) * dt * 3.0 if abs(frac) > 1e-8 else 1.0
    reach = ext[1] if not flip else ext[0]
    for lo, hi in ((q - 1.0, q + reach + frac * scale), (q + reach + frac * scale, q + 1.0)):
        got = forward_within(q, v, a, lo, hi, amax, jmax * dt, dt)
        if dist is not None:
            assert got == (lo - 1e-9 <= q + dist <= hi + 1e-9)
        elif got is not None:  # an early no where forward_stop has no distance
            assert got is False
        if got is False:
            assert not (lo - 1e-9 <= q + ext[0] and q + ext[1] <= hi + 1e-9)


def test_closed_form_stopping_distance_answers_most_states():
    """The closed form is not a rarely-taken branch: from a grid of states of a hexapod
    cylinder it answers all but the strongly opposing ones, and matches the simulation."""
    from motioncue.trajectory._brake import forward_stop

    lim = ActuatorLimits([-0.1], [0.1], [0.25], [4.0], [80.0])
    jl = JerkLimiter(lim, 0.01)
    answered = 0
    for v in np.linspace(-0.25, 0.25, 11):
        for a in np.linspace(-4.0, 4.0, 11):
            if not jl.is_admissible([0.0], [v], [a]):
                continue
            dist = forward_stop(float(v), float(a), 4.0, 0.8, 0.01)
            if dist is None:
                continue
            answered += 1
            lo, hi = jl.stopping_offset(0, float(v), float(a))
            assert dist == pytest.approx(hi if dist >= 0.0 else lo, rel=0, abs=1e-12)
    assert answered >= 60


@settings(max_examples=300)
@given(
    braking_states(),
    st.sampled_from(["top", "bottom", "far", "mid"]),
    st.one_of(st.floats(-1.0, 1.0), st.sampled_from([0.0, 1e-10, -1e-10, 2e-9, -2e-9])),
)
def test_fast_admissibility_decides_as_the_exact_simulation(case, where, frac):
    """The bound test and the early-exit simulation give the exact simulation's answer,
    for states whose braking ends near a stroke end (within a few frames) and far from it."""
    jl, i, v, a, dt = case
    lim = jl.limits
    lo, hi = float(lim.q_min[i]), float(lim.q_max[i])
    ext = jl.stopping_offset(i, v, a)
    assert ext is not None
    scale = (abs(v) + abs(a) * dt) * dt * 3.0 if abs(frac) > 1e-8 else 1.0
    if where == "top":
        q = hi - ext[1] + frac * scale
    elif where == "bottom":
        q = lo - ext[0] + frac * scale
    elif where == "far":
        q = lo + (hi - lo) * (0.5 + 0.5 * frac)
    else:
        q = 0.5 * (lo + hi) + frac * scale
    exact = lo - 1e-9 <= q <= hi + 1e-9 and lo - 1e-9 <= q + ext[0] and q + ext[1] <= hi + 1e-9
    assert jl._admissible(None, i, q, v, a, lo, hi) == exact


def _reference_step(jl, state, target):
    """One step of the jerk limiter written from its module docstring, each admissibility
    decided by the full simulation of P (``stopping_offset``: no closed-form bound, no early
    exit, no inlining): the oracle of the fast :meth:`JerkLimiter.step`. ``state`` is a
    dict of lists, updated."""
    from motioncue.trajectory._realtime import _level_step

    dt = float(jl.dt_s)
    inv_dt = 1.0 / dt
    out = []
    for i, (qmin, qmax, vmax, amax, jdt, half_inv_j, abig, _j) in enumerate(jl._params):
        t = float(target[i])
        if not math.isfinite(t):
            t = state["last_target"][i]
        state["last_target"][i] = t
        q, v, a = state["q"][i], state["v"][i], state["a"][i]

        def admissible(qn, vn, an, lo, hi, i=i):
            lo_off, hi_off = jl.stopping_offset(i, vn, an)
            return (
                lo - 1e-9 <= qn <= hi + 1e-9
                and lo - 1e-9 <= qn + lo_off
                and (qn + hi_off <= hi + 1e-9)
            )

        def next_state(w, w_prev, slack=0.0, q=q, v=v, a=a, vmax=vmax, amax=amax, jdt=jdt,
                       half_inv_j=half_inv_j, abig=abig):  # fmt: skip
            vb, _ab, landed = _level_step(
                v, a, w, w_prev, -vmax, vmax, amax, jdt, half_inv_j, abig, dt, inv_dt, slack
            )
            qb = q + vb * dt
            return qb, landed

        want = min(max((t - q) * inv_dt, -2.0 * vmax), 2.0 * vmax)
        # the landing test allows the limiter's stated rounding slack (_realtime._land_slack)
        _, landed = next_state(want, state["last_want"][i], jl._slack[i])
        state["last_want"][i] = want
        chosen = None
        if landed:
            v1 = (t - q) * inv_dt
            if admissible(t, v1, (v1 - v) * inv_dt, qmin, qmax):
                chosen = t
        if chosen is None:
            lo_w = max(t, qmin) if t < q else qmin
            hi_w = min(t, qmax) if t > q else qmax
            w_lo, w_hi = 0.0, want
            for k in range(11):  # the full wanted speed, then 10 bisection steps towards 0
                w = want if k == 0 else 0.5 * (w_lo + w_hi)
                qb, _ = next_state(w, w)
                vb = (qb - q) * inv_dt
                if admissible(qb, vb, (vb - v) * inv_dt, lo_w, hi_w):
                    chosen = qb
                    if k == 0:
                        break
                    w_lo = w
                else:
                    w_hi = w
            if chosen is None:  # the braking policy's own step
                chosen, _ = next_state(0.0, 0.0)
        v1 = (chosen - q) * inv_dt
        state["q"][i], state["v"][i], state["a"][i] = chosen, v1, (v1 - v) * inv_dt
        out.append(chosen)
    return out


@pytest.mark.parametrize("stream", ["feasible", "adversarial"])
def test_fast_step_gives_the_reference_steps_frames(stream):
    """The fast step (inlined admissibility, closed-form bound, early-exit simulation with
    closed-form staircase ends) gives the frames of the plain algorithm, frame for frame, on
    a hexapod's feasible ride and on uniform noise (each frame limited). Tolerance 1e-12 m:
    the two take the same decisions on the same floats, so they agree to the last bit
    unless a decision flips, which would move a frame by micrometres or more."""
    lim = ActuatorLimits(
        np.full(6, -0.1), np.full(6, 0.1), np.full(6, 0.25), np.full(6, 4.0), np.full(6, 80.0)
    )
    dt = 0.01
    jl = JerkLimiter(lim, dt)
    rng = np.random.default_rng(7)
    n = 300
    if stream == "feasible":
        t = np.arange(n) * dt
        f = rng.uniform(0.2, 1.5, 6)
        raw = 0.06 * np.sin(2 * np.pi * f * t[:, None] + rng.uniform(0, 6, 6))
        raw[100:120] += 0.03  # a bump the limiter has to soften
        targets = jl.run(jl.initial_state(np.zeros(6)), raw)  # made jerk-feasible
    else:
        targets = rng.uniform(-0.2, 0.2, (n, 6))
    targets[150, 2] = math.nan  # a non-finite target is held on either
    q0 = np.clip(targets[0], lim.q_min, lim.q_max)
    fast = jl.initial_state(q0)
    ref = {"q": list(q0), "v": [0.0] * 6, "a": [0.0] * 6, "last_target": list(q0),
           "last_want": [0.0] * 6}  # fmt: skip
    clamped = 0
    for k, row in enumerate(targets.tolist()):
        got = jl.step(fast, row)
        want = _reference_step(jl, ref, row)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12, err_msg=f"frame {k}")
        clamped += any(g != r for g, r in zip(got, row, strict=True))
    assert fast.n_simulated > 0  # the simulation path was exercised, not only the bound
    assert clamped > (n // 2 if stream == "adversarial" else 10)


@settings(max_examples=200)
@given(
    st.floats(0.02, 1.0), st.floats(0.5, 30.0), st.floats(5.0, 2000.0),
    st.sampled_from([0.001, 0.004, 0.01, 0.0166667, 0.02, 0.05]),
)  # fmt: skip
def test_bound_line_covers_brake_bound_over_its_box(vmax, amax, jmax, dt):
    """JerkLimiter.step accepts a next state without brake_bound when it lies bound_line's
    reach (x0 + slope |v|) inside the band: that is brake_bound's answer only if no state
    of the box (|v| <= v, |a| <= a) has a larger bound than the line at its |v|. Checked on
    a grid including the box's corners, and the line is not loose at them (the largest
    bound is there: within 1e-6 of the line)."""
    from motioncue.trajectory._brake import bound_line, brake_bound

    x0, slope, v_in, a_in = bound_line(vmax, amax, jmax, dt)
    assert vmax < v_in <= vmax * (1 + 2e-6) and amax < a_in <= amax * (1 + 2e-6)
    assert x0 > 0.0 and slope > 0.0
    closest = behind_closest = 0.0
    for v in [*np.linspace(-v_in, v_in, 21), 0.0, -0.0, 1e-12, -1e-12]:
        line = x0 + slope * abs(float(v))
        for a in [*np.linspace(-a_in, a_in, 21), 0.0, 1e-12, -1e-12]:
            down, up = brake_bound(float(v), float(a), amax, jmax, dt)
            assert max(down, up) <= line
            closest = max(closest, max(down, up) / line)
            # behind the motion (both ways at rest) the bound is at most the line's x0
            behind = down if v > 0.0 else up if v < 0.0 else max(down, up)
            assert behind <= x0
            behind_closest = max(behind_closest, behind / x0)
    assert closest >= 1 - 1e-6
    assert behind_closest >= 1 - 1e-6  # x0 is reached behind (a = -a_in at v -> 0)


@settings(max_examples=200)
@given(
    st.floats(0.5, 30.0), st.floats(5.0, 2000.0),
    st.sampled_from([0.001, 0.004, 0.01, 0.02, 0.05]), st.floats(0.0, 1.0),
)  # fmt: skip
def test_chase_saturation_is_where_vcap_reaches_a_max(amax, jmax, dt, frac):
    """From _chase_saturation's budget on, _vcap is at least a_max (so JerkLimiter.step may
    put abig in its place before clipping to the band |a| <= a_max), and the threshold is
    tight: just below the staircase budget of a_max, _vcap is below a_max."""
    from motioncue.trajectory._jerk import _chase_saturation
    from motioncue.trajectory._realtime import _vcap

    jdt = jmax * dt
    abig = 2.0 * amax
    sat = _chase_saturation(amax, jdt, abig)
    big = abig + abig * abig / (2.0 * jdt) + jdt
    for b in (sat, sat * (1 + 1e-12), sat + frac * (big - sat), big):
        assert _vcap(b, jdt, abig) >= amax
    assert _vcap(sat * (1 - 1e-5), jdt, abig) < amax


@settings(max_examples=200)
@given(
    st.floats(0.5, 30.0), st.floats(5.0, 2000.0),
    st.sampled_from([0.001, 0.004, 0.01, 0.02, 0.05]), st.floats(-0.1, 1.2),
)  # fmt: skip
def test_vcap_with_its_saturation_budget_given_is_vcap(amax, jmax, dt, frac):
    """JerkLimiter.step's _vcap_big (saturation budget precomputed, _stairs inlined) gives
    _realtime._vcap's value on budgets below, across and above the saturation budget and
    at zero."""
    from motioncue.trajectory._jerk import _vcap_big
    from motioncue.trajectory._realtime import _vcap

    jdt = jmax * dt
    abig = 2.0 * amax
    big = abig + abig * abig / (2.0 * jdt) + jdt
    for b in (frac * big, big, big * (1 - 1e-15), 0.0, -1.0, frac * jdt, 3.0 * jdt):
        assert _vcap_big(b, jdt, abig, big) == pytest.approx(_vcap(b, jdt, abig), rel=1e-15)


@settings(max_examples=200)
@given(
    st.floats(0.5, 30.0), st.floats(5.0, 2000.0),
    st.sampled_from([0.001, 0.004, 0.01, 0.02, 0.05]),
    st.lists(st.floats(-3.0, 3.0), min_size=2, max_size=40),
)  # fmt: skip
def test_bisection_chase_value_rises_with_the_wanted_speed(amax, jmax, dt, fracs):
    """_bisect ends its search at a refused wanted speed whose chase value lies beyond the
    band the other way, on two facts checked here on random budgets: the chase value (as
    _bisect computes it: -abig, -_vcap(-x), _vcap(x), abig across -sat, 0, sat, for
    x = (w - v) / dt) never falls as x rises (beyond rounding, far below its _PAST margin),
    and _vcap(x) <= x (so a chase value below lo comes from an x below lo: no landing)."""
    from motioncue.trajectory._jerk import _PAST, _chase_saturation, _vcap_big

    jdt = jmax * dt
    abig = 2.0 * amax
    big = abig + abig * abig / (2.0 * jdt) + jdt
    sat = _chase_saturation(amax, jdt, abig)

    def chase(x):
        if x >= sat:
            return abig
        if x <= -sat:
            return -abig
        return _vcap_big(x, jdt, abig, big) if x > 0.0 else -_vcap_big(-x, jdt, abig, big)

    xs = sorted({f * sat for f in fracs} | {sat, -sat, 0.0, jdt, -jdt})
    values = [chase(x) for x in xs]
    for x0, x1, c0, c1 in zip(xs, xs[1:], values, values[1:], strict=False):
        assert c1 >= c0 - 1e-15 * abig, (x0, x1, c0, c1)
        assert c1 >= c0 - 0.01 * _PAST * abig
    for x in xs:
        if 0.0 < x < sat:
            assert _vcap_big(x, jdt, abig, big) <= x * (1 + 1e-15)


@settings(max_examples=80)
@given(scenario())
def test_bisection_early_end_changes_no_frame(case):
    """The same frames, counters included, with _bisect's early end (a refused chase beyond
    the band) and without it (_PAST so large that no chase value is ever past), on
    adversarial streams from random admissible states (a wrong direction of the early end
    fails it)."""
    from motioncue.trajectory import _jerk

    jl, state, _hist, targets = case
    q0, v0, a0 = list(state.q), list(state.v), list(state.a)
    runs = []
    for past in (_jerk._PAST, 1e300):
        saved = _jerk._PAST
        _jerk._PAST = past
        try:
            st_ = jl.initial_state(q0, v0, a0)
            out = jl.run(st_, targets)
        finally:
            _jerk._PAST = saved
        runs.append((out, st_.n_clamped, st_.n_simulated, st_.max_deviation))
    np.testing.assert_allclose(runs[0][0], runs[1][0], rtol=0, atol=1e-12)
    assert runs[0][1:] == runs[1][1:]


@pytest.mark.parametrize(
    ("v_max", "a_max", "j_max", "dt"),
    [(0.05, 4.0, 20.0, 0.01), (0.4, 2.0, 30.0, 0.004), (0.25, 8.0, 400.0, 0.02)],
)
def test_fast_step_gives_the_reference_steps_frames_on_other_limits(v_max, a_max, j_max, dt):
    """As above on uniform noise with limits where P's braking meets the +-v_max caps (the
    first: the exact check simulates, no closed-form distance), where the chase saturates
    late (small jerk per frame) and where one frame's jerk exceeds a_max (large dt). Same
    1e-12 m tolerance."""
    n_ax = 3
    lim = ActuatorLimits(
        np.full(n_ax, -0.1), np.full(n_ax, 0.1), np.full(n_ax, v_max), np.full(n_ax, a_max),
        np.full(n_ax, j_max),
    )  # fmt: skip
    jl = JerkLimiter(lim, dt)
    rng = np.random.default_rng(11)
    n = 150
    targets = rng.uniform(-0.2, 0.2, (n, n_ax))
    q0 = np.clip(targets[0], lim.q_min, lim.q_max)
    fast = jl.initial_state(q0)
    ref = {"q": list(q0), "v": [0.0] * n_ax, "a": [0.0] * n_ax, "last_target": list(q0),
           "last_want": [0.0] * n_ax}  # fmt: skip
    for k, row in enumerate(targets.tolist()):
        got = jl.step(fast, row)
        want = _reference_step(jl, ref, row)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12, err_msg=f"frame {k}")
    assert fast.n_simulated > 0
    assert fast.n_clamped > n // 2
