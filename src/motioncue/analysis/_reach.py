"""What a rig can reach, from its platform and limits: the inputs of the physical bound and
of the compressive tilt.

:func:`rig_reach` (the reach along fx and fy, :class:`motioncue.cueing.RigReach`, for
:func:`motioncue.cueing.cue_bound`) and :func:`motioncue.analysis.tilt_reach` (the largest
pure tilt, for a preset's ``[tilt] reach_deg``) need the platform's kinematics and the
actuator limits; the cueing stage takes their results as numbers.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError
from ..cueing._bound import REACH_MARGIN, RigReach
from ..kinematics import dof_ranges
from ..trajectory import reachable

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits

__all__ = ["rig_reach"]


def _sample_poses(
    platform: Platform, limits: ActuatorLimits, n: int, seed: int
) -> NDArray[np.float64]:
    """Reachable poses: neutral, the single-DOF extremes, and random poses in their box."""
    rng_box = dof_ranges(platform)
    lo, hi = np.asarray(rng_box.lower), np.asarray(rng_box.upper)
    extremes = [np.zeros(6)]
    for k in range(6):
        for v in (lo[k], hi[k]):
            e = np.zeros(6)
            e[k] = 0.999 * v
            extremes.append(e)
    rng = np.random.default_rng(seed)
    span = np.maximum(np.abs(lo), np.abs(hi))
    cand = np.concatenate([np.asarray(extremes), rng.uniform(-1, 1, (n, 6)) * span], axis=0)
    ok = reachable(platform, cand, limits=limits)
    return np.asarray(cand[ok], dtype=float)


def _rate_reach(jac: NDArray[np.float64], limit: NDArray[np.float64], k: int) -> float:
    """max e_k' pdot subject to |jac pdot| <= limit (elementwise): an LP (HiGHS)."""
    from scipy.optimize import linprog

    n = jac.shape[1]
    c = np.zeros(n)
    c[k] = -1.0
    res = linprog(
        c,
        A_ub=np.concatenate([jac, -jac]),
        b_ub=np.concatenate([limit, limit]),
        bounds=[(None, None)] * n,
        method="highs",
    )
    if res.status == 3:  # unbounded: the DOF moves no actuator
        return math.inf
    return float(-res.fun) if res.status == 0 else 0.0


def rig_reach(
    platform: Platform,
    limits: ActuatorLimits,
    *,
    samples: int = 4000,
    rate_poses: int = 48,
    seed: int = 0,
    margin: float = REACH_MARGIN,
) -> RigReach:
    """The reach of a rig along fx (surge, pitch) and fy (sway, roll), from its limits.

    Stroke and tilt: the largest ``|x|, |y|, |pitch|, |roll|`` over the reachable poses
    among the single-DOF extremes (:func:`motioncue.kinematics.dof_ranges`) and ``samples``
    random poses in their box (:func:`motioncue.trajectory.reachable` with ``limits``).
    Speed, acceleration, tilt rate: the largest ``e' pdot`` with ``|J pdot| <= v_max``
    (``a_max`` for the acceleration, neglecting the velocity-product terms) at neutral and
    ``rate_poses`` of those poses (an LP each; ``J`` the platform's Jacobian on the DOFs it
    moves). Every figure is multiplied by ``margin`` (sampling finds maxima from below).

    Parameters
    ----------
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits
    samples, rate_poses, seed : int
    margin : float
        >= 1.

    Returns
    -------
    RigReach
    """
    if not (math.isfinite(margin) and margin >= 1.0):
        raise ConfigError(f"margin {margin!r} is invalid; allowed: a finite number >= 1")
    poses = _sample_poses(platform, limits, int(samples), seed)
    mask = np.asarray(platform.dof_mask, dtype=bool)
    peak = np.abs(poses).max(axis=0) * mask
    pick = poses[: 1 + 12] if len(poses) > 13 else poses
    if len(poses) > 13 and rate_poses > 0:
        rng = np.random.default_rng(seed + 1)
        extra = poses[13 + rng.choice(len(poses) - 13, min(rate_poses, len(poses) - 13), False)]
        pick = np.concatenate([pick, extra])
    jac_all = np.asarray(platform.jacobian(pick), dtype=float)[..., mask]
    dof_index = np.cumsum(mask) - 1  # column of each supported DOF in the masked Jacobian
    v_lim = np.asarray(limits.v_max, dtype=float)
    a_lim = np.asarray(limits.a_max, dtype=float)
    n_act = v_lim.shape[0]

    def rate(k: int, lim: NDArray[np.float64]) -> float:
        if not mask[k]:
            return 0.0
        best = 0.0
        for jac in jac_all:
            best = max(best, _rate_reach(jac[:n_act], lim, int(dof_index[k])))
        return best

    m = float(margin)
    return RigReach(
        stroke_m=(m * float(peak[0]), m * float(peak[1])),
        speed_m_s=(m * rate(0, v_lim), m * rate(1, v_lim)),
        accel_m_s2=(m * rate(0, a_lim), m * rate(1, a_lim)),
        tilt_rad=(min(m * float(peak[4]), 1.5), min(m * float(peak[3]), 1.5)),
        tilt_rate_rad_s=(m * rate(4, v_lim), m * rate(3, v_lim)),
    )
