"""Workspace-aware pose limiting: replace an unreachable pose by a reachable one.

Rule (documented, deterministic):

1. components of the pose the machine cannot produce (``~platform.dof_mask``) are set to
   zero (reported in ``dropped``);
2. a pose is *feasible* when the platform's inverse kinematics reaches it with every
   actuator inside the stroke (``platform.check(...).ok``) and, when ``limits`` are given,
   inside ``[limits.q_min, limits.q_max]``;
3. a feasible pose is returned unchanged (status ``"ok"``, scale 1);
4. otherwise the pose is scaled towards neutral, ``s * pose`` with ``s in [0, 1)``, which
   keeps the direction of the cue (every component keeps its sign and their ratios). ``s``
   is the largest value on the ray before the first infeasible one, found by three rounds
   of 16-point batched evaluation (resolution ``16**-3``, about 2.4e-4); every point between
   neutral and the returned pose on this grid is feasible. Status ``"clamped"``;
5. NaN/inf poses become neutral (status ``"invalid"``); if neutral itself is infeasible
   (limits narrower than the neutral pose) the result is neutral with status
   ``"unreachable"``.

Single poses on platforms whose actuators are all linear (no reachability question, only
the stroke) take a faster path for the real-time loop: the same ray, with ``s`` found by a
bracketing root search (Illinois variant of regula falsi) on the largest stroke overshoot,
to within 1e-6 in ``s``, keeping the bracket ``[feasible, infeasible]``; the returned pose is always
an evaluated feasible one. Where the feasible part of the ray is an interval (the usual,
star-shaped workspace) both paths find the same boundary (to the grid's resolution).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .._errors import ConfigError
from ._limits import ActuatorLimits

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..kinematics import Platform

__all__ = ["PoseLimitResult", "limit_pose"]

_GRID = 16
_ROUNDS = 3
_SINGLE_TOL = 1e-6  # bracket width of the single-pose root search (in the scale s)

STATUS = ("ok", "clamped", "invalid", "unreachable")


@dataclass(frozen=True, eq=False)
class PoseLimitResult:
    """Result of :func:`limit_pose` for poses (6,) or (N, 6).

    Attributes
    ----------
    pose : ndarray, (6,) or (N, 6)
        Feasible poses (m, rad).
    status : str or ndarray of str, () or (N,)
        ``"ok"``, ``"clamped"``, ``"invalid"`` or ``"unreachable"``.
    scale : float or ndarray, () or (N,)
        Factor applied to the requested pose (after dropping unsupported components);
        1 = untouched, 0 = neutral.
    amount : ndarray, (6,) or (N, 6)
        Requested minus returned pose, per component (m, rad): what was removed.
    dropped : ndarray of bool, (6,) or (N, 6)
        Components set to zero because the machine cannot produce them.
    q : ndarray, (n,) or (N, n)
        Actuator positions of the returned poses.
    """

    pose: np.ndarray
    status: str | np.ndarray
    scale: float | np.ndarray
    amount: np.ndarray
    dropped: np.ndarray
    q: np.ndarray

    @property
    def clamped(self) -> np.bool_ | np.ndarray:
        out: np.bool_ | np.ndarray = np.asarray(self.status) != "ok"
        return out


def _feasible(platform: Platform, poses: np.ndarray, limits: ActuatorLimits | None) -> np.ndarray:
    chk = platform.check(poses)
    ok = np.asarray(chk.ok, dtype=bool)
    if limits is not None:
        ok = ok & limits.contains(chk.q)
    return ok


def reachable(
    platform: Platform, poses: ArrayLike, *, limits: ActuatorLimits | None = None
) -> np.ndarray:
    """Which poses :func:`limit_pose` leaves untouched (status ``"ok"``), without limiting.

    Parameters
    ----------
    platform
        A :class:`motioncue.kinematics.Platform`.
    poses : array_like, (N, 6)
        Requested poses (m, rad) from neutral; components the platform does not move are
        ignored, as :func:`limit_pose` drops them.
    limits : ActuatorLimits, optional

    Returns
    -------
    ndarray of bool, (N,)
        False for non-finite poses and poses outside the workspace or the limits' stroke.
    """
    arr = np.asarray(poses, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise ConfigError(f"poses have shape {arr.shape}; expected (N, 6)")
    finite = np.all(np.isfinite(arr), axis=1)
    mask = np.asarray(platform.dof_mask, dtype=bool)
    req = np.where(finite[:, None] & mask[None, :], arr, 0.0)
    ok: np.ndarray = finite & _feasible(platform, req, limits)
    return ok


def limit_pose(
    platform: Platform, pose: ArrayLike, *, limits: ActuatorLimits | None = None
) -> PoseLimitResult:
    """Replace unreachable poses by the farthest reachable pose towards neutral (see module).

    Parameters
    ----------
    platform
        A :class:`motioncue.kinematics.Platform`.
    pose : array_like, (6,) or (N, 6)
        Requested poses ``[x, y, z, roll, pitch, yaw]`` (m, rad) from neutral.
    limits : ActuatorLimits, optional
        Narrower stroke to respect (for example with an extra safety margin).
    """
    arr = np.array(pose, dtype=float)
    single = arr.ndim == 1
    if single and arr.shape == (6,) and all(k == "linear" for k in platform.actuator_kinds):
        return _limit_one_linear(platform, arr, limits)
    poses = arr.reshape(-1, 6) if arr.size % 6 == 0 and arr.shape[-1:] == (6,) else None
    if poses is None or arr.ndim > 2:
        raise ConfigError(f"pose has shape {arr.shape}; expected (6,) or (N, 6)")
    N = poses.shape[0]
    mask = np.asarray(platform.dof_mask, dtype=bool)
    invalid = ~np.all(np.isfinite(poses), axis=1)
    req = np.where(invalid[:, None], 0.0, poses)
    dropped = (req != 0.0) & ~mask
    req = np.where(mask, req, 0.0)
    status = np.full(N, "ok", dtype=object)
    status[invalid] = "invalid"
    scale = np.where(invalid, 0.0, 1.0)
    ok = _feasible(platform, req, limits)
    todo = np.flatnonzero(~ok & ~invalid)
    out = req.copy()
    if todo.size:
        if not _feasible(platform, np.zeros((1, 6)), limits)[0]:
            out[todo] = 0.0
            scale[todo] = 0.0
            status[todo] = "unreachable"
        else:
            lo = np.zeros(todo.size)  # known feasible
            hi = np.ones(todo.size)  # known infeasible
            frac = np.arange(1, _GRID + 1) / (_GRID + 1)
            base = req[todo]
            for _ in range(_ROUNDS):
                s = lo[:, None] + (hi - lo)[:, None] * frac[None, :]  # (m, G)
                cand = s[:, :, None] * base[:, None, :]
                feas = _feasible(platform, cand.reshape(-1, 6), limits).reshape(s.shape)
                # first infeasible point on each ray; everything before it is feasible
                first_bad = np.where(feas.all(axis=1), _GRID, np.argmin(feas, axis=1))
                rows = np.arange(todo.size)
                new_lo = np.where(first_bad > 0, s[rows, np.maximum(first_bad - 1, 0)], lo)
                new_hi = np.where(first_bad < _GRID, s[rows, np.minimum(first_bad, _GRID - 1)], hi)
                lo, hi = new_lo, new_hi
            out[todo] = lo[:, None] * base
            scale[todo] = lo
            status[todo] = "clamped"
    q = np.asarray(platform.inverse(out), dtype=float)
    amount = np.where(invalid[:, None], 0.0, poses) - out
    amount = np.where(np.isfinite(amount), amount, 0.0)
    if single:
        return PoseLimitResult(out[0], str(status[0]), float(scale[0]), amount[0], dropped[0], q[0])
    return PoseLimitResult(out, status.astype(str), scale, amount, dropped, q)


def _limit_one_linear(
    platform: Platform, pose: np.ndarray, limits: ActuatorLimits | None
) -> PoseLimitResult:
    """Fast single-pose path for all-linear platforms (see module docstring)."""
    vals = pose.tolist()
    total = sum(vals)  # finite unless NaN or inf is in it (or finite values overflow it)
    if total - total != 0.0 and not all(map(math.isfinite, vals)):
        zero = np.zeros(6)
        q0 = np.asarray(platform.inverse(zero), dtype=float)
        return PoseLimitResult(zero, "invalid", 0.0, zero.copy(), np.zeros(6, bool), q0)
    mask = platform.dof_mask
    dropped = (pose != 0.0) & ~mask
    req = np.where(mask, pose, 0.0)
    if limits is None:
        lo_l, hi_l = platform.q_min.tolist(), platform.q_max.tolist()
    else:
        lo_l = np.maximum(platform.q_min, limits.q_min).tolist()
        hi_l = np.minimum(platform.q_max, limits.q_max).tolist()
    # feasible = inside the stroke by 1e-12 (m), room for the last-bit differences between
    # the platform's single-pose and batch inverse kinematics
    tol = 1e-12
    base = req.tolist()
    # the platform's single-pose inverse kinematics on plain floats: what platform.inverse
    # computes for one pose, without its array in and out (q stays a list until returned)
    inverse_one = platform._inverse_one
    bounds = list(zip(lo_l, hi_l, strict=True))

    def over(sc: float) -> tuple[float, list[float]]:
        q = inverse_one([sc * b for b in base])
        worst = -math.inf
        for qi, (a, b) in zip(q, bounds, strict=True):
            if qi - b > worst:
                worst = qi - b
            if a - qi > worst:
                worst = a - qi
        return worst + tol, q

    g1, q1 = over(1.0)
    if g1 - tol <= 0.0:
        return PoseLimitResult(req, "ok", 1.0, pose - req, dropped, np.array(q1))
    # neutral: q = q_neutral, no inverse kinematics needed
    g0 = tol + max(
        max(qn - b, a - qn) for qn, (a, b) in zip(platform.q_neutral.tolist(), bounds, strict=True)
    )
    if g0 > 0.0:
        zero = np.zeros(6)
        return PoseLimitResult(zero, "unreachable", 0.0, pose.copy(), dropped,
                               np.asarray(platform.q_neutral, dtype=float).copy())  # fmt: skip
    lo, hi, glo, ghi = 0.0, 1.0, g0, g1
    qlo: list[float] | None = None
    side = 0
    for _ in range(60):
        if hi - lo <= _SINGLE_TOL:
            break
        sc = (lo * ghi - hi * glo) / (ghi - glo)
        if not lo < sc < hi:
            sc = 0.5 * (lo + hi)
        g, q = over(sc)
        if g <= 0.0:
            lo, glo, qlo = sc, g, q
            if side == -1:
                ghi *= 0.5
            side = -1
        else:
            hi, ghi = sc, g
            if side == 1:
                glo *= 0.5
            side = 1
    out = lo * req
    q_out = np.asarray(platform.inverse(out), dtype=float) if qlo is None else np.array(qlo)
    return PoseLimitResult(out, "clamped", lo, pose - out, dropped, q_out)
