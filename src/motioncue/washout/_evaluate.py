"""Cue quality: vestibular models applied to the vehicle's and the simulator's motion.

Vestibular models (continuous, per axis, identical on the three axes)
---------------------------------------------------------------------
Semicircular canals (angular velocity -> perceived angular velocity), the Young & Oman
torsion-pendulum model with adaptation and rate sensitivity, with the parameters used in
motion-cueing work by Telban & Cardullo:

    w_hat / w = 80 s * 5.73 s * (1 + 0.06 s) / ((1 + 80 s)(1 + 5.73 s)(1 + 0.005 s))

(long time constant 5.73 s, adaptation 80 s, lead 0.06 s, short time constant 0.005 s;
unit gain in the mid band ``1/5.73 << w << 1/0.06`` rad/s).

Otoliths (specific force -> perceived specific force), Young & Meiry (1968):

    f_hat / f = K (1 + 13.2 s) / ((1 + 5.33 s)(1 + 0.66 s))

with ``K = 1`` here (Young & Meiry's ``K = 0.4`` converts to afferent firing units; unit
DC gain keeps perceived force in m/s^2), so the mid-band gain is ``13.2 / 5.33 = 2.48``.

Sources
-------
* L. R. Young, C. M. Oman, "Model for vestibular adaptation to horizontal rotation",
  Aerospace Medicine 40(10), 1969, 1076-1080.
* L. R. Young, J. L. Meiry, "A revised dynamic otolith model", Aerospace Medicine 39(6),
  1968, 606-608.
* R. J. Telban, F. M. Cardullo, "Motion cueing algorithm development: human-centered
  linear and nonlinear approaches", NASA/CR-2005-213747, 2005 (the canal parameters above
  and the use of both models for cue evaluation).
* L. D. Reid, M. A. Nahon, UTIAS Report 296, 1985 (vestibular models as an evaluation tool
  for washout algorithms).

Both models are applied to deviations from rest: ``f - [0, 0, g]`` and ``w``, so zero
initial filter states mean "upright and still". Each first-order factor is discretised by
the bilinear transform (no prewarp, so any sample rate works) and run as one section.

Simulator motion
----------------
From the poses, the platform's inertial acceleration ``a`` is the second difference of the
position, its attitude ``R = Rz Ry Rx`` and its Euler rates first differences of the angles.
The rider feels ``f_sim = R^T (a + [0, 0, g])`` (which contains the gravity component of
tilt) and ``w_sim = E(roll, pitch) * [roll', pitch', yaw']`` (Euler rates to body rates).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._filters import Section, tustin_section
from ._params import GRAVITY_M_S2

__all__ = [
    "AXIS_NAMES",
    "OTOLITH",
    "SEMICIRCULAR_CANAL",
    "CueingEvaluation",
    "VestibularModel",
    "evaluate_cueing",
    "simulator_motion",
]

AXIS_NAMES: tuple[str, ...] = ("fx", "fy", "fz", "wx", "wy", "wz")

Poly = tuple[float, ...]


@dataclass(frozen=True)
class VestibularModel:
    """A continuous vestibular transfer function as a product of first-order factors.

    Attributes
    ----------
    name : str
    factors : tuple of (num, den)
        Polynomials in ``s``, highest power first; the model is their product.
    source : str
        Where the transfer function is published.
    """

    name: str
    factors: tuple[tuple[Poly, Poly], ...]
    source: str

    def transfer_function(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(num, den)`` of the whole model, highest power of ``s`` first."""
        num = np.array([1.0])
        den = np.array([1.0])
        for b, a in self.factors:
            num = np.polymul(num, b)
            den = np.polymul(den, a)
        return num, den

    def response(self, w_rad_s: ArrayLike) -> NDArray[np.complex128]:
        """Frequency response ``H(j w)`` of the continuous model."""
        s = 1j * np.asarray(w_rad_s, dtype=float)
        h = np.ones_like(s)
        for b, a in self.factors:
            h = h * np.polyval(b, s) / np.polyval(a, s)
        return h

    def sos(self, fs_hz: float) -> NDArray[np.float64]:
        """Second-order sections of the bilinear-discretised model at ``fs_hz``."""
        secs: list[Section] = [tustin_section(b, a, fs_hz, None) for b, a in self.factors]
        return np.array(secs)

    def apply(self, x: ArrayLike, fs_hz: float) -> NDArray[np.float64]:
        """Filter ``x`` (N,) or (N, k) along time from rest."""
        from scipy.signal import sosfilt

        return np.asarray(sosfilt(self.sos(fs_hz), np.asarray(x, dtype=float), axis=0))


SEMICIRCULAR_CANAL = VestibularModel(
    name="semicircular canals",
    factors=(
        ((80.0, 0.0), (80.0, 1.0)),  # adaptation: 80 s / (1 + 80 s)
        ((5.73, 0.0), (5.73, 1.0)),  # cupula long time constant: 5.73 s / (1 + 5.73 s)
        ((0.06, 1.0), (0.005, 1.0)),  # rate sensitivity lead / short time constant
    ),
    source="Young & Oman 1969 form, parameters of Telban & Cardullo 2005 (NASA/CR-2005-213747)",
)

OTOLITH = VestibularModel(
    name="otoliths",
    factors=(
        ((13.2, 1.0), (5.33, 1.0)),  # (1 + 13.2 s) / (1 + 5.33 s)
        ((1.0,), (0.66, 1.0)),  # 1 / (1 + 0.66 s)
    ),
    source="Young & Meiry 1968, unit DC gain",
)


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


def simulator_motion(
    poses: ArrayLike, fs_hz: float
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Specific force and angular velocity the rider of the platform feels.

    Parameters
    ----------
    poses : (N, 6) array_like
        ``[x, y, z, roll, pitch, yaw]`` (m, rad) sampled at ``fs_hz``, starting at rest.
    fs_hz : float

    Returns
    -------
    f_sim : (N, 3) array
        ``R^T (a + [0, 0, g])`` in the platform frame (m/s^2).
    w_sim : (N, 3) array
        Body angular velocity of the platform (rad/s).

    Notes
    -----
    Derivatives are central differences (no delay; second order in the sample period):
    ``v[n] = (p[n+1] - p[n-1]) fs / 2``, ``a[n] = (p[n+1] - 2 p[n] + p[n-1]) fs^2``, with
    the pose held constant before the first and after the last sample.
    """
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[1] != 6:
        raise ConfigError(f"poses must have shape (N, 6); got {p.shape}")
    pad = np.concatenate([p[:1], p, p[-1:]], axis=0)
    acc = (pad[2:, :3] - 2.0 * pad[1:-1, :3] + pad[:-2, :3]) * (fs_hz * fs_hz)
    rates = (pad[2:, 3:] - pad[:-2, 3:]) * (0.5 * fs_hz)
    roll, pitch, yaw = p[:, 3], p[:, 4], p[:, 5]
    r = _rot_columns(roll, pitch, yaw)
    acc[:, 2] += GRAVITY_M_S2
    f_sim = np.einsum("nji,nj->ni", r, acc)  # R^T a
    droll, dpitch, dyaw = rates[:, 0], rates[:, 1], rates[:, 2]
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    w_sim = np.stack(
        [
            droll - sp * dyaw,
            cr * dpitch + sr * cp * dyaw,
            -sr * dpitch + cr * cp * dyaw,
        ],
        axis=1,
    )
    return f_sim, w_sim


@dataclass(frozen=True, eq=False)
class CueingEvaluation:
    """Perceived motion of vehicle and simulator, and the cue-quality metrics.

    Per-axis arrays are ordered ``fx, fy, fz, wx, wy, wz`` (:data:`AXIS_NAMES`), except
    ``workspace_use`` which is per DOF ``x, y, z, roll, pitch, yaw``.

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
        The false-cue thresholds used (m/s^2, rad/s).
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

    def summary(self) -> str:
        """A plain-text table of the metrics."""
        head = f"{'axis':>5} {'rms err':>9} {'corr':>6} {'delay s':>8} {'false':>6} {'false s':>8}"
        lines = [head]
        for i, name in enumerate(AXIS_NAMES):
            lines.append(
                f"{name:>5} {self.rms_error[i]:9.4f} {self.correlation[i]:6.3f} "
                f"{self.delay_s[i]:8.3f} {int(self.false_cue_count[i]):6d} "
                f"{self.false_cue_time_s[i]:8.2f}"
            )
        dofs = ("x", "y", "z", "roll", "pitch", "yaw")
        use = "  ".join(f"{d} {u:.0%}" for d, u in zip(dofs, self.workspace_use, strict=True))
        lines.append(f"workspace use: {use}")
        return "\n".join(lines)


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
    f_threshold_m_s2: float = 0.17,
    w_threshold_rad_s: float = math.radians(3.0),
    max_lag_s: float = 1.0,
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
    f_threshold_m_s2, w_threshold_rad_s : float
        Perceived magnitude above which a cue of the wrong sign counts as a false cue
        (defaults: 0.17 m/s^2 and 3 deg/s, customary vestibular thresholds).
    max_lag_s : float
        Largest delay searched by the cross-correlation.

    Returns
    -------
    CueingEvaluation
    """
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
    f_s, w_s = simulator_motion(p, fs_hz)
    oto = OTOLITH.sos(fs_hz)
    scc = SEMICIRCULAR_CANAL.sos(fs_hz)
    from scipy.signal import sosfilt

    pv = np.concatenate([sosfilt(oto, f_v - rest, axis=0), sosfilt(scc, w_v, axis=0)], axis=1)
    ps = np.concatenate([sosfilt(oto, f_s - rest, axis=0), sosfilt(scc, w_s, axis=0)], axis=1)
    err = ps - pv
    rms = np.sqrt(np.mean(err * err, axis=0)) if n else np.zeros(6)
    corr = np.full(6, math.nan)
    delay = np.full(6, math.nan)
    max_lag = max(0, round(max_lag_s * fs_hz))
    thr = np.array([f_threshold_m_s2] * 3 + [w_threshold_rad_s] * 3)
    count = np.zeros(6, dtype=np.int64)
    ftime = np.zeros(6)
    for i in range(6):
        a, b = ps[:, i], pv[:, i]
        if n > 1 and a.std() > 0.0 and b.std() > 0.0:
            corr[i] = float(np.corrcoef(a, b)[0, 1])
            delay[i] = _delay(a, b, fs_hz, max_lag)
        mask = (np.abs(a) > thr[i]) & (a * b < 0.0)
        count[i] = _episodes(mask)
        ftime[i] = float(np.count_nonzero(mask)) / fs_hz
    if workspace is None:
        use = np.full(6, math.nan)
    else:
        ws = np.asarray(workspace, dtype=float)
        peak = np.abs(p).max(axis=0) if n else np.zeros(6)
        with np.errstate(divide="ignore", invalid="ignore"):
            use = np.where(ws > 0.0, peak / np.where(ws > 0.0, ws, 1.0), 0.0)
        use = np.where((ws <= 0.0) & (peak > 0.0), math.inf, use)
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
    )
