"""Offline ride optimisation (casadi): feasibility, identity on feasible input, optimality."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.trajectory import (
    ActuatorLimits,
    JerkLimiter,
    RealtimeLimiter,
    check_trajectory,
    limit_ride,
)

DT = 0.01


def _lim(n=2, j=None):
    return ActuatorLimits(
        np.zeros(n), np.full(n, 0.3), np.full(n, 0.5), np.full(n, 5.0),
        None if j is None else np.full(n, j),
    )  # fmt: skip


def _ride(N=1500, n=2, seed=0):
    rng = np.random.default_rng(seed)
    t = np.arange(N) * DT
    # starts at rest (cosines), so it is feasible from the default initial state
    q = 0.05 + 0.1 * (1 - np.cos(2 * np.pi * 0.25 * t))[:, None] * np.ones(n)
    q += 0.01 * (1 - np.cos(2 * np.pi * rng.uniform(0.1, 0.5, n) * t[:, None]))
    return q


def test_feasible_ride_is_returned_unchanged():
    lim = _lim()
    q = _ride()
    res = limit_ride(q, DT, lim)
    assert res.status == "unchanged"
    assert np.array_equal(res.q, q)
    assert res.max_deviation == 0.0


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_infeasible_ride_is_feasible_and_no_worse_than_the_realtime_limiter(seed):
    lim = _lim()
    rng = np.random.default_rng(seed)
    q = _ride(seed=seed)
    q[300:340] += 0.12  # a step up and back down that is too fast
    q[700, 0] = 5.0  # a spike far out of stroke
    q[900:960, 1] = 0.35  # beyond the stroke end
    q[1100, 1] = np.nan
    q[1200:1300] += 0.02 * rng.standard_normal((100, 2))  # chatter
    res = limit_ride(q, DT, lim)
    assert res.status == "optimised"
    assert res.check.ok, res.check
    assert res.n_repaired == 0
    assert res.n_solver_failures == 0
    # same initial state as limit_ride's default: at rest at the first frame
    rt = RealtimeLimiter(lim, DT)
    q_rt = rt.run(rt.initial_state(q[0]), q)
    fin = np.isfinite(q)
    dev_rt = np.where(fin, np.abs(q_rt - q), 0.0)
    dev_opt = np.where(fin, np.abs(res.q - q), 0.0)
    assert res.objective <= res.objective_realtime
    assert np.sum(dev_opt**2) <= np.sum(dev_rt**2)
    assert res.max_deviation <= dev_rt.max() + 1e-12
    assert res.max_deviation == pytest.approx(dev_opt.max())
    assert dev_opt[res.where_index] == res.max_deviation
    # the spike (5.0 on actuator 0) is where the largest deviation is
    assert res.where_index == (700, 0)


def test_small_problem_matches_an_independent_qp_solver():
    """scipy SLSQP on the same QP (closed form of the constraints) as oracle."""
    from scipy.optimize import minimize

    lim = _lim(n=1)
    N = 40
    t = np.arange(N) * DT
    q = (0.15 + 0.14 * np.sign(np.sin(2 * np.pi * 2 * t)))[:, None]  # square wave
    res = limit_ride(q, DT, lim, pad_s=1.0)
    assert res.check.ok
    q0 = np.clip(q[0, 0], 0, 0.3)
    # rows: speed (frame k vs k-1, with q[-1] = q0) and accel (with q[-2] = q[-1] = q0),
    # plus the free frames after the ride the optimiser adds: emulate with M extra frames
    M = lim.braking_steps(DT) + 1
    K = N + M
    D1 = np.eye(K) - np.eye(K, k=-1)
    D2 = np.eye(K) - 2 * np.eye(K, k=-1) + np.eye(K, k=-2)
    c1 = np.zeros(K)
    c1[0] = -q0  # x0 - q[-1]
    c2 = np.zeros(K)
    c2[0] = -q0  # x0 - 2 q[-1] + q[-2]
    c2[1] = q0  # x1 - 2 x0 + q[-1]
    vb, ab = 0.5 * DT, 5.0 * DT**2
    # |D1 x + c1| <= vb and |D2 x + c2| <= ab as A x <= b (SLSQP: 1 s where trust-constr took
    # 30 s or more, and closer to the optimum)
    A = np.vstack([D1, -D1, D2, -D2])
    b = np.concatenate([vb - c1, vb + c1, ab - c2, ab + c2])
    cons = [{"type": "ineq", "fun": lambda x: b - A @ x, "jac": lambda x: -A}]
    wts = np.concatenate([np.ones(N), np.zeros(M)])
    tgt = np.concatenate([q[:, 0], np.full(M, q[-1, 0])])

    def f(x):
        return float(np.sum(wts * (x - tgt) ** 2))

    def g(x):
        return 2 * wts * (x - tgt)

    ora = minimize(
        f, np.clip(tgt, 0, 0.3), jac=g, bounds=[(0, 0.3)] * K, constraints=cons,
        method="SLSQP", options={"ftol": 1e-12, "maxiter": 500},
    )  # fmt: skip
    assert ora.success, ora.message
    assert np.all(A @ ora.x <= b + 1e-12)  # the oracle's answer is feasible
    assert res.objective == pytest.approx(ora.fun, rel=1e-4)
    np.testing.assert_allclose(res.q[:, 0], ora.x[:N], atol=2e-4)


def test_long_window_is_solved_in_chunks_close_to_one_piece():
    lim = _lim(n=1)
    N = 900
    t = np.arange(N) * DT
    q = (0.15 + 0.16 * np.sin(2 * np.pi * 1.2 * t))[:, None]  # infeasible everywhere
    one = limit_ride(q, DT, lim, chunk=1024)
    many = limit_ride(q, DT, lim, chunk=192)
    for r in (one, many):
        assert r.check.ok
        assert r.n_repaired == 0
        assert r.n_solver_failures == 0
    assert many.objective <= one.objective * 1.02
    assert many.objective <= many.objective_realtime


def test_jerk_limit_is_honoured_when_configured():
    lim = _lim(n=1, j=200.0)
    q = _ride(N=600, n=1)
    q[200:230] += 0.1
    res = limit_ride(q, DT, lim)
    chk = check_trajectory(res.q, DT, lim, history=np.full((3, 1), q[0, 0]))
    assert chk.ok, chk
    assert res.status == "optimised"
    # no worse than the jerk-limited real-time limiter on the same input
    jl = JerkLimiter(lim, DT)
    q_rt = jl.run(jl.initial_state(q[0]), q)
    assert res.objective <= np.sum((q_rt - q) ** 2)
    assert res.objective_realtime == pytest.approx(np.sum((q_rt - q) ** 2))


def test_bad_arguments_are_named():
    from motioncue import ConfigError

    with pytest.raises(ConfigError, match="shape"):
        limit_ride(np.zeros((10, 3)), DT, _lim())
    with pytest.raises(ConfigError, match="weights"):
        limit_ride(np.zeros((10, 2)) + 0.1, DT, _lim(), weights=-np.ones(10))


@settings(max_examples=12, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(30, 260), st.sampled_from([0.004, 0.01, 0.02]))
def test_random_rides_are_feasible_and_no_worse_than_the_limiter(seed, N, dt):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 4))
    lim = ActuatorLimits(
        rng.uniform(-0.1, 0.0, n), rng.uniform(0.05, 0.2, n), rng.uniform(0.1, 1.0, n),
        rng.uniform(1.0, 20.0, n),
    )  # fmt: skip
    span = lim.q_max - lim.q_min
    q = lim.q_min + span * np.cumsum(rng.normal(0, 0.1, (N, n)), axis=0)
    q[rng.integers(0, N)] = rng.choice([np.nan, 1e6, -1e6])
    res = limit_ride(q, dt, lim)
    assert res.check.ok, res.check
    assert np.all(np.isfinite(res.q))
    assert res.objective <= res.objective_realtime * (1 + 1e-12)
    if res.status == "unchanged":
        assert np.array_equal(res.q, q)


def test_ride_plot_is_written(tmp_path):
    from motioncue.trajectory import plot_ride

    lim = _lim()
    q = _ride(N=300)
    q[100:120] += 0.1
    res = limit_ride(q, DT, lim)
    rt = RealtimeLimiter(lim, DT)
    q_rt = rt.run(rt.initial_state(q[0]), q)
    out = plot_ride(q, res.q, DT, lim, tmp_path / "ride.png", q_realtime=q_rt, title="test")
    data = out.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert len(data) > 10_000
