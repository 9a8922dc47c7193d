"""Whole-ride optimal cueing (``algorithm = "optimal"``): offline, for ride files only.

The recording is known in advance, so the perceived-motion error of :mod:`._mpc`'s model (the
same platform model, vestibular error, weights and constraints) is minimised with the
vehicle's *actual* future motion instead of a prediction: the platform can move before an
event. A long ride is cut into overlapping windows of ``window_s``; each window's QP is solved
from the state the previous windows reached, and its first ``stride_s`` are kept (the rest of
the window only makes the kept part aware of what follows). Within a window the input (the
platform acceleration) is held over blocks of ``block_samples`` samples; the leg lengths are
linearised about the previous window's plan where it overlaps (about the neutral pose after
it, and everywhere when that solve fails or there is no previous plan), then the window is
solved again with them linearised about that first plan at every block end (a second
sequential-QP pass; the first plan is kept when that solve fails, except with the fz guard
below: the legs' rows about a first plan at the stroke's edge can be infeasible, so the fz
guard's rows are then solved with the first pass's legs rows, and the first plan, which
knows nothing of the tilt's fz, is kept only if that fails too). The usable stroke is
``stroke_use`` of the real one (the rest absorbs what the linearisation misses); speed,
acceleration, tilt and combined-tilt (``tilt_fz_use``) limits are those of :mod:`._mpc`.
Knowing the ride, the plan can also hold the combined tilt tighter exactly where the loss of
vertical force a tilt brings would oppose the vehicle (``tilt_fz_use_against``: at the block
ends where the vehicle's perceived fz is above its threshold, e.g. downforce in a fast
corner), and use more tilt everywhere else.

The linear model does not see the vertical force a tilt takes away, ``g (cos roll cos pitch -
1)``. With a sign guard on fz (``sign_guard[2] > 0``) and roll and pitch both moved, the
sequential-QP pass prices it where a rider feels it: that loss, linearised about the first
plan sample by sample, drives the otolith's fz model (the loss of the samples already kept,
exact, carried from window to window), and the rider's perceived fz so found may oppose the
vehicle's by at most ``sign_guard[2]`` thresholds at every block end (an fz reversal or a
wrong-sign fz cue: a drop felt while the car is pressed down).

The sign guard's rows are set at the block ends; with ``sign_guard_every = k`` those of every
guarded channel but fz also every ``k``-th sample within each block: the rider's motion is
judged sample by sample, and a car's perceived rate (a formula car's roll rate: road
texture) can change sign every few samples, so a tilt felt with the car's own rotation is
left free and one felt against it is held within the guard at each sample.

The QP of a window has a constant Hessian (built once per design); its gradient comes from
the vehicle's motion over the window (one simulation of the model from rest); it is solved by
the same casadi conic plugin as the MPC, or for ``solver = "daqp"`` by DAQP on a working set
of its rows (:class:`WorkingSetQp`: the rows the plan violates, grown until none is; the same
optimum with a fraction of the rows and guard slacks, the set of the window before as the
start). A window whose solve fails is driven by the
classical fallback tracker of :mod:`._mpc` (counted in :attr:`OptimalResult.fallbacks`).

:meth:`OptimalCueing.step` raises :class:`~motioncue._errors.ConfigError`: a live ride has no
future to optimise over (use ``algorithm = "mpc"``).
"""

from __future__ import annotations

import math
from collections.abc import MutableSequence, Sequence
from dataclasses import dataclass, field, replace
from typing import ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._mpc import (
    TILT_OCTAGON,
    DaqpQp,
    MpcResult,
    MpcState,
    PlanCueing,
    QpData,
    QpOutcome,
    QpSolver,
    SoftGuardQp,
    SoftRows,
    accel_rows,
    build_model,
    fallback_accel,
    guard_channels,
    input_bounds,
    input_responses,
    octagon_bound,
    qp_solver,
    recording_arrays,
    reference,
    sign_guard_bounds,
    slack_hessian,
    slack_terms,
    terminal_weight,
    tilt_axes,
    tilt_fz_bound,
)
from ._params import GRAVITY_M_S2

__all__ = ["OptimalCueing", "OptimalResult"]


def _fz_change(x: NDArray[np.float64], u: NDArray[np.float64], active: tuple[int, ...]) -> float:
    """The change of the rider's vertical specific force (m/s^2) at pose and rate ``x`` with
    input ``u``, without heave: ``g (cos roll cos pitch - 1) - sin roll a_y + cos roll sin pitch
    a_x`` (``R^T (a + g e_z)`` of roll, then pitch)."""
    ax = float(u[active.index(0)]) if 0 in active else 0.0
    ay = float(u[active.index(1)]) if 1 in active else 0.0
    cr, sr = math.cos(x[3]), math.sin(x[3])
    cp, sp = math.cos(x[4]), math.sin(x[4])
    return GRAVITY_M_S2 * (cr * cp - 1.0) - sr * ay + cr * sp * ax


class WorkingSetQp:
    """The window QP of :class:`~._mpc.SoftGuardQp` (hard rows and soft one-sided guard rows,
    each slack priced ``weight (s + s^2 / 2)``) solved on a growing working set of its rows.

    A window has far more rows (legs' stroke, speed and force at every block end, tilt rates,
    the guard) than bind; DAQP's set-up costs about ``rows x variables^2`` a solve and a soft
    row brings a slack variable. So the problem is solved with the rows violated by a first
    guess only (a relaxation: fewer rows, a slack only for the guard rows kept), every row the
    solution violates is added, and it is solved again until none is: the solution of the
    last relaxation is then feasible for the whole problem, so it is its optimum (a guard row
    left out is met with a zero slack). A guard row kept is first a hard row (no slack
    variable); it gets its slack when the rows kept cannot all be met, or when its multiplier
    exceeds the slack's price (then a zero slack is not optimal); a hard guard row whose
    multiplier is within the price is the optimum with a zero slack. Each solve is
    warm-started from the last one's active set. ``max_rounds`` relaxations at most; then the
    whole problem is solved. A relaxation that DAQP proves infeasible, with no guard row left
    to price, ends the solve as failed: the whole problem has all its rows and more, so it is
    infeasible too (solving it anyway took seconds per window on a large working set).

    Parameters
    ----------
    hess : (n, n) array
        Hessian of the inputs' cost (constant per design).
    weight : float
        Price of a guard row's slack (per threshold, :class:`~._mpc.SoftGuardQp`).
    tol : float
        A row counts as violated beyond ``tol (1 + |bound|)`` (its own units).
    max_rounds : int
        Relaxations solved before falling back to the whole problem.
    """

    def __init__(
        self, hess: NDArray[np.float64], weight: float, tol: float = 1e-7, max_rounds: int = 24
    ) -> None:
        self.hess = np.ascontiguousarray(hess, dtype=float)
        self.n = int(hess.shape[0])
        self.weight = float(weight)
        self.tol = float(tol)
        self.max_rounds = int(max_rounds)
        self.solves = 0
        """Relaxations solved so far (for benchmarks)."""
        self.infeasible = False
        """The last relaxation was proved infeasible (:attr:`DaqpQp.infeasible`)."""
        self.last: tuple[NDArray[np.bool_], NDArray[np.float64]] | None = None
        """The last successful solve's active rows (a mask) and its multipliers."""

    def solve(
        self,
        qp: QpData,
        guard: SoftRows | None = None,
        guess: NDArray[np.float64] | None = None,
        start: tuple[NDArray[np.bool_], NDArray[np.float64]] | None = None,
    ) -> tuple[bool, NDArray[np.float64]]:
        """``(ok, u)``: the optimum of ``0.5 u' H u + g' u + weight sum(s + s^2 / 2)`` over
        ``qp``'s rows and bounds and the soft rows ``guard`` (``A_g u + s >= lo_g`` where
        ``lo_g`` is finite, else ``A_g u - s <= hi_g``; none without ``guard``);
        ``guess`` ``(n,)``: a plan whose violated rows start the working set (default zero);
        ``start``: rows (a mask of ``[A; A_g]``) to start with too and their multipliers (a
        warm start, e.g. :attr:`last` of a similar problem). The final working set and its
        multipliers are kept in :attr:`last` (its active rows only)."""
        n = self.n
        if guard is None:
            guard = SoftRows(np.zeros((0, n)), np.zeros(0), np.zeros(0))
        a_all = np.concatenate([qp.a, guard.a], axis=0)
        lo_all = np.concatenate([qp.lba, guard.lo])
        hi_all = np.concatenate([qp.uba, guard.hi])
        whole = QpData(qp.g, a_all, lo_all, hi_all, qp.lbx, qp.ubx)  # hard and soft rows
        soft = np.zeros(a_all.shape[0], dtype=bool)
        soft[qp.a.shape[0] :] = True
        live: NDArray[np.bool_] = np.isfinite(lo_all) | np.isfinite(hi_all)
        tol_lo = self.tol * (1.0 + np.abs(np.where(np.isfinite(lo_all), lo_all, 0.0)))
        tol_hi = self.tol * (1.0 + np.abs(np.where(np.isfinite(hi_all), hi_all, 0.0)))

        def violated(u: NDArray[np.float64]) -> NDArray[np.bool_]:
            au = a_all @ u
            return live & ((au < lo_all - tol_lo) | (au > hi_all + tol_hi))

        u0 = np.zeros(n) if guess is None else np.asarray(guess, dtype=float)
        work = violated(u0)
        lam_rows = np.zeros(a_all.shape[0])  # the last solve's multipliers, by row
        lam_u = np.zeros(n)
        if start is not None and start[0].shape == work.shape:
            work |= start[0] & live
            lam_rows = np.where(work, start[1], 0.0)
        slack = np.zeros_like(work)  # the guard rows given their slack so far
        for _ in range(self.max_rounds):
            ok, u, lam_rows, lam_u = self._relaxed(whole, soft & slack, work, lam_rows, lam_u)
            hard = work & soft & ~slack
            if not ok:
                if not hard.any():
                    if self.infeasible:  # fewer rows than the whole problem, and infeasible
                        self.last = None
                        return False, u
                    break
                slack |= hard  # a guard that cannot be met: its rows priced
                continue
            over = hard & (np.abs(lam_rows) > self.weight * (1.0 + 1e-9))
            if over.any():  # worth more than its price: its slack may be used
                slack |= over
                continue
            more = violated(u) & ~work
            if not more.any():
                self.last = (work & (lam_rows != 0.0), lam_rows)
                return True, u
            work |= more
        ok, u, lam_rows, _ = self._relaxed(whole, soft, live, np.zeros(a_all.shape[0]), np.zeros(n))
        self.last = (live & (lam_rows != 0.0), lam_rows) if ok else None
        return ok, u

    def _relaxed(
        self,
        whole: QpData,
        soft: NDArray[np.bool_],
        work: NDArray[np.bool_],
        lam_rows: NDArray[np.float64],
        lam_u: NDArray[np.float64],
    ) -> QpOutcome:
        """The problem ``whole`` (every row, hard and soft) on the rows ``work``, those in
        ``soft`` with their slack, warm-started from the multipliers ``lam_rows`` (by row of
        ``whole``) and ``lam_u``; returns ``(ok, u, lam_rows, lam_u)``."""
        n = self.n
        rows = np.flatnonzero(work)
        srows = rows[soft[rows]]
        k = srows.size
        a_w = np.zeros((rows.size, n + k))
        a_w[:, :n] = whole.a[rows]
        lo_w, hi_w = whole.lba[rows], whole.uba[rows]
        pos = np.flatnonzero(soft[rows])
        sigma = np.where(np.isfinite(lo_w[pos]), 1.0, -1.0)
        a_w[pos, n + np.arange(k)] = sigma
        h = slack_hessian(self.hess, self.weight, k) if k else self.hess
        lam_x = np.concatenate([lam_u, np.zeros(k)])
        self.solves += 1
        g_s, lbx_s, ubx_s = slack_terms(whole.g, whole.lbx, whole.ubx, self.weight, k)
        solver = DaqpQp(h, rows.size)
        ok, z, la, lx = solver.solve(
            QpData(g_s, a_w, lo_w, hi_w, lbx_s, ubx_s), warm=(None, lam_rows[rows], lam_x)
        )
        self.infeasible = solver.infeasible
        out = np.zeros(whole.a.shape[0])
        if ok:
            out[rows] = la
        return ok, z[:n], out, lx[:n]


@dataclass(frozen=True, eq=False)
class _WindowQp:
    """One window's QP (:meth:`OptimalCueing._window_qp`) and the free motion it was built
    from (``nb`` block ends, ``nU`` inputs, ``nx`` states, ``n`` samples in the window)."""

    qp: QpData  # gradient, rows (legs, tilt rate, octagon), bounds; the Hessian is _hess
    pose_free: NDArray[np.float64]  # (nb, 6): pose at the block ends without input
    pose_gain: NDArray[np.float64]  # (nb, 6, nU): pose at the block ends from the inputs
    x_ends: NDArray[np.float64]  # (nb, nx): free state at the block ends
    xf: NDArray[np.float64]  # (n + 1, nx): free state over the window


@dataclass(frozen=True, eq=False)
class OptimalResult(MpcResult):
    """Outcome of :meth:`OptimalCueing.run`: the fields of :class:`MpcResult` (poses,
    bad samples, the input used, ``fs_hz``), counted by window where the MPC counts samples.

    Attributes
    ----------
    fallbacks : int
        Windows whose solve failed (the classical fallback tracker ran there).
    windows : int
        Windows solved.
    solve_ms : (windows,) array
        Wall time of each window's solve (ms).
    """

    windows: int


@dataclass(frozen=True, eq=False)
class OptimalCueing(PlanCueing):
    """Whole-ride optimal cueing of a preset with an ``[mpc]`` table at ``fs_hz`` (offline).

    Parameters
    ----------
    params : CueingParams
        ``params.mpc`` (default :class:`MpcParams`) sets weights, limits and windows.
    fs_hz : float
        Sample rate (Hz).
    """

    offline: ClassVar[bool] = True
    """Needs the whole recording: the live bridge refuses it."""

    n_window: int = field(init=False)
    n_stride: int = field(init=False)
    _gam: NDArray[np.float64] = field(init=False, repr=False)
    _hess: NDArray[np.float64] = field(init=False, repr=False)
    _tw: NDArray[np.float64] = field(init=False, repr=False)
    _a_mat: NDArray[np.float64] = field(init=False, repr=False)
    _qp: QpSolver | DaqpQp = field(init=False, repr=False)
    _a_guard: NDArray[np.float64] = field(init=False, repr=False)
    _qp_guard: SoftGuardQp | None = field(init=False, repr=False)
    _ws: WorkingSetQp | None = field(init=False, repr=False)
    _fz_h: NDArray[np.float64] | None = field(init=False, repr=False)
    _fz_free: NDArray[np.float64] | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._set_up_plan()
        fs = self.fs_hz
        mp = self.mpc
        bs = mp.block_samples
        n_stride = max(bs, round(mp.stride_s * fs / bs) * bs)
        n_window = max(n_stride + bs, round(mp.window_s * fs / bs) * bs)
        object.__setattr__(self, "model", build_model(self.params.dofs, mp, fs))
        object.__setattr__(self, "n_window", n_window)
        object.__setattr__(self, "n_stride", n_stride)
        self._condense()

    # ------------------------------------------------------------------ the window QP
    def _condense(self) -> None:
        m = self.model
        nb = self.n_window // self.mpc.block_samples
        nu, nx = m.nu, m.nx
        n_u = nb * nu
        gam = np.zeros((self.n_window + 1, nx, n_u))
        q = m.q
        hess = np.zeros((n_u, n_u))
        ends = np.arange(1, nb + 1) * self.mpc.block_samples
        for k, gam_k in enumerate(input_responses(m, ends), start=1):
            gam[k] = gam_k
            hess += gam[k].T @ q @ gam[k]
        tw = terminal_weight(m)
        hess += gam[-1].T @ tw @ gam[-1]
        for j in range(nb):
            sl = slice(j * nu, (j + 1) * nu)
            hess[sl, sl] += self.mpc.block_samples * m.r
        wj = self._w_jerk()
        if wj is not None:  # w_jerk |u_b - u_{b-1}|^2, the first block's u_{-1} in the gradient
            for j in range(nb):
                sl = slice(j * nu, (j + 1) * nu)
                hess[sl, sl] += np.diag(wj)
                if j > 0:
                    prev = slice((j - 1) * nu, j * nu)
                    hess[prev, prev] += np.diag(wj)
                    hess[prev, sl] -= np.diag(wj)
                    hess[sl, prev] -= np.diag(wj)
        hess = 2.0 * 0.5 * (hess + hess.T)
        # constraints at block ends, legs linearised about neutral
        lim = self.limits
        jac = np.asarray(lim.platform.jacobian(np.zeros(6)), dtype=float)
        ge = gam[ends]  # (nb, nx, nU)
        a_pos = np.einsum("lj,bju->blu", jac, ge[:, 0:6])
        a_vel = np.einsum("lj,bju->blu", jac, ge[:, 6:12])
        rows = [a_pos, a_vel, accel_rows(jac[:, list(m.active)], nb)]
        tilt = tilt_axes(self.params.dofs)
        if tilt:
            rows.append(ge[:, [6 + i for i in tilt]])
        if self._combined_tilt_bound() is not None:
            rows.append(np.einsum("ck,bku->bcu", TILT_OCTAGON, ge[:, 3:5]))
        a_mat = np.concatenate([r.reshape(-1, n_u) for r in rows], axis=0)
        object.__setattr__(self, "_gam", gam)
        object.__setattr__(self, "_hess", hess)
        object.__setattr__(self, "_tw", tw)
        object.__setattr__(self, "_a_mat", a_mat)
        # the mpc route to the solver (DAQP's own interface for "daqp": casadi's argument
        # conversion of the dense window matrices took most of a solve's time)
        object.__setattr__(self, "_qp", qp_solver(self.mpc.solver, hess, a_mat.shape[0]))
        # sign guard: the perceived simulator motion ce_i (x - x_vehicle) at block ends
        guard = self._guard_channels()
        ce_thr = m.ce[guard] / m.thresholds[guard][:, None]  # rows in thresholds
        a_guard = np.einsum("gx,bxu->bgu", ce_thr, ge).reshape(-1, n_u)
        inner = self._inner_samples()
        if inner.size:  # and within the blocks (sign_guard_every), fz excepted, block-major
            gi = self._inner_channels()
            ce_in = m.ce[gi] / m.thresholds[gi][:, None]
            a_in = np.einsum("gx,kxu->kgu", ce_in, gam[inner]).reshape(-1, n_u)
            a_guard = np.concatenate([a_guard, a_in], axis=0)
        object.__setattr__(self, "_a_guard", a_guard)
        object.__setattr__(
            self,
            "_qp_guard",
            SoftGuardQp(
                self.mpc.solver,
                hess,
                a_mat.shape[0],
                a_guard.shape[0],
                self.mpc.sign_guard_weight,
                direct=True,
            )
            if guard
            else None,
        )
        object.__setattr__(
            self,
            "_ws",
            WorkingSetQp(hess, self.mpc.sign_guard_weight) if self.mpc.solver == "daqp" else None,
        )
        self._condense_fz()

    def _w_jerk(self) -> NDArray[np.float64] | None:
        """``w_jerk`` of the moved degrees of freedom (the inputs' order); None: all 0."""
        wj = np.asarray(self.mpc.w_jerk, dtype=float)[list(self.model.active)]
        return wj if np.any(wj > 0.0) else None

    def _fz_guarded(self) -> bool:
        """Whether the plan's perceived fz includes the tilt's loss of vertical force (a
        sign guard on fz, roll and pitch both moved)."""
        return self.mpc.sign_guard[2] > 0.0 and bool(self.params.dofs[3] and self.params.dofs[4])

    def _condense_fz(self) -> None:
        """The otolith fz model's response to a change of the rider's vertical force:
        impulse response ``h`` ``(n_window + 1,)`` (perceived fz at sample ``k`` of a unit
        change held over sample 0) and the free response ``(n_window + 1, nx)`` of a state."""
        if not self._fz_guarded():
            object.__setattr__(self, "_fz_h", None)
            object.__setattr__(self, "_fz_free", None)
            return
        m = self.model
        n = self.n_window
        b = -m.bd[:, 2]  # the otolith fz input of the rider's own specific force
        h = np.empty(n + 1)
        h[0] = -m.de[2, 2]  # its feed-through
        free = np.empty((n + 1, m.nx))
        free[0] = m.ce[2]
        z = b.copy()
        for k in range(1, n + 1):
            h[k] = m.ce[2] @ z
            z = m.a @ z
            free[k] = free[k - 1] @ m.a
        object.__setattr__(self, "_fz_h", h)
        object.__setattr__(self, "_fz_free", free)

    def _fz_rows(
        self,
        xf: NDArray[np.float64],
        u_plan: NDArray[np.float64],
        z0: NDArray[np.float64],
        vz: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Rows of the fz guard: the rider's perceived fz (thresholds) as ``A u + c``, in each
        block at the sample where the plan ``u_plan`` gives the lowest one while the vehicle's
        perceived fz ``vz`` ``(n_window + 1,)`` is positive (a drop felt then is a wrong-sign
        cue), with the sign to guard (1 there, 0 in a block without such a sample).

        The change of vertical force (roll, pitch and the x, y accelerations,
        :func:`_fz_change`) is linearised about ``u_plan`` sample by sample and drives the
        otolith fz model from its state ``z0`` (that of the motion already kept); ``xf``
        ``(n_window + 1, nx)`` is the window's free response. Returns ``(A (blocks, n_u),
        c (blocks,), sign (blocks,))``."""
        assert self._fz_h is not None and self._fz_free is not None
        m = self.model
        g = GRAVITY_M_S2
        n = self.n_window
        bs = self.mpc.block_samples
        nb = n // bs
        gam = self._gam
        roll0 = xf[:, 3] + gam[:, 3] @ u_plan
        pitch0 = xf[:, 4] + gam[:, 4] @ u_plan
        n_u = u_plan.shape[0]
        sel = np.zeros((2, n + 1, n_u))  # the x, y acceleration of each sample
        blk = np.minimum(np.arange(n + 1) // bs, nb - 1) * m.nu
        for row, axis in enumerate((0, 1)):
            if axis in m.active:
                sel[row, np.arange(n + 1), blk + m.active.index(axis)] = 1.0
        ax0, ay0 = sel[0] @ u_plan, sel[1] @ u_plan
        cr, sr, cp, sp = np.cos(roll0), np.sin(roll0), np.cos(pitch0), np.sin(pitch0)
        fz0 = g * (cr * cp - 1.0) - sr * ay0 + cr * sp * ax0
        d_roll = -g * sr * cp - cr * ay0 - sr * sp * ax0
        d_pitch = -g * cr * sp + cr * cp * ax0
        d_ax, d_ay = cr * sp, -sr
        const = fz0 + d_roll * (xf[:, 3] - roll0) + d_pitch * (xf[:, 4] - pitch0)
        const = const - d_ax * ax0 - d_ay * ay0
        lin = (
            d_roll[:, None] * gam[:, 3]
            + d_pitch[:, None] * gam[:, 4]
            + d_ax[:, None] * sel[0]
            + d_ay[:, None] * sel[1]
        )  # (n + 1, n_u)
        # the plan's perceived fz at every sample, then the sample guarded in each block
        zfree = self._fz_free @ z0
        per = np.convolve(self._fz_h, fz0)[: n + 1] + zfree
        k_of = np.arange(1, nb + 1) * bs  # default: the block end
        sign = np.zeros(nb)
        for j in range(nb):
            ks = np.arange(j * bs + 1, (j + 1) * bs + 1)
            pos = ks[vz[ks] > 0.0]
            if pos.size:
                k_of[j] = pos[np.argmin(per[pos])]
                sign[j] = 1.0
        h = self._fz_h
        toe = np.zeros((nb, n + 1))
        for j, k in enumerate(k_of):
            toe[j, : k + 1] = h[k::-1]
        thr = float(m.thresholds[2])
        return (toe @ lin) / thr, (toe @ const + zfree[k_of]) / thr, sign

    def _guard_channels(self) -> list[int]:
        return guard_channels(self.mpc)

    def _combined_tilt_bound(self) -> float | None:
        """Bound of the combined-tilt rows (:func:`~._mpc.tilt_fz_bound`; ``None``: none,
        also when roll or pitch is not moved; ``pi`` when only ``tilt_fz_use_against`` asks
        for the rows)."""
        if not (self.params.dofs[3] and self.params.dofs[4]):
            return None
        b = tilt_fz_bound(self.mpc, float(self.model.thresholds[2]))
        if b is None and self._against_bound() is not None:
            return math.pi
        return b

    def _against_bound(self) -> float | None:
        """Bound of the combined-tilt rows where the vehicle's perceived fz is above its
        threshold (``tilt_fz_use_against``; ``None``: the same bound everywhere)."""
        if not (self.params.dofs[3] and self.params.dofs[4]):
            return None
        if self.mpc.tilt_fz_use_against <= 0.0:
            return None
        return tilt_fz_bound(
            replace(self.mpc, tilt_fz_use=self.mpc.tilt_fz_use_against),
            float(self.model.thresholds[2]),
        )

    def _inner_samples(self) -> NDArray[np.int64]:
        """Window samples (state indices, block-major) within the blocks whose perceived
        motion the sign guard also bounds (``sign_guard_every``; empty: block ends only)."""
        every = self.mpc.sign_guard_every
        if every <= 0 or not self._inner_channels():
            return np.zeros(0, dtype=np.int64)
        bs = self.mpc.block_samples
        nb = self.n_window // bs
        offs = np.arange(every, bs, every)
        return (np.arange(nb)[:, None] * bs + offs[None, :]).reshape(-1).astype(np.int64)

    def _inner_channels(self) -> list[int]:
        """The guarded channels bounded within the blocks too: all but fz (whose guard needs
        the tilt's loss of vertical force, at the block ends only)."""
        return [i for i in self._guard_channels() if i != 2]

    def _guard_bounds(
        self,
        xf_win: NDArray[np.float64],
        xv_win: NDArray[np.float64],
        sign_win: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Bounds of the sign-guard rows, in thresholds: at the block ends per guarded
        channel, then at :meth:`_inner_samples` per :meth:`_inner_channels`. ``xf_win``
        ``(n_window + 1, nx)``: the window's free state, ``xv_win``: the vehicle-only state,
        ``sign_win`` ``(n_window + 1, 6)``: the sign of the vehicle's perceived motion (0
        where unconstrained), each by state index."""
        m = self.model
        guard = self._guard_channels()
        ends = np.arange(1, self.n_window // self.mpc.block_samples + 1) * self.mpc.block_samples
        free = (xf_win[ends] - xv_win[ends]) @ (m.ce[guard] / m.thresholds[guard][:, None]).T
        lo, hi = sign_guard_bounds(self.mpc, sign_win[ends][:, guard], free)
        inner = self._inner_samples()
        if not inner.size:
            return lo, hi
        gi = self._inner_channels()
        free_in = (xf_win[inner] - xv_win[inner]) @ (m.ce[gi] / m.thresholds[gi][:, None]).T
        g = np.asarray(self.mpc.sign_guard)[gi]
        v = sign_win[inner][:, gi]
        lo_in = np.where(v > 0, -g - free_in, -np.inf).reshape(-1)
        hi_in = np.where(v < 0, g - free_in, np.inf).reshape(-1)
        return np.concatenate([lo, lo_in]), np.concatenate([hi, hi_in])

    def _window_qp(
        self,
        x0: NDArray[np.float64],
        d: NDArray[np.float64],
        about: NDArray[np.float64] | None = None,
        against: NDArray[np.bool_] | None = None,
        u_before: NDArray[np.float64] | None = None,
    ) -> _WindowQp:
        """The QP (gradient, constraint matrix and bounds) of one window from state ``x0``
        with vehicle motion ``d`` ``(n_window + 1, 6)``; the legs linearised about neutral or, with
        ``about`` ``(blocks, 6)``, about those poses at the block ends; ``against``
        ``(blocks,)``: the block ends whose combined tilt takes the tighter bound of
        ``tilt_fz_use_against``; ``u_before`` ``(nu,)``: the input applied just before the
        window (the first block's step from it is priced by ``w_jerk``; None: from 0)."""
        m = self.model
        n = self.n_window
        bs = self.mpc.block_samples
        nb = n // bs
        xf = np.empty((n + 1, m.nx))
        xf[0] = x0
        bdd = d @ m.bd.T  # (n + 1, nx)
        a_t = m.a.T
        for k in range(1, n + 1):
            xf[k] = xf[k - 1] @ a_t + bdd[k - 1]
        zxd = m.zx.T @ m.zd
        lin = xf[1:] @ m.q + d[1:] @ zxd.T  # (n, nx): Q x_k + Zx'Zd d_k
        g = 2.0 * np.einsum("knu,kn->u", self._gam[1:], lin)
        g += 2.0 * self._gam[-1].T @ (self._tw @ xf[-1])
        wj = self._w_jerk()
        if wj is not None and u_before is not None:
            g[: m.nu] -= 2.0 * wj * u_before
        lim = self.limits
        ends = np.arange(1, nb + 1) * bs
        fe = xf[ends]
        a_mat = self._a_mat
        if about is None:
            jac = np.asarray(lim.platform.jacobian(np.zeros(6)), dtype=float)
            pos_free = fe[:, 0:6] @ jac.T
            vel_free = fe[:, 6:12] @ jac.T
            nl = jac.shape[0]
        else:
            jb = np.asarray(lim.platform.jacobian(about), dtype=float)  # (nb, nl, 6)
            qb = np.asarray(lim.platform.inverse(about), dtype=float)  # (nb, nl)
            off = qb - np.einsum("blj,bj->bl", jb, about) - lim.q_mid
            pos_free = np.einsum("blj,bj->bl", jb, fe[:, 0:6]) + off
            vel_free = np.einsum("blj,bj->bl", jb, fe[:, 6:12])
            nl = jb.shape[1]
            ge = self._gam[ends]
            a_mat = a_mat.copy()
            a_mat[: nb * nl] = np.einsum("blj,bju->blu", jb, ge[:, 0:6]).reshape(nb * nl, -1)
            a_mat[nb * nl : 2 * nb * nl] = np.einsum("blj,bju->blu", jb, ge[:, 6:12]).reshape(
                nb * nl, -1
            )
        lo = [-lim.q_half - pos_free, -lim.v_max - vel_free, np.broadcast_to(-lim.a_max, (nb, nl))]
        hi = [lim.q_half - pos_free, lim.v_max - vel_free, np.broadcast_to(lim.a_max, (nb, nl))]
        tilt = tilt_axes(self.params.dofs)
        if tilt:
            tf = fe[:, [6 + i for i in tilt]]
            lo.append(-lim.tilt_rate - tf)
            hi.append(lim.tilt_rate - tf)
        bound = self._combined_tilt_bound()
        if bound is not None:
            cf = fe[:, 3:5] @ TILT_OCTAGON.T
            bv = np.broadcast_to(octagon_bound(bound), cf.shape)
            tight = self._against_bound()
            if tight is not None and against is not None and np.any(against):
                bv = np.where(against[:, None], np.minimum(bv, octagon_bound(tight)), bv)
            lo.append(-bv - cf)
            hi.append(bv - cf)
        lba = np.concatenate([np.asarray(v).reshape(-1) for v in lo])
        uba = np.concatenate([np.asarray(v).reshape(-1) for v in hi])
        lbx, ubx = input_bounds(m, lim, nb * m.nu)
        return _WindowQp(
            QpData(g, a_mat, lba, uba, lbx, ubx), xf[ends, 0:6], self._gam[ends, 0:6], xf[ends], xf
        )

    def _solve_window(
        self,
        win: _WindowQp,
        xv_win: NDArray[np.float64],
        sign_win: NDArray[np.float64],
        use_guard: bool,
        fz: tuple[NDArray[np.float64], ...] | None = None,
        guess: NDArray[np.float64] | None = None,
        start: tuple[NDArray[np.bool_], NDArray[np.float64]] | None = None,
    ) -> tuple[bool, NDArray[np.float64]]:
        """Solve one window's QP ``win`` (from :meth:`_window_qp`), with the sign-guard rows
        when ``use_guard``; ``fz`` (from :meth:`_fz_rows`): the fz guard rows with the tilt's
        loss of vertical force. On the DAQP route the QP is solved on a working set of its
        rows (:class:`WorkingSetQp`) started from the rows ``guess`` violates."""
        qp = win.qp
        ws = self._ws
        if use_guard and self._qp_guard is not None:
            glo, ghi = self._guard_bounds(win.xf, xv_win, sign_win)
            a_guard = self._a_guard
            if fz is not None:
                guard = self._guard_channels()
                ng = len(guard)
                iz = guard.index(2)
                n_end = ng * (self.n_window // self.mpc.block_samples)  # the block ends' rows
                a_guard = a_guard.copy()
                a_guard[iz:n_end:ng] = fz[0]
                gz = self.mpc.sign_guard[2]
                glo[iz:n_end:ng] = np.where(fz[2] > 0.0, -gz - fz[1], -np.inf)
                ghi[iz:n_end:ng] = np.inf
            soft = SoftRows(a_guard, glo, ghi)
            if ws is not None and isinstance(self._qp_guard._qp, DaqpQp):
                return ws.solve(qp, soft, guess, start)
            ok, u, _, _ = self._qp_guard.solve(qp, soft)
        elif ws is not None and isinstance(self._qp, DaqpQp):
            return ws.solve(qp, guess=guess, start=start)
        else:
            ok, u, _, _ = self._qp.solve(qp)
        return ok, u

    def _row_groups(self) -> list[int]:
        """Rows per block end of each group of ``[A; A_g]`` (each group block-major, in the
        order of :meth:`_condense`)."""
        nl = int(np.asarray(self.limits.platform.jacobian(np.zeros(6))).shape[0])
        sizes = [nl, nl, nl]
        tilt = tilt_axes(self.params.dofs)
        if tilt:
            sizes.append(len(tilt))
        if self._combined_tilt_bound() is not None:
            sizes.append(4)
        guard = self._guard_channels()
        if guard:
            sizes.append(len(guard))
        inner = self._inner_samples()
        if inner.size:
            sizes.append(
                inner.size
                // (self.n_window // self.mpc.block_samples)
                * len(self._inner_channels())
            )
        return sizes

    def _shifted(
        self, start: tuple[NDArray[np.bool_], NDArray[np.float64]] | None, shift: int
    ) -> tuple[NDArray[np.bool_], NDArray[np.float64]] | None:
        """A working set and its multipliers moved ``shift`` blocks earlier (the next window's
        rows of the same block ends; the last blocks' rows empty)."""
        if start is None:
            return None
        nb = self.n_window // self.mpc.block_samples
        work, lam = start
        w_out, l_out = np.zeros_like(work), np.zeros_like(lam)
        at = 0
        for c in self._row_groups():
            size = nb * c
            if at + size > work.size:
                return None
            wv, lv = work[at : at + size], lam[at : at + size]
            w_out[at : at + (nb - shift) * c] = wv[shift * c :]
            l_out[at : at + (nb - shift) * c] = lv[shift * c :]
            at += size
        # guard rows absent from a solve without the guard: the sizes disagree
        return (w_out, l_out) if at == work.size else None

    # ------------------------------------------------------------------ interface
    def initial_state(self) -> MpcState:
        """A fresh state (platform at neutral and at rest)."""
        return MpcState(x=np.zeros(self.model.nx), classical=self.classical.initial_state())

    def reset(self, state: MpcState) -> None:
        """Put ``state`` back to :meth:`initial_state` (in place)."""
        state.x[:] = 0.0
        self.classical.reset(state.classical)
        state.warm_u = state.warm_lam_a = state.warm_lam_x = None

    def step(
        self,
        state: MpcState,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        """Not available: optimal cueing needs the whole recording.

        Raises
        ------
        ConfigError
            Always (use ``algorithm = "mpc"`` for live rides).
        """
        raise ConfigError(
            'algorithm = "optimal" needs the whole recording (cue, generate, compare); '
            'for live rides use algorithm = "mpc"'
        )

    def run(self, f: ArrayLike, w: ArrayLike, state: MpcState | None = None) -> OptimalResult:
        """The whole recording ``f``, ``w`` (N, 3) at ``fs_hz``, window by window (with one
        BLAS thread: the window matrices are too small for more to pay).

        Returns
        -------
        OptimalResult
        """
        from threadpoolctl import threadpool_limits

        with threadpool_limits(limits=1, user_api="blas"):
            return self._run(f, w, state)

    def _run(self, f: ArrayLike, w: ArrayLike, state: MpcState | None) -> OptimalResult:
        import time

        fa, wa = recording_arrays(f, w)
        st = self.initial_state() if state is None else state
        n = fa.shape[0]
        # bad samples and the fallback poses: the classical washout of the same preset
        pose_c = np.zeros((n, 6))
        bad = np.zeros(n, dtype=bool)
        used = np.zeros((n, 6))
        bad0 = st.bad_samples
        for k in range(n):
            before = st.classical.bad_samples
            pose_c[k] = self.classical.step(st.classical, fa[k].tolist(), wa[k].tolist())
            bad[k] = st.classical.bad_samples != before
            used[k] = st.classical.hold
        d_all = used.copy()
        d_all[:, 2] -= GRAVITY_M_S2
        m = self.model
        guard = self._guard_channels()
        up_all = np.zeros(n, dtype=bool)
        vz_all = np.zeros(n)  # the vehicle's perceived fz (with a guard)
        if self._against_bound() is not None:  # the vehicle's perceived fz above threshold
            xz = np.zeros(m.nx)
            for k in range(n):
                xz = m.a @ xz + m.bd @ d_all[k]
                up_all[k] = -(m.ce[2] @ xz + m.de[2] @ d_all[k]) > m.thresholds[2]
        if guard:  # the vehicle's perceived motion (its sign) and the reference-only states
            xt = np.zeros(m.nx)
            xv_all = np.zeros((n, m.nx))
            sign_all = np.zeros((n, 6))
            r_all, _ = reference(d_all, self.mpc, self.fs_hz)
            xv = np.zeros(m.nx)
            for k in range(n):
                xt = m.a @ xt + m.bd @ d_all[k]
                xv = m.a @ xv + m.bd @ r_all[k]
                xv_all[k] = xv
                e_k = m.ce @ xt + m.de @ d_all[k]
                sign_all[k] = -np.sign(e_k)
                vz_all[k] = -e_k[2]
        # the tracked copy; with ref_adapt_peak_m_s2 its gain follows the causal envelope from
        # the recording's start (MpcCueing's, sample by sample), foresight left to the plan
        d_all, _ = reference(d_all, self.mpc, self.fs_hz)
        nw, ns, bs = self.n_window, self.n_stride, self.mpc.block_samples
        poses = np.zeros((n, 6))
        times: list[float] = []
        fallbacks = 0
        start = 0
        nb = nw // bs
        shift = ns // bs
        prev: NDArray[np.float64] | None = None  # the last plan's poses at the block ends
        u_prev: NDArray[np.float64] | None = None  # the last plan's inputs, shifted
        w_prev: tuple[NDArray[np.bool_], NDArray[np.float64]] | None = None  # its working set
        fz_on = self._fz_guarded()
        u_before = np.zeros(m.nu)  # the input applied last (w_jerk prices the step from it)
        z_fz = np.zeros(m.nx)  # the otolith fz state of the tilt's loss of vertical force
        b_fz = -m.bd[:, 2]
        while start < n:
            idx_raw = np.arange(start, start + nw + 1)
            idx = np.minimum(idx_raw, n - 1)
            d = d_all[idx]
            if start + nw + 1 > n:  # past the end: the vehicle at rest
                d[n - start :] = 0.0
            t0 = time.perf_counter()
            ok = False
            u = np.zeros(0)
            p_free = g_end = np.zeros(0)
            sg = xv_e = np.zeros(0)
            ab = start + np.arange(1, nb + 1) * bs - 1  # samples at the block ends
            up = up_all[np.minimum(ab, n - 1)] & (ab < n)
            if guard:  # by state index k of the window: sample start + k - 1
                kw = start + np.arange(nw + 1) - 1
                kwc = np.clip(kw, 0, n - 1)
                sg = sign_all[kwc] * ((kw >= 0) & (kw < n))[:, None]
                xv_e = xv_all[kwc]
            firsts = (prev, None) if prev is not None else (None,)
            ups = (up, None) if up.any() else (None,)
            tries = [
                (gd, fi, ua)
                for ua in ups
                for gd in ((True, False) if guard else (False,))
                for fi in firsts
            ]
            # (the guard is soft, so without it is only a last resort of a failed solve; so is
            # the same tilt bound everywhere)
            use_guard = False
            use_up: NDArray[np.bool_] | None = None
            for use_guard, first, use_up in tries:
                qp = self._window_qp(st.x, d, first, use_up, u_before)
                p_free, g_end = qp.pose_free, qp.pose_gain
                ok, u = self._solve_window(
                    qp, xv_e, sg, use_guard, guess=u_prev, start=self._shifted(w_prev, shift)
                )
                if ok:
                    break
            if ok:  # again with the legs (and the tilt's fz) linearised about this plan
                about = p_free + g_end @ u
                qp2 = self._window_qp(st.x, d, about, use_up, u_before)
                fz = (
                    self._fz_rows(qp2.xf, u, z_fz, vz_all[idx] * (idx_raw < n))
                    if fz_on and use_guard
                    else None
                )
                w1 = self._ws.last if self._ws is not None else None
                ok2, u2 = self._solve_window(qp2, xv_e, sg, use_guard, fz, guess=u, start=w1)
                if not ok2 and fz is not None:
                    # the legs' rows about the first plan can be infeasible (a first plan at
                    # the stroke's edge); the first plan itself knows nothing of the tilt's
                    # fz, so the fz rows are kept with the first pass's legs
                    ok2, u2 = self._solve_window(qp, xv_e, sg, use_guard, fz, guess=u, start=w1)
                w_prev = self._ws.last if self._ws is not None and ok2 else w1
                if ok2:  # else keep the first plan
                    u = u2
                plan = p_free + g_end @ u
                prev = np.zeros_like(plan)  # the next window starts about this plan's rest
                prev[: nb - shift] = plan[shift:]
                u_prev = np.zeros_like(u)  # this plan's rest: the next window's first guess
                u_prev[: (nb - shift) * m.nu] = u[shift * m.nu :]
            else:
                prev = None
                u_prev = None
                w_prev = None
            times.append((time.perf_counter() - t0) * 1e3)
            st.solves += 1
            keep = min(ns, n - start)
            if not ok:
                st.failed += 1
                fallbacks += 1
            for k in range(keep):
                if ok:
                    j = k // bs
                    uk = u[j * m.nu : (j + 1) * m.nu]
                else:
                    uk = fallback_accel(m, self.limits, st.x, pose_c[start + k])
                if fz_on:  # the change of vertical force of the motion kept, exact
                    z_fz = m.a @ z_fz + b_fz * _fz_change(st.x, uk, m.active)
                st.x = m.a @ st.x + m.bu @ uk + m.bd @ d_all[start + k]
                poses[start + k] = st.x[:6]
                u_before = np.asarray(uk, dtype=float)
            start += keep
        st.solve_ms.extend(times)
        return OptimalResult(
            poses=poses,
            bad_samples=st.bad_samples - bad0,
            bad_mask=bad,
            f_used=used[:, 0:3],
            w_used=used[:, 3:6],
            fallbacks=fallbacks,
            windows=len(times),
            solve_ms=np.asarray(times),
            fs_hz=self.fs_hz,
        )
