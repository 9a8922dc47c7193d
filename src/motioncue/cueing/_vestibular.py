"""Vestibular models with their sources, perception thresholds, and the perceived-motion error.

Two named model sets, selectable by name (:data:`MODEL_SETS`, :func:`get_model_set`):

``telban-cardullo-2005`` (default)
    R. J. Telban, F. M. Cardullo, *Motion Cueing Algorithm Development: Human-Centered
    Linear and Nonlinear Approaches*, NASA/CR-2005-213747, 2005, chapter 2 (vestibular
    system models), the models they use in the optimal and nonlinear algorithms:

    * semicircular canals, the same on the three axes (Young & Oman torsion pendulum with
      adaptation and the rate-sensitive lead)::

          w_hat / w = 80 * 5.73 s^2 (1 + 0.06 s) / ((1 + 80 s)(1 + 5.73 s)(1 + 0.005 s))

      (adaptation 80 s, cupula long time constant 5.73 s, lead 0.06 s, short time
      constant 0.005 s; unit gain in the band ``1/5.73 << w << 1/0.06`` rad/s);
    * otoliths, the same on the three axes (their revision of Young & Meiry)::

          f_hat / f = K (1 + 10 s) / ((1 + 5 s)(1 + 0.016 s)),  published K = 0.4

``reid-nahon-zacharias``
    L. D. Reid, M. A. Nahon, *Flight simulation motion-base drive algorithms: part 1*,
    UTIAS Report 296, 1985 (vestibular models as an evaluation tool, taken from
    G. L. Zacharias, *Motion cue models for pilot-vehicle analysis*, AMRL-TR-78-2, 1978):

    * semicircular canals per axis, no lead::

          w_hat / w = tau_a tau_L s^2 / ((1 + tau_a s)(1 + tau_L s)(1 + tau_S s))

      with ``tau_a = 30 s``, ``tau_S = 0.1 s`` and ``tau_L`` 6.1 s (roll), 5.3 s (pitch),
      10.2 s (yaw);
    * otoliths (Young & Meiry 1968), the same on the three axes::

          f_hat / f = K (1 + 13.2 s) / ((1 + 5.33 s)(1 + 0.66 s)),  published K = 0.4

Where the sources disagree: the two otolith models differ (Telban & Cardullo's lead
10 s / lag 5 s / 0.016 s against Young & Meiry's 13.2 / 5.33 / 0.66 s), and so do the canal
time constants (80 s adaptation and the 0.06 s lead of Telban & Cardullo against 30 s and no
lead in Reid & Nahon's set); each set follows its own source exactly and neither is mixed
into the other.

Provenance note: the primary PDFs were not in the reference corpus available when this
module was written; the constants are those of the sources as widely reproduced (the
Telban & Cardullo set also in model-predictive cueing code that cites it), and the page
numbers are not given because they could not be checked against the printed page.

Gain convention (the otoliths' "factor of two")
-----------------------------------------------
The published otolith gain ``K = 0.4`` converts to afferent firing rate. Here both otolith
models are normalised to **unit steady-state (DC) gain** (``K = 1``), so a sustained
specific force is perceived at its own value in m/s^2. Their lead makes the mid-band gain
``tau_a / tau_L``: 2.0 for Telban & Cardullo, 2.48 for Young & Meiry. Short pulses of
specific force (between about 0.1 and 10 rad/s) are therefore "perceived" up to 2 to 2.5
times their size by the model, for the vehicle and the simulator alike; this is the model's
rate sensitivity, not a scale error. Plots and tables show this normalised output and say
so in their notes.

Perception thresholds
---------------------
Per axis, from Reid & Nahon (1985) (from Zacharias 1978): specific force 0.17 m/s^2 (x, y),
0.28 m/s^2 (z); angular velocity 3.0 deg/s (roll), 3.6 deg/s (pitch), 2.6 deg/s (yaw). Both
sets use them (Telban & Cardullo work with the same values; as above, not checked against
their printed page). They replace the earlier single 0.17 m/s^2 and 3 deg/s for all axes.

Discretisation
--------------
Each model is a continuous LTI system (:meth:`VestibularModel.to_control` gives the
:class:`control.TransferFunction`, whose poles, zeros, DC gain and frequency response the
tests check against the published constants).
It is discretised by the bilinear (Tustin) transform, poles, zeros and gain mapped in
closed form, and run as second-order sections (:func:`scipy.signal.sosfilt`). The error is
stated exactly: the discrete frequency response is the continuous one at the warped
frequency ``(2/T) tan(w T / 2)``, a relative frequency error of ``(w T)^2 / 12`` (0.03 % at
1 Hz, 0.8 % at 5 Hz, sampling at 100 Hz). The first-order hold (exact for inputs linear
between samples, i.e. identical to :func:`scipy.signal.lsim`) was tried and rejected: the
canal's lead (high-frequency gain 0.06 / 0.005 = 12) amplifies the corners of the
linear interpolation, an error of about 1 % at fs / 50 on smooth (band-limited) signals,
eight times the bilinear transform's.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from .._frozen import readonly

__all__ = [
    "AXIS_NAMES",
    "AXIS_UNITS",
    "DEFAULT_MODEL_SET",
    "DEFAULT_WEIGHTS",
    "MODEL_SETS",
    "VestibularModel",
    "VestibularModelSet",
    "get_model_set",
    "perceived_motion_error",
]

AXIS_NAMES: tuple[str, ...] = ("fx", "fy", "fz", "wx", "wy", "wz")
AXIS_UNITS: tuple[str, ...] = ("m/s^2", "m/s^2", "m/s^2", "rad/s", "rad/s", "rad/s")

Poly = tuple[float, ...]


@dataclass(frozen=True)
class VestibularModel:
    """A continuous vestibular transfer function as a product of low-order factors.

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

    def to_control(self) -> Any:
        """The model as a continuous :class:`control.TransferFunction`."""
        import control

        num, den = self.transfer_function()
        return control.tf(num, den)

    def response(self, w_rad_s: ArrayLike) -> NDArray[np.complex128]:
        """Frequency response ``H(j w)`` of the continuous model (product of the factors)."""
        s = 1j * np.asarray(w_rad_s, dtype=float)
        h = np.ones_like(s)
        for b, a in self.factors:
            h = h * np.polyval(b, s) / np.polyval(a, s)
        return h

    def poles(self) -> NDArray[np.float64]:
        """Continuous poles (rad/s), from the factors' denominators."""
        return np.sort(np.concatenate([np.roots(a).real for _, a in self.factors]))

    def dc_gain(self) -> float:
        """Steady-state gain ``H(0)``."""
        num, den = self.transfer_function()
        return float(num[-1] / den[-1])

    def sos(self, fs_hz: float) -> NDArray[np.float64]:
        """Second-order sections of the bilinear (Tustin) equivalent at ``fs_hz``.

        Exactly ``H_d(exp(j w T)) = H(j (2/T) tan(w T / 2))``: the continuous response at a
        warped frequency (relative frequency error ``(w T)^2 / 12``, 0.03 % at 1 Hz and
        100 Hz sampling); poles, zeros and gain are mapped in closed form
        (:func:`scipy.signal.bilinear_zpk`), so ``s = 0`` zeros land exactly on ``z = 1``.
        """
        if not (math.isfinite(fs_hz) and fs_hz > 0.0):
            raise ConfigError(f"sample rate {fs_hz!r} Hz is invalid; allowed: a finite number > 0")
        return _tustin_sos(self.factors, float(fs_hz)).copy()

    def apply(self, x: ArrayLike, fs_hz: float) -> NDArray[np.float64]:
        """Filter ``x`` (N,) or (N, k) along time from rest."""
        from scipy.signal import sosfilt

        return np.asarray(sosfilt(self.sos(fs_hz), np.asarray(x, dtype=float), axis=0))


@lru_cache(maxsize=64)
def _tustin_sos(factors: tuple[tuple[Poly, Poly], ...], fs_hz: float) -> NDArray[np.float64]:
    from scipy.signal import bilinear_zpk, zpk2sos

    zeros = np.concatenate([np.roots(b) if len(b) > 1 else np.array([]) for b, _ in factors])
    poles = np.concatenate([np.roots(a) for _, a in factors])
    k = float(np.prod([b[0] / a[0] for b, a in factors]))
    zd, pd, kd = bilinear_zpk(zeros, poles, k, fs_hz)
    return readonly(zpk2sos(zd, pd, kd, pairing="nearest"))


def _canal_tc(
    tau_a: float, tau_l: float, tau_lead: float, tau_s: float, src: str, axis: str
) -> VestibularModel:
    lead: tuple[Poly, Poly] = ((tau_lead, 1.0), (tau_s, 1.0))
    if not tau_lead:
        lead = ((1.0,), (tau_s, 1.0))
    return VestibularModel(
        name=f"semicircular canal ({axis})",
        factors=(
            ((tau_a, 0.0), (tau_a, 1.0)),  # adaptation tau_a s / (1 + tau_a s)
            ((tau_l, 0.0), (tau_l, 1.0)),  # cupula long time constant tau_L s / (1 + tau_L s)
            lead,
        ),
        source=src,
    )


def _otolith(tau_a: float, tau_l: float, tau_s: float, src: str) -> VestibularModel:
    return VestibularModel(
        name="otolith",
        factors=(((tau_a, 1.0), (tau_l, 1.0)), ((1.0,), (tau_s, 1.0))),
        source=src,
    )


_TC = "Telban & Cardullo 2005, NASA/CR-2005-213747, ch. 2"
_RN = "Reid & Nahon 1985, UTIAS Report 296 (models of Zacharias 1978)"

#: Telban & Cardullo (2005) canal, identical on the three axes.
TC_CANAL = _canal_tc(80.0, 5.73, 0.06, 0.005, _TC + " (Young & Oman form)", "x, y, z")
#: Telban & Cardullo (2005) otolith, unit DC gain (published K = 0.4).
TC_OTOLITH = _otolith(10.0, 5.0, 0.016, _TC + ", unit DC gain (published K = 0.4)")
#: Young & Meiry (1968) otolith as used by Reid & Nahon, unit DC gain (published K = 0.4).
YM_OTOLITH = _otolith(13.2, 5.33, 0.66, "Young & Meiry 1968 via " + _RN + ", unit DC gain")

#: Per-axis thresholds (m/s^2, m/s^2, m/s^2, rad/s, rad/s, rad/s), Reid & Nahon 1985.
THRESHOLDS: tuple[float, ...] = (
    0.17,
    0.17,
    0.28,
    math.radians(3.0),
    math.radians(3.6),
    math.radians(2.6),
)
_THR_SOURCE = (
    "Reid & Nahon 1985 (UTIAS 296, from Zacharias 1978), as used by Telban & Cardullo 2005: "
    "0.17, 0.17, 0.28 m/s^2; 3.0, 3.6, 2.6 deg/s"
)


@dataclass(frozen=True)
class VestibularModelSet:
    """Otolith and canal models per axis with the perception thresholds, under one name.

    Attributes
    ----------
    name : str
    otolith : tuple of 3 VestibularModel
        Specific-force models for x, y, z (body frame, ISO 8855).
    canal : tuple of 3 VestibularModel
        Angular-velocity models for roll (x), pitch (y), yaw (z).
    thresholds : tuple of 6 floats
        Perception thresholds ``fx, fy, fz`` (m/s^2) and ``wx, wy, wz`` (rad/s).
    source : str
        Where the models and thresholds are published.
    """

    name: str
    otolith: tuple[VestibularModel, VestibularModel, VestibularModel]
    canal: tuple[VestibularModel, VestibularModel, VestibularModel]
    thresholds: tuple[float, ...]
    source: str
    threshold_source: str = field(default=_THR_SOURCE)

    def channel_models(self) -> tuple[VestibularModel, ...]:
        """The six channel models in :data:`AXIS_NAMES` order."""
        return (*self.otolith, *self.canal)

    def otolith_midband_gain(self) -> float:
        """``tau_a / tau_L`` of the x otolith: its gain between the lead and lag corners."""
        (b, a), _ = self.otolith[0].factors
        return float(b[0] / a[0])

    def filter(self, x: ArrayLike, fs_hz: float) -> NDArray[np.float64]:
        """Apply the six channel models to ``x`` (N, 6) from rest, channels grouped by model."""
        from scipy.signal import sosfilt

        arr = np.asarray(x, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != 6:
            raise ConfigError(f"need an (N, 6) array of fx, fy, fz, wx, wy, wz; got {arr.shape}")
        if arr.shape[0] == 0:
            return arr.copy()
        xt = np.ascontiguousarray(arr.T)
        out = np.empty_like(xt)
        for model, idx in _groups(self):
            out[idx] = sosfilt(model.sos(fs_hz), xt[idx], axis=-1)
        return np.ascontiguousarray(out.T)


@lru_cache(maxsize=16)
def _groups(ms: VestibularModelSet) -> tuple[tuple[VestibularModel, list[int]], ...]:
    groups: dict[VestibularModel, list[int]] = {}
    for i, m in enumerate(ms.channel_models()):
        groups.setdefault(m, []).append(i)
    return tuple(groups.items())


MODEL_SETS: Mapping[str, VestibularModelSet] = {
    "telban-cardullo-2005": VestibularModelSet(
        name="telban-cardullo-2005",
        otolith=(TC_OTOLITH, TC_OTOLITH, TC_OTOLITH),
        canal=(TC_CANAL, TC_CANAL, TC_CANAL),
        thresholds=THRESHOLDS,
        source=_TC,
    ),
    "reid-nahon-zacharias": VestibularModelSet(
        name="reid-nahon-zacharias",
        otolith=(YM_OTOLITH, YM_OTOLITH, YM_OTOLITH),
        canal=(
            _canal_tc(30.0, 6.1, 0.0, 0.1, _RN, "roll"),
            _canal_tc(30.0, 5.3, 0.0, 0.1, _RN, "pitch"),
            _canal_tc(30.0, 10.2, 0.0, 0.1, _RN, "yaw"),
        ),
        thresholds=THRESHOLDS,
        source=_RN,
    ),
}

DEFAULT_MODEL_SET = "telban-cardullo-2005"

#: Default channel weights of :func:`perceived_motion_error` (fx, fy, fz, wx, wy, wz).
#: All 1: each channel is already normalised by its perception threshold, so one unit of
#: error means "one just-perceptible step" on every channel and no channel is favoured
#: without evidence; pass other weights to favour, e.g., the horizontal forces.
DEFAULT_WEIGHTS: tuple[float, ...] = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0)


def get_model_set(model: str | VestibularModelSet) -> VestibularModelSet:
    """The model set named ``model`` (or ``model`` itself); :class:`ConfigError` if unknown."""
    if isinstance(model, VestibularModelSet):
        return model
    try:
        return MODEL_SETS[model]
    except (KeyError, TypeError):
        raise ConfigError(
            f"vestibular model set {model!r} is unknown; allowed: {', '.join(MODEL_SETS)}"
        ) from None


def check_weights(weights: ArrayLike | None) -> NDArray[np.float64]:
    """Validated weights (6,), finite, >= 0, not all zero."""
    w = np.asarray(DEFAULT_WEIGHTS if weights is None else weights, dtype=float)
    if w.shape != (6,) or not np.all(np.isfinite(w)) or np.any(w < 0.0) or not np.any(w > 0.0):
        raise ConfigError(
            f"weights {np.asarray(weights).tolist()!r} are invalid; allowed: 6 finite numbers "
            ">= 0, not all zero (fx, fy, fz, wx, wy, wz)"
        )
    return w


def _stack(f: ArrayLike, w: ArrayLike, what: str) -> NDArray[np.float64]:
    fa = np.asarray(f, dtype=float)
    wa = np.asarray(w, dtype=float)
    if fa.ndim != 2 or fa.shape[1] != 3 or wa.shape != fa.shape:
        raise ConfigError(f"{what}: need f (N, 3) and w (N, 3); got {fa.shape}, {wa.shape}")
    return np.concatenate([fa, wa], axis=1)


def normalised_error_rms(
    err: NDArray[np.float64], thresholds: ArrayLike, weights: NDArray[np.float64]
) -> float:
    """``sqrt(sum_i w_i mean((e_i / thr_i)^2) / sum_i w_i)`` of an (N, 6) perceived error."""
    if err.shape[0] == 0:
        return 0.0
    ms = np.mean(np.square(err / np.asarray(thresholds, dtype=float)), axis=0)
    return float(math.sqrt(float(np.dot(weights, ms)) / float(weights.sum())))


def perceived_motion_error(
    vehicle_f: ArrayLike,
    vehicle_w: ArrayLike,
    sim_f: ArrayLike,
    sim_w: ArrayLike,
    fs_hz: float,
    *,
    model: str | VestibularModelSet = DEFAULT_MODEL_SET,
    weights: ArrayLike | None = None,
) -> float:
    """One scalar cue-quality objective: weighted RMS perceived error in thresholds.

    ``J = sqrt( sum_i w_i mean_t((p_sim_i - p_veh_i)^2 / thr_i^2) / sum_i w_i )`` over the
    channels ``i`` = fx, fy, fz (otoliths) and wx, wy, wz (canals), where ``p`` is the
    model set's perceived motion and ``thr_i`` its perception threshold. ``J`` is
    dimensionless: 1 means the perceived motion is off by one threshold, RMS over time and
    channels. Because the models are linear, ``p_sim - p_veh = H (sim - vehicle)``: only the
    difference is filtered (six channels, one pass).

    Parameters
    ----------
    vehicle_f, sim_f : (N, 3) array_like
        Specific force (m/s^2), body frame (ISO 8855, z up, so rest is ``[0, 0, g]``).
    vehicle_w, sim_w : (N, 3) array_like
        Angular velocity (rad/s), body frame.
    fs_hz : float
        Sample rate (Hz).
    model : str or VestibularModelSet
        A name in :data:`MODEL_SETS`; default ``"telban-cardullo-2005"``.
    weights : (6,) array_like, optional
        Non-negative channel weights; default :data:`DEFAULT_WEIGHTS` (all 1).

    Returns
    -------
    float
        ``J`` (thresholds); 0 for empty inputs.
    """
    ms = get_model_set(model)
    w = check_weights(weights)
    if not (math.isfinite(fs_hz) and fs_hz > 0.0):
        raise ConfigError(f"sample rate {fs_hz!r} Hz is invalid; allowed: a finite number > 0")
    veh = _stack(vehicle_f, vehicle_w, "vehicle")
    sim = _stack(sim_f, sim_w, "simulator")
    if veh.shape != sim.shape:
        raise ConfigError(f"vehicle and simulator lengths differ: {veh.shape[0]} != {sim.shape[0]}")
    diff = sim - veh
    if not np.all(np.isfinite(diff)):
        raise ConfigError("perceived_motion_error needs finite inputs")
    return normalised_error_rms(ms.filter(diff, fs_hz), ms.thresholds, w)
