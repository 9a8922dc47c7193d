"""The helpers of :meth:`ActuatorLimits.from_platform` (whose docstring gives the rules), and
the tightening of a limits table: to the controller's own stroke, to the rounding to whole
pulses, to a planning table that keeps the park position.

The controller is used only through its interface (:class:`motioncue.output.Controller`); no
controller kind is named here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .._errors import ConfigError, LimitError
from ._limits import ActuatorLimits

if TYPE_CHECKING:
    from numpy.typing import NDArray

    from ..kinematics import Drive, Platform
    from ..output import Controller, DriveExpectations, PulseLimits

__all__ = ["planning_limits", "pulse_rounding_limits", "within_controller_stroke"]


def _per_axis(
    name: str, value: float | Sequence[float] | NDArray[np.float64] | None, n: int
) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.array(value, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, float(arr[0]))
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: one number or {n} numbers")
    return arr


def _check_drives(platform: Platform, expect: DriveExpectations, who: str) -> None:
    """Refuse a platform drive that disagrees with what the controller's parameters say."""
    drives = platform.drives
    kinds = tuple(platform.actuator_kinds)
    ppr = np.asarray(drives.pulses_per_rev, dtype=float).reshape(-1)
    lead = np.abs(np.asarray(drives.units_per_rev, dtype=float).reshape(-1))
    pname = platform.name
    if expect.pulses_per_rev is not None:
        for i, value in enumerate(ppr):
            if abs(value - expect.pulses_per_rev) > 1e-9 * max(value, 1.0):
                raise ConfigError(
                    f"{who}: {expect.pulses_per_rev:g} pulses per motor turn "
                    f"({expect.pulses_per_rev_source}) disagrees with platform {pname!r}'s "
                    f"drive on actuator {i + 1}: {value:g} pulses per turn; the positions sent "
                    "would be wrong. Make them agree"
                )
    if expect.lead_m is not None:
        for i, kind in enumerate(kinds):
            if kind == "linear" and abs(lead[i] - expect.lead_m) > 1e-9 * expect.lead_m:
                raise ConfigError(
                    f"{who}: lead {expect.lead_m * 1e3:g} mm ({expect.lead_source}) disagrees "
                    f"with platform {pname!r}'s lead {lead[i] * 1e3:g} mm on actuator {i + 1}"
                )


def _within_stroke(
    drives: Drive, pl: PulseLimits, q_min: np.ndarray, q_max: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``[q_min, q_max] (n,)`` (SI) intersected with the controller's stroke ``pl``
    (:class:`PulseLimits`, pulses); an axis without a controller stroke keeps its own."""
    pulses = np.stack([pl.stroke_lo, pl.stroke_hi])
    finite = np.isfinite(pulses)
    ends = np.asarray(
        drives.from_pulses(np.where(finite, pulses, 0.0).round().astype(np.int64)),
        dtype=float,
    )
    lo_si, hi_si = np.minimum(ends[0], ends[1]), np.maximum(ends[0], ends[1])
    has = finite[0] & finite[1]
    return (
        np.where(has, np.maximum(q_min, lo_si), q_min),
        np.where(has, np.minimum(q_max, hi_si), q_max),
    )


def within_controller_stroke(
    limits: ActuatorLimits, platform: Platform, controller: Controller, rate_hz: float | None = None
) -> tuple[ActuatorLimits, str | None]:
    """``limits`` with their stroke kept within the controller's own (MBOX Fn0C0 x Fn0C1,
    IMAX stroke_mm / PA40), as :meth:`ActuatorLimits.from_platform` builds it.

    A limits table made for other controller parameters (another file, a box whose Fn0C0
    was changed since) may reach further than the controller accepts: the encoder refuses
    such a frame, and a platform moving toward that end cannot then brake within the
    controller's stroke, so even the park frames are refused. Planning within the narrower
    stroke from the start keeps every frame, the park included, acceptable.

    Returns
    -------
    limits : ActuatorLimits
        ``limits`` itself when nothing changes, else a copy with ``q_min``, ``q_max`` (n,)
        narrowed.
    note : str or None
        What was narrowed, in pulses, for the user; None when nothing was.

    Raises
    ------
    LimitError
        The two strokes do not overlap on some axis, or the park position is outside the
        controller's stroke (nothing could be driven and parked there).
    """
    pl = controller.pulse_limits(rate_hz)
    if not pl.has_stroke:
        return limits, None
    q_min, q_max = _within_stroke(platform.drives, pl, limits.q_min, limits.q_max)
    if np.array_equal(q_min, limits.q_min) and np.array_equal(q_max, limits.q_max):
        return limits, None
    where = pl.sources.get("stroke", f"controller {controller.name} stroke")
    park = np.asarray(platform.q_park, dtype=float)
    if np.any(q_min >= q_max) or np.any(park < q_min) or np.any(park > q_max):
        raise LimitError(
            f"the controller's own stroke ({where}: [{pl.stroke_lo.tolist()}, "
            f"{pl.stroke_hi.tolist()}] pulses) leaves no room for the limits table's stroke "
            "and park; check the controller's parameters"
        )
    sources = dict(limits.sources)
    sources["stroke"] = f"{sources.get('stroke', 'limits table')} within {where}"
    narrowed = replace(limits, q_min=q_min, q_max=q_max, sources=sources)
    note = (
        f"limits: stroke kept within the controller's own ({where}), narrower than the "
        "limits table's"
    )
    return narrowed, note


def pulse_rounding_limits(
    limits: ActuatorLimits, platform: Platform, dt_s: float
) -> ActuatorLimits:
    """Limits tightened so that rounding to whole pulses cannot push a frame past them.

    Rounding moves each frame by at most half a pulse, so a speed by at most ``1 / dt`` and a
    second difference by at most ``2 / dt^2`` pulses; the stroke ends of the pulse table are
    already rounded inwards.
    """
    ppu = np.abs(np.asarray(platform.drives.pulses_per_unit, dtype=float))
    v_margin = 1.0 / (ppu * dt_s)
    a_margin = 2.0 / (ppu * dt_s * dt_s)
    half = 0.5 / ppu
    if np.any(limits.v_max <= 2 * v_margin) or np.any(limits.a_max <= 2 * a_margin):
        raise LimitError(
            f"frame period {dt_s * 1e3:.3f} ms is too short for the pulse resolution: rounding "
            "alone would use more than half of the speed or acceleration limit"
        )
    j_max = None
    if limits.j_max is not None:
        j_max = limits.j_max - 4.0 / (ppu * dt_s**3)
        if np.any(j_max <= 0):
            raise LimitError("jerk limit is below the pulse rounding at this frame rate")
    return ActuatorLimits(
        limits.q_min + half,
        limits.q_max - half,
        limits.v_max - v_margin,
        limits.a_max - a_margin,
        j_max,
        limits.names,
        limits.kinds,
        limits.sources,
    )


def planning_limits(
    limits: ActuatorLimits,
    platform: Platform,
    dt_s: float,
    *,
    real: ActuatorLimits | None = None,
) -> ActuatorLimits:
    """:func:`pulse_rounding_limits` of ``limits``, its stroke widened to hold the park position
    when the ``real`` limits (default ``limits``) hold it.

    Park is the homed position, pulse 0, which rounding leaves exactly where it is; a
    controller stroke that starts at its origin (MBOX Fn0C0) puts it on the stroke end, half a
    pulse outside the stroke tightened for rounding. A park outside the real stroke is left
    outside: the planning says so where it meets it.
    """
    real = limits if real is None else real
    tight = pulse_rounding_limits(limits, platform, dt_s)
    park = np.asarray(platform.q_park, dtype=float)
    if np.all((park >= tight.q_min) & (park <= tight.q_max)):
        return tight
    if not np.all((park >= real.q_min - 1e-12) & (park <= real.q_max + 1e-12)):
        return tight
    return ActuatorLimits(
        np.minimum(tight.q_min, park), np.maximum(tight.q_max, park), tight.v_max,
        tight.a_max, tight.j_max, tight.names, tight.kinds, tight.sources,
    )  # fmt: skip
