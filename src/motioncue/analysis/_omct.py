"""The Objective Motion Cueing Test (OMCT): frequency response of the whole motion chain.

What is measured
----------------
The OMCT (Hosman & Advani; ICAO 9625) measures the frequency response of the *complete*
motion system, cueing algorithm and motion platform together, with sinusoidal inputs at
fixed test frequencies, and compares it with the response of the vehicle (here: 1).
motioncue runs the chain a ride goes through, frame by frame at the frame rate:

    vehicle (f, w) -> cueing (:class:`ClassicalWashout`) -> workspace limiting
    (:func:`motioncue.trajectory.limit_pose`, limits tightened by the pulse rounding)
    -> inverse kinematics -> real-time actuator limiter (:class:`RealtimeLimiter`, or
    :class:`JerkLimiter` when the limits have a jerk limit, as in the live bridge)
    -> actuator positions -> forward kinematics -> platform pose -> platform motion

and measures the platform motion: the angular velocity ``W`` (body frame, from the Euler
angles and their rates) and the specific force at the rider's head ``h`` (the preset's
``head_offset_m`` where the washout has one, else the platform origin),
``f = R^T (a + [0, 0, g]) + W' x h + W x (W x h)`` (``a`` the inertial acceleration of the
origin). Derivatives are 5-point central
differences (relative error ``(w dt)^4 / 30`` for a sinusoid: below 1e-5 at 15.849 rad/s
and 100 Hz). Positions are the limiter's output in SI, before the rounding to whole drive
pulses (half a pulse: 0.25 um on the bundled hexapod). The chain starts at the neutral
pose at rest.

For each signal path and test frequency the input is ``A sin(w t)`` on one input channel
(all others at rest: ``f = [0, 0, g]``, ``w = 0``). The run lasts ``settle`` (whole
periods, at least 2 and at least ``12 / sigma`` s where ``sigma`` is the slowest decay
rate of the continuous design, so that the transients have decayed below ``e^-12``) plus
:data:`MEASURE_PERIODS` periods; over the measured periods the input and the output are
each fitted by least squares with ``c + a sin(w t) + b cos(w t)``; the gain is the ratio of
the output to the input first-harmonic amplitude and the phase the difference of their
phases (degrees, wrapped to (-180, 180]). Over whole periods the first-harmonic fit is
orthogonal to the constant and to every higher harmonic a limit may produce.

Signal paths and test frequencies
---------------------------------
The twelve test frequencies are those of the OMCT, log-spaced at five per decade:
``0.100, 0.158, 0.251, 0.398, 0.631, 1.000, 1.585, 2.512, 3.981, 6.310, 10.000, 15.849``
rad/s (:data:`OMCT_FREQUENCIES_RAD_S`). The paths (:data:`OMCT_PATHS`) are the ten of the
OMCT, named by input and output:

* rotational, angular rate in to platform angular rate out (rad/s per rad/s):
  ``p->p`` (roll), ``q->q`` (pitch), ``r->r`` (yaw). The OMCT states these as angle in to
  angle out; for a sinusoid the ratio and phase are the same;
* translational, specific force in to platform specific force out (per m/s^2):
  ``ax->ax`` (surge), ``ay->ay`` (sway), ``az->az`` (heave);
* cross-coupling of tilt coordination, specific force in to angular rate out
  (rad/s per m/s^2): ``ax->q``, ``ay->p``;
* cross-coupling of rotation, angular rate in to specific force out (m/s^2 per rad/s):
  ``q->ax``, ``p->ay`` (the false specific force a rotation leaves).

Input amplitudes
----------------
**The amplitudes are motioncue's own, not the standard's table.** ICAO 9625 (Attachment F
of the 3rd edition, the OMCT appendix of the 4th) specifies an input amplitude per path
and frequency; we could not obtain that table (its text is not openly published), so
:func:`omct_amplitude` uses amplitudes of the size a car gives a rider, chosen with the
same intent (large enough to reach the limits a ride reaches, small enough for the
cueing's linear range on a well-tuned simulator):

* rotational: an angle amplitude of 5 deg, reduced above 4.47 rad/s so that the angular
  acceleration amplitude stays at 100 deg/s^2: rate amplitude ``w * min(5 deg,
  100 deg/s^2 / w^2)`` (0.5 deg/s at 0.1 rad/s, 20 deg/s at 4 rad/s, 6.3 deg/s at 15.8);
* translational and tilt paths: a specific-force amplitude of 1 m/s^2 (0.1 g) on every
  axis and at every frequency.

``amplitude_scale`` scales them all (the linear check uses a small one).

Analytic linear response
------------------------
:func:`linear_response` is the small-signal response of the *continuous* classical
washout on a platform with no limits, built with python-control from
:meth:`ClassicalWashout.continuous` (``H_R = s * rot``, ``H_T = s^2 * trans``,
``G_T = tilt``) and the gains ``k_f`` (``f_scale``), ``k_w`` (``w_scale``) and ``k_t``
(the tilt gain ``tilt_scale`` where the washout has one, else ``k_f``):

* ``p->p``: ``k_w H_R``; likewise ``q->q``, ``r->r``;
* ``ax->ax``: ``k_t G_T + H_T (k_f - k_t G_T)`` (tilt supplies ``k_t G_T``, the
  translational channel the rest, high-passed); ``ay->ay`` likewise; ``az->az``:
  ``k_f H_T``;
* ``ax->q``: ``-k_t s G_T / g`` (forward force pitches nose up, negative pitch);
  ``ay->p``: ``+k_t s G_T / g``;
* ``q->ax``: ``-g k_w (1 - H_T) H_R / s``; ``p->ay``: ``+g k_w (1 - H_T) H_R / s``
  (gravity tilted by the rotational cue, partly compensated by the translational channel);
* with a head offset ``h`` every specific-force path gains ``(1 - H_T) (s W x h)``, ``W``
  the path's linear body rate: the head's tangential acceleration, which the washout feeds
  (negated) to the translational channel, so that only its high-passed part is cancelled.
  (The washout forms ``W'`` by backward differences, a one-frame lag of that term: its
  discrete response departs from this line by up to 11 % / 5 deg at 15.8 rad/s with
  100 Hz frames and a 0.6 m head height, 1.2 % / 0.5 deg at 1000 Hz.)

With no limit reached the measurement matches it to the discretisation error of the
Tustin sections at the frame rate (``tests/test_omct.py``).

References
----------
* ICAO Doc 9625, *Manual of Criteria for the Qualification of Flight Simulation Training
  Devices*, Volume I - Aeroplanes, 4th ed., 2015: the OMCT appendix (3rd ed. 2009:
  Attachment F, "Frequency-domain motion cueing system performance test").
* R. Hosman, S. Advani, "Design and evaluation of the objective motion cueing test and
  criterion", The Aeronautical Journal 120(1227), 2016, 873-891.
* O. Stroosma, M. M. van Paassen, M. Mulder, R. Hosman, S. Advani, "Applying the
  Objective Motion Cueing Test to a classical washout algorithm", AIAA Modeling and
  Simulation Technologies Conference, 2013, AIAA 2013-4834.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError
from ..cueing import ClassicalWashout, CueingParams
from ..cueing._algorithm import check_rig
from ..cueing._params import GRAVITY_M_S2
from ..pipeline._chain import offline_chain
from ..trajectory import pulse_rounding_limits

if TYPE_CHECKING:
    from control import TransferFunction

    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits

__all__ = [
    "MEASURE_PERIODS",
    "OMCT_FREQUENCIES_RAD_S",
    "OMCT_PATHS",
    "OmctPath",
    "OmctPoint",
    "OmctResult",
    "linear_response",
    "omct_amplitude",
    "platform_motion",
    "plot_omct",
    "run_omct",
]

OMCT_FREQUENCIES_RAD_S: tuple[float, ...] = tuple(10.0 ** (-1.0 + k / 5.0) for k in range(12))
"""The twelve OMCT test frequencies (rad/s): 0.100 to 15.849, five per decade."""

MEASURE_PERIODS = 3
"""Whole periods over which the first harmonic is fitted (after the settling periods)."""

_D2R = math.pi / 180.0


@dataclass(frozen=True)
class OmctPath:
    """One signal path of the OMCT.

    Attributes
    ----------
    name : str
        ``"in->out"``, e.g. ``"ax->q"``.
    description : str
    input_kind, output_kind : str
        ``"f"`` (specific force, m/s^2) or ``"w"`` (angular rate, rad/s).
    input_axis, output_axis : int
        0, 1, 2 = x, y, z (roll, pitch, yaw for rates).
    """

    name: str
    description: str
    input_kind: str
    input_axis: int
    output_kind: str
    output_axis: int

    @property
    def input_unit(self) -> str:
        return "m/s^2" if self.input_kind == "f" else "rad/s"

    @property
    def gain_unit(self) -> str:
        """Unit of the gain (output unit per input unit); ``"-"`` when dimensionless."""
        if self.input_kind == self.output_kind:
            return "-"
        return "(rad/s)/(m/s^2)" if self.output_kind == "w" else "(m/s^2)/(rad/s)"


OMCT_PATHS: tuple[OmctPath, ...] = (
    OmctPath("p->p", "roll rate to roll rate", "w", 0, "w", 0),
    OmctPath("q->q", "pitch rate to pitch rate", "w", 1, "w", 1),
    OmctPath("r->r", "yaw rate to yaw rate", "w", 2, "w", 2),
    OmctPath("ax->ax", "surge specific force to surge specific force", "f", 0, "f", 0),
    OmctPath("ay->ay", "sway specific force to sway specific force", "f", 1, "f", 1),
    OmctPath("az->az", "heave specific force to heave specific force", "f", 2, "f", 2),
    OmctPath("ax->q", "surge specific force to pitch rate (tilt coordination)", "f", 0, "w", 1),
    OmctPath("ay->p", "sway specific force to roll rate (tilt coordination)", "f", 1, "w", 0),
    OmctPath("q->ax", "pitch rate to surge specific force (rotation cross-coupling)", "w", 1,
             "f", 0),
    OmctPath("p->ay", "roll rate to sway specific force (rotation cross-coupling)", "w", 0,
             "f", 1),
)  # fmt: skip
"""The ten signal paths, in the OMCT's order (rotational, translational, cross-coupling)."""

_PATHS_BY_NAME = {p.name: p for p in OMCT_PATHS}

_SHORT = {
    "p->p": "roll",
    "q->q": "pitch",
    "r->r": "yaw",
    "ax->ax": "surge",
    "ay->ay": "sway",
    "az->az": "heave",
    "ax->q": "surge to pitch, tilt",
    "ay->p": "sway to roll, tilt",
    "q->ax": "pitch to surge",
    "p->ay": "roll to sway",
}


def _path(name_or_path: str | OmctPath) -> OmctPath:
    if isinstance(name_or_path, OmctPath):
        return name_or_path
    key = str(name_or_path).strip()
    if "->" not in key and key.count("-") == 1:
        key = key.replace("-", "->")  # "ax-q": the shell-safe spelling of "ax->q"
    try:
        return _PATHS_BY_NAME[key]
    except KeyError:
        hint = (
            " (a shell reads '>' as a redirection: quote the name, 'ax->q', or write ax-q)"
            if str(name_or_path).strip().endswith("-")
            else ""
        )
        raise ConfigError(
            f"OMCT path {name_or_path!r} is unknown; allowed: {', '.join(_PATHS_BY_NAME)}"
            f" (or in-out, e.g. ax-q){hint}"
        ) from None


def omct_amplitude(path: str | OmctPath, frequency_rad_s: float) -> float:
    """Input amplitude of ``path`` at ``frequency_rad_s`` (m/s^2 or rad/s).

    motioncue's own amplitudes, **not** ICAO 9625's table (see the module docstring):
    rotational rate ``w * min(5 deg, 100 deg/s^2 / w^2)``, specific force 1 m/s^2.
    """
    p = _path(path)
    w = float(frequency_rad_s)
    if not (math.isfinite(w) and w > 0.0):
        raise ConfigError(f"frequency {frequency_rad_s!r} rad/s is invalid; allowed: > 0")
    if p.input_kind == "f":
        return 1.0
    return w * min(5.0 * _D2R, 100.0 * _D2R / (w * w))


# ---------------------------------------------------------------------------------- analytic
def _tf(num: Sequence[float], den: Sequence[float]) -> TransferFunction:
    import control

    return control.tf(list(num), list(den))


def _head_offset(params: CueingParams) -> tuple[float, float, float]:
    """The rider's head offset of the preset (m), zero where the washout has none."""
    h = params.head_offset_m
    return (float(h[0]), float(h[1]), float(h[2]))


def _linear_systems(design: ClassicalWashout) -> dict[str, TransferFunction]:
    """The continuous small-signal transfer function of every path (python-control)."""
    import control

    cont = design.continuous()
    p = design.params
    g = GRAVITY_M_S2
    s = control.tf("s")
    one = _tf([1.0], [1.0])
    zero = _tf([0.0], [1.0])
    g_t = _tf(*cont["tilt"][0])
    kf, kw = p.f_scale, p.w_scale
    kt = p.tilt_scale or (kf[0], kf[1])
    mx, my, mz, mr, mp, myaw = (1.0 if d else 0.0 for d in p.dofs)
    # a DOF the machine does not move passes no cue: its filters are zero
    h_r = [m * s * _tf(*nd) for m, nd in zip((mr, mp, myaw), cont["rot"], strict=True)]
    ht = [m * s * s * _tf(*nd) for m, nd in zip((mx, my, mz), cont["trans"], strict=True)]
    # angle of the rotational channel per unit input rate (H_R / s)
    ang = [m * _tf(*nd) for m, nd in zip((mr, mp, myaw), cont["rot"], strict=True)]
    tilt_x = mp * kt[0] * g_t  # f_x -> -g * pitch (tilt-coordination force)
    tilt_y = mr * kt[1] * g_t  # f_y -> +g * roll
    # linear platform response: body rates W (per input) and specific force at the origin
    rates: dict[str, list[TransferFunction]] = {
        "p": [kw[0] * h_r[0], zero, zero],
        "q": [zero, kw[1] * h_r[1], zero],
        "r": [zero, zero, kw[2] * h_r[2]],
        "ax": [zero, -s * tilt_x / g, zero],
        "ay": [s * tilt_y / g, zero, zero],
        "az": [zero, zero, zero],
    }
    force: dict[str, list[TransferFunction]] = {
        "p": [zero, g * kw[0] * (one - ht[1]) * ang[0], zero],
        "q": [-g * kw[1] * (one - ht[0]) * ang[1], zero, zero],
        "r": [zero, zero, zero],
        "ax": [tilt_x + ht[0] * (kf[0] * one - tilt_x), zero, zero],
        "ay": [zero, tilt_y + ht[1] * (kf[1] * one - tilt_y), zero],
        "az": [zero, zero, kf[2] * ht[2]],
    }
    hx, hy, hz = _head_offset(p)
    if hx or hy or hz:
        # the head feels W' x h on top of the origin; the washout feeds -W' x h to the
        # translational channel, which cancels its high-passed part: (1 - H_T) (s W x h)
        for key, wv in rates.items():
            dw = [s * c for c in wv]
            cross = [dw[1] * hz - dw[2] * hy, dw[2] * hx - dw[0] * hz, dw[0] * hy - dw[1] * hx]
            force[key] = [force[key][i] + (one - ht[i]) * cross[i] for i in range(3)]
    out: dict[str, TransferFunction] = {}
    for path in OMCT_PATHS:
        src = path.name.split("->")[0]
        table = rates if path.output_kind == "w" else force
        out[path.name] = table[src][path.output_axis]
    return out


def linear_response(
    design: ClassicalWashout,
    path: str | OmctPath,
    frequencies_rad_s: Sequence[float] | NDArray[np.float64],
) -> NDArray[np.complex128]:
    """Small-signal frequency response of the continuous classical washout on an unlimited
    platform, at ``frequencies_rad_s`` (see the module docstring for the formulas).

    Parameters
    ----------
    design : ClassicalWashout
    path : str or OmctPath
        One of :data:`OMCT_PATHS` (``"p->p"``...).
    frequencies_rad_s : sequence of float

    Returns
    -------
    (n,) complex array
        ``H(jw)`` in output unit per input unit.
    """
    p = _path(path)
    sys = _linear_systems(design)[p.name]
    w = np.asarray(frequencies_rad_s, dtype=float)
    return np.asarray(sys(1j * w), dtype=complex).reshape(w.shape)


def _slowest_decay_rate(design: ClassicalWashout) -> float:
    """Smallest ``-Re(pole)`` over the continuous design's factors (1/s)."""
    cont = design.continuous()
    rates: list[float] = []
    for key in ("tilt", "rot", "trans"):
        for _num, den in cont[key]:
            roots = np.roots(np.asarray(den, dtype=float))
            rates.extend(float(-r.real) for r in roots if -r.real > 0.0)
    return min(rates) if rates else 1.0


# ---------------------------------------------------------------------------------- results
@dataclass(frozen=True)
class OmctPoint:
    """The measurement of one path at one test frequency.

    Attributes
    ----------
    path : str
        ``"p->p"``...
    frequency_rad_s : float
    amplitude : float
        Input amplitude (m/s^2 or rad/s, :attr:`OmctPath.input_unit`).
    gain, phase_deg : float
        Measured first-harmonic gain (output per input unit) and phase (deg, (-180, 180]).
    linear_gain, linear_phase_deg : float
        The analytic small-signal response of the continuous washout (no limits).
    frames : int
        Frames run (settling and measured).
    workspace_clamped : int
        Frames whose pose the workspace limiting scaled back towards neutral.
    actuator_limited : int
        Frames the actuator limiter changed (speed, acceleration, stroke).
    """

    path: str
    frequency_rad_s: float
    amplitude: float
    gain: float
    phase_deg: float
    linear_gain: float
    linear_phase_deg: float
    frames: int
    workspace_clamped: int
    actuator_limited: int

    @property
    def gain_error(self) -> float:
        """``gain / linear_gain - 1`` (nan where the linear gain is 0)."""
        return self.gain / self.linear_gain - 1.0 if self.linear_gain > 0.0 else math.nan

    @property
    def phase_error_deg(self) -> float:
        """``phase - linear_phase`` wrapped to (-180, 180] deg."""
        return _wrap_deg(self.phase_deg - self.linear_phase_deg)

    def to_dict(self) -> dict[str, object]:
        return {
            "path": self.path,
            "frequency_rad_s": self.frequency_rad_s,
            "amplitude": self.amplitude,
            "gain": self.gain,
            "phase_deg": self.phase_deg,
            "linear_gain": self.linear_gain,
            "linear_phase_deg": self.linear_phase_deg,
            "gain_error": _finite_or_none(self.gain_error),
            "phase_error_deg": self.phase_error_deg,
            "frames": self.frames,
            "workspace_clamped": self.workspace_clamped,
            "actuator_limited": self.actuator_limited,
        }


def _finite_or_none(x: float) -> float | None:
    return x if math.isfinite(x) else None


def _wrap_deg(x: float) -> float:
    y = (x + 180.0) % 360.0 - 180.0
    return 180.0 if y == -180.0 else y


@dataclass(frozen=True)
class OmctResult:
    """An OMCT run: every path at every test frequency.

    Attributes
    ----------
    points : tuple of OmctPoint
        In path order, then frequency order.
    rate_hz : float
        Frame rate (and cueing sample rate) of the runs.
    amplitude_scale : float
        Factor applied to :func:`omct_amplitude`.
    labels : dict
        ``preset``, ``platform``, ``controller`` names (for reports).
    """

    points: tuple[OmctPoint, ...]
    rate_hz: float
    amplitude_scale: float
    labels: dict[str, str] = field(default_factory=dict)

    @property
    def paths(self) -> tuple[str, ...]:
        seen: dict[str, None] = {}
        for pt in self.points:
            seen.setdefault(pt.path, None)
        return tuple(seen)

    def for_path(self, path: str) -> tuple[OmctPoint, ...]:
        return tuple(pt for pt in self.points if pt.path == path)

    def to_dict(self) -> dict[str, object]:
        return {
            "test": "objective motion cueing test (OMCT), motioncue amplitudes",
            **self.labels,
            "rate_hz": self.rate_hz,
            "amplitude_scale": self.amplitude_scale,
            "units": {
                "frequency": "rad/s",
                "amplitude": "input unit: m/s^2 (specific force) or rad/s (angular rate)",
                "gain": "output unit per input unit",
                "phase": "deg, output relative to input, wrapped to (-180, 180]",
            },
            "paths": [
                {
                    "path": p.name,
                    "description": p.description,
                    "input_unit": p.input_unit,
                    "gain_unit": p.gain_unit,
                }
                for p in OMCT_PATHS
                if p.name in self.paths
            ],
            "points": [pt.to_dict() for pt in self.points],
        }

    def table(self) -> str:
        """A text table with units and an explanation of its columns."""
        lines = [
            "OMCT: frequency response of the whole chain (cueing, workspace limiting, "
            "actuator limits)",
            "  "
            + ", ".join(
                [f"{k} {v}" for k, v in self.labels.items()]
                + [f"{self.rate_hz:g} Hz frames", f"amplitudes x{self.amplitude_scale:g}"]
            ),
            "columns: w = test frequency (rad/s); amp = input amplitude (m/s^2 for ax/ay/az, "
            "deg/s for p/q/r);",
            "  gain, phase = measured first harmonic of the platform output over the input "
            "(output unit per input unit; deg);",
            "  lin gain, lin phase = analytic response of the linear continuous washout "
            "(no limits);",
            "  dgain = gain / lin gain - 1 (%); dphase = phase - lin phase (deg);",
            "  ws% / act% = frames clamped by the workspace limiting / changed by the actuator "
            "limiter (% of the run)",
        ]
        units = {p.name: p for p in OMCT_PATHS}
        for name in self.paths:
            p = units[name]
            lines.append("")
            lines.append(f"{name}: {p.description}; gain in {p.gain_unit}")
            lines.append(
                f"{'w rad/s':>8} {'amp':>8} {'gain':>10} {'phase':>8} {'lin gain':>10} "
                f"{'lin ph':>8} {'dgain%':>8} {'dphase':>7} {'ws%':>6} {'act%':>6}"
            )
            for pt in self.for_path(name):
                amp = pt.amplitude / _D2R if p.input_kind == "w" else pt.amplitude
                dg = pt.gain_error * 100.0
                lines.append(
                    f"{pt.frequency_rad_s:8.3f} {amp:8.3g} {pt.gain:10.4g} "
                    f"{pt.phase_deg:8.1f} {pt.linear_gain:10.4g} {pt.linear_phase_deg:8.1f} "
                    f"{dg:8.2f} {pt.phase_error_deg:7.2f} "
                    f"{100.0 * pt.workspace_clamped / pt.frames:6.1f} "
                    f"{100.0 * pt.actuator_limited / pt.frames:6.1f}"
                )
        return "\n".join(lines)


# ---------------------------------------------------------------------------------- chain
def _d1(x: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
    """5-point central first derivative along axis 0 (drops 2 samples each end)."""
    return (-x[4:] + 8.0 * x[3:-1] - 8.0 * x[1:-3] + x[:-4]) / (12.0 * dt)


def _d2(x: NDArray[np.float64], dt: float) -> NDArray[np.float64]:
    """5-point central second derivative along axis 0 (drops 2 samples each end)."""
    return (-x[4:] + 16.0 * x[3:-1] - 30.0 * x[2:-2] + 16.0 * x[1:-3] - x[:-4]) / (12.0 * dt * dt)


def platform_motion(
    poses: NDArray[np.float64], dt_s: float, point_m: Sequence[float] = (0.0, 0.0, 0.0)
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Specific force at a point of the platform and the platform's angular velocity, both
    in the platform frame.

    Parameters
    ----------
    poses : (N, 6) array
        ``[x, y, z, roll, pitch, yaw]`` (m, rad) on a uniform grid of period ``dt_s``.
    dt_s : float
    point_m : 3 floats
        The point ``h`` (platform frame, from the platform origin, m) where the specific
        force is measured: the rider's head.

    Returns
    -------
    f, w : (N - 8, 3) arrays
        For samples 4 .. N-5: ``f = R^T (a + [0, 0, g]) + W' x h + W x (W x h)`` (m/s^2; ``a``
        the inertial acceleration of the origin) and the body angular velocity ``W``
        (rad/s), ``R = Rz(yaw) Ry(pitch) Rx(roll)``.
    """
    pos = poses[:, :3]
    ang = poses[:, 3:]
    acc = _d2(pos, dt_s)
    rates = _d1(ang, dt_s)
    phi, th, psi = (ang[2:-2, k] for k in range(3))
    dphi, dth, dpsi = rates[:, 0], rates[:, 1], rates[:, 2]
    sf, cf = np.sin(phi), np.cos(phi)
    st, ct = np.sin(th), np.cos(th)
    sp, cp = np.sin(psi), np.cos(psi)
    # body rates of ZYX Euler angles
    w = np.column_stack([dphi - dpsi * st, dth * cf + dpsi * sf * ct, -dth * sf + dpsi * cf * ct])
    v = acc + np.array([0.0, 0.0, GRAVITY_M_S2])
    # R^T v with R = Rz Ry Rx: first Rz^T, then Ry^T, then Rx^T
    v1x = cp * v[:, 0] + sp * v[:, 1]
    v1y = -sp * v[:, 0] + cp * v[:, 1]
    v1z = v[:, 2]
    v2x = ct * v1x - st * v1z
    v2z = st * v1x + ct * v1z
    f = np.column_stack([v2x, cf * v1y + sf * v2z, -sf * v1y + cf * v2z])
    h = np.asarray(point_m, dtype=float)
    w_in = w[2:-2]
    f_in = f[2:-2]
    if np.any(h != 0.0):
        dw = _d1(w, dt_s)  # body angular acceleration (the body derivative of W)
        f_in = f_in + np.cross(dw, h) + np.cross(w_in, np.cross(w_in, h))
    return f_in, w_in


def _first_harmonic(y: NDArray[np.floating], t: NDArray[np.floating], w: float) -> complex:
    """Least-squares ``c + a sin(wt) + b cos(wt)``; returns the phasor ``a + j b``
    (amplitude ``|.|``, phase ``angle(.)`` relative to ``sin(wt)``)."""
    m = np.column_stack([np.ones_like(t), np.sin(w * t), np.cos(w * t)])
    coef, *_ = np.linalg.lstsq(m, y, rcond=None)
    return complex(coef[1], coef[2])


Progress = Callable[[str, float], None]


def run_omct(
    design: ClassicalWashout,
    platform: Platform,
    limits: ActuatorLimits,
    *,
    paths: Sequence[str] | None = None,
    frequencies_rad_s: Sequence[float] | None = None,
    amplitude_scale: float = 1.0,
    labels: dict[str, str] | None = None,
    progress: Progress | None = None,
) -> OmctResult:
    """Run the OMCT through the whole chain (see the module docstring).

    Parameters
    ----------
    design : ClassicalWashout
        The cueing, discretised at the frame rate (``design.fs_hz``).
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits
        The limits table in SI (``ActuatorLimits.from_platform(platform, controller,
        rate_hz=...)``); tightened by the pulse rounding as in the live bridge.
    paths : sequence of str, optional
        Subset of :data:`OMCT_PATHS` names (default: all ten).
    frequencies_rad_s : sequence of float, optional
        Default :data:`OMCT_FREQUENCIES_RAD_S`; each below the Nyquist frequency / 4.
    amplitude_scale : float
        Factor on :func:`omct_amplitude`, in (0, 100].
    labels : dict, optional
        Names for the report (``preset``, ``platform``, ``controller``).
    progress : callable, optional
        ``progress(description, fraction_done)``.

    Returns
    -------
    OmctResult

    Raises
    ------
    ConfigError
        Unknown path, a frequency out of range, an invalid amplitude scale, or limits that
        do not fit the platform.
    """
    sel = [_path(p) for p in (paths if paths is not None else [p.name for p in OMCT_PATHS])]
    if not sel:
        raise ConfigError("paths is empty; allowed: names from " + ", ".join(_PATHS_BY_NAME))
    freqs = [float(w) for w in (frequencies_rad_s or OMCT_FREQUENCIES_RAD_S)]
    fs = float(design.fs_hz)
    dt = 1.0 / fs
    for w in freqs:
        if not (math.isfinite(w) and 0.0 < w <= math.pi * fs / 4.0):
            raise ConfigError(
                f"test frequency {w!r} rad/s is invalid; allowed: (0, {math.pi * fs / 4.0:g}] "
                f"rad/s at {fs:g} Hz frames (a quarter of Nyquist)"
            )
    sc = amplitude_scale
    if isinstance(sc, bool) or not isinstance(sc, int | float) or not 0.0 < sc <= 100.0:
        raise ConfigError(f"amplitude_scale = {sc!r} is invalid; allowed: (0, 100]")
    check_rig(platform, limits)
    tight = pulse_rounding_limits(limits, platform, dt)
    settle_s = 12.0 / _slowest_decay_rate(design)
    head = _head_offset(design.params)
    g = GRAVITY_M_S2
    linear = _linear_systems(design)
    points: list[OmctPoint] = []
    total = len(sel) * len(freqs)
    for i, p in enumerate(sel):
        lin = np.asarray(linear[p.name](1j * np.asarray(freqs)), dtype=complex).reshape(-1)
        for j, w in enumerate(freqs):
            if progress is not None:
                progress(f"{p.name} at {w:.3f} rad/s", (i * len(freqs) + j) / total)
            amp = sc * omct_amplitude(p, w)
            period = 2.0 * math.pi / w
            n_settle = max(2, math.ceil(settle_s / period))
            n_per = period * fs
            n_meas = round(MEASURE_PERIODS * n_per)
            n_total = math.ceil(n_settle * n_per) + n_meas + 8
            t = np.arange(n_total) * dt
            u = amp * np.sin(w * t)
            f_in = np.zeros((n_total, 3))
            f_in[:, 2] = g
            w_in = np.zeros((n_total, 3))
            (f_in if p.input_kind == "f" else w_in)[:, p.input_axis] += u
            out = offline_chain(design, f_in, w_in, platform, tight, fs).delivered
            f_out, w_out = platform_motion(out.poses, dt, head)
            y_all = (f_out if p.output_kind == "f" else w_out)[:, p.output_axis]
            sl = slice(n_total - 4 - n_meas, n_total - 4)  # measured periods, interior
            t_m = t[sl]
            y = y_all[sl.start - 4 : sl.stop - 4]
            h_in = _first_harmonic(u[sl], t_m, w)
            h_out = _first_harmonic(y, t_m, w)
            ratio = h_out / h_in
            points.append(
                OmctPoint(
                    path=p.name,
                    frequency_rad_s=w,
                    amplitude=amp,
                    gain=abs(ratio),
                    phase_deg=_wrap_deg(math.degrees(math.atan2(ratio.imag, ratio.real))),
                    linear_gain=float(abs(lin[j])),
                    linear_phase_deg=_wrap_deg(math.degrees(float(np.angle(lin[j])))),
                    frames=n_total,
                    workspace_clamped=out.clamped,
                    actuator_limited=out.limiter_clamped,
                )
            )
    if progress is not None:
        progress("done", 1.0)
    return OmctResult(tuple(points), fs, float(sc), dict(labels or {}))


# ---------------------------------------------------------------------------------- plot
def plot_omct(
    result: OmctResult, design: ClassicalWashout, path: str | Path, *, title: str = ""
) -> Path:
    """Write a PNG in the OMCT's format: per path, the gain (log-log) above the phase (deg,
    log frequency axis), the analytic linear response of ``design`` as a line and the
    measured points as markers.

    Parameters
    ----------
    result : OmctResult
    design : ClassicalWashout
        The design measured (for the analytic line).
    path : str or Path
        Output PNG, written atomically.
    title : str

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ConfigError
        The file cannot be written.
    """
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .._atomic import atomic_write_bytes

    names = result.paths
    ncol = min(5, len(names))
    nrow = math.ceil(len(names) / ncol)
    fig = plt.figure(figsize=(3.3 * ncol, 5.0 * nrow + 0.6), layout="constrained")
    grid = fig.add_gridspec(2 * nrow, ncol, height_ratios=[1.2, 1.0] * nrow)
    w_all = [pt.frequency_rad_s for pt in result.points]
    w_line = np.logspace(math.log10(min(w_all) / 1.5), math.log10(max(w_all) * 1.5), 200)
    info = {p.name: p for p in OMCT_PATHS}
    for k, name in enumerate(names):
        r, c = divmod(k, ncol)
        ax_g = fig.add_subplot(grid[2 * r, c])
        ax_p = fig.add_subplot(grid[2 * r + 1, c], sharex=ax_g)
        pts = result.for_path(name)
        lin = linear_response(design, name, w_line)
        w_pts = np.array([pt.frequency_rad_s for pt in pts])
        gains = np.array([pt.gain for pt in pts])
        phases = np.array([pt.phase_deg for pt in pts])
        lin_gain = np.abs(lin)
        lin_phase = np.degrees(np.unwrap(np.angle(lin)))
        # the measured phases on the branch of the analytic line (nearest multiple of 360)
        lin_at = np.interp(np.log(w_pts), np.log(w_line), lin_phase)
        phases = phases + 360.0 * np.round((lin_at - phases) / 360.0)
        if np.any(lin_gain > 0.0):
            ax_g.loglog(w_line, np.where(lin_gain > 0.0, lin_gain, np.nan), "-", lw=1.2,
                        label="linear washout (analytic)")  # fmt: skip
        else:
            ax_g.set_xscale("log")
        ok = gains > 0.0
        ax_g.plot(w_pts[ok], gains[ok], "o", ms=5, mfc="none", label="measured chain")
        limited = np.array([pt.workspace_clamped + pt.actuator_limited > 0 for pt in pts])
        if np.any(limited & ok):
            ax_g.plot(w_pts[limited & ok], gains[limited & ok], "x", ms=7, color="C3")  # fmt: skip
        if np.any(ok) or np.any(lin_gain > 0.0):
            ax_g.set_yscale("log")
        ax_g.set_title(f"{name} ({_SHORT[name]})", fontsize=9)
        unit = info[name].gain_unit
        ax_g.set_ylabel("gain" + ("" if unit == "-" else f" [{unit}]"), fontsize=8)
        ax_g.grid(which="both", alpha=0.3)
        ax_g.tick_params(which="both", labelsize=8, labelbottom=False)
        ax_p.semilogx(w_line, lin_phase, "-", lw=1.2)
        ax_p.plot(w_pts, phases, "o", ms=5, mfc="none")
        if np.any(limited):
            ax_p.plot(w_pts[limited], phases[limited], "x", ms=7, color="C3")
        ax_p.set_ylabel("phase [deg]", fontsize=8)
        ax_p.set_xlabel("frequency [rad/s]", fontsize=8)
        ax_p.grid(which="both", alpha=0.3)
        ax_p.tick_params(which="both", labelsize=8)
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color="C0", lw=1.2, label="linear washout, analytic (python-control)"),
        Line2D([], [], color="C1", marker="o", mfc="none", ls="", label="measured: whole chain"),
        Line2D([], [], color="C3", marker="x", ls="", label="workspace or actuator limit reached"),
    ]
    fig.legend(handles=handles, loc="outside lower center", ncol=3, fontsize=9)
    head = title or "Objective motion cueing test"
    fig.suptitle(
        f"{head}\n{result.rate_hz:g} Hz frames; input amplitudes: motioncue's (x"
        f"{result.amplitude_scale:g}), not ICAO 9625's table; markers: measured through "
        "cueing, workspace and actuator limits",
        fontsize=10,
    )
    buf = io.BytesIO()
    try:
        fig.savefig(buf, format="png", dpi=90)
    finally:
        plt.close(fig)
    out = Path(path)
    try:
        atomic_write_bytes(out, buf.getvalue(), "plot")
    except OSError as exc:
        raise ConfigError(f"{out}: cannot write plot: {exc}") from exc
    return out
