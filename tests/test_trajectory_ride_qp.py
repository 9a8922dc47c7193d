"""The offline ride's window QP (casadi conic + PIQP) against Ipopt, and its Ipopt retry."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.trajectory import (
    ActuatorLimits,
    RealtimeLimiter,
    _offline,
    check_trajectory,
    limit_ride,
)
from motioncue.trajectory._offline import _ChunkSolver
from motioncue.trajectory._ride_qp import ConicChunkSolver, Window, difference_rows


@pytest.mark.parametrize("jerk", [False, True])
@pytest.mark.parametrize("tail", [False, True])
def test_difference_rows_are_the_backward_differences(jerk, tail):
    """Each row applied to stacked frames equals numpy's n-th difference at its frame."""
    L = 9
    h = 3 if jerk else 2
    z = np.random.default_rng(0).normal(size=h + L + h)
    M, order = difference_rows(L, jerk, tail)
    got = M @ z
    want = []
    for o in (1, 2, 3) if jerk else (1, 2):
        d = np.diff(z, n=o)  # d[i - o] is the backward difference ending at z[i]
        frames = L + (o if tail else 0)
        want.append(d[h - o : h - o + frames])
        assert np.sum(order == o) == frames
    np.testing.assert_allclose(got, np.concatenate(want), rtol=0, atol=1e-12)  # round-off


def _window(seed, L, jerk, tail):
    """A feasible random window problem (scaled units) whose target breaks the limits."""
    rng = np.random.default_rng(seed)
    h = 3 if jerk else 2
    bounds = (-60.0, 60.0, 6.25, 1.0, 0.3 if jerk else 0.0)
    k = np.arange(h + L + h)
    # a smooth feasible reference: |d1| <= 2.5, |d2| <= 0.125, |d3| <= 0.00625, |z| <= 50
    z = 50.0 * np.sin(0.05 * k + rng.uniform(0, 2 * np.pi))
    xd = z[h : h + L] + rng.normal(0, 8.0, L)  # chatter: speed/accel/jerk bounds active
    xd[L // 3 : L // 3 + 5] += 40.0  # a step past the stroke end
    w = rng.uniform(0.5, 2.0, L)
    w[L // 2] = 0.0  # a bridged (non-finite) frame
    return xd, w, z[:h], (z[h + L :] if tail else None), bounds, z[h : h + L]


@pytest.mark.parametrize("jerk", [False, True])
@pytest.mark.parametrize("tail", [False, True])
@pytest.mark.parametrize("seed", [0, 1])
def test_window_qp_matches_ipopt(jerk, tail, seed):
    """PIQP and Ipopt (a separately built symbolic model) agree on one window.

    Tolerances: objective within 1e-8 relative, every frame within 1e-4 scaled units (the
    solution is unique except at the zero-weight frame, whose neighbours pin it through
    the difference bounds), both meet the bounds to 1e-9.
    """
    L = 128
    xd, w, hist, tail_x, bounds, x0 = _window(seed, L, jerk, tail)
    x_qp, ok_qp = ConicChunkSolver(L, jerk, tail).solve(Window(xd, w, hist, tail_x, bounds, x0))
    x_ip, ok_ip = _ChunkSolver(L, jerk).solve(Window(xd, w, hist, tail_x, bounds, x0))
    assert ok_qp and ok_ip
    f = [0.5 * np.sum(w * (x - xd) ** 2) for x in (x_qp, x_ip)]
    assert f[0] == pytest.approx(f[1], rel=1e-8)
    np.testing.assert_allclose(x_qp, x_ip, atol=1e-4)
    h = hist.size
    for x in (x_qp, x_ip):
        stacked = np.concatenate([hist, x] + ([tail_x] if tail else []))
        assert np.all(x >= bounds[0] - 1e-9) and np.all(x <= bounds[1] + 1e-9)
        for o, b in zip((1, 2, 3), bounds[2:], strict=True):
            if o == 3 and not jerk:
                continue
            d = np.diff(stacked, n=o)[h - o :]
            assert np.max(np.abs(d)) <= b + 1e-9, (o, np.max(np.abs(d)) - b)
    # the limits are active: the target itself is far from feasible
    assert f[0] > 1.0


def test_window_qp_rejects_a_tail_it_was_not_built_for():
    xd, w, hist, tail_x, bounds, x0 = _window(0, 64, False, True)
    with pytest.raises(ValueError, match="tail"):
        ConicChunkSolver(64, False, False).solve(Window(xd, w, hist, tail_x, bounds, x0))
    with pytest.raises(ValueError, match="tail"):
        ConicChunkSolver(64, False, True).solve(Window(xd, w, hist, None, bounds, x0))


def _random_ride(seed, jerk):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 4))
    N = int(rng.integers(100, 600))
    dt = float(rng.choice([0.004, 0.01, 0.02]))
    lim = ActuatorLimits(
        rng.uniform(-0.1, 0.0, n), rng.uniform(0.05, 0.2, n), rng.uniform(0.1, 1.0, n),
        rng.uniform(1.0, 20.0, n), rng.uniform(50.0, 400.0, n) if jerk else None,
    )  # fmt: skip
    span = lim.q_max - lim.q_min
    q = lim.q_min + span * (0.5 + np.cumsum(rng.normal(0, 0.05, (N, n)), axis=0))
    return q, dt, lim


@settings(max_examples=10, deadline=None)
@given(st.integers(0, 2**32 - 1), st.booleans())
def test_qp_rides_match_ipopt_rides(seed, jerk):
    """Whole rides: the QP path and the Ipopt path give the same optimum.

    Tolerances: objective within 1e-8 relative (seen: <= 2e-10), frames within 1e-5 of the
    stroke span (seen: <= 2e-6); both feasible, neither repaired, no solver failure.
    """
    q, dt, lim = _random_ride(seed, jerk)
    qp = limit_ride(q, dt, lim, backend="qp")
    ip = limit_ride(q, dt, lim, backend="ipopt")
    for r in (qp, ip):
        assert r.check.ok, r.check
        assert r.n_repaired == 0
        assert r.n_solver_failures == 0
        assert r.objective <= r.objective_realtime
    assert qp.status == ip.status
    assert qp.n_windows == ip.n_windows
    assert qp.objective == pytest.approx(ip.objective, rel=1e-8, abs=1e-300)
    span = float(np.max(lim.q_max - lim.q_min))
    np.testing.assert_allclose(qp.q, ip.q, rtol=0, atol=1e-5 * span)


def test_public_limit_ride_uses_the_qp_path(monkeypatch):
    q, dt, lim = _random_ride(3, False)
    calls = {"qp": 0, "ipopt": 0}
    qp_solve, ip_solve = ConicChunkSolver.solve, _ChunkSolver.solve

    def count_qp(self, *a):
        calls["qp"] += 1
        return qp_solve(self, *a)

    def count_ip(self, *a):
        calls["ipopt"] += 1
        return ip_solve(self, *a)

    monkeypatch.setattr(ConicChunkSolver, "solve", count_qp)
    monkeypatch.setattr(_ChunkSolver, "solve", count_ip)
    res = limit_ride(q, dt, lim)
    assert res.status == "optimised"
    assert calls["qp"] >= res.n_windows > 0
    assert calls["ipopt"] == 0


def test_a_window_the_qp_misses_is_retried_with_ipopt(monkeypatch):
    q, dt, lim = _random_ride(5, False)
    ref = limit_ride(q, dt, lim, backend="ipopt")

    def fail(self, win):
        return np.full(self.length, np.nan), False

    monkeypatch.setattr(ConicChunkSolver, "solve", fail)
    res = limit_ride(q, dt, lim)
    assert res.n_solver_failures == 0  # every window was rescued
    np.testing.assert_array_equal(res.q, ref.q)
    assert res.objective == ref.objective


def test_a_window_the_tight_qp_misses_is_retried_with_default_tolerances(monkeypatch):
    q, dt, lim = _random_ride(11, True)
    ref = limit_ride(q, dt, lim, backend="ipopt")
    calls = {"loose": 0, "ipopt": 0}
    qp_solve, ip_solve = ConicChunkSolver.solve, _ChunkSolver.solve

    def tight_fails(self, win):
        if not self.loose:
            return np.full(win.xd.shape, np.nan), False
        calls["loose"] += 1
        return qp_solve(self, win)

    def count_ip(self, *a):
        calls["ipopt"] += 1
        return ip_solve(self, *a)

    monkeypatch.setattr(ConicChunkSolver, "solve", tight_fails)
    monkeypatch.setattr(_ChunkSolver, "solve", count_ip)
    res = limit_ride(q, dt, lim)
    assert calls["loose"] >= res.n_windows > 0
    assert calls["ipopt"] == 0
    assert res.n_solver_failures == 0
    assert res.check.ok, res.check
    # PIQP's default tolerances: same optimum as Ipopt within 1e-6 relative
    assert res.objective == pytest.approx(ref.objective, rel=1e-6)


def test_windows_no_solver_solves_are_counted_and_still_limited(monkeypatch):
    q, dt, lim = _random_ride(7, False)

    def fail(self, win):
        return np.full(win.xd.shape, np.nan), False

    monkeypatch.setattr(ConicChunkSolver, "solve", fail)
    monkeypatch.setattr(_ChunkSolver, "solve", fail)
    res = limit_ride(q, dt, lim)
    assert res.n_solver_failures >= res.n_windows > 0
    assert np.all(np.isfinite(res.q))
    assert res.check.ok, res.check
    # independent check from the same default initial state (at rest at the first frame)
    hist = np.repeat(np.clip(q[:1], lim.q_min, lim.q_max), 3, axis=0)
    assert check_trajectory(res.q, dt, lim, history=hist).ok
    rt = RealtimeLimiter(lim, dt)
    q_rt = rt.run(rt.initial_state(q[0]), q)
    assert res.objective <= float(np.sum((q_rt - q) ** 2)) * (1 + 1e-12)


def test_unknown_backend_is_named():
    from motioncue import ConfigError

    with pytest.raises(ConfigError, match="backend"):
        lim = ActuatorLimits(np.zeros(1), np.ones(1), np.ones(1), np.ones(1))
        _offline.limit_ride(np.zeros((10, 1)), 0.01, lim, backend="x")
