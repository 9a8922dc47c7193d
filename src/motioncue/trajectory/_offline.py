"""Offline ride optimisation: the feasible actuator trajectory closest to a desired one.

Problem (per actuator ``i``, on the ride's fixed frame grid; the clock is never bent)::

    minimise    sum_k w[k, i] (q[k, i] - q_des[k, i])**2
    subject to  q_min <= q[k] <= q_max,  |v[k]| <= v_max,  |a[k]| <= a_max  (|j[k]| <= j_max)

with the finite differences of :mod:`motioncue.trajectory._limits`, formed with the two
(three) frames of the initial state before ``q[0]`` and, at the end of the ride, with
``braking_steps`` free extra frames so that the last frame can still stop in stroke.
Actuators are independent, so each is its own quadratic programme.

Solution strategy (so that 10-minute rides work):

1. frames where the desired trajectory breaks a limit (stroke, speed, acceleration, jerk,
   the discrete braking bound, or a non-finite value) are found with vectorised finite
   differences; they are grown by ``pad_s`` on both sides and merged into windows;
2. outside the windows the desired frames are kept as they are (they are feasible there);
   each window is solved as a sparse convex QP (casadi ``conic`` with PIQP, one solver
   built per window length and reused, see :mod:`._ride_qp`; a window it does not solve
   is retried at PIQP's default tolerances, then with Ipopt), joined to the frames before
   it (fixed history) and after it (fixed desired frames: the join differences are
   constraints);
3. a window longer than ``chunk`` frames is solved in overlapping chunks: the first
   ``chunk - overlap`` frames of each chunk are kept; ``overlap`` is at least the number of
   frames needed to stop, which makes the kept end state able to stop in stroke, so the
   next chunk is always feasible;
4. the result is passed through the exact :class:`RealtimeLimiter` from the same initial
   state (a feasible trajectory passes through bit for bit; solver round-off can only be
   corrected towards the limits), then checked with :func:`check_trajectory`;
5. the objective is compared with the real-time limiter's output on the same input; if the
   limiter happened to be closer (possible in principle because windows and chunks are
   local), the limiter's output is returned (status ``"realtime"``). With a jerk limit the
   baseline is the :class:`JerkLimiter`, and the solver's result must meet the jerk limit
   by itself (the exact repair pass is second order); if it does not, the baseline is
   returned. If no candidate meets every limit, :class:`~motioncue.LimitError` is raised.

The input is returned unchanged (status ``"unchanged"``) when it is already feasible.
Non-finite desired frames get weight 0 (the optimiser bridges them).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from .._errors import ConfigError, LimitError
from ._jerk import JerkLimiter
from ._limits import ActuatorLimits, LimitCheck, check_trajectory
from ._realtime import RealtimeLimiter
from ._ride_qp import ConicChunkSolver, Window

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["OptimisedRide", "limit_ride"]

_TIGHTEN = 1e-7  # relative tightening of the limits inside the solver (round-off room)
_BLOCK = 64  # window lengths are rounded up to a multiple of this (few distinct solvers)


@dataclass(frozen=True, eq=False)
class OptimisedRide:
    """Result of :func:`limit_ride`.

    Attributes
    ----------
    q : ndarray, (N, n)
        Feasible trajectory on the input's grid (SI).
    status : str
        ``"unchanged"`` (input feasible, returned as is), ``"optimised"`` (solver solution),
        ``"realtime"`` (the real-time limiter's output was closer and is returned).
    max_deviation : float
        Largest ``|q - q_desired|`` over finite desired frames (SI).
    where_index : tuple of int
        ``(frame, actuator)`` of ``max_deviation``.
    rms_deviation : ndarray, (n,)
        Root mean square deviation per actuator.
    objective, objective_realtime : float
        ``sum w (q - q_desired)**2`` of this result and of the real-time limiter's output.
    check : LimitCheck
        Finite-difference check of ``q`` (with the initial state's frames as history).
    n_windows : int
        Number of windows solved (over all actuators).
    n_repaired : int
        Frames the final exact limiter pass had to change (0 when the solver met the
        tightened limits; any change is counted and reported, never hidden).
    n_solver_failures : int
        Chunks where no solver reported success (neither the QP solver nor the Ipopt
        retry); their result still went through the exact repair and the check; counted so
        that it is never silent.
    solve_time_s : float
        Wall time of the whole call.
    """

    q: np.ndarray
    status: str
    max_deviation: float
    where_index: tuple[int, int]
    rms_deviation: np.ndarray
    objective: float
    objective_realtime: float
    check: LimitCheck
    n_windows: int
    n_repaired: int
    n_solver_failures: int
    solve_time_s: float


class _ChunkSolver:
    """A casadi/Ipopt QP for one actuator window of fixed length L (scaled units)."""

    def __init__(self, length: int, jerk: bool) -> None:
        import casadi as ca

        L = length
        h = 3 if jerk else 2
        x = ca.SX.sym("x", L)
        xd = ca.SX.sym("xd", L)
        w = ca.SX.sym("w", L)
        hist = ca.SX.sym("hist", h)  # frames before x[0], oldest first
        tail = ca.SX.sym("tail", h)  # fixed frames after x[L-1]
        tail_on = ca.SX.sym("tail_on")
        full = ca.vertcat(hist, x, tail)
        n_in = h + L  # frames up to the window's end
        d1 = full[h:n_in] - full[h - 1 : n_in - 1]
        d2 = full[h:n_in] - 2 * full[h - 1 : n_in - 1] + full[h - 2 : n_in - 2]
        # join differences that reach into the fixed tail (multiplied by tail_on)
        t1 = tail_on * (full[n_in] - full[n_in - 1])
        t2 = tail_on * ca.vertcat(
            full[n_in] - 2 * full[n_in - 1] + full[n_in - 2],
            full[n_in + 1] - 2 * full[n_in] + full[n_in - 1],
        )
        g = [d1, t1, d2, t2]
        self.n_rows = [L, 1, L, 2]
        if jerk:
            d3 = (
                full[h:n_in]
                - 3 * full[h - 1 : n_in - 1]
                + 3 * full[h - 2 : n_in - 2]
                - full[h - 3 : n_in - 3]
            )
            t3 = tail_on * ca.vertcat(
                full[n_in] - 3 * full[n_in - 1] + 3 * full[n_in - 2] - full[n_in - 3],
                full[n_in + 1] - 3 * full[n_in] + 3 * full[n_in - 1] - full[n_in - 2],
                full[n_in + 2] - 3 * full[n_in + 1] + 3 * full[n_in] - full[n_in - 1],
            )
            g += [d3, t3]
            self.n_rows += [L, 3]
        f = 0.5 * ca.sum1(w * (x - xd) ** 2)
        p = ca.vertcat(xd, w, hist, tail, tail_on)
        opts: dict[str, Any] = {
            "ipopt": {
                "print_level": 0,
                "sb": "yes",
                "tol": 1e-10,
                "mu_strategy": "adaptive",
                "bound_relax_factor": 0.0,
                "hessian_constant": "yes",
                "max_iter": 3000,
            },
            "print_time": False,
        }
        self.jerk = jerk
        self.h = h
        self.length = L
        self.solver = ca.nlpsol(
            "ride_chunk", "ipopt", {"x": x, "p": p, "f": f, "g": ca.vertcat(*g)}, opts
        )

    def solve(self, win: Window) -> tuple[np.ndarray, bool]:
        """Solve one window (as :meth:`ConicChunkSolver.solve`)."""
        xd, w, hist, tail, bounds, x_init = win
        lo_x, hi_x, vb, ab, jb = bounds
        L, h = self.length, self.h
        tail_vals = np.zeros(h) if tail is None else tail
        p = np.concatenate([xd, w, hist, tail_vals, [0.0 if tail is None else 1.0]])
        lim = [vb, vb, ab, ab] + ([jb, jb] if self.jerk else [])
        ub = np.concatenate([np.full(n, b) for n, b in zip(self.n_rows, lim, strict=True)])
        r = self.solver(x0=np.clip(x_init, lo_x, hi_x), p=p, lbg=-ub, ubg=ub, lbx=lo_x, ubx=hi_x)
        ok = bool(self.solver.stats().get("success", False))
        return np.asarray(r["x"], dtype=float).reshape(L), ok


def _bad_frames(q: np.ndarray, dt: float, lim: ActuatorLimits, hist: np.ndarray) -> np.ndarray:
    """(N, n) mask of frames where the desired trajectory breaks a limit (vectorised)."""
    full = np.concatenate([hist, q])
    h = hist.shape[0]
    with np.errstate(invalid="ignore", over="ignore"):
        v = (full[h:] - full[h - 1 : -1]) / dt
        a = (full[h:] - 2 * full[h - 1 : -1] + full[h - 2 : -2]) / dt**2
        bad = ~np.isfinite(q)
        bad |= (q < lim.q_min) | (q > lim.q_max)
        bad |= np.abs(v) > lim.v_max
        bad |= np.abs(a) > lim.a_max
        if lim.j_max is not None and h >= 3:
            j = (full[h:] - 3 * full[h - 1 : -1] + 3 * full[h - 2 : -2] - full[h - 3 : -3]) / dt**3
            bad |= np.abs(j) > lim.j_max
        adt = lim.a_max * dt
        n = np.floor(np.abs(v) / adt)
        dist = dt * (n * np.abs(v) - adt * n * (n + 1) / 2)
        bad |= (v > 0) & (q + dist > lim.q_max)
        bad |= (v < 0) & (q - dist < lim.q_min)
    out: np.ndarray = bad
    return out


def _windows(bad: np.ndarray, pad: int, n_frames: int) -> list[tuple[int, int]]:
    """Merged [start, end) windows around bad frames, grown by pad, rounded to _BLOCK."""
    idx = np.flatnonzero(bad)
    out: list[tuple[int, int]] = []
    gap = _BLOCK + 4  # closer windows are merged: rounding and joins never reach the next
    for k in idx:
        s, e = max(0, int(k) - pad), min(n_frames, int(k) + pad + 1)
        if out and s <= out[-1][1] + gap:
            out[-1] = (out[-1][0], max(out[-1][1], e))
        else:
            out.append((s, e))
    rounded: list[tuple[int, int]] = []
    for s, e in out:
        length = _BLOCK * math.ceil((e - s) / _BLOCK)
        e2 = min(n_frames, s + length)
        s2 = max(0, e2 - length)
        if rounded and s2 <= rounded[-1][1] + gap:
            rounded[-1] = (rounded[-1][0], max(rounded[-1][1], e2))
        else:
            rounded.append((s2, e2))
    return rounded


def limit_ride(
    q_desired: ArrayLike,
    dt_s: float,
    limits: ActuatorLimits,
    *,
    weights: ArrayLike | None = None,
    q0: ArrayLike | None = None,
    v0: ArrayLike | None = None,
    pad_s: float = 1.0,
    chunk: int = 1024,
    backend: str = "qp",
) -> OptimisedRide:
    """Closest feasible trajectory to ``q_desired`` on the same time grid (see module doc).

    Parameters
    ----------
    q_desired : array_like, (N, n)
        Desired actuator positions, one row per frame (SI). NaN/inf rows get weight 0.
    dt_s : float
        Frame period (s).
    limits : ActuatorLimits
        Limits to meet (jerk included when set).
    weights : array_like, (N,) or (N, n), optional
        Non-negative weights ``w`` of the squared deviations (default 1).
    q0, v0 : array_like, (n,), optional
        State before the first frame (last frame sent and its speed); default: at rest at the
        first desired frame clipped into the stroke.
    pad_s : float
        Time added on both sides of each infeasible stretch before solving (s).
    chunk : int
        Longest window solved at once (frames); longer windows use overlapping chunks.
    backend : {"qp", "ipopt"}
        Window solver: ``"qp"`` (default) the sparse QP solver
        (:class:`~motioncue.trajectory._ride_qp.ConicChunkSolver`), retried at PIQP's
        default tolerances and then with Ipopt for any window it does not solve;
        ``"ipopt"`` Ipopt only (the reference the tests compare the QP path with).

    Returns
    -------
    OptimisedRide
    """
    if backend not in ("qp", "ipopt"):
        raise ConfigError(f"backend = {backend!r} is invalid; allowed: 'qp', 'ipopt'")
    t_start = time.perf_counter()
    qd = np.array(q_desired, dtype=float)
    if qd.ndim != 2 or qd.shape[1] != limits.n_actuators or qd.shape[0] < 1:
        raise ConfigError(
            f"q_desired has shape {qd.shape}; expected (N, {limits.n_actuators}) with N >= 1"
        )
    if not (0.0 < dt_s <= 1.0):
        raise ConfigError(f"dt_s = {dt_s!r} is invalid; allowed: a period in (0, 1] s")
    N, n = qd.shape
    w = np.ones((N, n)) if weights is None else np.array(weights, dtype=float)
    if w.ndim == 1:
        w = np.repeat(w[:, None], n, axis=1)
    if w.shape != (N, n) or not np.all(np.isfinite(w)) or np.any(w < 0):
        raise ConfigError("weights must be finite, >= 0, of shape (N,) or (N, n)")
    finite = np.isfinite(qd)
    w = np.where(finite, w, 0.0)

    rt = RealtimeLimiter(limits.without_jerk(), dt_s)
    # the real-time baseline: with a jerk limit, the jerk-limited limiter (so it competes
    # on equal terms); the exact repair pass uses the second-order limiter in both cases
    jl = None if limits.j_max is None else JerkLimiter(limits, dt_s)
    if q0 is None:
        first = np.array(
            [qd[np.argmax(finite[:, i]), i] if finite[:, i].any() else np.nan for i in range(n)]
        )
        mid = 0.5 * (limits.q_min + limits.q_max)
        q0 = np.clip(np.where(np.isfinite(first), first, mid), limits.q_min, limits.q_max)
    q0 = np.asarray(q0, dtype=float).reshape(n)
    v0 = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).reshape(n)
    hist = np.stack([q0 - 2 * v0 * dt_s, q0 - v0 * dt_s, q0])  # oldest first, 3 frames
    # the baseline's initial state raises if the state is not admissible
    if jl is None:
        rt_state = rt.initial_state(q0, v0)
        q_rt, n_clamped = rt.run(rt_state, qd), rt_state.n_clamped
    else:
        jl_state = jl.initial_state(q0, v0)
        q_rt, n_clamped = jl.run(jl_state, qd), jl_state.n_clamped
    obj_rt = float(np.sum(w * np.where(finite, q_rt - qd, 0.0) ** 2))

    def result(
        q: np.ndarray, status: str, n_windows: int, n_rep: int, n_failed: int = 0
    ) -> OptimisedRide:
        dev = np.where(finite, np.abs(q - qd), 0.0)
        k, i = np.unravel_index(int(np.argmax(dev)), dev.shape)
        cnt = np.maximum(finite.sum(axis=0), 1)
        rms = np.sqrt(np.sum(dev**2, axis=0) / cnt)
        obj = float(np.sum(w * dev**2))
        return OptimisedRide(
            q=q,
            status=status,
            max_deviation=float(dev[k, i]),
            where_index=(int(k), int(i)),
            rms_deviation=rms,
            objective=obj,
            objective_realtime=obj_rt,
            check=check_trajectory(q, dt_s, limits, history=hist),
            n_windows=n_windows,
            n_repaired=n_rep,
            n_solver_failures=n_failed,
            solve_time_s=time.perf_counter() - t_start,
        )

    bad = _bad_frames(qd, dt_s, limits, hist)
    if not bad.any() and n_clamped == 0:
        return result(qd.copy(), "unchanged", 0, 0)

    # ------------------------------------------------------------ windows per actuator
    j_max = limits.j_max
    jerk = j_max is not None
    n_stop = limits.braking_steps(dt_s)
    if j_max is not None:
        n_stop += int(np.max(np.ceil(limits.a_max / (j_max * dt_s)))) + 1
    pad = max(round(pad_s / dt_s), 2 * n_stop)
    overlap = max(2 * n_stop, _BLOCK)
    chunk = max(int(chunk), overlap + _BLOCK)
    chunk = _BLOCK * math.ceil(chunk / _BLOCK)
    ipopt_solvers: dict[int, _ChunkSolver] = {}
    qp_solvers: dict[tuple[int, bool, bool], ConicChunkSolver] = {}

    def solve_chunk(length: int, win: Window) -> tuple[np.ndarray, bool]:
        # QP with tight tolerances, then with PIQP's default ones (windows with very large
        # scaled numbers, where the tight ones are below round-off), then Ipopt
        for loose in (False, True) if backend == "qp" else ():
            key = (length, win.tail is not None, loose)
            if key not in qp_solvers:
                qp_solvers[key] = ConicChunkSolver(length, jerk, win.tail is not None, loose)
            x, ok = qp_solvers[key].solve(win)
            if ok:
                return x, ok
        # Ipopt: the reference backend, and the retry for a window the QP solver missed
        if length not in ipopt_solvers:
            ipopt_solvers[length] = _ChunkSolver(length, jerk)
        x, ok = ipopt_solvers[length].solve(win)
        if not np.all(np.isfinite(x)):
            # never seen; keeps NaN out of the repair pass (which then limits the start point)
            x, ok = np.clip(win.x_init, win.bounds[0], win.bounds[1]), False
        return x, ok

    # desired values far outside the stroke are pulled to within one stroke length of it
    span = limits.q_max - limits.q_min
    target = np.clip(np.where(finite, qd, 0.5 * (limits.q_min + limits.q_max)),
                     limits.q_min - span, limits.q_max + span)  # fmt: skip
    q_opt = np.where(finite, qd, q_rt).copy()
    n_windows = 0
    n_failed = 0
    for i in range(n):
        s_i = float(limits.a_max[i]) * dt_s**2  # scale: one unit = full accel for one frame
        off = float(0.5 * (limits.q_min[i] + limits.q_max[i]))
        tight = 1.0 - _TIGHTEN
        lo_x = (float(limits.q_min[i]) - off) / s_i + _TIGHTEN * float(span[i]) / s_i
        hi_x = (float(limits.q_max[i]) - off) / s_i - _TIGHTEN * float(span[i]) / s_i
        vb = float(limits.v_max[i]) * dt_s / s_i * tight
        ab = tight
        jb = (float(j_max[i]) * dt_s**3 / s_i * tight) if j_max is not None else 0.0
        bounds = (lo_x, hi_x, vb, ab, jb)
        col_t = (target[:, i] - off) / s_i
        col_rt = (q_rt[:, i] - off) / s_i
        h = 3 if jerk else 2
        x_all = np.concatenate([(hist[:, i] - off) / s_i, (q_opt[:, i] - off) / s_i])
        H0 = 3  # index of frame 0 in x_all (hist has 3 frames)
        for s, e0 in _windows(bad[:, i], pad, N):
            n_windows += 1
            # a window ending near the ride's end runs to it (room for the stopping frames)
            e = N if e0 + n_stop + 2 * _BLOCK + h >= N else e0
            start = s
            while True:
                remaining = e - start
                at_end = e == N
                need = remaining + (n_stop if at_end else 0)
                if need <= chunk:
                    length = _BLOCK * math.ceil(need / _BLOCK)
                    last = True
                else:
                    length = chunk
                    last = False
                xd = np.zeros(length)
                ww = np.zeros(length)
                xi = np.zeros(length)
                m = min(length, N - start)
                xd[:m] = col_t[start : start + m]
                ww[:m] = w[start : start + m, i]
                xi[:m] = col_rt[start : start + m]
                if m < length:
                    xd[m:] = xd[m - 1] if m else 0.0
                    xi[m:] = xi[m - 1] if m else 0.0
                hist_x = x_all[H0 + start - h : H0 + start]
                tail = None
                if last and not at_end:
                    # join to the fixed (desired, feasible) frames after the solved range
                    tail = x_all[H0 + start + length : H0 + start + length + h]
                x, ok = solve_chunk(length, Window(xd, ww, hist_x, tail, bounds, xi))
                n_failed += 0 if ok else 1
                keep = min(m, length) if last else length - overlap
                x_all[H0 + start : H0 + start + keep] = x[:keep]
                if last:
                    break
                start += keep
        q_opt[:, i] = x_all[H0:] * s_i + off

    # ------------------------------------------------------------ exact repair and compare
    state2 = rt.initial_state(q0, v0)
    q_fin = rt.run(state2, q_opt)
    n_rep = int(state2.n_clamped)
    out = result(q_fin, "optimised", n_windows, n_rep, n_failed)
    fallback = result(q_rt, "realtime", n_windows, n_rep, n_failed)
    # the real-time limiter's output competes where it meets every limit (always, up to
    # round-off; checked rather than assumed)
    if fallback.check.ok and (not out.check.ok or out.objective > obj_rt):
        return fallback
    if not out.check.ok:
        raise LimitError(f"no trajectory meeting every limit was found: {out.check}")
    return out
