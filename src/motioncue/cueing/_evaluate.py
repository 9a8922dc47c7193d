"""Cue quality: vestibular models applied to the vehicle's and the simulator's motion.

The vestibular models, their sources and the perception thresholds are in
:mod:`motioncue.cueing._vestibular` (named model sets; default ``telban-cardullo-2005``,
also ``reid-nahon-zacharias``). Both models are applied to deviations from rest:
``f - [0, 0, g]`` and ``w``, so zero initial filter states mean "upright and still".

Conventions
-----------
ISO 8855 body axes (x forward, y left, z up), attitude ``R = Rz(yaw) Ry(pitch) Rx(roll)``
(platform frame to inertial), specific force ``f = R^T (a - g_vec)`` with
``g_vec = [0, 0, -g]``, so at rest ``f = [0, 0, g]``.

Simulator motion
----------------
From the poses, the platform's inertial acceleration ``a`` is the second difference of the
position, its attitude ``R`` and its Euler rates first differences of the angles. At the
platform origin the rider feels ``f_o = R^T (a + [0, 0, g])`` (which contains the gravity
component of tilt) and ``w = E(roll, pitch) * [roll', pitch', yaw']`` (Euler rates to body
rates). At the head, offset ``r`` (m, platform frame) from the origin,
``f_head = f_o + alpha x r + w x (w x r)`` with ``alpha = dw/dt`` (body frame; the
derivative of the body components of ``w`` equals the body components of the inertial
angular acceleration because ``w x w = 0``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._metrics import CueMetrics, _masks, correlation, cue_metrics
from ._params import GRAVITY_M_S2
from ._vestibular import (
    AXIS_NAMES,
    AXIS_UNITS,
    DEFAULT_MODEL_SET,
    TC_CANAL,
    YM_OTOLITH,
    VestibularModel,
    VestibularModelSet,
    check_weights,
    get_model_set,
    normalised_error_rms,
)

__all__ = [
    "AXIS_NAMES",
    "OTOLITH",
    "SEMICIRCULAR_CANAL",
    "CueingEvaluation",
    "VestibularModel",
    "evaluate_cueing",
    "simulator_motion",
]

#: The Telban & Cardullo (2005) canal (the default set's, identical on the three axes).
SEMICIRCULAR_CANAL: VestibularModel = TC_CANAL
#: The Young & Meiry (1968) otolith with unit DC gain (the ``reid-nahon-zacharias`` set's).
OTOLITH: VestibularModel = YM_OTOLITH


def _rot_columns(
    roll: NDArray[np.float64], pitch: NDArray[np.float64], yaw: NDArray[np.float64]
) -> NDArray[np.float64]:
    """R = Rz(yaw) Ry(pitch) Rx(roll) per sample, shape (N, 3, 3)."""
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    r = np.empty((roll.shape[0], 3, 3))
    r[:, 0, 0] = cy * cp
    r[:, 0, 1] = cy * sp * sr - sy * cr
    r[:, 0, 2] = cy * sp * cr + sy * sr
    r[:, 1, 0] = sy * cp
    r[:, 1, 1] = sy * sp * sr + cy * cr
    r[:, 1, 2] = sy * sp * cr - cy * sr
    r[:, 2, 0] = -sp
    r[:, 2, 1] = cp * sr
    r[:, 2, 2] = cp * cr
    return r


def _check_offset(head_offset_m: ArrayLike | None) -> NDArray[np.float64] | None:
    if head_offset_m is None:
        return None
    r = np.asarray(head_offset_m, dtype=float)
    if r.shape != (3,) or not np.all(np.isfinite(r)) or np.any(np.abs(r) > 10.0):
        raise ConfigError(
            f"head offset {np.asarray(head_offset_m).tolist()!r} is invalid; allowed: three "
            "finite numbers (x, y, z in m from the platform origin, each within +-10 m)"
        )
    return r if np.any(r) else None


def simulator_motion(
    poses: ArrayLike, fs_hz: float, *, head_offset_m: ArrayLike | None = None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Specific force and angular velocity the rider of the platform feels.

    Parameters
    ----------
    poses : (N, 6) array_like
        ``[x, y, z, roll, pitch, yaw]`` (m, rad) sampled at ``fs_hz``, starting at rest.
    fs_hz : float
    head_offset_m : (3,) array_like, optional
        Position of the rider's head relative to the platform origin, platform frame (m,
        ISO 8855). Default: the origin (zero offset, the numbers of earlier versions).

    Returns
    -------
    f_sim : (N, 3) array
        ``R^T (a + [0, 0, g]) + alpha x r + w x (w x r)`` in the platform frame (m/s^2).
    w_sim : (N, 3) array
        Body angular velocity of the platform (rad/s).

    Notes
    -----
    Derivatives are central differences (no delay; second order in the sample period):
    ``v[n] = (p[n+1] - p[n-1]) fs / 2``, ``a[n] = (p[n+1] - 2 p[n] + p[n-1]) fs^2``, and
    ``alpha`` the central difference of ``w``, on the poses extended by
    :func:`extended_poses`: **held before the first sample** (the ride starts from rest, as
    the vestibular filters do) and **continued at the last velocity after the last one** (the
    data ends, the platform's motion does not: nothing is assumed about what comes next, so
    no stop is charged that did not happen). At the last sample this makes the acceleration
    zero and the velocity the backward difference ``(p[N-1] - p[N-2]) fs``; a platform that
    stops within the data is still charged its stop where it happens. :mod:`._bound`'s
    relaxation uses the same convention.
    """
    r_head = _check_offset(head_offset_m)
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[1] != 6:
        raise ConfigError(f"poses must have shape (N, 6); got {p.shape}")
    if p.shape[0] == 0:
        return np.zeros((0, 3)), np.zeros((0, 3))
    ext = extended_poses(p, 2)  # samples -2 .. N+1
    acc = (ext[3:-1, :3] - 2.0 * ext[2:-2, :3] + ext[1:-3, :3]) * (fs_hz * fs_hz)
    # angles and Euler rates at samples -1 .. N (for alpha's central difference)
    ang = ext[1:-1, 3:]
    rates = (ext[2:, 3:] - ext[:-2, 3:]) * (0.5 * fs_hz)
    roll, pitch, yaw = p[:, 3], p[:, 4], p[:, 5]
    r = _rot_columns(roll, pitch, yaw)
    acc[:, 2] += GRAVITY_M_S2
    f_sim = np.einsum("nji,nj->ni", r, acc)  # R^T a
    droll, dpitch, dyaw = rates[:, 0], rates[:, 1], rates[:, 2]
    cr, sr = np.cos(ang[:, 0]), np.sin(ang[:, 0])
    cp, sp = np.cos(ang[:, 1]), np.sin(ang[:, 1])
    w_ext = np.stack(
        [
            droll - sp * dyaw,
            cr * dpitch + sr * cp * dyaw,
            -sr * dpitch + cr * cp * dyaw,
        ],
        axis=1,
    )
    w_sim = w_ext[1:-1]
    if r_head is not None:
        alpha = (w_ext[2:] - w_ext[:-2]) * (0.5 * fs_hz)
        rr = np.broadcast_to(r_head, w_sim.shape)
        f_sim = f_sim + np.cross(alpha, rr) + np.cross(w_sim, np.cross(w_sim, rr))
    return f_sim, w_sim


def extended_poses(poses: ArrayLike, k: int) -> NDArray[np.float64]:
    """The poses with ``k`` samples added at each end, as :func:`simulator_motion` sees them.

    Parameters
    ----------
    poses : (N, D) array_like
        Poses (or any coordinates) sampled at a constant rate, N >= 1.
    k : int
        Samples added at each end (>= 0).

    Returns
    -------
    (N + 2 k, D) array
        ``k`` copies of the first pose (the ride starts from rest), the poses, then ``k``
        samples continuing the last velocity: ``p[N-1] + j (p[N-1] - p[N-2])``, j = 1..k (held
        if N = 1).
    """
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[0] == 0 or k < 0:
        raise ConfigError(f"extended_poses needs poses (N >= 1, D) and k >= 0; got {p.shape}, {k}")
    step = p[-1] - p[-2] if p.shape[0] >= 2 else np.zeros(p.shape[1])
    after = p[-1] + np.arange(1, k + 1)[:, None] * step
    return np.concatenate([np.repeat(p[:1], k, axis=0), p, after], axis=0)


_NOTES = """Notes
  Perceived motion: each channel through the vestibular model set named above (otoliths
  for fx fy fz, semicircular canals for wx wy wz), vehicle and simulator alike, from rest.
  unit     unit of the perceived signal (rad/s channels are shown in deg/s here).
  thr      perception threshold of the axis, in that unit (source: the model set).
  rms err  RMS over time of (perceived simulator - perceived vehicle), in that unit.
  err/thr  rms err divided by thr: the error in just-perceptible steps.
  corr     Pearson correlation of perceived simulator and perceived vehicle (1 = same
           shape; blank when either is constant).
  delay s  lag (s) maximising their cross-correlation within the search window; > 0: the
           simulator's cue comes late; blank when no peak inside the window.
  false n  episodes where |perceived simulator| > thr with the sign opposite to the
           vehicle's (a cue in the wrong direction); false s: their total time (s).
  missed s time (s) when |perceived vehicle| > thr but |perceived simulator| <= thr.
  J        perceived-motion error: sqrt(sum_i w_i mean((sim_i - veh_i)/thr_i)^2 / sum_i w_i),
           dimensionless (in thresholds); relative to standing still, one term of the
           cue score that motioncue tune minimises (motioncue.cueing.cue_score).
  Otolith gain: the otolith models are normalised to unit steady-state gain (published
  K = 0.4 is in afferent firing units), so a sustained force is perceived at its value;
  their lead gives a mid-band gain tau_a/tau_L (2.0 Telban-Cardullo, 2.48 Young-Meiry), so
  brief pulses appear up to that factor larger, for vehicle and simulator alike.
  workspace use: max |pose| / half range per DOF (100% = at the limit).
  share    rendered share rms(sim) / rms(vehicle) of the perceived motion (1 = full size).
  gain     least-squares slope of perceived sim on perceived vehicle (the in-phase share).
  missed%  % of the time |vehicle| > thr and |sim| <= thr (as missed s, per sample).
  revers%  reversals: % of the time both > thr with opposite signs.
  spur%    spurious cues: % of the time |sim| > thr while |vehicle| <= thr (either sign).
  false%   all false cues: % of the time |sim| > thr opposite to the vehicle, any size.
  clamped  % of the frames scaled back into the workspace by the chain (when known)."""


@dataclass(frozen=True, eq=False)
class CueingEvaluation:
    """Perceived motion of vehicle and simulator, and the cue-quality metrics.

    Per-axis arrays are ordered ``fx, fy, fz, wx, wy, wz`` (:data:`AXIS_NAMES`; units
    m/s^2 and rad/s), except ``workspace_use`` which is per DOF
    ``x, y, z, roll, pitch, yaw``.

    Attributes
    ----------
    fs_hz : float
    perceived_vehicle, perceived_sim : (N, 6) arrays
        Otolith output for ``f - [0, 0, g]`` (m/s^2) and canal output for ``w`` (rad/s).
    rms_error : (6,) array
        RMS of ``perceived_sim - perceived_vehicle``.
    correlation : (6,) array
        Pearson correlation; NaN where either signal is constant.
    delay_s : (6,) array
        Lag maximising the cross-correlation within ``+-max_lag_s`` (positive: the
        simulator lags); NaN where undefined (a constant signal, or the maximum on the edge
        of the search window, i.e. no peak).
    false_cue_count : (6,) int array
        Episodes where ``|sim| > threshold`` with the sign opposite to the vehicle's.
    false_cue_time_s : (6,) array
        Total duration of those episodes.
    workspace_use : (6,) array
        ``max |pose| / half range`` per DOF (0 for an unused DOF, inf if a DOF with zero
        range moved).
    thresholds : (6,) array
        The perception thresholds used (m/s^2, rad/s).
    missed_cue_count, missed_cue_time_s : (6,) arrays
        Episodes and total time with ``|vehicle| > threshold`` and ``|sim| <= threshold``.
    perceived_error : float
        :func:`perceived_motion_error` of the run (dimensionless, in thresholds).
    weights : (6,) array
        The channel weights of ``perceived_error``.
    model_set : str
        Name of the vestibular model set.
    head_offset_m : (3,) array
        Head position used for the simulator's specific force (m, platform frame).
    clamped_share : float
        Fraction of the frames the chain clamped to the workspace, when the caller knew it
        (NaN otherwise); carried into :attr:`metrics`.

    The cue strength and cue errors (rendered share, gain, missed cues, reversals, spurious
    and false cues) are :attr:`metrics` (:func:`motioncue.cueing.cue_metrics`).
    """

    fs_hz: float
    perceived_vehicle: NDArray[np.float64]
    perceived_sim: NDArray[np.float64]
    rms_error: NDArray[np.float64]
    correlation: NDArray[np.float64]
    delay_s: NDArray[np.float64]
    false_cue_count: NDArray[np.int64]
    false_cue_time_s: NDArray[np.float64]
    workspace_use: NDArray[np.float64]
    thresholds: NDArray[np.float64]
    missed_cue_count: NDArray[np.int64] = field(default_factory=lambda: np.zeros(6, np.int64))
    missed_cue_time_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    perceived_error: float = math.nan
    weights: NDArray[np.float64] = field(default_factory=lambda: np.ones(6))
    model_set: str = DEFAULT_MODEL_SET
    head_offset_m: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    clamped_share: float = math.nan

    @cached_property
    def metrics(self) -> CueMetrics:
        """:func:`motioncue.cueing.cue_metrics` of the perceived motion (computed once)."""
        c = self.clamped_share
        return cue_metrics(
            self.perceived_vehicle,
            self.perceived_sim,
            self.thresholds,
            clamped_share=c if math.isfinite(c) else None,
        )

    def table(self) -> str:
        """The per-axis metrics table with a units row (no notes)."""

        def num(v: float, fmt: str) -> str:
            return format(v, fmt) if math.isfinite(v) else ""

        head = (
            f"{'axis':<5} {'unit':<6} {'thr':>6} {'rms err':>8} {'err/thr':>7} {'corr':>6} "
            f"{'delay s':>7} {'false n':>7} {'false s':>7} {'missed s':>8}"
        )
        lines = [head]
        for i, name in enumerate(AXIS_NAMES):
            k = 180.0 / math.pi if i >= 3 else 1.0
            unit = "deg/s" if i >= 3 else AXIS_UNITS[i]
            lines.append(
                f"{name:<5} {unit:<6} {self.thresholds[i] * k:6.2f} "
                f"{self.rms_error[i] * k:8.3f} {self.rms_error[i] / self.thresholds[i]:7.2f} "
                f"{num(self.correlation[i], '6.3f'):>6} {num(self.delay_s[i], '7.2f'):>7} "
                f"{int(self.false_cue_count[i]):7d} {self.false_cue_time_s[i]:7.2f} "
                f"{self.missed_cue_time_s[i]:8.2f}"
            )
        return "\n".join(lines)

    def summary(self, *, notes: bool = True) -> str:
        """A plain-text table of the metrics, the objective, and (default) the notes."""
        use = self._workspace_text()
        w = " ".join(f"{v:g}" for v in self.weights)
        r = ", ".join(f"{v:g}" for v in self.head_offset_m)
        lines = [
            f"vestibular models: {self.model_set}; head offset [{r}] m",
            self.table(),
            f"perceived-motion error J = {self.perceived_error:.3f} thresholds "
            f"(weights fx fy fz wx wy wz: {w})",
            use,
            "cue strength and cue errors (share of samples; definitions: "
            "motioncue.cueing.cue_metrics):",
            self.metrics.table(),
        ]
        if notes:
            lines.append(_NOTES)
        return "\n".join(lines)

    def _workspace_text(self) -> str:
        """The workspace-use line: per DOF in %, or why there is no figure."""
        dofs = ("x", "y", "z", "roll", "pitch", "yaw")
        use = np.asarray(self.workspace_use, dtype=float)
        if np.all(np.isnan(use)):
            return "workspace use: not measured (no workspace half range given)"

        def one(d: str, u: float) -> str:
            if math.isnan(u):
                return f"{d} -"
            if math.isinf(u):
                return f"{d} moved (no range)"
            return f"{d} {u:.0%}"

        text = "workspace use: " + "  ".join(one(d, u) for d, u in zip(dofs, use, strict=True))
        if np.any(use[np.isfinite(use) | np.isinf(use)] > 1.0):
            text += (
                "\n  above 100 %: the poses leave the workspace (this is the cue before "
                "workspace limiting, which scales such poses back in generate, bridge and "
                "compare)"
            )
        return text


def _delay(sim: NDArray[np.float64], veh: NDArray[np.float64], fs_hz: float, max_lag: int) -> float:
    from scipy.signal import correlate, correlation_lags

    a = sim - sim.mean()
    b = veh - veh.mean()
    if not (np.any(a) and np.any(b)):
        return math.nan
    c = correlate(a, b, mode="full", method="fft")
    lags = correlation_lags(a.size, b.size, mode="full")
    keep = np.abs(lags) <= max_lag
    lag = int(lags[keep][int(np.argmax(c[keep]))])
    if max_lag > 0 and abs(lag) == max_lag:
        return math.nan  # the best match is at the edge of the search: no peak found
    return lag / fs_hz


def _episodes(mask: NDArray[np.bool_]) -> int:
    if mask.size == 0:
        return 0
    return int(mask[0]) + int(np.count_nonzero(mask[1:] & ~mask[:-1]))


def evaluate_cueing(
    f_vehicle: ArrayLike,
    w_vehicle: ArrayLike,
    poses: ArrayLike,
    fs_hz: float,
    *,
    workspace: ArrayLike | None = None,
    model: str | VestibularModelSet = DEFAULT_MODEL_SET,
    thresholds: ArrayLike | None = None,
    weights: ArrayLike | None = None,
    head_offset_m: ArrayLike | None = None,
    max_lag_s: float = 1.0,
    clamped_share: float | None = None,
) -> CueingEvaluation:
    """Compare the motion the rider of the platform perceives with the vehicle's.

    Parameters
    ----------
    f_vehicle, w_vehicle : (N, 3) array_like
        Vehicle specific force (m/s^2) and angular velocity (rad/s), body frame, finite
        (use :attr:`WashoutResult.f_used` / ``w_used``).
    poses : (N, 6) array_like
        Platform poses at the same samples.
    fs_hz : float
    workspace : (6,) array_like, optional
        Half range per DOF (m, rad) for ``workspace_use``; NaN use if omitted.
    model : str or VestibularModelSet
        Vestibular model set (default ``"telban-cardullo-2005"``).
    thresholds : (6,) array_like, optional
        Perception thresholds (m/s^2 x3, rad/s x3) for the false- and missed-cue metrics and
        the objective; default: the model set's (Reid & Nahon 1985).
    weights : (6,) array_like, optional
        Channel weights of the perceived-motion error (default all 1).
    head_offset_m : (3,) array_like, optional
        Rider's head relative to the platform origin (m, platform frame); default zero.
    max_lag_s : float
        Largest delay searched by the cross-correlation.
    clamped_share : float, optional
        Fraction (0..1) of the frames the chain clamped to the workspace, for
        :attr:`CueingEvaluation.metrics` (which cannot see it in the poses).

    Returns
    -------
    CueingEvaluation
    """
    ms = get_model_set(model)
    wts = check_weights(weights)
    thr = np.asarray(ms.thresholds if thresholds is None else thresholds, dtype=float)
    if thr.shape != (6,) or not np.all(np.isfinite(thr)) or np.any(thr <= 0.0):
        raise ConfigError(
            f"thresholds {np.asarray(thresholds).tolist()!r} are invalid; allowed: 6 finite "
            "numbers > 0 (m/s^2 x3, rad/s x3)"
        )
    if not (math.isfinite(fs_hz) and fs_hz > 0.0):
        raise ConfigError(f"sample rate {fs_hz!r} Hz is invalid; allowed: a finite number > 0")
    if clamped_share is not None and not (0.0 <= float(clamped_share) <= 1.0):
        raise ConfigError(f"clamped share {clamped_share!r} is invalid; allowed: a fraction 0..1")
    f_v = np.asarray(f_vehicle, dtype=float)
    w_v = np.asarray(w_vehicle, dtype=float)
    p = np.asarray(poses, dtype=float)
    n = p.shape[0] if p.ndim == 2 else -1
    if f_v.shape != (n, 3) or w_v.shape != (n, 3) or p.shape != (n, 6):
        raise ConfigError(
            f"need f (N, 3), w (N, 3), poses (N, 6); got {f_v.shape}, {w_v.shape}, {p.shape}"
        )
    if not (np.isfinite(f_v).all() and np.isfinite(w_v).all() and np.isfinite(p).all()):
        raise ConfigError("evaluate_cueing needs finite inputs (use WashoutResult.f_used/w_used)")
    rest = np.array([0.0, 0.0, GRAVITY_M_S2])
    f_s, w_s = simulator_motion(p, fs_hz, head_offset_m=head_offset_m)
    pv = ms.filter(np.concatenate([f_v - rest, w_v], axis=1), fs_hz)
    ps = ms.filter(np.concatenate([f_s - rest, w_s], axis=1), fs_hz)
    err = ps - pv
    rms = np.sqrt(np.mean(err * err, axis=0)) if n else np.zeros(6)
    corr = np.full(6, math.nan)
    delay = np.full(6, math.nan)
    max_lag = max(0, round(max_lag_s * fs_hz))
    count = np.zeros(6, dtype=np.int64)
    ftime = np.zeros(6)
    mcount = np.zeros(6, dtype=np.int64)
    mtime = np.zeros(6)
    masks = _masks(pv, ps, thr)
    for i in range(6):
        a, b = ps[:, i], pv[:, i]
        corr[i] = correlation(a, b)
        if math.isfinite(corr[i]):
            delay[i] = _delay(a, b, fs_hz, max_lag)
        count[i] = _episodes(masks.false[:, i])
        ftime[i] = float(np.count_nonzero(masks.false[:, i])) / fs_hz
        mcount[i] = _episodes(masks.missed[:, i])
        mtime[i] = float(np.count_nonzero(masks.missed[:, i])) / fs_hz
    if workspace is None:
        use = np.full(6, math.nan)
    else:
        ws = np.asarray(workspace, dtype=float)
        peak = np.abs(p).max(axis=0) if n else np.zeros(6)
        with np.errstate(divide="ignore", invalid="ignore"):
            use = np.where(ws > 0.0, peak / np.where(ws > 0.0, ws, 1.0), 0.0)
        use = np.where((ws <= 0.0) & (peak > 0.0), math.inf, use)
    r_head = np.zeros(3) if head_offset_m is None else np.asarray(head_offset_m, dtype=float)
    return CueingEvaluation(
        fs_hz=float(fs_hz),
        perceived_vehicle=pv,
        perceived_sim=ps,
        rms_error=rms,
        correlation=corr,
        delay_s=delay,
        false_cue_count=count,
        false_cue_time_s=ftime,
        workspace_use=use,
        thresholds=thr,
        missed_cue_count=mcount,
        missed_cue_time_s=mtime,
        perceived_error=normalised_error_rms(err, thr, wts),
        weights=wts,
        model_set=ms.name,
        head_offset_m=r_head,
        clamped_share=math.nan if clamped_share is None else float(clamped_share),
    )
