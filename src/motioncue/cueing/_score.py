"""The cue score: one number for how well the rider's perceived motion follows the vehicle's.

Why not the perceived-motion error ``J`` alone
----------------------------------------------
``J`` (:func:`motioncue.cueing.perceived_motion_error`) compares the perceived motion of the
rider with the *unscaled* perceived motion of the vehicle. A racing car pulls 2-4 g for
seconds; a hexapod cues at most about 0.2 g of it (by tilt), so on car drives ``J`` is
dominated by sustained forces no platform can give: on the bundled tuning drives every
preset tried, good or bad, lands within a few per cent of the same ``J``, and ``J`` even
ranks a preset that holds the actuators on their stops for 40 % of a lap above one that does
not. Minimising ``J`` alone therefore tunes for nothing the rider can feel.

The score
---------
``score = J_rel + C + W_false * false + W_missed * missed``, lower is better, every term
dimensionless:

``J_rel``
    ``J`` divided by ``J0``, the ``J`` of a platform that does not move (the vehicle's own
    perceived motion in thresholds; floored at one threshold): 1 means no better than
    standing still. It rewards giving as much of the motion as the platform can.
``C``
    ``sum_i c_i (1 - rho_i) / sum_i c_i`` over the *active* channels, where ``rho_i`` is the
    Pearson correlation of perceived simulator and perceived vehicle motion on channel ``i``
    (a constant signal counts as 0) and ``c_i`` are :data:`CORRELATION_WEIGHTS` (fx and fy
    count double). A channel is active when the vehicle's perceived motion is above its
    threshold at least :data:`ACTIVE_FRACTION` of the time: the shape of a motion nobody
    perceives means nothing (the lateral force of a coordinated turn, for example).
``false``
    the fraction of the time with a false cue on at least one channel: the rider perceives a
    motion above threshold in the direction opposite to the vehicle's ("false cues (all)"
    of :func:`motioncue.cueing.cue_metrics`, the definition of ``motioncue compare``).
``missed``
    the mean over the active channels of the fraction of the time when the vehicle's
    perceived motion is above threshold and the rider's is not ("missed" of
    :func:`motioncue.cueing.cue_metrics`).

The weights (:data:`FALSE_CUE_WEIGHT` 2, :data:`MISSED_CUE_WEIGHT` 0.5) make ten per cent of
false cues cost as much as a correlation 0.2 lower on fx and fy: a cue in the wrong direction
is worse than a cue too weak, and a weak cue is better than none. They are motioncue's
choice, not a published standard; ``motioncue compare`` prints every term so a researcher
can weigh them differently.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._metrics import _masks, correlation
from ._vestibular import check_weights, normalised_error_rms

__all__ = [
    "ACTIVE_FRACTION",
    "CORRELATION_WEIGHTS",
    "FALSE_CUE_WEIGHT",
    "MISSED_CUE_WEIGHT",
    "CueScore",
    "cue_score",
]

CORRELATION_WEIGHTS: tuple[float, ...] = (2.0, 2.0, 1.0, 1.0, 1.0, 1.0)
"""Weights of ``1 - rho`` per channel (fx fy fz wx wy wz)."""

FALSE_CUE_WEIGHT = 2.0
"""Weight of the false-cue fraction (any channel)."""

MISSED_CUE_WEIGHT = 0.5
"""Weight of the mean missed-cue fraction (active channels)."""

ACTIVE_FRACTION = 0.05
"""A channel counts in ``C`` and ``missed`` when the vehicle's perceived motion is above
threshold at least this fraction of the time."""


@dataclass(frozen=True, eq=False)
class CueScore:
    """The cue score of one run and its terms (see the module docstring).

    Attributes
    ----------
    score : float
        ``relative_error + correlation_term + 2 false_fraction + 0.5 missed_fraction``.
    relative_error : float
        ``J / J0``.
    correlation_term : float
        Weighted mean of ``1 - rho`` over the active channels (0 when none is active).
    false_fraction : float
        Fraction of the samples with a false cue on any channel.
    missed_fraction : float
        Mean missed-cue fraction over the active channels (0 when none is active).
    correlation : (6,) array
        Per-channel correlation (NaN where a signal is constant).
    active : (6,) bool array
    """

    score: float
    relative_error: float
    correlation_term: float
    false_fraction: float
    missed_fraction: float
    correlation: NDArray[np.float64]
    active: NDArray[np.bool_]


def cue_score(
    perceived_vehicle: ArrayLike,
    perceived_sim: ArrayLike,
    thresholds: ArrayLike,
    *,
    weights: ArrayLike | None = None,
) -> CueScore:
    """Score perceived motion (see the module docstring for the definition).

    Parameters
    ----------
    perceived_vehicle, perceived_sim : (N, 6) array_like
        Perceived specific force minus rest (m/s^2, fx fy fz) and angular velocity (rad/s,
        wx wy wz), e.g. :attr:`CueingEvaluation.perceived_vehicle` / ``perceived_sim``.
    thresholds : (6,) array_like
        Perception thresholds (m/s^2 x3, rad/s x3), > 0.
    weights : (6,) array_like, optional
        Channel weights of ``J`` (default all 1).

    Returns
    -------
    CueScore
    """
    pv = np.asarray(perceived_vehicle, dtype=float)
    ps = np.asarray(perceived_sim, dtype=float)
    thr = np.asarray(thresholds, dtype=float)
    if pv.ndim != 2 or pv.shape[1] != 6 or ps.shape != pv.shape:
        raise ConfigError(f"cue_score needs two (N, 6) arrays; got {pv.shape} and {ps.shape}")
    if thr.shape != (6,) or not np.all(np.isfinite(thr)) or np.any(thr <= 0.0):
        raise ConfigError(f"thresholds {thr.tolist()!r} are invalid; allowed: 6 numbers > 0")
    if not (np.isfinite(pv).all() and np.isfinite(ps).all()):
        raise ConfigError("cue_score needs finite perceived motion")
    w = check_weights(weights)
    n = pv.shape[0]
    pst, pvt = np.ascontiguousarray(ps.T), np.ascontiguousarray(pv.T)
    corr = np.array([correlation(pst[i], pvt[i]) for i in range(6)])
    if n == 0:
        return CueScore(0.0, 0.0, 0.0, 0.0, 0.0, corr, np.zeros(6, dtype=bool))
    masks = _masks(pv, ps, thr)
    active = (np.abs(pv) > thr).mean(axis=0) >= ACTIVE_FRACTION
    j = normalised_error_rms(ps - pv, thr, w)
    j0 = max(normalised_error_rms(pv, thr, w), 1.0)
    cw = np.where(active, np.asarray(CORRELATION_WEIGHTS), 0.0)
    rho = np.nan_to_num(corr, nan=0.0)
    c_term = float(np.dot(cw, 1.0 - rho) / cw.sum()) if cw.sum() > 0.0 else 0.0
    false = float(np.mean(np.any(masks.false, axis=1)))
    missed_ch = np.mean(masks.missed, axis=0)
    missed = float(missed_ch[active].mean()) if active.any() else 0.0
    rel = j / j0
    score = rel + c_term + FALSE_CUE_WEIGHT * false + MISSED_CUE_WEIGHT * missed
    return CueScore(
        score=float(score),
        relative_error=float(rel),
        correlation_term=c_term,
        false_fraction=false,
        missed_fraction=missed,
        correlation=corr,
        active=active,
    )
