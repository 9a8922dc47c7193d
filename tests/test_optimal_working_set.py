"""The optimal plan's working-set QP (:class:`~motioncue.cueing._optimal.WorkingSetQp`) gives
the optimum of the whole problem.

Oracles: the whole problem with every row and every guard slack, through casadi's ``daqp``
conic plugin (:class:`~motioncue.cueing._mpc.SoftGuardQp` on :class:`QpSolver`, a separate
argument path), on random problems with many inactive rows, binding rows and guard rows that
cannot all be met; and on a one-variable problem, the closed form of the soft guard.
"""

from __future__ import annotations

import numpy as np

from motioncue.cueing._mpc import QpData, SoftGuardQp, SoftRows
from motioncue.cueing._optimal import WorkingSetQp


def _problem(seed: int, n: int = 12, m: int = 60, ng: int = 20) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    l_mat = rng.normal(size=(n, n))
    hess = l_mat @ l_mat.T + n * np.eye(n)
    g = rng.normal(scale=30.0, size=n)  # an unconstrained optimum far outside the rows
    a = rng.normal(size=(m, n))
    lba = -rng.uniform(1.0, 4.0, m)
    uba = rng.uniform(1.0, 4.0, m)
    lba[::7] = -np.inf  # one-sided rows
    a_g = rng.normal(size=(ng, n))
    lo_g = np.where(np.arange(ng) % 2 == 0, rng.uniform(0.5, 3.0, ng), -np.inf)
    hi_g = np.where(np.arange(ng) % 2 == 1, -rng.uniform(0.5, 3.0, ng), np.inf)
    lo_g[3], hi_g[3] = -np.inf, np.inf  # a row with no bound at all
    lbx = np.full(n, -2.0)
    ubx = np.full(n, 2.0)
    return hess, g, a, lba, uba, lbx, ubx, a_g, lo_g, hi_g


def test_the_working_set_gives_the_whole_problems_optimum() -> None:
    weight = 50.0
    binding = slacked = 0
    for seed in range(6):
        hess, g, a, lba, uba, lbx, ubx, a_g, lo_g, hi_g = _problem(seed)
        full = SoftGuardQp("daqp", hess, a.shape[0], a_g.shape[0], weight)
        ok_f, z, _, _ = full.solve_full(QpData(g, a, lba, uba, lbx, ubx), SoftRows(a_g, lo_g, hi_g))
        assert ok_f
        u_full, s_full = z[: hess.shape[0]], z[hess.shape[0] :]
        ws = WorkingSetQp(hess, weight)
        ok, u = ws.solve(QpData(g, a, lba, uba, lbx, ubx), SoftRows(a_g, lo_g, hi_g))
        assert ok
        np.testing.assert_allclose(u, u_full, rtol=0, atol=1e-7)
        assert ws.last is not None
        au = a @ u_full
        binding += int(np.sum(np.isclose(au, uba, atol=1e-7) | np.isclose(au, lba, atol=1e-7)))
        slacked += int(np.sum(s_full > 1e-6))
        # the relaxations kept fewer rows than the whole problem has
        assert ws.last[0].sum() < a.shape[0] + a_g.shape[0]
    assert binding >= 6 and slacked >= 3  # the cases test binding rows and paid slacks


def test_a_warm_start_from_an_earlier_solve_gives_the_same_optimum() -> None:
    hess, g, a, lba, uba, lbx, ubx, a_g, lo_g, hi_g = _problem(11)
    ws = WorkingSetQp(hess, 50.0)
    guard = SoftRows(a_g, lo_g, hi_g)
    ok, u = ws.solve(QpData(g, a, lba, uba, lbx, ubx), guard)
    assert ok and ws.last is not None
    g2 = g + np.random.default_rng(1).normal(scale=3.0, size=g.size)  # a nearby problem
    qp2 = QpData(g2, a, lba, uba, lbx, ubx)
    ok2, u2 = ws.solve(qp2, guard, guess=u, start=ws.last)
    ok3, u3 = WorkingSetQp(hess, 50.0).solve(qp2, guard)
    assert ok2 and ok3
    np.testing.assert_allclose(u2, u3, rtol=0, atol=1e-7)
    assert np.max(np.abs(u2 - u)) > 1e-3  # the problems differ


def test_a_guard_that_cannot_be_met_is_priced_as_the_closed_form() -> None:
    # min 0.5 h u^2 + g u + w (s + s^2/2), u + s >= lo, |u| <= 1 (a row), no bounds on u:
    # with s > 0 at the optimum, h u + g = w (1 + s) and s = lo - u:
    # u = (w (1 + lo) - g) / (h + w), when that u is inside [-1, 1] and below lo
    h, g, w, lo = 2.0, 10.0, 3.0, 4.0
    ws = WorkingSetQp(np.array([[h]]), w)
    ok, u = ws.solve(
        QpData(
            np.array([g]),
            np.array([[1.0]]),
            np.array([-1.0]),
            np.array([1.0]),
            np.array([-np.inf]),
            np.array([np.inf]),
        ),
        SoftRows(np.array([[1.0]]), np.array([lo]), np.array([np.inf])),
    )
    want = (w * (1.0 + lo) - g) / (h + w)
    assert -1.0 < want < lo
    assert ok
    np.testing.assert_allclose(u, [want], rtol=0, atol=1e-9)


def test_a_guard_worth_more_than_its_price_takes_its_slack() -> None:
    # the same problem without the |u| <= 1 row: the guard u >= lo could be met (u = lo), but
    # its multiplier there, h lo + g = 18, exceeds the price w = 3, so the optimum pays a slack:
    # u = (w (1 + lo) - g) / (h + w) = 1, s = 3; a cheap guard (w = 100) is met exactly
    h, g, lo = 2.0, 10.0, 4.0
    for w, want in ((3.0, (3.0 * (1.0 + lo) - g) / (h + 3.0)), (100.0, lo)):
        ok, u = WorkingSetQp(np.array([[h]]), w).solve(
            QpData(
                np.array([g]),
                np.zeros((0, 1)),
                np.zeros(0),
                np.zeros(0),
                np.array([-np.inf]),
                np.array([np.inf]),
            ),
            SoftRows(np.array([[1.0]]), np.array([lo]), np.array([np.inf])),
        )
        assert ok
        np.testing.assert_allclose(u, [want], rtol=0, atol=1e-9)


def test_the_bundled_plan_on_a_working_set_is_the_whole_qps_plan() -> None:
    from dataclasses import replace
    from pathlib import Path

    from motioncue.cueing import load_cueing
    from motioncue.cueing._optimal import OptimalCueing

    root = Path(__file__).resolve().parents[1]
    rec = root / "configs" / "recordings" / "street-formula.csv"  # a tuning drive
    a = np.loadtxt(rec, delimiter=",", skiprows=1, max_rows=3700)[3000:3700]
    f, w = a[:, 1:4].copy(), a[:, 4:7].copy()
    # the guard's rows at the block ends only: with the preset's rows at every sample too
    # (session 27) the whole QPs of this 7 s excerpt take 76 s (960 more soft rows a window);
    # that case is checked on 1 s windows in tests/test_optimal_sign_guard_every.py
    base = load_cueing("optimal-hexapod")
    assert base.mpc is not None
    params = replace(base, mpc=replace(base.mpc, sign_guard_every=0))
    fast = OptimalCueing(params, 100.0)
    assert fast._ws is not None
    whole = OptimalCueing(params, 100.0)
    object.__setattr__(whole, "_ws", None)  # every row and guard slack in every solve
    got, want = fast.run(f, w), whole.run(f, w)
    assert got.fallbacks == want.fallbacks == 0 and got.windows == want.windows >= 3
    assert np.ptp(want.poses[:, 3]) > np.radians(3.0)  # the excerpt moves the plan (roll)
    assert fast._ws.solves > 2 * got.windows  # relaxations were grown (not one solve each)
    # the same optimum, each solve to DAQP's primal tolerance (1e-6 of a row), carried from
    # window to window by the state: 10 um, 10 urad
    np.testing.assert_allclose(got.poses, want.poses, rtol=0, atol=1e-5)  # m, rad


def test_a_relaxation_proved_infeasible_ends_the_solve_without_the_whole_problem() -> None:
    # u0 >= 1 and u0 <= 0 (two hard rows) cannot both hold. The first relaxation keeps the
    # row the zero guess violates (u0 >= 1) and is met at u0 = 1, which violates the other;
    # the second keeps both and DAQP proves it infeasible. The whole problem has both rows
    # too, so it is not solved (it cost seconds a window on the bundled plan's large working
    # sets): two relaxations, not three. The oracle: the whole problem through casadi's daqp
    # plugin is infeasible as well.
    hess = np.eye(2)
    qp = QpData(
        np.zeros(2),
        np.array([[1.0, 0.0], [1.0, 0.0]]),
        np.array([1.0, -np.inf]),
        np.array([np.inf, 0.0]),
        np.full(2, -5.0),
        np.full(2, 5.0),
    )
    ws = WorkingSetQp(hess, 10.0)
    ok, _ = ws.solve(qp)
    assert not ok and ws.infeasible and ws.last is None
    assert ws.solves == 2, ws.solves
    full = SoftGuardQp("daqp", hess, 2, 0, 10.0)
    ok_f, _, _, _ = full.solve_full(qp, SoftRows(np.zeros((0, 2)), np.zeros(0), np.zeros(0)))
    assert not ok_f
    # a feasible problem after it: solved, and not marked infeasible
    qp_ok = QpData(qp.g, qp.a, np.array([1.0, -np.inf]), np.array([np.inf, 2.0]), qp.lbx, qp.ubx)
    ok2, u2 = ws.solve(qp_ok)
    assert ok2 and not ws.infeasible
    np.testing.assert_allclose(u2, [1.0, 0.0], rtol=0, atol=1e-9)
