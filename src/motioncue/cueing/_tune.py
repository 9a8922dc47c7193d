"""Automatic tuning of a cueing preset: the strongest cue within cue-quality targets.

What is tuned
-------------
Sixteen main parameters of a base preset (:data:`TUNED_PARAMETERS`), each within fixed
bounds, searched in log space (all are positive scales, frequencies or limits spanning a
decade or more): the translational force scales (x, y, z), the translational high-pass
natural frequency and third-order break (x and y share them) and the heave high-pass
frequency, the tilt-coordination scales (x, y), the tilt low-pass frequency, tilt rate and
acceleration limits and the tilt limit (the largest tilt: with the tilt scales it decides how
much sustained force is cued), the rotational scale and high-pass frequency (roll and pitch
share them) and the yaw scale and high-pass frequency. Everything else (limits, dampings,
input rejection, workspace, head offset) is kept from the base preset.

A preset with ``algorithm = "mpc"`` or ``"optimal"`` is tuned on its plan instead
(:data:`MPC_TUNED_PARAMETERS`: the scale and soft limit of the tracked copy of fx, fy, the
plan's tilt-rate limit, the canal weight, the x/y pose weight and the tilt acceleration
weight; with the compressive reference, ``ref_shape``, :data:`MPC_STRENGTH_TUNED_PARAMETERS`:
the copy's gain per axis, the share of the tilt reach, the curve's exponent and the roll and
pitch sign guard as well); its classical tables (the fallback washout) and every other
``[mpc]`` setting are kept. :func:`tuned_parameters` gives the table of a preset.

A classical preset with the compressive tilt (``[tilt] shape``) is tuned on
:data:`STRENGTH_TUNED_PARAMETERS` instead: the gains, limit and exponent of the compressive
curves, the share of the platform's tilt reach (:func:`tilt_reach`), the tilt's lead, and
the filters as above.

The objective and the limits
----------------------------
Each candidate runs the cheap chain of ``generate`` on every recording (resampled once, up
front): the cueing run, workspace limiting (:func:`motioncue.trajectory.limit_pose` with the
pulse-rounding-tightened limits of the platform and controller) and the evaluation of the
*delivered* poses through the vestibular models: the mean over the recordings of the cue
score (:func:`motioncue.cueing.cue_score`: the perceived-motion error ``J`` relative to a
platform that stands still, plus the lost correlation, the false-cue and the missed-cue
fractions; its module says why ``J`` alone does not work on car drives) with
``objective="score"``; with ``objective="strength"`` (the default of ``motioncue tune``) the
geometric mean of the rendered shares of fx and fy of the recordings pooled
(:func:`motioncue.cueing.cue_metrics`), to be maximised subject to :class:`StrengthTargets`
(reversals, false cues, correlation, clamping): the cue score can be won by barely moving
(correlation is blind to scale, false cues and clamping fall as the motion shrinks), the
strength cannot. ``J`` itself is reported before and after. The full casadi ride
optimisation is not run.

The platform's limits are a **penalty** (Deb's feasibility rule folded into one number): a
candidate is feasible when its actuator positions after workspace limiting break no limit
(stroke, speed, acceleration, and jerk where the limits have one, with the discrete
definitions of :mod:`motioncue.trajectory._limits`) on any frame, and at most
:data:`MAX_CLAMPED_FRACTION` (1 %) of its poses were clamped by workspace limiting.
A feasible candidate scores its cue score; an infeasible one scores
``PENALTY_BASE * (1 + excess)``, above every feasible candidate, ranked by how far it is
from feasible (``excess`` = fraction of frames breaking a limit plus the clamped fraction
above 1 %). The result must be feasible, or nothing is written.

The optimiser
-------------
:func:`scipy.optimize.differential_evolution` (SciPy, maintained, already a dependency),
chosen over CMA-ES (the ``cma`` package) because it is bounded natively (no repair or
penalty for the box), is seeded and deterministic, evaluates a whole generation at once
(``updating="deferred"``) through a map-like ``workers`` callable, so the same code runs
the evaluations in-process, in a local process pool or on a Dask cluster, and it accepts the
base preset as a member of the first population (``x0``), so the result is never worse than
the base when the base is feasible. Polishing (a serial L-BFGS-B on a noisy, clamped
objective) is off.

Reproducibility: for a seed and a number of generations the candidates and their scores are
the same wherever they are evaluated (the map returns the results in order); a run stopped
by the wall-time budget depends on the machine's speed, so give ``generations`` for a
bit-identical reproduction.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError, LimitError, TransportError
from ._metrics import CueMetrics, cue_metrics
from ._params import GRAVITY_M_S2, INTENSITY_KEYS, CueingParams
from ._vestibular import DEFAULT_MODEL_SET, get_model_set

__all__ = [
    "MAX_CLAMPED_FRACTION",
    "MPC_STRENGTH_TUNED_PARAMETERS",
    "MPC_TUNED_PARAMETERS",
    "OBJECTIVES",
    "PENALTY_BASE",
    "STRENGTH_TUNED_PARAMETERS",
    "TUNED_PARAMETERS",
    "ChainMetrics",
    "StrengthTargets",
    "TuneObjective",
    "TuneResult",
    "at_intensity",
    "chain_metrics",
    "gentle_values",
    "params_from_vector",
    "preset_toml",
    "tilt_reach",
    "tune_cueing",
    "tuned_parameters",
    "vector_from_params",
]

OBJECTIVES: tuple[str, ...] = ("strength", "score")
"""The tuning objectives: ``"strength"`` (the largest rendered share within the cue-quality
targets, :class:`StrengthTargets`) and ``"score"`` (the cue score, lower is better)."""

MAX_CLAMPED_FRACTION = 0.01
"""Largest fraction of the poses workspace limiting may clamp in a feasible candidate."""

PENALTY_BASE = 1.0e6
"""Score of an infeasible candidate at zero excess (above any feasible ``J``)."""

_D2R = math.pi / 180.0


@dataclass(frozen=True)
class _Parameter:
    name: str
    lo: float
    hi: float
    unit: str


TUNED_PARAMETERS: tuple[_Parameter, ...] = (
    _Parameter("f_scale_x", 0.02, 1.0, "-"),
    _Parameter("f_scale_y", 0.02, 1.0, "-"),
    _Parameter("f_scale_z", 0.02, 1.0, "-"),
    _Parameter("trans_wn_xy_rad_s", 1.0, 20.0, "rad/s"),
    _Parameter("trans_wb_xy_rad_s", 0.05, 5.0, "rad/s"),
    _Parameter("tilt_scale_x", 0.01, 1.0, "-"),
    _Parameter("tilt_scale_y", 0.01, 1.0, "-"),
    _Parameter("tilt_wn_rad_s", 1.0, 20.0, "rad/s"),
    _Parameter("tilt_rate_limit_deg_s", 2.0, 40.0, "deg/s"),
    _Parameter("tilt_accel_limit_deg_s2", 5.0, 500.0, "deg/s^2"),
    _Parameter("tilt_limit_deg", 2.0, 25.0, "deg"),
    _Parameter("w_scale_rp", 0.05, 1.0, "-"),
    _Parameter("rot_wn_rp_rad_s", 0.2, 5.0, "rad/s"),
    _Parameter("w_scale_yaw", 0.02, 1.0, "-"),
    _Parameter("rot_wn_yaw_rad_s", 0.2, 5.0, "rad/s"),
    _Parameter("trans_wn_z_rad_s", 1.0, 20.0, "rad/s"),
)
"""The tuned parameters, their bounds (searched in log space) and units."""


MPC_TUNED_PARAMETERS: tuple[_Parameter, ...] = (
    _Parameter("ref_scale_xy", 0.05, 1.0, "-"),
    _Parameter("ref_limit_xy_m_s2", 0.3, 10.0, "m/s^2"),
    _Parameter("plan_tilt_rate_limit_deg_s", 1.0, 40.0, "deg/s"),
    _Parameter("w_error_rp", 0.1, 30.0, "-"),
    _Parameter("w_pose_xy", 1.0, 300.0, "-"),
    _Parameter("w_acc_tilt", 0.1, 100.0, "-"),
)
"""The tuned parameters of an ``mpc`` or ``optimal`` preset (its ``[mpc]`` table): x and y
share each value; searched in log space like :data:`TUNED_PARAMETERS`."""

MPC_STRENGTH_TUNED_PARAMETERS: tuple[_Parameter, ...] = (
    _Parameter("ref_scale_x", 0.02, 1.0, "-"),
    _Parameter("ref_scale_y", 0.02, 1.0, "-"),
    _Parameter("ref_reach_use", 0.2, 1.0, "-"),
    _Parameter("ref_shape", 1.0, 8.0, "-"),
    _Parameter("plan_tilt_rate_limit_deg_s", 1.0, 40.0, "deg/s"),
    _Parameter("w_error_rp", 0.01, 30.0, "-"),
    _Parameter("w_pose_xy", 1.0, 300.0, "-"),
    _Parameter("w_acc_tilt", 0.01, 100.0, "-"),
    _Parameter("sign_guard_rp", 0.1, 5.0, "-"),
)
"""The tuned parameters of an ``mpc`` or ``optimal`` preset with the compressive reference
(``[mpc] ref_shape``): the gain of the tracked copy per axis, the share of the plan's tilt
reach its fx/fy limits use, the curve's exponent, the plan's tilt rate, the canal, x/y pose
and tilt-acceleration weights, and the sign guard of roll and pitch rate (only where the
base guards them; x and y share the others). Searched in log space."""

STRENGTH_TUNED_PARAMETERS: tuple[_Parameter, ...] = (
    _Parameter("f_scale_x", 0.01, 1.5, "-"),
    _Parameter("f_scale_y", 0.01, 1.5, "-"),
    _Parameter("f_limit_xy_m_s2", 0.2, 6.0, "m/s^2"),
    _Parameter("f_shape_xy", 1.0, 8.0, "-"),
    _Parameter("f_scale_z", 0.02, 1.0, "-"),
    _Parameter("trans_wn_xy_rad_s", 1.0, 20.0, "rad/s"),
    _Parameter("trans_wb_xy_rad_s", 0.05, 5.0, "rad/s"),
    _Parameter("tilt_scale_x", 0.01, 2.0, "-"),
    _Parameter("tilt_scale_y", 0.01, 2.0, "-"),
    _Parameter("tilt_shape", 1.0, 8.0, "-"),
    _Parameter("tilt_reach_use", 0.3, 1.0, "-"),
    _Parameter("tilt_wn_rad_s", 1.0, 30.0, "rad/s"),
    _Parameter("tilt_rate_limit_deg_s", 2.0, 60.0, "deg/s"),
    _Parameter("tilt_accel_limit_deg_s2", 5.0, 1000.0, "deg/s^2"),
    _Parameter("w_scale_rp", 0.05, 1.0, "-"),
    _Parameter("rot_wn_rp_rad_s", 0.2, 5.0, "rad/s"),
    _Parameter("w_scale_yaw", 0.02, 1.0, "-"),
    _Parameter("rot_wn_yaw_rad_s", 0.2, 5.0, "rad/s"),
    _Parameter("trans_wn_z_rad_s", 1.0, 20.0, "rad/s"),
    _Parameter("lead_x_s", 0.02, 0.6, "s"),
    _Parameter("lead_y_s", 0.02, 0.6, "s"),
)
"""The tuned parameters of a classical preset with the compressive tilt (``[tilt] shape``):
the compressive curves' gains, limit and exponents in place of the plain scales, and the
share of the platform's tilt reach in place of the tilt limit. Searched in log space."""

assert tuple(p.name for p in STRENGTH_TUNED_PARAMETERS) == INTENSITY_KEYS

_PLANS = ("mpc", "optimal")


def tuned_parameters(params: CueingParams) -> tuple[_Parameter, ...]:
    """The table tuned for ``params``: :data:`MPC_TUNED_PARAMETERS` for an ``mpc`` or
    ``optimal`` preset (:data:`MPC_STRENGTH_TUNED_PARAMETERS` with the compressive reference,
    ``ref_shape``), :data:`STRENGTH_TUNED_PARAMETERS` for a classical one with the
    compressive tilt (``tilt_shape``), :data:`TUNED_PARAMETERS` otherwise."""
    if params.algorithm in _PLANS:
        if _plan_of(params).ref_shape > 0.0:
            return MPC_STRENGTH_TUNED_PARAMETERS
        return MPC_TUNED_PARAMETERS
    if params.tilt_shape is not None:
        return STRENGTH_TUNED_PARAMETERS
    return TUNED_PARAMETERS


def at_intensity(params: CueingParams, percent: float) -> CueingParams:
    """The preset at an intensity: a point of its tuned range, not a plain gain.

    ``100`` is the preset itself (its tables: the strongest tuned point within its cue
    budget), ``0`` its ``[intensity] gentle`` end (tuned for a tighter false-cue budget);
    between, every tuned parameter (:data:`STRENGTH_TUNED_PARAMETERS`: gains, limits,
    exponents, filter frequencies, tilt rate and reach share) is interpolated geometrically,
    ``v = v0^(1 - t) v100^t`` with ``t = percent / 100`` (the tuner's log space), so that every
    point is a complete washout design between two tuned ones. Whatever the intensity, the
    chain after the washout (workspace limiting, the actuator limiter) keeps every frame
    within the limits.

    Parameters
    ----------
    params : CueingParams
        A preset with an intensity range (``intensity_gentle``).
    percent : float
        0 to 100.

    Returns
    -------
    CueingParams
        Named ``"NAME@PCT%"`` (the preset itself at 100).

    Raises
    ------
    ConfigError
        ``percent`` outside 0..100, or a preset without an intensity range.
    """
    if isinstance(percent, bool) or not (math.isfinite(percent) and 0.0 <= percent <= 100.0):
        raise ConfigError(f"intensity {percent!r} % is invalid; allowed: 0 to 100")
    if params.intensity_gentle is None:
        raise ConfigError(
            f"preset {params.name!r} has no tuned intensity range (no [intensity] table); "
            "give a preset that has one (e.g. racing-hexapod) or leave out the intensity"
        )
    if percent == 100.0:
        return params
    t = percent / 100.0
    strong = vector_from_params(params)
    gentle = _clip_log(STRENGTH_TUNED_PARAMETERS, params.intensity_gentle)
    x = gentle + t * (strong - gentle)
    return params_from_vector(params, x.tolist(), name=f"{params.name}@{percent:g}%")


def tilt_reach(platform: Any, limits: Any = None) -> tuple[float, float, float, float]:
    """The platform's reach in pure tilt about neutral: ``(roll-, roll+, pitch-, pitch+)``.

    The largest angle (rad, magnitude, to 0.01 deg) such that every pure roll (or pitch) pose
    from neutral up to it in that direction is reachable
    (:func:`motioncue.trajectory.reachable`: inside the workspace and, with ``limits``, the
    stroke those limits allow). A direction the platform cannot tilt at all gives 0.01 deg
    (the least a preset accepts).

    Parameters
    ----------
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits, optional

    Returns
    -------
    tuple of 4 floats
    """
    from ..trajectory import reachable

    angles = np.radians(np.arange(1, 6001) * 0.01)  # 0.01 .. 60 deg
    out = []
    for axis in (3, 4):
        for sign in (-1.0, 1.0):
            poses = np.zeros((angles.size, 6))
            poses[:, axis] = sign * angles
            ok = np.asarray(reachable(platform, poses, limits=limits), dtype=bool)
            first_bad = int(np.argmin(ok)) if not ok.all() else angles.size
            out.append(float(angles[max(first_bad - 1, 0)]))
    return (out[0], out[1], out[2], out[3])


def _log_bounds(params: CueingParams | None = None) -> list[tuple[float, float]]:
    table = TUNED_PARAMETERS if params is None else tuned_parameters(params)
    return [(math.log(p.lo), math.log(p.hi)) for p in table]


def _clip_log(table: Sequence[_Parameter], values: Sequence[float]) -> NDArray[np.float64]:
    out = np.empty(len(table))
    for i, (p, v) in enumerate(zip(table, values, strict=True)):
        out[i] = math.log(min(max(float(v), p.lo), p.hi))
    return out


def _plan_of(params: CueingParams) -> Any:
    from ._mpc_params import MpcParams

    return params.mpc if params.mpc is not None else MpcParams()


def vector_from_params(params: CueingParams) -> NDArray[np.float64]:
    """The base preset as a point of the search space (log values, clipped to the bounds).

    A classical preset without ``tilt_scale`` starts with its translational ``f_scale``
    (x, y) as tilt scales; one without ``tilt_accel_limit_rad_s2`` at the upper acceleration
    bound. An ``mpc`` or ``optimal`` preset gives its ``[mpc]`` values (x and y: their
    geometric mean; an unset plan tilt-rate limit: the ``[tilt]`` table's).
    """
    if params.algorithm in _PLANS:
        mp = _plan_of(params)
        tr = mp.tilt_rate_limit_rad_s
        if mp.ref_shape > 0.0:
            guard = [g for g in mp.sign_guard[3:5] if g > 0.0]
            return _clip_log(
                MPC_STRENGTH_TUNED_PARAMETERS,
                (
                    mp.ref_scale[0],
                    mp.ref_scale[1],
                    mp.ref_reach_use if mp.ref_reach_use > 0.0 else 1.0,
                    mp.ref_shape,
                    (params.tilt_rate_limit_rad_s if tr is None else tr) / _D2R,
                    math.sqrt(max(mp.w_error[3], 1e-9) * max(mp.w_error[4], 1e-9)),
                    math.sqrt(max(mp.w_pose[0], 1e-9) * max(mp.w_pose[1], 1e-9)),
                    math.sqrt(max(mp.w_acc[3], 1e-9) * max(mp.w_acc[4], 1e-9)),
                    math.sqrt(guard[0] * guard[-1]) if guard else 0.7,
                ),
            )
        return _clip_log(
            MPC_TUNED_PARAMETERS,
            (
                math.sqrt(max(mp.ref_scale[0], 1e-9) * max(mp.ref_scale[1], 1e-9)),
                math.sqrt(mp.ref_limit[0] * mp.ref_limit[1]),
                (params.tilt_rate_limit_rad_s if tr is None else tr) / _D2R,
                math.sqrt(max(mp.w_error[3], 1e-9) * max(mp.w_error[4], 1e-9)),
                math.sqrt(max(mp.w_pose[0], 1e-9) * max(mp.w_pose[1], 1e-9)),
                math.sqrt(max(mp.w_acc[3], 1e-9) * max(mp.w_acc[4], 1e-9)),
            ),
        )
    tilt = params.tilt_scale if params.tilt_scale is not None else params.f_scale[:2]
    accel = params.tilt_accel_limit_rad_s2
    if params.tilt_shape is not None:
        fsh = params.f_shape if params.f_shape is not None else (2.0, 2.0, 2.0)
        return _clip_log(
            STRENGTH_TUNED_PARAMETERS,
            (
                params.f_scale[0],
                params.f_scale[1],
                math.sqrt(params.f_limit_m_s2[0] * params.f_limit_m_s2[1]),
                math.sqrt(fsh[0] * fsh[1]),
                params.f_scale[2],
                math.sqrt(params.trans_wn_rad_s[0] * params.trans_wn_rad_s[1]),
                math.sqrt(
                    max(params.trans_wb_rad_s[0], 1e-9) * max(params.trans_wb_rad_s[1], 1e-9)
                ),
                tilt[0],
                tilt[1],
                params.tilt_shape,
                params.tilt_reach_use,
                params.tilt_wn_rad_s,
                params.tilt_rate_limit_rad_s / _D2R,
                STRENGTH_TUNED_PARAMETERS[13].hi if accel is None else accel / _D2R,
                math.sqrt(params.w_scale[0] * params.w_scale[1]),
                math.sqrt(params.rot_wn_rad_s[0] * params.rot_wn_rad_s[1]),
                params.w_scale[2],
                params.rot_wn_rad_s[2],
                params.trans_wn_rad_s[2],
                0.02 if params.lead_s is None else params.lead_s[0],
                0.02 if params.lead_s is None else params.lead_s[1],
            ),
        )
    values = (
        params.f_scale[0],
        params.f_scale[1],
        params.f_scale[2],
        math.sqrt(params.trans_wn_rad_s[0] * params.trans_wn_rad_s[1]),
        math.sqrt(max(params.trans_wb_rad_s[0], 1e-9) * max(params.trans_wb_rad_s[1], 1e-9)),
        tilt[0],
        tilt[1],
        params.tilt_wn_rad_s,
        params.tilt_rate_limit_rad_s / _D2R,
        TUNED_PARAMETERS[9].hi if accel is None else accel / _D2R,
        params.tilt_limit_rad / _D2R,
        math.sqrt(params.w_scale[0] * params.w_scale[1]),
        math.sqrt(params.rot_wn_rad_s[0] * params.rot_wn_rad_s[1]),
        params.w_scale[2],
        params.rot_wn_rad_s[2],
        params.trans_wn_rad_s[2],
    )
    return _clip_log(TUNED_PARAMETERS, values)


def gentle_values(params: CueingParams) -> tuple[float, ...]:
    """The tuned parameters of a compressive-tilt preset, in their units (the values of an
    ``[intensity] gentle`` table, :data:`INTENSITY_KEYS` order)."""
    return tuple(float(math.exp(v)) for v in vector_from_params(params))


def params_from_vector(base: CueingParams, x: Sequence[float], name: str = "") -> CueingParams:
    """The base preset with the tuned parameters set from a point ``x`` (log values)."""
    table = tuned_parameters(base)
    if len(x) != len(table):
        raise ConfigError(f"tuning vector has {len(x)} values; expected {len(table)}")
    v = [min(max(math.exp(float(xi)), p.lo), p.hi) for xi, p in zip(x, table, strict=True)]
    if base.algorithm in _PLANS:
        mp = _plan_of(base)

        def xy(old: Sequence[float], value: float) -> tuple[float, ...]:
            return (value, value, *old[2:])

        def rp(old: Sequence[float], value: float) -> tuple[float, ...]:
            return (*old[:3], value, value, old[5])

        if mp.ref_shape > 0.0:
            sg = list(mp.sign_guard)
            for i in (3, 4):
                if sg[i] > 0.0:
                    sg[i] = v[8]
            plan = replace(
                mp,
                ref_scale=(v[0], v[1], *mp.ref_scale[2:]),
                ref_reach_use=v[2],
                ref_shape=v[3],
                tilt_rate_limit_rad_s=v[4] * _D2R,
                w_error=rp(mp.w_error, v[5]),
                w_pose=xy(mp.w_pose, v[6]),
                w_acc=rp(mp.w_acc, v[7]),
                sign_guard=tuple(sg),
            )
            return replace(base, name=name or base.name, mpc=plan)
        plan = replace(
            mp,
            ref_scale=xy(mp.ref_scale, v[0]),
            ref_limit=xy(mp.ref_limit, v[1]),
            tilt_rate_limit_rad_s=v[2] * _D2R,
            w_error=rp(mp.w_error, v[3]),
            w_pose=xy(mp.w_pose, v[4]),
            w_acc=rp(mp.w_acc, v[5]),
        )
        return replace(base, name=name or base.name, mpc=plan)
    if base.tilt_shape is not None:
        fz_shape = base.f_shape[2] if base.f_shape is not None else v[3]
        return replace(
            base,
            name=name or base.name,
            algorithm="classical",
            f_scale=(v[0], v[1], v[4]),
            f_limit_m_s2=(v[2], v[2], base.f_limit_m_s2[2]),
            f_shape=(v[3], v[3], fz_shape),
            trans_wn_rad_s=(v[5], v[5], v[18]),
            trans_wb_rad_s=(v[6], v[6], base.trans_wb_rad_s[2]),
            tilt_scale=(v[7], v[8]),
            tilt_shape=v[9],
            tilt_reach_use=v[10],
            tilt_wn_rad_s=v[11],
            tilt_rate_limit_rad_s=v[12] * _D2R,
            tilt_accel_limit_rad_s2=v[13] * _D2R,
            w_scale=(v[14], v[14], v[16]),
            rot_wn_rad_s=(v[15], v[15], v[17]),
            lead_s=(v[19], v[20]),
        )
    return replace(
        base,
        name=name or base.name,
        algorithm="classical",
        f_scale=(v[0], v[1], v[2]),
        trans_wn_rad_s=(v[3], v[3], v[15]),
        trans_wb_rad_s=(v[4], v[4], base.trans_wb_rad_s[2]),
        tilt_scale=(v[5], v[6]),
        tilt_wn_rad_s=v[7],
        tilt_rate_limit_rad_s=v[8] * _D2R,
        tilt_accel_limit_rad_s2=v[9] * _D2R,
        tilt_limit_rad=v[10] * _D2R,
        w_scale=(v[11], v[11], v[13]),
        rot_wn_rad_s=(v[12], v[12], v[14]),
    )


@dataclass(frozen=True)
class _Drive:
    """One recording, resampled: vehicle specific force and angular velocity (N, 3)."""

    label: str
    f: NDArray[np.float64]
    w: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ChainMetrics:
    """What the cheap chain delivers on the recordings for one parameter set.

    Attributes
    ----------
    objective : float
        Mean cue score over the recordings (:func:`motioncue.cueing.cue_score`; lower is
        better): the tuning objective.
    per_drive_objective : tuple of float
    perceived_error : float
        Mean perceived-motion error ``J`` over the recordings (thresholds).
    correlation : (6,) array
        Mean over the recordings of the per-axis correlation (fx fy fz wx wy wz; a constant
        signal counts as 0).
    false_cue_time_s : (6,) array
        Total false-cue time per axis over the recordings (s).
    false_cue_fraction : float
        Fraction of all samples with a false cue on any axis.
    missed_cue_fraction : float
        Mean over the recordings of the score's missed-cue fraction.
    duration_s : float
        Total duration of the recordings (s).
    clamped_fraction : float
        Fraction of all poses clamped by workspace limiting.
    violating_frames : int
        Frames whose actuator positions break a limit (stroke, speed, acceleration, jerk).
    cue : CueMetrics or None
        Rendered share, gain, missed, reversed, spurious and false cues and the clamped
        share, pooled over the recordings (their samples concatenated;
        :func:`motioncue.cueing.cue_metrics`); None when the run stopped early.
    strength : float
        ``sqrt(rendered share fx * rendered share fy)`` of ``cue`` (the geometric mean:
        both count, neither can be dropped): the ``"strength"`` objective (higher is better;
        0 for a platform at rest).
    """

    objective: float
    per_drive_objective: tuple[float, ...]
    perceived_error: float = math.nan
    correlation: NDArray[np.float64] = field(default_factory=lambda: np.full(6, math.nan))
    false_cue_time_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    false_cue_fraction: float = 0.0
    missed_cue_fraction: float = 0.0
    duration_s: float = 0.0
    clamped_fraction: float = 0.0
    violating_frames: int = 0
    cue: CueMetrics | None = None
    strength: float = 0.0

    @property
    def feasible(self) -> bool:
        """Zero violating frames and at most 1 % of the poses clamped."""
        return self.violating_frames == 0 and self.clamped_fraction <= MAX_CLAMPED_FRACTION


@dataclass(frozen=True)
class StrengthTargets:
    """The cue-quality constraints of the ``"strength"`` objective (fractions, not %).

    A candidate within the actuator limits meets them when, over the recordings pooled
    (:attr:`ChainMetrics.cue`, the definitions of :mod:`motioncue.cueing._metrics`),
    reversals on any channel take at most ``max_reversals`` of the time, false cues on any
    channel at most ``max_false``, the fx and fy correlations are at least ``min_corr_fx``
    and ``min_corr_fy``, and at most ``max_clamped`` of all poses are clamped. The defaults
    are issue 20's acceptance figures; a tune meant to hold on other drives should ask for a
    margin.
    """

    max_reversals: float = 0.02
    max_false: float = 0.15
    max_clamped: float = 0.01
    min_corr_fx: float = 0.95
    min_corr_fy: float = 0.90

    def __post_init__(self) -> None:
        for name in ("max_reversals", "max_false", "max_clamped"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 < v <= 1.0):
                raise ConfigError(f"{name} = {v!r} is invalid; allowed: (0, 1]")
        for name in ("min_corr_fx", "min_corr_fy"):
            v = getattr(self, name)
            if not (math.isfinite(v) and -1.0 <= v < 1.0):
                raise ConfigError(f"{name} = {v!r} is invalid; allowed: [-1, 1)")

    def violation(self, m: ChainMetrics) -> float:
        """Sum of the relative excesses over the targets (0: all met; inf without
        :attr:`ChainMetrics.cue`)."""
        c = m.cue
        if c is None:
            return math.inf

        def over(value: float, bound: float, scale: float) -> float:
            if not math.isfinite(value):
                return 1.0
            return max(0.0, value - bound) / scale

        corr = np.nan_to_num(c.correlation, nan=0.0)
        return (
            over(c.reversals_any, self.max_reversals, self.max_reversals)
            + over(c.false_any, self.max_false, self.max_false)
            + over(m.clamped_fraction, self.max_clamped, self.max_clamped)
            + over(self.min_corr_fx, float(corr[0]), 1.0 - self.min_corr_fx)
            + over(self.min_corr_fy, float(corr[1]), 1.0 - self.min_corr_fy)
        )


def _violating_frames(q: NDArray[np.float64], dt_s: float, limits: Any) -> int:
    """Frames (of the cue, starting at rest at its first pose) breaking a limit."""
    tol = 1e-9
    bad = np.any((q < limits.q_min - tol) | (q > limits.q_max + tol), axis=1)
    hist = np.concatenate([q[:1], q[:1], q[:1], q], axis=0)  # at rest before the first frame
    v = np.diff(hist, axis=0)[2:] / dt_s
    a = (hist[3:] - 2.0 * hist[2:-1] + hist[1:-2]) / dt_s**2
    bad |= np.any(np.abs(v) > limits.v_max * (1.0 + tol), axis=1)
    bad |= np.any(np.abs(a) > limits.a_max * (1.0 + tol), axis=1)
    if limits.j_max is not None:
        j = (hist[3:] - 3.0 * hist[2:-1] + 3.0 * hist[1:-2] - hist[:-3]) / dt_s**3
        bad |= np.any(np.abs(j) > limits.j_max * (1.0 + tol), axis=1)
    return int(np.count_nonzero(bad))


class TuneObjective:
    """The tuning objective: picklable (sent once to each process or Dask worker).

    Parameters
    ----------
    base : CueingParams
        Preset whose other parameters are kept.
    drives : sequence of (label, f, w)
        Recordings resampled to ``rate_hz``: specific force (N, 3) m/s^2, angular velocity
        (N, 3) rad/s.
    platform
        A :class:`motioncue.kinematics.Platform`.
    limits : motioncue.trajectory.ActuatorLimits
        The limits of the chain (pulse-rounding tightened, as ``generate`` uses them).
    rate_hz : float
    model : str
        Vestibular model set.
    objective : str
        ``"score"`` (default): minimise the mean cue score. ``"strength"``: maximise
        :attr:`ChainMetrics.strength` subject to ``targets`` (Deb's feasibility rule folded
        into one number, lower is better: ``-strength`` for a candidate meeting every
        target, ``1 + violation`` for one that does not, the limit penalty above both).
        Standing still scores 0, so it can no longer win.
    targets : StrengthTargets, optional
        Constraints of the ``"strength"`` objective (default: issue 20's acceptance).
    """

    def __init__(
        self,
        base: CueingParams,
        drives: Sequence[tuple[str, Any, Any]],
        platform: Any,
        limits: Any,
        rate_hz: float,
        model: str = DEFAULT_MODEL_SET,
        objective: str = "score",
        targets: StrengthTargets | None = None,
    ) -> None:
        get_model_set(model)
        if objective not in OBJECTIVES:
            raise ConfigError(f"objective {objective!r} is invalid; allowed: {OBJECTIVES}")
        self.objective = objective
        self.targets = targets if targets is not None else StrengthTargets()
        if not drives:
            raise ConfigError("tuning needs at least one recording")
        self.base = base
        self.drives = tuple(
            _Drive(lbl, np.ascontiguousarray(f, float), np.ascontiguousarray(w, float))
            for lbl, f, w in drives
        )
        self.platform = platform
        self.limits = limits
        self.rate_hz = float(rate_hz)
        self.model = model
        self._models = get_model_set(model)
        self._pv_cache: dict[int, tuple[Any, Any, Any]] = {}

    def _perceived_vehicle(self, i: int, f: NDArray[np.float64], w: NDArray[np.float64]) -> Any:
        """The vehicle's perceived motion on drive ``i`` (cached: it does not depend on the
        tuned parameters, only on the input the algorithm used)."""
        cached = self._pv_cache.get(i)
        if cached is not None and np.array_equal(cached[0], f) and np.array_equal(cached[1], w):
            return cached[2]
        rest = np.array([0.0, 0.0, GRAVITY_M_S2])
        pv = self._models.filter(np.concatenate([f - rest, w], axis=1), self.rate_hz)
        self._pv_cache[i] = (np.array(f), np.array(w), pv)
        return pv

    def metrics(self, params: CueingParams, *, full: bool = False) -> ChainMetrics:
        """Run the cheap chain with ``params`` on every recording.

        ``full``: compute every metric even for a candidate that is infeasible by its
        clamped poses alone; without it, such a candidate returns at once with an infinite
        objective and its clamped fraction (the penalty ranks it by that).
        """
        from ..trajectory import limit_pose, reachable
        from ._algorithm import make_cueing
        from ._evaluate import simulator_motion
        from ._score import cue_score
        from ._vestibular import normalised_error_rms

        design = make_cueing(params, self.rate_hz)
        runs = [design.run(d.f, d.w) for d in self.drives]
        if not full:
            # a candidate whose cue leaves the workspace too often is infeasible whatever the
            # rest: skip workspace limiting (slow on clamped poses) and the evaluation
            n_req = sum(int(np.asarray(r.poses).shape[0]) for r in runs)
            n_out = sum(
                int(np.count_nonzero(~reachable(self.platform, r.poses, limits=self.limits)))
                for r in runs
            )
            if n_out > MAX_CLAMPED_FRACTION * n_req:
                return ChainMetrics(
                    objective=math.inf,
                    per_drive_objective=(),
                    duration_s=n_req / self.rate_hz,
                    clamped_fraction=n_out / max(n_req, 1),
                )
        dt = 1.0 / self.rate_hz
        thr = self._models.thresholds
        ones = np.ones(6)
        scores: list[float] = []
        js: list[float] = []
        corr = np.zeros(6)
        false_s = np.zeros(6)
        false_any = 0
        missed = 0.0
        pvs: list[NDArray[np.float64]] = []
        pss: list[NDArray[np.float64]] = []
        n_all = clamped = violating = 0
        rest = np.array([0.0, 0.0, GRAVITY_M_S2])
        for i, (d, res) in enumerate(zip(self.drives, runs, strict=True)):
            f_used = np.asarray(getattr(res, "f_used", d.f), dtype=float)
            w_used = np.asarray(getattr(res, "w_used", d.w), dtype=float)
            lim = limit_pose(self.platform, res.poses, limits=self.limits)
            poses = np.asarray(lim.pose, dtype=float)
            clamped += int(np.count_nonzero(np.asarray(lim.status) != "ok"))
            n_all += poses.shape[0]
            violating += _violating_frames(np.asarray(lim.q, dtype=float), dt, self.limits)
            pv = self._perceived_vehicle(i, f_used, w_used)
            f_s, w_s = simulator_motion(poses, self.rate_hz, head_offset_m=params.head_offset_m)
            ps = self._models.filter(np.concatenate([f_s - rest, w_s], axis=1), self.rate_hz)
            sc = cue_score(pv, ps, thr)
            scores.append(sc.score)
            js.append(normalised_error_rms(ps - pv, thr, ones))
            corr += np.nan_to_num(sc.correlation, nan=0.0)
            wrong = (np.abs(ps) > thr) & (ps * pv < 0.0)
            false_s += wrong.sum(axis=0) / self.rate_hz
            false_any += int(np.count_nonzero(wrong.any(axis=1)))
            missed += sc.missed_fraction
            pvs.append(pv)
            pss.append(ps)
        nd = len(self.drives)
        pooled = cue_metrics(
            np.concatenate(pvs), np.concatenate(pss), thr, clamped_share=clamped / max(n_all, 1)
        )
        share = np.nan_to_num(pooled.rendered_share, nan=0.0)
        return ChainMetrics(
            objective=float(np.mean(scores)),
            per_drive_objective=tuple(scores),
            perceived_error=float(np.mean(js)),
            correlation=corr / nd,
            false_cue_time_s=false_s,
            false_cue_fraction=false_any / max(n_all, 1),
            missed_cue_fraction=missed / nd,
            duration_s=n_all / self.rate_hz,
            clamped_fraction=clamped / max(n_all, 1),
            violating_frames=violating,
            cue=pooled,
            strength=float(math.sqrt(max(share[0], 0.0) * max(share[1], 0.0))),
        )

    def score(self, m: ChainMetrics) -> float:
        """The penalised objective of a run (see the module docstring)."""
        if m.feasible and not math.isfinite(m.objective):
            return PENALTY_BASE * 1e6
        if m.feasible and self.objective == "strength":
            v = self.targets.violation(m)
            return 1.0 + v if v > 0.0 else -m.strength
        if m.feasible:
            return m.objective
        n = max(m.duration_s * self.rate_hz, 1.0)
        excess = m.violating_frames / n + max(0.0, m.clamped_fraction - MAX_CLAMPED_FRACTION)
        return PENALTY_BASE * (1.0 + excess)

    def __call__(self, x: NDArray[np.float64]) -> float:
        """Penalised objective of a point ``x`` of the search space (log values)."""
        try:
            params = params_from_vector(self.base, np.asarray(x, dtype=float).tolist())
            return self.score(self.metrics(params))
        except ConfigError:
            return PENALTY_BASE * 1e6


# --------------------------------------------------------------------- evaluation back ends
_INSTALLED: list[TuneObjective] = []


def _install(objective: TuneObjective) -> None:
    _INSTALLED[:] = [objective]


def _score_installed(x: NDArray[np.float64]) -> float:
    return _INSTALLED[0](x)


def _score_with(objective: TuneObjective, x: NDArray[np.float64]) -> float:
    return objective(x)


class _Evaluator:
    """Map-like ``(func, xs) -> list`` for differential_evolution, counting evaluations.

    ``func`` (SciPy's wrapper around the objective) is not shipped: each back end already
    holds the objective (in-process, installed in each pool process, or scattered to the
    Dask workers) and calls it on each ``x``; the results come back in order.
    """

    def __init__(self, objective: TuneObjective, workers: int, scheduler: str | None) -> None:
        self.objective = objective
        self.evaluations = 0
        self.where = "in-process"
        self._workers = workers
        self._pool: Any = None
        self._client: Any = None
        self._future: Any = None
        self._address = ""
        if scheduler is not None:
            self._start_dask(scheduler)
        elif workers > 1:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(
                max_workers=workers,
                mp_context=multiprocessing.get_context("spawn"),
                initializer=_install,
                initargs=(objective,),
            )
            self.where = f"{workers} local processes"

    def _start_dask(self, scheduler: str) -> None:
        try:
            from distributed import Client
        except ImportError as exc:
            raise ConfigError(
                "--scheduler needs the Dask distributed package: pip install 'motioncue[dask]'"
            ) from exc
        try:
            client = Client(scheduler, timeout=20, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ConfigError(f"cannot reach the Dask scheduler {scheduler}: {msg}") from exc
        self._client = client
        self._address = scheduler
        n = len(client.scheduler_info().get("workers", {}))
        if n == 0:
            try:
                client.wait_for_workers(1, timeout=20)
            except (OSError, TimeoutError) as exc:
                client.close()
                raise ConfigError(f"the Dask scheduler {scheduler} has no workers") from exc
            n = len(client.scheduler_info().get("workers", {}))
        self._future = client.scatter(self.objective, broadcast=True, hash=False)
        self.where = f"Dask scheduler {scheduler} ({n} workers)"

    def __call__(self, func: Callable[[Any], float], xs: Iterable[Any]) -> list[float]:
        points = [np.asarray(x, dtype=float) for x in xs]
        self.evaluations += len(points)
        if self._client is not None:
            from distributed import KilledWorker

            futures = self._client.map(
                _score_with, [self._future] * len(points), points, pure=False
            )
            try:
                return [float(v) for v in self._client.gather(futures)]
            except (OSError, KilledWorker) as exc:
                msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise TransportError(f"Dask cluster {self._address}: {msg}") from exc
        if self._pool is not None:
            chunk = max(1, len(points) // (4 * self._workers))
            return [float(v) for v in self._pool.map(_score_installed, points, chunksize=chunk)]
        return [float(self.objective(x)) for x in points]

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None


# --------------------------------------------------------------------- the tuner
@dataclass(frozen=True, eq=False)
class TuneResult:
    """The outcome of :func:`tune_cueing`.

    Attributes
    ----------
    params : CueingParams
        The tuned preset (feasible).
    before, after : ChainMetrics
        The base preset's and the tuned preset's full metrics on the recordings.
    x : (16,) array
        The best point (log values of :data:`TUNED_PARAMETERS`).
    generations : int
    evaluations : int
    wall_s : float
    stop_reason : str
    where : str
        Where the evaluations ran.
    """

    params: CueingParams
    before: ChainMetrics
    after: ChainMetrics
    x: NDArray[np.float64]
    generations: int
    evaluations: int
    wall_s: float
    stop_reason: str
    where: str


@dataclass
class _RunState:
    last: float
    gen: int = 0
    gen_s: float = 0.0
    stop: str = "converged"


Progress = Callable[[int, float, float, int], None]
"""``progress(generation, best_score, evaluations_per_s, evaluations)``."""


def tune_cueing(
    objective: TuneObjective,
    *,
    seed: int = 0,
    budget_s: float = 300.0,
    generations: int = 100,
    popsize: int = 6,
    workers: int = 1,
    scheduler: str | None = None,
    name: str = "tuned",
    progress: Progress | None = None,
    init_spread: float | None = None,
) -> TuneResult:
    """Minimise the penalised perceived-motion error with differential evolution.

    Parameters
    ----------
    objective : TuneObjective
    seed : int
        Seed of the optimiser (same seed and generations: same result, wherever evaluated).
    budget_s : float
        Wall-time budget (s): no generation is started that would end past it (predicted from
        the last one); the first population is always evaluated.
    generations : int
        Most generations after the first population.
    popsize : int
        Population size per tuned parameter (population ``popsize * 16``).
    workers : int
        Local processes (1: in this process); ignored when ``scheduler`` is given.
    scheduler : str, optional
        Dask scheduler address (``tcp://host:port``): evaluate there. Its workers need
        motioncue (the same version) importable; the recordings travel with the objective.
    name : str
        Name of the tuned preset.
    progress : callable, optional
        Called after each generation.
    init_spread : float, optional
        Start from a population about the base preset instead of a Latin hypercube over the
        whole box: the base plus seeded normal steps of this standard deviation in the log
        space (0.3: about +-35 %), clipped to the bounds. A local search from a good base.

    Raises
    ------
    ConfigError
        A bad argument, or the scheduler cannot be reached (or has no worker).
    TransportError
        The cluster failed during the run (a lost connection, a killed worker).
    LimitError
        No feasible candidate was found (zero violations, at most 1 % clamped).
    """
    from scipy.optimize import differential_evolution

    if not (isinstance(seed, int) and 0 <= seed < 2**32):
        raise ConfigError(f"seed {seed!r} is invalid; allowed: an integer in [0, 2^32)")
    if not (math.isfinite(budget_s) and budget_s > 0.0):
        raise ConfigError(f"budget {budget_s!r} s is invalid; allowed: a finite number > 0")
    if not (isinstance(generations, int) and 0 <= generations <= 100_000):
        raise ConfigError(f"generations {generations!r} is invalid; allowed: 0 to 100000")
    if not (isinstance(popsize, int) and 2 <= popsize <= 100):
        raise ConfigError(f"popsize {popsize!r} is invalid; allowed: 2 to 100")
    if not (isinstance(workers, int) and 1 <= workers <= 1024):
        raise ConfigError(f"workers {workers!r} is invalid; allowed: 1 to 1024")
    if init_spread is not None and not (math.isfinite(init_spread) and 0.0 < init_spread <= 5.0):
        raise ConfigError(f"init spread {init_spread!r} is invalid; allowed: (0, 5]")

    t0 = time.monotonic()  # the budget counts everything, connecting included
    evaluator = _Evaluator(objective, workers, scheduler)  # an unreachable cluster: first
    try:
        before = objective.metrics(objective.base, full=True)
    except BaseException:
        evaluator.close()
        raise
    x0 = vector_from_params(objective.base)
    bounds = _log_bounds(objective.base)
    init: Any = "latinhypercube"
    if init_spread is not None:
        lo = np.array([b[0] for b in bounds])
        hi = np.array([b[1] for b in bounds])
        steps = np.random.default_rng([seed, 1]).normal(
            0.0, init_spread, (popsize * len(x0), len(x0))
        )
        init = np.clip(x0 + steps, lo, hi)
        init[0] = x0
    state = _RunState(last=t0)

    def callback(intermediate_result: Any) -> bool:
        now = time.monotonic()
        state.gen += 1
        state.gen_s = now - state.last
        state.last = now
        elapsed = now - t0
        if progress is not None:
            rate = evaluator.evaluations / elapsed if elapsed > 0 else 0.0
            progress(state.gen, float(intermediate_result.fun), rate, evaluator.evaluations)
        if elapsed + state.gen_s > budget_s:
            state.stop = f"wall-time budget {budget_s:g} s"
            return True
        return False

    try:
        res = differential_evolution(
            objective,
            bounds,
            maxiter=generations,
            popsize=popsize,
            rng=np.random.default_rng(seed),
            callback=callback,
            polish=False,
            updating="deferred",
            workers=evaluator,
            x0=x0,
            init=init,
            tol=1e-3,
        )
    finally:
        evaluator.close()
    wall = time.monotonic() - t0
    if state.stop == "converged" and state.gen >= generations:
        state.stop = f"{generations} generations"
    best = np.asarray(res.x, dtype=float)
    params = params_from_vector(objective.base, best.tolist(), name=name)
    after = objective.metrics(params, full=True)
    if not after.feasible:
        raise LimitError(
            f"no feasible parameter set found in {state.gen} generations "
            f"({evaluator.evaluations} evaluations): the best breaks a limit on "
            f"{after.violating_frames} frames and clamps {after.clamped_fraction:.2%} of "
            f"the poses (allowed: 0 and {MAX_CLAMPED_FRACTION:.0%}); nothing written"
        )
    return TuneResult(
        params=params,
        before=before,
        after=after,
        x=best,
        generations=state.gen,
        evaluations=evaluator.evaluations,
        wall_s=wall,
        stop_reason=state.stop,
        where=evaluator.where,
    )


# --------------------------------------------------------------------- writing the preset
def _fmt(v: float) -> str:
    return repr(float(v))


def _vec(values: Iterable[float], k: float = 1.0) -> str:
    return "[" + ", ".join(_fmt(v * k) for v in values) + "]"


def preset_toml(params: CueingParams, comments: Sequence[str] = ()) -> str:
    """The TOML text of a preset (the layout :func:`load_cueing` reads): the classical
    tables, and for an ``mpc`` or ``optimal`` preset its ``[mpc]`` table.

    Angles are written in degrees, lengths in millimetres (the file's units); ``comments``
    become ``#`` lines at the top.
    """
    from ._params import DOF_NAMES

    r2d = 1.0 / _D2R
    lines = [f"# {c}".rstrip() for c in comments]
    lines += [
        f"description = {_quote(f'{params.name}: tuned by motioncue tune')}",
        f"algorithm = {_quote(params.algorithm)}",
        "dofs = ["
        + ", ".join(f'"{n}"' for n, on in zip(DOF_NAMES, params.dofs, strict=True) if on)
        + "]",
        "",
        "[scaling]",
        f"f_scale = {_vec(params.f_scale)}",
        f"f_limit_m_s2 = {_vec(params.f_limit_m_s2)}",
        f"w_scale = {_vec(params.w_scale)}",
        f"w_limit_deg_s = {_vec(params.w_limit_rad_s, r2d)}",
        f"soft_knee = {_fmt(params.soft_knee)}",
    ]
    if params.f_shape is not None:
        lines.append(f"f_shape = {_vec(params.f_shape)}")
    if params.w_shape is not None:
        lines.append(f"w_shape = {_vec(params.w_shape)}")
    if params.lead_s is not None:
        lines.append(f"lead_s = {_vec(params.lead_s)}")
    lines += [
        "",
        "[translational]",
        f"wn_rad_s = {_vec(params.trans_wn_rad_s)}",
        f"zeta = {_vec(params.trans_zeta)}",
        f"wb_rad_s = {_vec(params.trans_wb_rad_s)}",
        "",
        "[tilt]",
        f"wn_rad_s = {_fmt(params.tilt_wn_rad_s)}",
        f"zeta = {_fmt(params.tilt_zeta)}",
        f"rate_limit_deg_s = {_fmt(params.tilt_rate_limit_rad_s * r2d)}",
        f"limit_deg = {_fmt(params.tilt_limit_rad * r2d)}",
    ]
    if params.tilt_scale is not None:
        lines.append(f"scale = {_vec(params.tilt_scale)}")
    if params.tilt_accel_limit_rad_s2 is not None:
        lines.append(f"accel_limit_deg_s2 = {_fmt(params.tilt_accel_limit_rad_s2 * r2d)}")
    if params.tilt_shape is not None:
        lines.append(f"shape = {_fmt(params.tilt_shape)}")
    if params.tilt_reach_rad is not None:
        lines.append(f"reach_deg = {_vec(params.tilt_reach_rad, r2d)}")
        lines.append(f"reach_use = {_fmt(params.tilt_reach_use)}")
    if params.tilt_additive:
        lines.append("additive = true")
    lines += [
        "",
        "[rotational]",
        f"wn_rad_s = {_vec(params.rot_wn_rad_s)}",
        f"zeta = {_vec(params.rot_zeta)}",
        "",
        "[input]",
        f"reject_f_m_s2 = {_fmt(params.reject_f_m_s2)}",
        f"reject_w_deg_s = {_fmt(params.reject_w_rad_s * r2d)}",
        "",
        "[workspace]",
        f"half_range_mm = {_vec(params.workspace[:3], 1e3)}",
        f"half_range_deg = {_vec(params.workspace[3:], r2d)}",
        "",
        "[head]",
        f"offset_mm = {_vec(params.head_offset_m, 1e3)}",
        "",
    ]
    if params.algorithm in _PLANS and params.mpc is not None:
        lines += _mpc_lines(params.mpc)
    if params.intensity_gentle is not None:
        lines += ["[intensity.gentle]"]
        lines += [
            f"{k} = {_fmt(v)}" for k, v in zip(INTENSITY_KEYS, params.intensity_gentle, strict=True)
        ]
        lines.append("")
    return "\n".join(lines)


def _mpc_lines(mp: Any) -> list[str]:
    """The ``[mpc]`` table of :func:`preset_toml`."""
    r2d = 1.0 / _D2R
    lines = [
        "[mpc]",
        f"platform = {_quote(mp.platform)}",
        f"controller = {_quote(mp.controller)}",
        f"horizon_s = {_fmt(mp.horizon_s)}",
        f"blocks = {mp.blocks}",
    ]
    for key in ("w_error", "w_pose", "w_vel", "w_acc", "ref_scale", "ref_scale_hf", "sign_guard"):
        lines.append(f"{key} = {_vec(getattr(mp, key))}")
    lines += [
        f"ref_limit_m_s2 = {_vec(mp.ref_limit[:3])}",
        f"ref_limit_deg_s = {_vec([min(1e9, v * r2d) for v in mp.ref_limit[3:]])}",
    ]
    for key in (
        "prediction_tau_s",
        "ref_split_hz",
        "ref_shape",
        "ref_reach_use",
        "tilt_fz_use",
        "sign_guard_weight",
        "stroke_use",
        "rate_use",
        "deadline_ms",
        "window_s",
        "stride_s",
    ):
        lines.append(f"{key} = {_fmt(getattr(mp, key))}")
    lines.append(f"block_samples = {mp.block_samples}")
    if mp.tilt_rate_limit_rad_s is not None:
        lines.append(f"tilt_rate_limit_deg_s = {_fmt(mp.tilt_rate_limit_rad_s * r2d)}")
    lines += [f"solver = {_quote(mp.solver)}", ""]
    return lines


def _quote(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def write_preset(path: str | Path, text: str) -> Path:
    """Write the preset text atomically (no half-written file on a failure)."""
    from .._atomic import atomic_write_bytes

    return atomic_write_bytes(path, text.encode("utf-8"), what="preset")


def chain_metrics(objective: TuneObjective, params: CueingParams) -> ChainMetrics:
    """Full metrics of ``params`` on the objective's recordings (correlation, false cues)."""
    return objective.metrics(params, full=True)
