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
sequential-QP pass; the first plan is kept when that solve fails). The usable stroke is
``stroke_use`` of the real one (the rest absorbs what the linearisation misses); speed,
acceleration, tilt and combined-tilt (``tilt_fz_use``) limits are those of :mod:`._mpc`.
Knowing the ride, the plan can also hold the combined tilt tighter exactly where the loss of
vertical force a tilt brings would oppose the vehicle (``tilt_fz_use_against``: at the block
ends where the vehicle's perceived fz is above its threshold, e.g. downforce in a fast
corner), and use more tilt everywhere else.

The QP of a window has a constant Hessian (built once per design); its gradient comes from
the vehicle's motion over the window (one simulation of the model from rest); it is solved by
the same casadi conic plugin as the MPC. A window whose solve fails is driven by the
classical fallback tracker of :mod:`._mpc` (counted in :attr:`OptimalResult.fallbacks`).

:meth:`OptimalCueing.step` raises :class:`~motioncue._errors.ConfigError`: a live ride has no
future to optimise over (use ``algorithm = "mpc"``).
"""

from __future__ import annotations

import math
from collections.abc import MutableSequence, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._classical import ClassicalWashout
from ._mpc import (
    LinearModel,
    MpcState,
    QpSolver,
    RigLimits,
    SoftGuardQp,
    build_model,
    fallback_accel,
    reference,
    resolve_reach,
    rig_limits,
    terminal_weight,
    tilt_fz_bound,
)
from ._mpc_params import MpcParams
from ._params import GRAVITY_M_S2, CueingParams

if TYPE_CHECKING:
    from ._algorithm import Rig

__all__ = ["OptimalCueing", "OptimalResult"]


@dataclass(frozen=True, eq=False)
class OptimalResult:
    """Outcome of :meth:`OptimalCueing.run`.

    Attributes
    ----------
    poses : (N, 6) array
        Platform poses (m, rad).
    bad_samples : int
    bad_mask : (N,) bool array
    f_used, w_used : (N, 3) arrays
        The input after bad samples were held.
    fallbacks : int
        Windows whose solve failed (the classical fallback tracker ran there).
    windows : int
        Windows solved.
    solve_ms : (windows,) array
        Wall time of each window's solve (ms).
    fs_hz : float
    """

    poses: NDArray[np.float64]
    bad_samples: int
    bad_mask: NDArray[np.bool_]
    f_used: NDArray[np.float64]
    w_used: NDArray[np.float64]
    fallbacks: int
    windows: int
    solve_ms: NDArray[np.float64]
    fs_hz: float


@dataclass(frozen=True, eq=False)
class OptimalCueing:
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

    params: CueingParams
    fs_hz: float
    rig: Rig | None = None
    mpc: MpcParams = field(init=False)
    classical: ClassicalWashout = field(init=False)
    model: LinearModel = field(init=False)
    limits: RigLimits = field(init=False)
    n_window: int = field(init=False)
    n_stride: int = field(init=False)
    _gam: NDArray[np.float64] = field(init=False, repr=False)
    _hess: NDArray[np.float64] = field(init=False, repr=False)
    _tw: NDArray[np.float64] = field(init=False, repr=False)
    _a_mat: NDArray[np.float64] = field(init=False, repr=False)
    _qp: QpSolver = field(init=False, repr=False)
    _a_guard: NDArray[np.float64] = field(init=False, repr=False)
    _qp_guard: SoftGuardQp | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        classical = ClassicalWashout(self.params, self.fs_hz)
        fs = classical.fs_hz
        object.__setattr__(self, "fs_hz", fs)
        mp = self.params.mpc if self.params.mpc is not None else MpcParams()
        bs = mp.block_samples
        n_stride = max(bs, round(mp.stride_s * fs / bs) * bs)
        n_window = max(n_stride + bs, round(mp.window_s * fs / bs) * bs)
        limits = rig_limits(self.params, mp, fs, self.rig)
        mp = resolve_reach(mp, limits)
        model = build_model(self.params.dofs, mp, fs)
        object.__setattr__(self, "mpc", mp)
        object.__setattr__(self, "classical", classical)
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "limits", limits)
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
        for k in range(1, self.n_window + 1):
            j = (k - 1) // self.mpc.block_samples
            gam[k] = m.a @ gam[k - 1]
            gam[k][:, j * nu : (j + 1) * nu] += m.bu
            hess += gam[k].T @ q @ gam[k]
        tw = terminal_weight(m)
        hess += gam[-1].T @ tw @ gam[-1]
        for j in range(nb):
            sl = slice(j * nu, (j + 1) * nu)
            hess[sl, sl] += self.mpc.block_samples * m.r
        hess = 2.0 * 0.5 * (hess + hess.T)
        # constraints at block ends, legs linearised about neutral
        lim = self.limits
        jac = np.asarray(lim.platform.jacobian(np.zeros(6)), dtype=float)
        ends = np.arange(1, nb + 1) * self.mpc.block_samples
        ge = gam[ends]  # (nb, nx, nU)
        a_pos = np.einsum("lj,bju->blu", jac, ge[:, 0:6])
        a_vel = np.einsum("lj,bju->blu", jac, ge[:, 6:12])
        nl = jac.shape[0]
        a_acc = np.zeros((nb, nl, n_u))
        ja = jac[:, list(m.active)]
        for b in range(nb):
            a_acc[b, :, b * nu : (b + 1) * nu] = ja
        rows = [a_pos, a_vel, a_acc]
        tilt = [i for i in (3, 4) if self.params.dofs[i]]
        if tilt:
            rows.append(ge[:, [6 + i for i in tilt]])
        if self._combined_tilt_bound() is not None:
            rows.append(
                np.stack([ge[:, 3] + ge[:, 4], ge[:, 3] - ge[:, 4], ge[:, 3], ge[:, 4]], axis=1)
            )
        a_mat = np.concatenate([r.reshape(-1, n_u) for r in rows], axis=0)
        object.__setattr__(self, "_gam", gam)
        object.__setattr__(self, "_hess", hess)
        object.__setattr__(self, "_tw", tw)
        object.__setattr__(self, "_a_mat", a_mat)
        object.__setattr__(self, "_qp", QpSolver(self.mpc.solver, hess, a_mat.shape[0]))
        # sign guard: the perceived simulator motion ce_i (x - x_vehicle) at block ends
        guard = self._guard_channels()
        ce_thr = m.ce[guard] / m.thresholds[guard][:, None]  # rows in thresholds
        a_guard = np.einsum("gx,bxu->bgu", ce_thr, ge).reshape(-1, n_u)
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
            )
            if guard
            else None,
        )

    def _guard_channels(self) -> list[int]:
        return [i for i in range(6) if self.mpc.sign_guard[i] > 0.0]

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

    def _guard_bounds(
        self,
        xf_ends: NDArray[np.float64],
        xv_ends: NDArray[np.float64],
        sign_ends: NDArray[np.float64],
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Bounds of the sign-guard rows: at block ends (``xf_ends`` free state, ``xv_ends``
        the vehicle-only state, ``sign_ends`` the sign of the vehicle's perceived motion, 0
        where unconstrained), per guarded channel, in thresholds."""
        m = self.model
        guard = self._guard_channels()
        g = np.asarray(self.mpc.sign_guard)[guard]
        free = (xf_ends - xv_ends) @ (m.ce[guard] / m.thresholds[guard][:, None]).T
        sg = sign_ends[:, guard]
        lo = np.where(sg > 0, -g - free, -np.inf)
        hi = np.where(sg < 0, g - free, np.inf)
        return lo.reshape(-1), hi.reshape(-1)

    def _window_qp(
        self,
        x0: NDArray[np.float64],
        d: NDArray[np.float64],
        about: NDArray[np.float64] | None = None,
        against: NDArray[np.bool_] | None = None,
    ) -> tuple[NDArray[np.float64], ...]:
        """Gradient, constraint matrix and bounds of one window from state ``x0`` with vehicle
        motion ``d`` ``(n_window + 1, 6)``; the legs linearised about neutral or, with
        ``about`` ``(blocks, 6)``, about those poses at the block ends; ``against``
        ``(blocks,)``: the block ends whose combined tilt takes the tighter bound of
        ``tilt_fz_use_against``."""
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
        tilt = [i for i in (3, 4) if self.params.dofs[i]]
        if tilt:
            tf = fe[:, [6 + i for i in tilt]]
            lo.append(-lim.tilt_rate - tf)
            hi.append(lim.tilt_rate - tf)
        bound = self._combined_tilt_bound()
        if bound is not None:
            cf = np.stack([fe[:, 3] + fe[:, 4], fe[:, 3] - fe[:, 4], fe[:, 3], fe[:, 4]], axis=1)
            bv = np.broadcast_to(
                np.array([bound, bound, bound / np.sqrt(2.0), bound / np.sqrt(2.0)]), cf.shape
            )
            tight = self._against_bound()
            if tight is not None and against is not None and np.any(against):
                bt = np.array([tight, tight, tight / np.sqrt(2.0), tight / np.sqrt(2.0)])
                bv = np.where(against[:, None], np.minimum(bv, bt), bv)
            lo.append(-bv - cf)
            hi.append(bv - cf)
        lba = np.concatenate([np.asarray(v).reshape(-1) for v in lo])
        uba = np.concatenate([np.asarray(v).reshape(-1) for v in hi])
        n_u = nb * m.nu
        lbx = np.full(n_u, -np.inf)
        ubx = np.full(n_u, np.inf)
        if np.isfinite(lim.tilt_accel):
            for j, i in enumerate(m.active):
                if i in (3, 4):
                    lbx[j :: m.nu] = -lim.tilt_accel
                    ubx[j :: m.nu] = lim.tilt_accel
        return g, a_mat, lba, uba, lbx, ubx, xf[ends, 0:6], self._gam[ends, 0:6], xf[ends]

    def _solve_window(
        self,
        qp: tuple[NDArray[np.float64], ...],
        xv_ends: NDArray[np.float64],
        sign_ends: NDArray[np.float64],
        use_guard: bool,
    ) -> tuple[bool, NDArray[np.float64]]:
        """Solve one window's QP ``qp`` (from :meth:`_window_qp`), with the sign-guard rows
        when ``use_guard``."""
        g, a_mat, lba, uba, lbx, ubx = qp[:6]
        if use_guard and self._qp_guard is not None:
            glo, ghi = self._guard_bounds(qp[8], xv_ends, sign_ends)
            ok, u, _, _ = self._qp_guard.solve(
                g, a_mat, lba, uba, lbx, ubx, self._a_guard, glo, ghi
            )
        else:
            ok, u, _, _ = self._qp.solve(g, a_mat, lba, uba, lbx, ubx)
        return ok, u

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
        """The whole recording ``f``, ``w`` (N, 3) at ``fs_hz``, window by window.

        Returns
        -------
        OptimalResult
        """
        import time

        fa = np.asarray(f, dtype=float)
        wa = np.asarray(w, dtype=float)
        if fa.ndim != 2 or fa.shape[1] != 3 or wa.shape != fa.shape:
            raise ConfigError(f"need f and w of shape (N, 3); got {fa.shape} and {wa.shape}")
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
                sign_all[k] = -np.sign(m.ce @ xt + m.de @ d_all[k])
        d_all, _ = reference(d_all, self.mpc, self.fs_hz)
        nw, ns, bs = self.n_window, self.n_stride, self.mpc.block_samples
        poses = np.zeros((n, 6))
        times: list[float] = []
        fallbacks = 0
        start = 0
        nb = nw // bs
        shift = ns // bs
        prev: NDArray[np.float64] | None = None  # the last plan's poses at the block ends
        while start < n:
            idx = np.minimum(np.arange(start, start + nw + 1), n - 1)
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
            if guard:
                ab = start + np.arange(1, nb + 1) * bs - 1  # samples at the block ends
                abc = np.minimum(ab, n - 1)
                sg = sign_all[abc] * (ab < n)[:, None]
                xv_e = xv_all[abc]
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
                qp = self._window_qp(st.x, d, first, use_up)
                p_free, g_end = qp[6], qp[7]
                ok, u = self._solve_window(qp, xv_e, sg, use_guard)
                if ok:
                    break
            if ok:  # again with the legs linearised about this plan (sequential QP)
                about = p_free + g_end @ u
                ok2, u2 = self._solve_window(
                    self._window_qp(st.x, d, about, use_up), xv_e, sg, use_guard
                )
                if ok2:  # else keep the first plan
                    u = u2
                plan = p_free + g_end @ u
                prev = np.zeros_like(plan)  # the next window starts about this plan's rest
                prev[: nb - shift] = plan[shift:]
            else:
                prev = None
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
                st.x = m.a @ st.x + m.bu @ uk + m.bd @ d_all[start + k]
                poses[start + k] = st.x[:6]
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
