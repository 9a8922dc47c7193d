"""RealtimeLimiter.run checks stretches of landing frames at once; it must give exactly what
step() gives frame by frame (the frames and the whole final state), whatever the stream."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.trajectory import ActuatorLimits, RealtimeLimiter, braking_speed_cap
from test_limiter import limits_and_dt, scenario


def _state_fields(state) -> tuple:
    return (list(state.q), list(state.v), list(state.last_target), state.n_frames,
            state.n_clamped, state.n_nonfinite, list(state.clamped_axes),
            state.max_deviation)  # fmt: skip


def _assert_run_is_step_by_step(rt: RealtimeLimiter, q0, v0, targets: np.ndarray) -> np.ndarray:
    state_run = rt.initial_state(q0, v0)
    out = rt.run(state_run, targets)
    state_step = rt.initial_state(q0, v0)
    streamed = np.array([rt.step(state_step, row) for row in targets.tolist()])
    streamed = streamed.reshape(targets.shape)
    # the same arithmetic, so the same bits (run's promise, as test_batch_equals_streaming)
    assert np.array_equal(out, streamed)
    assert _state_fields(state_run) == _state_fields(state_step)
    return out


@settings(max_examples=150)
@given(scenario())
def test_run_is_step_by_step_on_adversarial_streams(case):
    """Steps, spikes, NaN and inf, chatter, far targets from any admissible state."""
    lim, dt, q0, v0, targets = case
    _assert_run_is_step_by_step(RealtimeLimiter(lim, dt), q0, v0, targets)


@st.composite
def mostly_feasible(draw):
    """Long streams that land for hundreds of frames (sinusoids inside the limits) with
    disturbances where the limiter must act: a jump, a run at the stroke end at top speed,
    NaN, a held target beyond the stroke."""
    lim, dt = draw(limits_and_dt())
    n = lim.n_actuators
    length = draw(st.integers(200, 1500))
    t = np.arange(length) * dt
    mid, half = (lim.q_min + lim.q_max) / 2, (lim.q_max - lim.q_min) / 2
    frac = draw(st.floats(0.05, 1.2))  # above 1: the stroke ends are reached
    w = np.array([draw(st.floats(0.1, 1.0)) for _ in range(n)])
    # amplitude within speed and acceleration limits (A w <= v_max, A w^2 <= a_max)
    amp = frac * np.minimum(half, np.minimum(lim.v_max / w, lim.a_max / w**2))
    targets = mid + amp * np.sin(w * t[:, None])
    q0 = targets[0].copy()
    for _ in range(draw(st.integers(0, 4))):
        k = draw(st.integers(1, length - 1))
        kind = draw(st.sampled_from(["jump", "nan", "beyond", "slam"]))
        span = draw(st.integers(1, 60))
        if kind == "jump":
            targets[k:] += half * draw(st.floats(-0.5, 0.5))
        elif kind == "nan":
            targets[k : k + span] = np.nan
        elif kind == "beyond":
            targets[k : k + span] = lim.q_max + half
        else:  # speeding up within the limits into the stroke end, braking too late
            top = 0.9 * np.minimum(
                lim.v_max,
                [braking_speed_cap(2 * h, a, dt) for h, a in zip(half, lim.a_max, strict=True)],
            )
            steps = np.arange(1, length - k + 1)[:, None]
            v = np.minimum(0.5 * lim.a_max * dt * steps, top)
            sign = draw(st.sampled_from([1.0, -1.0]))
            targets[k:] = targets[k - 1] + sign * np.cumsum(v, axis=0) * dt
    return lim, dt, q0, targets


@settings(max_examples=60)
@given(mostly_feasible())
def test_run_is_step_by_step_on_long_mostly_landing_streams(case):
    lim, dt, q0, targets = case
    _assert_run_is_step_by_step(RealtimeLimiter(lim, dt), q0, None, targets)


def test_landing_stretches_are_not_stepped_one_by_one(monkeypatch: pytest.MonkeyPatch):
    """The point of run()'s fast path: a feasible stream of 20 000 frames is decided in a
    few array checks (step() is called for none of it), a stream with a jump far beyond the
    acceleration limit goes to step() only around the jump, and both pass through exactly."""
    lim = ActuatorLimits(np.zeros(6), np.full(6, 0.25), np.full(6, 0.3), np.full(6, 4.0))
    rt = RealtimeLimiter(lim, 0.01)
    t = np.arange(20_000) * 0.01
    targets = 0.125 + 0.05 * np.sin(0.7 * t[:, None] + np.arange(6))
    calls = 0
    step = RealtimeLimiter.step

    def counted(self, state, row):
        nonlocal calls
        calls += 1
        return step(self, state, row)

    monkeypatch.setattr(RealtimeLimiter, "step", counted)
    state = rt.initial_state(targets[0], 0.05 * 0.7 * np.cos(np.arange(6)))
    out = rt.run(state, targets[1:])
    assert calls == 0 and np.array_equal(out, targets[1:])
    assert state.n_frames == len(targets) - 1 and state.n_clamped == 0
    jumped = targets.copy()
    jumped[5000:] += 0.05
    state = rt.initial_state(targets[0], 0.05 * 0.7 * np.cos(np.arange(6)))
    out = rt.run(state, jumped[1:])
    assert 0 < state.n_clamped < calls < 1000
    assert np.array_equal(out[:4999], jumped[1:5000])
    assert math.isclose(out[-1, 0], jumped[-1, 0], abs_tol=1e-12)  # caught up again
