"""The coupled reach of a rig: how far translation and tilt go *together* on each channel.

:func:`reach_coupling` gives, per horizontal channel, the half-planes
(:class:`motioncue.cueing.ReachPolygon`) that contain every reachable ``(p, tau)`` (the
translation and the tilt's specific force over g: ``(x, -sin pitch)`` for fx,
``(y, cos pitch sin roll)`` for fy) and every ``(pdot, taudot)`` the actuator speed limits
allow at a reachable pose, the other four degrees of freedom free. They cut the corners of
:func:`rig_reach`'s boxes: a hexapod's legs cannot give the largest surge and the largest
pitch at once. The exact kinematics are used (no linearisation of the legs): each offset is
the support of the projected workspace in its direction, found from below (random poses,
then a local search along the reachable poses) and multiplied by the reach's margin, the
standard :func:`rig_reach` holds its boxes to.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError
from ..cueing._bound import REACH_MARGIN, ReachPolygon, RigReach
from ..kinematics import dof_ranges
from ..trajectory import reachable

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits

__all__ = ["reach_coupling"]

_TRANS = (0, 1)  # pose index of the channel's translation (fx: x, fy: y)


def _tau(poses: NDArray[np.float64], channel: int) -> NDArray[np.float64]:
    """The tilt's specific force over g (simulator_motion: ``R^T [0, 0, g]``)."""
    if channel == 0:
        return np.asarray(-np.sin(poses[:, 4]))
    return np.asarray(np.cos(poses[:, 4]) * np.sin(poses[:, 3]))


def _tau_grad(poses: NDArray[np.float64], channel: int) -> NDArray[np.float64]:
    """``d tau / d pose`` (N, 6): ``taudot = grad . posedot`` exactly."""
    g = np.zeros((poses.shape[0], 6))
    roll, pitch = poses[:, 3], poses[:, 4]
    if channel == 0:
        g[:, 4] = -np.cos(pitch)
    else:
        g[:, 3] = np.cos(pitch) * np.cos(roll)
        g[:, 4] = -np.sin(pitch) * np.sin(roll)
    return g


def _directions(m: int) -> NDArray[np.float64]:
    a = 2.0 * math.pi * np.arange(m) / m
    return np.stack([np.cos(a), np.sin(a)], axis=1)


def _pose_support(
    platform: Platform,
    limits: ActuatorLimits,
    normal: NDArray[np.float64],
    channel: int,
    start: NDArray[np.float64],
    span: NDArray[np.float64],
    rng: np.random.Generator,
    rounds: int,
) -> tuple[float, NDArray[np.float64]]:
    """The largest ``normal . (p, tau)`` over reachable poses, from below: the best of
    ``start`` improved by a local random search (perturbations shrinking round by round, each
    kept only if reachable and better)."""

    def score(x: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(normal[0] * x[:, _TRANS[channel]] + normal[1] * _tau(x, channel))

    s = score(start)
    order = np.argsort(s)[::-1][:12]
    best, best_s = start[order], s[order]
    mask = np.asarray(platform.dof_mask, dtype=float)
    for r in range(rounds):
        sigma = 0.15 * (0.02 / 0.15) ** (r / max(rounds - 1, 1))
        cand = best[:, None, :] + rng.normal(0.0, 1.0, (best.shape[0], 24, 6)) * span * sigma
        cand = (cand * mask).reshape(-1, 6)
        ok = reachable(platform, cand, limits=limits)
        cs = np.where(ok, score(cand), -np.inf).reshape(best.shape[0], 24)
        j = np.argmax(cs, axis=1)
        better = cs[np.arange(best.shape[0]), j] > best_s
        best[better] = cand.reshape(best.shape[0], 24, 6)[better, j[better]]
        best_s = np.where(better, cs[np.arange(best.shape[0]), j], best_s)
    i = int(np.argmax(best_s))
    return float(best_s[i]), best[i]


def _rate_support(
    jac: NDArray[np.float64],
    grad_p: NDArray[np.float64],
    grad_t: NDArray[np.float64],
    normal: NDArray[np.float64],
    v_lim: NDArray[np.float64],
) -> float:
    """``max normal . (grad_p . qd, grad_t . qd)`` s.t. ``|jac qd| <= v_lim``: an LP (HiGHS)."""
    from scipy.optimize import linprog

    c = -(normal[0] * grad_p + normal[1] * grad_t)
    if not np.any(c):
        return 0.0
    res = linprog(
        c,
        A_ub=np.concatenate([jac, -jac]),
        b_ub=np.concatenate([v_lim, v_lim]),
        bounds=[(None, None)] * jac.shape[1],
        method="highs",
    )
    if res.status == 3:
        return math.inf
    if res.status != 0:
        raise ConfigError(f"the coupled reach's rate LP failed: {res.message}")
    return float(-res.fun)


def reach_coupling(
    platform: Platform,
    limits: ActuatorLimits,
    reach: RigReach,
    *,
    directions: int = 8,
    samples: int = 60000,
    rounds: int = 30,
    rate_poses: int = 48,
    seed: int = 0,
    margin: float = REACH_MARGIN,
) -> RigReach:
    """``reach`` with its coupled reach (:attr:`RigReach.coupling`) for this rig.

    Parameters
    ----------
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits
        The limits ``reach`` was computed with (:func:`motioncue.analysis.rig_reach`).
    reach : RigReach
        Its boxes (kept: the half-planes are added to them).
    directions : int
        Half-planes per polygon (>= 3), evenly spread in the coordinates normalised by the
        boxes.
    samples : int
        Random candidate poses in the single-DOF ranges' box (about 2 % are reachable on a
        hexapod); the best per direction start the local search.
    rounds : int
        Local-search rounds per direction.
    rate_poses : int
        Reachable poses whose Jacobian gives the rate polygon (with neutral and the poses the
        pose polygon's search ended on).
    seed : int
    margin : float
        Each offset (found from below) is multiplied by it (>= 1).

    Returns
    -------
    RigReach
        ``reach`` with ``coupling`` set and its boxes widened where the search went further
        (poses combining DOFs reach beyond :func:`rig_reach`'s single-DOF box).
    """
    if directions < 4 or directions % 4:
        raise ConfigError(f"directions {directions!r} is invalid; allowed: a multiple of 4, >= 4")
    if not (math.isfinite(margin) and margin >= 1.0):
        raise ConfigError(f"margin {margin!r} is invalid; allowed: a finite number >= 1")
    rng = np.random.default_rng(seed)
    box = dof_ranges(platform)
    lo, hi = np.asarray(box.lower, dtype=float), np.asarray(box.upper, dtype=float)
    span = np.maximum(np.abs(lo), np.abs(hi))
    mask = np.asarray(platform.dof_mask, dtype=bool)
    cand = np.concatenate([np.zeros((1, 6)), rng.uniform(-1.0, 1.0, (int(samples), 6)) * span])
    cand = cand * mask
    poses = cand[reachable(platform, cand, limits=limits)]
    if poses.shape[0] == 0:
        raise ConfigError("no reachable pose found for the coupled reach")
    unit = _directions(int(directions))
    v_lim = np.asarray(limits.v_max, dtype=float)
    n_act = v_lim.shape[0]
    pick = poses[: 1 + rate_poses]
    polys: list[ReachPolygon] = []
    boxes: dict[str, list[float]] = {k: [] for k in ("stroke", "tilt", "speed", "rate", "acc")}
    a_lim = np.asarray(limits.a_max, dtype=float)
    q = directions // 4  # index of the direction (0, 1); 2 q: (-1, 0); 3 q: (0, -1)
    for ch in range(2):
        p_scale = max(reach.stroke_m[ch], 1e-9)
        t_scale = max(math.sin(reach.tilt_rad[ch]), 1e-9)
        normals = unit / np.array([p_scale, t_scale])
        offsets, ends = [], []
        for nrm in normals:
            h, end = _pose_support(platform, limits, nrm, ch, poses, span, rng, rounds)
            offsets.append(margin * max(h, 0.0))
            ends.append(end)
        at = np.concatenate([pick, np.asarray(ends)])
        jac = np.asarray(platform.jacobian(at), dtype=float)[:, :n_act, :][..., mask]
        gp = np.zeros((at.shape[0], 6))
        gp[:, _TRANS[ch]] = 1.0
        gp, gt = gp[:, mask], _tau_grad(at, ch)[:, mask]
        r_scale = (max(reach.speed_m_s[ch], 1e-9), max(reach.tilt_rate_rad_s[ch], 1e-9))
        r_normals = unit / np.array(r_scale)
        r_off = [
            margin * max(_rate_support(jac[j], gp[j], gt[j], nrm, v_lim) for j in range(len(at)))
            for nrm in r_normals
        ]
        if not all(math.isfinite(x) and x > 0.0 for x in [*offsets, *r_off]):
            raise ConfigError(
                f"the coupled reach of channel {ch} is degenerate (offsets {offsets!r}, "
                f"{r_off!r}); allowed: finite and > 0 (the rig moves both ways)"
            )
        polys.append(ReachPolygon(normals, np.array(offsets), r_normals, np.array(r_off)))
        # the boxes widened to what the search found along the axes: rig_reach samples only
        # the single-DOF ranges' box, and a pose combining DOFs reaches beyond it
        boxes["stroke"].append(max(reach.stroke_m[ch], p_scale * max(offsets[0], offsets[2 * q])))
        t_max = t_scale * max(offsets[q], offsets[3 * q])
        boxes["tilt"].append(max(reach.tilt_rad[ch], math.asin(min(t_max, 0.999))))
        boxes["speed"].append(max(reach.speed_m_s[ch], r_scale[0] * max(r_off[0], r_off[2 * q])))
        boxes["rate"].append(
            max(reach.tilt_rate_rad_s[ch], r_scale[1] * max(r_off[q], r_off[3 * q]))
        )
        acc = max(_rate_support(jac[j], gp[j], gt[j], np.array([1.0, 0.0]), a_lim)
                  for j in range(len(at)))  # fmt: skip
        boxes["acc"].append(max(reach.accel_m_s2[ch], margin * acc))
    from dataclasses import replace

    def two(k: str) -> tuple[float, float]:
        return (boxes[k][0], boxes[k][1])

    return replace(
        reach,
        stroke_m=two("stroke"),
        tilt_rad=two("tilt"),
        speed_m_s=two("speed"),
        tilt_rate_rad_s=two("rate"),
        accel_m_s2=two("acc"),
        coupling=(polys[0], polys[1]),
    )
