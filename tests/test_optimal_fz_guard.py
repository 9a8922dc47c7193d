"""The optimal plan's fz guard: the tilt's loss of vertical force, as a rider feels it.

The plan's linear model has no fz from roll, pitch or the x/y accelerations under a tilt (it
is second order); with ``sign_guard[2] > 0`` the optimal plan linearises that change about
its first plan and guards the perceived fz through the otolith model (issue 20: fz reversals
against a bumpy car's perceived fz). Oracles: scipy's rotations for the specific force, the
model set's own ``filter`` (second-order sections, not the plan's state space) for the
perception, finite differences for the linearisation.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motioncue.cueing import evaluate_cueing, get_model_set, load_cueing
from motioncue.cueing._optimal import OptimalCueing, _fz_change

FS = 100.0
G = 9.80665
ROOT = Path(__file__).resolve().parents[1]


def _with(params, **kw):  # type: ignore[no-untyped-def]
    return dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, **kw))


def test_the_change_of_vertical_force_is_that_of_the_rotated_specific_force() -> None:
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(4)
    active = (0, 1, 3, 4)
    for _ in range(200):
        x = np.zeros(20)
        x[3], x[4] = rng.uniform(-0.3, 0.3, 2)
        u = rng.uniform(-5.0, 5.0, 4)
        a = np.array([u[0], u[1], 0.0])
        rot = Rotation.from_euler("ZYX", [0.0, x[4], x[3]])  # yaw, pitch, roll
        f_head = rot.inv().apply(a + np.array([0.0, 0.0, G]))
        assert _fz_change(x, u, active) == pytest.approx(f_head[2] - G, abs=1e-12)


def _design() -> OptimalCueing:
    params = _with(
        load_cueing("optimal-hexapod"),
        sign_guard=(0.7, 0.7, 0.9, 0.7, 0.7, 0.0),
        window_s=1.0,
        stride_s=0.5,
        block_samples=10,
    )
    design = OptimalCueing(params, FS)
    assert design._fz_guarded()
    return design


def _perceived_fz(design: OptimalCueing, u: np.ndarray) -> np.ndarray:
    """The rider's perceived fz (m/s^2) of the window's motion from rest under inputs ``u``,
    by the model set's own filter of the exact change of vertical force."""
    m = design.model
    n = design.n_window
    bs = design.mpc.block_samples
    x = np.einsum("kxu,u->kx", design._gam, u)  # from rest, the vehicle still: xf = 0
    fz = np.array([_fz_change(x[k], u[(k // bs) * m.nu :][: m.nu], m.active) for k in range(n)])
    sig = np.zeros((n, 6))
    sig[:, 2] = fz
    return get_model_set("telban-cardullo-2005").filter(sig, FS)[:, 2]


def test_the_fz_rows_are_the_perceived_fz_at_the_plan_and_its_tangent() -> None:
    design = _design()
    m = design.model
    n, bs = design.n_window, design.mpc.block_samples
    nb = n // bs
    rng = np.random.default_rng(7)
    u0 = np.zeros(nb * m.nu)
    shape = np.array([1.5, -2.0, 4.0, -3.0])  # x, y, roll, pitch accelerations
    for j in range(nb):  # a smooth roll and pitch to ~10 deg, with x/y accelerations
        u0[j * m.nu : (j + 1) * m.nu] = shape * np.cos(2 * np.pi * j / nb)
    xf = np.zeros((n + 1, m.nx))
    thr = float(m.thresholds[2])
    oracle = _perceived_fz(design, u0)
    tilt = np.degrees(np.abs(np.einsum("kxu,u->kx", design._gam, u0)[:, 3:5]).max())
    assert 5.0 < tilt < 20.0
    a, c, sign = design._fz_rows(xf, u0, np.zeros(m.nx), np.ones(n + 1))
    assert np.all(sign == 1.0)
    got = (a @ u0 + c) * thr
    # each block's row is its lowest perceived fz; the plan's otolith is the zero-order-hold
    # state space of the transfer function, the filter its bilinear sections: on this fast
    # motion (10 deg in 0.5 s) they differ by up to 4 % of the peak
    want = np.array([oracle[j * bs : (j + 1) * bs].min() for j in range(nb)])
    scale = np.abs(oracle).max()
    assert scale > 0.1  # a felt drop: the rows have something to guard
    np.testing.assert_allclose(got, want, atol=0.05 * scale)
    # the tangent: at one fixed sample per block (the vehicle's fz positive only at the block
    # ends), the rows of a step du away, exact there, differ from the tangent by O(du^2)
    ends = np.zeros(n + 1)
    ends[bs::bs] = 1.0
    a0, c0, _ = design._fz_rows(xf, u0, np.zeros(m.nx), ends)
    du = rng.normal(size=u0.shape)
    errs = []
    for h in (0.2, 0.1):
        a1, c1, _ = design._fz_rows(xf, u0 + h * du, np.zeros(m.nx), ends)
        exact = a1 @ (u0 + h * du) + c1
        assert np.abs(exact - (a0 @ u0 + c0)).max() > 1e-3  # the step moves the rows
        errs.append(np.abs(exact - (a0 @ (u0 + h * du) + c0)).max())
    assert 3.0 < errs[0] / errs[1] < 5.0  # second order
    # no guarded sample where the vehicle's perceived fz is not positive
    _, _, none = design._fz_rows(xf, u0, np.zeros(m.nx), -np.ones(n + 1))
    assert not none.any()


def test_the_fz_guard_cuts_wrong_sign_fz_cues_on_a_bumpy_drive() -> None:
    rec = ROOT / "configs" / "recordings" / "street-formula.csv"  # a tuning drive
    a = np.loadtxt(rec, delimiter=",", skiprows=1, max_rows=4000)[2500:4000]
    f, w = a[:, 1:4].copy(), a[:, 4:7].copy()
    base = _with(load_cueing("optimal-hexapod"), tilt_fz_use_against=0.0)
    sg = list(base.mpc.sign_guard)
    times = []
    for gz in (0.0, 0.9):
        sg[2] = gz
        res = OptimalCueing(_with(base, sign_guard=tuple(sg)), FS).run(f, w)
        assert res.fallbacks == 0
        ev = evaluate_cueing(res.f_used, res.w_used, res.poses, FS)
        times.append(float(ev.false_cue_time_s[2]))
    assert times[0] > 0.5  # without the fz guard the tilt is felt as a drop against the car
    assert times[1] <= 0.4 * times[0]  # measured: 0.52 s against 1.74 s of the 15 s


def test_the_fz_guard_holds_when_the_second_pass_legs_rows_are_infeasible(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The second pass's legs rows (linearised about a first plan at the stroke's edge) can be
    infeasible; the fz guard's rows are then solved with the first pass's legs rows, not
    dropped with the second pass (the first plan knows nothing of the tilt's fz). Forced
    here: every second pass (a window QP first seen with the fz rows) fails."""
    rec = ROOT / "configs" / "recordings" / "street-formula.csv"  # a tuning drive
    a = np.loadtxt(rec, delimiter=",", skiprows=1, max_rows=4000)[2500:4000]
    f, w = a[:, 1:4].copy(), a[:, 4:7].copy()
    # the guard's other rows at the block ends only (sign_guard_every = 0, as when measured):
    # with them at every sample too (the preset since session 27) every window's working set,
    # its second passes all failed here, takes 4x the time (15 s against 3.4 s of this test)
    base = _with(load_cueing("optimal-hexapod"), tilt_fz_use_against=0.0, sign_guard_every=0)
    sg = list(base.mpc.sign_guard)
    sg[2] = 0.9
    design = OptimalCueing(_with(base, sign_guard=tuple(sg)), FS)
    solve_window = OptimalCueing._solve_window
    first_pass: list[object] = []  # the QPs themselves (kept alive: no id reused)
    broken_passes: list[int] = []

    def broken(self, qp, xv_ends, sign_ends, use_guard, fz=None, guess=None, start=None):  # type: ignore[no-untyped-def]
        if fz is None:
            first_pass.append(qp)
        elif not any(qp is q for q in first_pass):  # a second pass: its legs rows fail
            broken_passes.append(1)
            return False, np.zeros_like(qp.qp.g)
        return solve_window(self, qp, xv_ends, sign_ends, use_guard, fz, guess, start)

    times = []
    for patch in (False, True):
        if patch:
            monkeypatch.setattr(OptimalCueing, "_solve_window", broken)
        res = design.run(f, w)
        assert res.fallbacks == 0
        ev = evaluate_cueing(res.f_used, res.w_used, res.poses, FS)
        times.append(float(ev.false_cue_time_s[2]))
    assert len(broken_passes) == res.windows  # every window's second pass failed
    # measured: 0.56 s as planned, 0.51 s with every second pass failed; keeping the first
    # plans instead (no fz rows) 1.50 s, and 1.74 s without the fz guard (the test above)
    assert times[1] <= times[0] + 0.2
    assert times[1] <= 0.5 * 1.74
