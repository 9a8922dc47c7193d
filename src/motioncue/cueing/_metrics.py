"""Cue strength and cue errors: how much of the vehicle's perceived motion the rider gets.

The definitions are written once, here and in ``docs/cue-metrics.md``; every table, JSON
file and docstring of motioncue that shows one of these figures refers to them.

Signature (stable API)
----------------------
``cue_metrics(perceived_vehicle, perceived_platform, thresholds, *, clamped_share=None)
-> CueMetrics``

* ``perceived_vehicle``, ``perceived_platform``: (N, 6) arrays, the vestibular models'
  output (:class:`motioncue.cueing.VestibularModelSet.filter`) for the vehicle's and the
  platform's motion as deviations from rest, channels ``fx fy fz`` (m/s^2) and ``wx wy wz``
  (rad/s); e.g. :attr:`CueingEvaluation.perceived_vehicle` and ``perceived_sim``.
* ``thresholds``: (6,) perception thresholds in the same units, > 0.
* ``clamped_share``: fraction (0..1) of the frames the chain clamped to the workspace;
  the metrics cannot see it in perceived motion, so the chain passes it in (NaN if omitted).

To pool several drives, concatenate their perceived motion along time (the pooled share is
then the RMS ratio over all samples, the pooled correlation that of all samples).

Definitions (per channel ``i``, ``v`` the perceived vehicle, ``p`` the perceived platform,
``thr`` the threshold; fractions are of all ``N`` samples)
-------------------------------------------------------------------------------------
rendered share
    ``rms(p) / rms(v)``: how strong the cue is relative to the vehicle's (1 = full size,
    0 = nothing). NaN where ``v`` is identically zero. Blind to shape and sign: read it with
    the correlation and the reversals.
gain
    The least-squares slope of felt on vehicle through the origin,
    ``k = sum(p v) / sum(v v)``, the ``k`` minimising ``sum (p - k v)^2``: the share of the
    vehicle's motion the rider gets *in phase* (``share * corr`` for zero-mean signals).
    Differs from the share when the cue is delayed, distorted or of the wrong sign.
correlation
    Pearson correlation of ``p`` and ``v`` (1 = same shape, any scale); NaN where either is
    constant.
missed
    ``|v| > thr`` and ``|p| <= thr``: the vehicle's motion is perceptible, the rider's not.
reversals
    ``|v| > thr``, ``|p| > thr`` and ``p v < 0``: both perceptible, in opposite directions.
spurious
    ``|p| > thr`` and ``|v| <= thr``: the rider perceives a motion the vehicle does not
    make (either sign).
false cues (all)
    ``|p| > thr`` and ``p v < 0``: the rider perceives a motion opposite to the vehicle's,
    whatever the vehicle's size (reversals plus the opposite-sign part of the spurious
    cues). The definition of ``motioncue compare``'s false-cue columns and of the cue score.
clamped
    Share of the frames the chain scaled back into the platform's workspace (passed in).

The ``*_any`` figures are the fraction of samples with that event on at least one channel.

Sources
-------
Missed and false cues against perception thresholds follow L. D. Reid, M. A. Nahon,
*Flight simulation motion-base drive algorithms*, UTIAS Reports 296 (1985) and 307 (1986)
(vestibular models as an evaluation tool) and R. J. Telban, F. M. Cardullo,
NASA/CR-2005-213747 (2005), whose thresholds :mod:`motioncue.cueing._vestibular` uses; the
split of false cues into reversals and spurious cues and the rendered share (a motion
scaling factor) follow the driving-simulator literature on motion scaling, e.g.
A. Berthoz et al., *Motion scaling for high-performance driving simulators*, IEEE Trans.
Human-Machine Systems 43 (2013), where drivers preferred rendered gains of about 0.4-0.75.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._vestibular import AXIS_NAMES

__all__ = ["JOLT_CUTOFF_HZ", "CueMasks", "CueMetrics", "cue_masks", "cue_metrics", "jolt"]


class CueMasks(NamedTuple):
    """Per-sample events (N, 6) bool, as defined in :func:`motioncue.cueing.cue_metrics`."""

    missed: NDArray[np.bool_]
    reversal: NDArray[np.bool_]
    spurious: NDArray[np.bool_]
    false: NDArray[np.bool_]


def _check(
    perceived_vehicle: ArrayLike, perceived_platform: ArrayLike, thresholds: ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    pv = np.asarray(perceived_vehicle, dtype=float)
    ps = np.asarray(perceived_platform, dtype=float)
    thr = np.asarray(thresholds, dtype=float)
    if pv.ndim != 2 or pv.shape[1] != 6 or ps.shape != pv.shape:
        raise ConfigError(
            f"cue metrics need two (N, 6) arrays of perceived motion; got {pv.shape} and {ps.shape}"
        )
    if thr.shape != (6,) or not np.all(np.isfinite(thr)) or np.any(thr <= 0.0):
        raise ConfigError(
            f"thresholds {thr.tolist()!r} are invalid; allowed: 6 finite numbers > 0 "
            "(m/s^2 x3, rad/s x3)"
        )
    if not (np.isfinite(pv).all() and np.isfinite(ps).all()):
        raise ConfigError("cue metrics need finite perceived motion")
    return pv, ps, thr


def cue_masks(
    perceived_vehicle: ArrayLike, perceived_platform: ArrayLike, thresholds: ArrayLike
) -> CueMasks:
    """The per-sample missed, reversed, spurious and false cues (module docstring).

    Parameters
    ----------
    perceived_vehicle, perceived_platform : (N, 6) array_like
        Perceived motion (m/s^2 x3, rad/s x3), deviations from rest.
    thresholds : (6,) array_like
        Perception thresholds, > 0.

    Returns
    -------
    CueMasks
        Four (N, 6) boolean arrays.
    """
    pv, ps, thr = _check(perceived_vehicle, perceived_platform, thresholds)
    return _masks(pv, ps, thr)


def _masks(pv: NDArray[np.float64], ps: NDArray[np.float64], thr: NDArray[np.float64]) -> CueMasks:
    above_v = np.abs(pv) > thr
    above_p = np.abs(ps) > thr
    opposite = ps * pv < 0.0
    return CueMasks(
        missed=above_v & ~above_p,
        reversal=above_v & above_p & opposite,
        spurious=above_p & ~above_v,
        false=above_p & opposite,
    )


def correlation(a: NDArray[np.float64], b: NDArray[np.float64]) -> float:
    """Pearson correlation of two (N,) signals; NaN if N < 2 or either is constant."""
    if a.shape[0] < 2:
        return math.nan
    da, db = a - a.mean(), b - b.mean()
    # elementwise sums, not BLAS dot: threaded BLAS on a loaded machine is far slower here
    sa, sb = float(np.sum(da * da)), float(np.sum(db * db))
    if sa <= 0.0 or sb <= 0.0:
        return math.nan
    return float(np.sum(da * db) / math.sqrt(sa * sb))


def _clean(v: float) -> float | None:
    return v if math.isfinite(v) else None


@dataclass(frozen=True, eq=False)
class CueMetrics:
    """Cue strength and cue errors of one run (definitions: :func:`cue_metrics`).

    Per-channel arrays are (6,), ordered ``fx fy fz wx wy wz`` (:data:`AXIS_NAMES`);
    fractions are of all samples (0..1).

    Attributes
    ----------
    rendered_share : (6,) array
        ``rms(p) / rms(v)``; NaN where the vehicle's perceived motion is zero.
    gain : (6,) array
        Least-squares slope ``sum(p v) / sum(v v)``; NaN where the vehicle's is zero.
    correlation : (6,) array
        Pearson correlation; NaN where either signal is constant.
    missed, reversals, spurious, false_cues : (6,) arrays
        Fractions of the samples with each event.
    vehicle_above : (6,) array
        Fraction of the samples with ``|v| > thr`` (the most a channel can miss).
    missed_any, reversals_any, spurious_any, false_any : float
        Fractions of the samples with the event on at least one channel.
    clamped : float
        Share of the frames clamped to the workspace (passed in; NaN if unknown).
    thresholds : (6,) array
        The thresholds used (m/s^2 x3, rad/s x3).
    n_samples : int
    """

    rendered_share: NDArray[np.float64]
    gain: NDArray[np.float64]
    correlation: NDArray[np.float64]
    missed: NDArray[np.float64]
    reversals: NDArray[np.float64]
    spurious: NDArray[np.float64]
    false_cues: NDArray[np.float64]
    vehicle_above: NDArray[np.float64]
    missed_any: float
    reversals_any: float
    spurious_any: float
    false_any: float
    clamped: float
    thresholds: NDArray[np.float64]
    n_samples: int

    PER_CHANNEL = (
        "rendered_share",
        "gain",
        "correlation",
        "missed",
        "reversals",
        "spurious",
        "false_cues",
        "vehicle_above",
    )
    """The per-channel fields, in :meth:`to_dict`'s order."""

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: per-channel figures as ``{field: {channel: value}}`` (NaN as None),
        the ``*_any`` figures, ``clamped`` and ``n_samples``."""
        out: dict[str, object] = {}
        for name in self.PER_CHANNEL:
            arr = getattr(self, name)
            out[name] = {a: _clean(float(v)) for a, v in zip(AXIS_NAMES, arr, strict=True)}
        for name in ("missed_any", "reversals_any", "spurious_any", "false_any", "clamped"):
            out[name] = _clean(float(getattr(self, name)))
        out["n_samples"] = int(self.n_samples)
        return out

    def table(self, channels: tuple[int, ...] = (0, 1, 2, 3, 4, 5)) -> str:
        """A plain-text table: one row per channel, shares and gains as numbers, events in %."""

        def num(v: float, fmt: str) -> str:
            return format(v, fmt) if math.isfinite(v) else "-"

        head = (
            f"{'axis':<5} {'share':>6} {'gain':>6} {'corr':>6} {'missed%':>7} {'revers%':>7} "
            f"{'spur%':>6} {'false%':>6}"
        )
        lines = [head]
        for i in channels:
            lines.append(
                f"{AXIS_NAMES[i]:<5} {num(self.rendered_share[i], '6.3f'):>6} "
                f"{num(self.gain[i], '6.3f'):>6} {num(self.correlation[i], '6.3f'):>6} "
                f"{100 * self.missed[i]:7.1f} {100 * self.reversals[i]:7.2f} "
                f"{100 * self.spurious[i]:6.1f} {100 * self.false_cues[i]:6.2f}"
            )
        clamp = "-" if not math.isfinite(self.clamped) else f"{100 * self.clamped:.2f} %"
        lines.append(
            f"any   missed {100 * self.missed_any:.1f} %, reversals "
            f"{100 * self.reversals_any:.2f} %, spurious {100 * self.spurious_any:.1f} %, "
            f"false {100 * self.false_any:.2f} %, clamped {clamp}"
        )
        return "\n".join(lines)


def cue_metrics(
    perceived_vehicle: ArrayLike,
    perceived_platform: ArrayLike,
    thresholds: ArrayLike,
    *,
    clamped_share: float | None = None,
) -> CueMetrics:
    """Rendered share, gain, correlation, missed/reversed/spurious/false cues of one run.

    Definitions and sources: the module docstring and
    ``docs/cue-metrics.md``.

    Parameters
    ----------
    perceived_vehicle, perceived_platform : (N, 6) array_like
        Perceived motion of the vehicle and of the platform's rider, deviations from rest
        (m/s^2 for fx fy fz, rad/s for wx wy wz), finite.
    thresholds : (6,) array_like
        Perception thresholds (m/s^2 x3, rad/s x3), finite and > 0.
    clamped_share : float, optional
        Fraction (0..1) of the frames clamped to the workspace by the chain; NaN if omitted.

    Returns
    -------
    CueMetrics

    Raises
    ------
    ConfigError
        Shapes, non-finite values, thresholds <= 0, or a clamped share outside 0..1.
    """
    pv, ps, thr = _check(perceived_vehicle, perceived_platform, thresholds)
    if clamped_share is None:
        clamped = math.nan
    else:
        clamped = float(clamped_share)
        if not (0.0 <= clamped <= 1.0):
            raise ConfigError(
                f"clamped share {clamped_share!r} is invalid; allowed: a fraction 0..1"
            )
    n = pv.shape[0]
    pst, pvt = np.ascontiguousarray(ps.T), np.ascontiguousarray(pv.T)
    corr = np.array([correlation(pst[i], pvt[i]) for i in range(6)])
    vv = np.sum(pvt * pvt, axis=1)
    pp = np.sum(pst * pst, axis=1)
    pvp = np.sum(pst * pvt, axis=1)
    ok = vv > 0.0
    safe = np.where(ok, vv, 1.0)
    share = np.where(ok, np.sqrt(pp / safe), math.nan)
    gain = np.where(ok, pvp / safe, math.nan)
    if n == 0:
        zeros = np.zeros(6)
        return CueMetrics(
            share, gain, corr, zeros, zeros.copy(), zeros.copy(), zeros.copy(), zeros.copy(),
            0.0, 0.0, 0.0, 0.0, clamped, thr, 0,
        )  # fmt: skip
    m = _masks(pv, ps, thr)
    return CueMetrics(
        rendered_share=share,
        gain=gain,
        correlation=corr,
        missed=m.missed.mean(axis=0),
        reversals=m.reversal.mean(axis=0),
        spurious=m.spurious.mean(axis=0),
        false_cues=m.false.mean(axis=0),
        vehicle_above=(np.abs(pv) > thr).mean(axis=0),
        missed_any=float(m.missed.any(axis=1).mean()),
        reversals_any=float(m.reversal.any(axis=1).mean()),
        spurious_any=float(m.spurious.any(axis=1).mean()),
        false_any=float(m.false.any(axis=1).mean()),
        clamped=clamped,
        thresholds=thr,
        n_samples=int(n),
    )


JOLT_CUTOFF_HZ = 2.0
"""Lower edge (Hz) of the band :func:`jolt` measures."""


def jolt(
    perceived: ArrayLike, fs_hz: float, thresholds: ArrayLike, cutoff_hz: float = JOLT_CUTOFF_HZ
) -> NDArray[np.float64]:
    """The brief pulses in a perceived motion: its rms above ``cutoff_hz``, in thresholds.

    Parameters
    ----------
    perceived : (N, k) array_like
        Perceived motion (the vestibular models' output, e.g.
        :attr:`CueingEvaluation.perceived_sim`), uniform at ``fs_hz``.
    fs_hz : float
        Sample rate (Hz), above ``2 cutoff_hz``.
    thresholds : (k,) array_like
        Perception thresholds of the channels (> 0, the units of ``perceived``).
    cutoff_hz : float
        The band's lower edge (Hz; default 2 Hz, above the sustained and onset cues of a
        vehicle's manoeuvres and below road texture's 6-20 Hz).

    Returns
    -------
    (k,) ndarray
        Per channel the rms of ``perceived`` through a 4th-order Butterworth high-pass at
        ``cutoff_hz`` run forwards and backwards (zero phase, so a pulse is not moved),
        divided by the threshold. A steady or slowly varying motion gives about 0, a
        sinusoid well above the cutoff of amplitude ``a`` about ``a / sqrt(2) / thr``. The
        vehicle's own (road texture, kerbs) is the reference for a simulator's: a simulator
        far above it gives pulses the vehicle did not have (a plan's steps of acceleration
        through the otoliths' lead felt as knocks). Shorter than 30 samples: NaN.
    """
    from scipy.signal import butter, sosfiltfilt

    p = np.asarray(perceived, dtype=float)
    thr = np.asarray(thresholds, dtype=float)
    if p.ndim != 2 or thr.shape != (p.shape[1],) or np.any(~(thr > 0.0)):
        raise ConfigError(
            f"jolt needs perceived (N, k) and k thresholds > 0; got {p.shape} and {thr.shape}"
        )
    if not (math.isfinite(fs_hz) and math.isfinite(cutoff_hz) and 0.0 < 2.0 * cutoff_hz < fs_hz):
        raise ConfigError(
            f"jolt: cutoff {cutoff_hz!r} Hz at {fs_hz!r} Hz is invalid; allowed: 0 < cutoff "
            "< fs / 2"
        )
    if p.shape[0] < 30:
        return np.full(p.shape[1], np.nan)
    sos = butter(4, cutoff_hz, "highpass", fs=fs_hz, output="sos")
    hp = sosfiltfilt(sos, np.nan_to_num(p), axis=0)
    return np.asarray(np.sqrt(np.mean(hp**2, axis=0)) / thr, dtype=float)
