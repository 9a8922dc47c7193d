"""The optimal plan's QPs through DAQP's own interface give the plans of casadi's plugin.

``OptimalCueing`` solves its window QPs on the ``mpc`` route (:func:`~motioncue.cueing._mpc.
qp_solver`: DAQP's own interface for ``solver = "daqp"``, the guard's slacks included); the
oracle is the same QP through casadi's ``daqp`` conic plugin (:class:`~motioncue.cueing._mpc.
QpSolver`, a separate argument path), swapped into a second design.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from motioncue.cueing import load_cueing
from motioncue.cueing._mpc import DaqpQp, QpSolver, SoftGuardQp
from motioncue.cueing._optimal import OptimalCueing

FS = 100.0
ROOT = Path(__file__).resolve().parents[1]


def test_the_direct_route_gives_the_casadi_plugins_plan() -> None:
    rec = ROOT / "configs" / "recordings" / "street-formula.csv"  # a tuning drive
    # 5 s: three windows of the 2 s stride, the fewest the test accepts (each costs the same)
    a = np.loadtxt(rec, delimiter=",", skiprows=1, max_rows=3500)[3000:3500]
    f, w = a[:, 1:4].copy(), a[:, 4:7].copy()
    # the guard at the block ends only (sign_guard_every = 0): with the preset's guard at every
    # sample (session 27) casadi's daqp plugin fails the first window's QP that DAQP's own
    # interface and the working set solve to the same optimum (cost -144496.34, measured), so
    # the oracle would compare a different fallback; the working set is checked against the
    # direct route with the preset's own guard in tests/test_optimal_working_set.py
    base = load_cueing("optimal-hexapod")
    assert base.mpc is not None
    params = dataclasses.replace(base, mpc=dataclasses.replace(base.mpc, sign_guard_every=0))
    direct = OptimalCueing(params, FS)
    assert isinstance(direct._qp, DaqpQp)
    # the whole window QP on this route (its working-set solve is checked against this route
    # in tests/test_optimal_working_set.py)
    object.__setattr__(direct, "_ws", None)
    assert direct._qp_guard is not None and direct.mpc.sign_guard[2] > 0.0  # the fz guard too
    oracle = OptimalCueing(params, FS)
    mp = oracle.mpc
    object.__setattr__(oracle, "_qp", QpSolver(mp.solver, oracle._hess, oracle._a_mat.shape[0]))
    object.__setattr__(
        oracle,
        "_qp_guard",
        SoftGuardQp(
            mp.solver,
            oracle._hess,
            oracle._a_mat.shape[0],
            oracle._a_guard.shape[0],
            mp.sign_guard_weight,
        ),
    )
    assert oracle._qp_guard is not None and isinstance(oracle._qp_guard._qp, QpSolver)
    got, want = direct.run(f, w), oracle.run(f, w)
    assert got.fallbacks == want.fallbacks == 0
    assert got.windows == want.windows >= 3
    span = np.ptp(want.poses, axis=0)
    assert span[3] > np.radians(3.0)  # the excerpt moves the plan (roll)
    # the same solver on two argument paths: equal to rounding (measured 1.5e-13)
    np.testing.assert_allclose(got.poses, want.poses, rtol=0, atol=1e-8)  # m, rad
