"""Effective actuator limits from platform + drive + controller parameters (+ overrides).

The controller is used only through its interface (:class:`motioncue.output.Controller`):
``drive_expectations()``, ``pulse_limits(rate_hz)`` and ``catch_up_factor``. No controller
kind is named here. Rules, each recorded in :attr:`ActuatorLimits.sources`:

Agreement
    The controller's pulses per motor turn and screw lead (linear actuators) must equal the
    platform's drive, otherwise the positions sent would be other lengths than planned: a
    :class:`~motioncue.ConfigError` names both values.

Stroke
    The platform's usable stroke ``[q_min, q_max]`` (its config already keeps ``margin_mm``
    from each end stop), shrunk by ``stroke_margin`` (SI, optional extra margin), and
    intersected with the controller's stroke in pulses where its parameters set one.

Speed, acceleration (``v_max``, ``a_max``)
    The smallest of: the override; the platform's own ``[limits]``; the controller's
    pulse limits converted through the drive (``pulses / |pulses_per_unit|``).

Catch-up
    A controller that may play frames ``c = catch_up_factor`` times faster than their time
    stamps (MBOX Fn012 = 1200: ``c = 1.2``) moves the motors ``c`` times as fast as the frames
    say, and accelerates ``c**2`` as hard. The limits are planned on the host's clock, so every
    speed limit is divided by ``c`` and every acceleration (jerk) limit by ``c**2`` (``c**3``).

Jerk (``j_max``)
    Only from the override or the platform (no controller parameter defines it).

A quantity with no source raises :class:`~motioncue.ConfigError` naming what to give.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING

import numpy as np

from .._errors import ConfigError, LimitError
from ._limits import ActuatorLimits

if TYPE_CHECKING:
    from ..kinematics import Drive, Platform
    from ..output import Controller, DriveExpectations, PulseLimits

__all__ = ["limits_from_platform", "pulse_rounding_limits", "within_controller_stroke"]


def _per_axis(name: str, value: float | Sequence[float] | None, n: int) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.array(value, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, float(arr[0]))
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: one number or {n} numbers")
    return arr


def limits_from_platform(
    platform: Platform,
    controller: Controller | None = None,
    *,
    stroke_margin: float | Sequence[float] | None = None,
    v_max: float | Sequence[float] | None = None,
    a_max: float | Sequence[float] | None = None,
    j_max: float | Sequence[float] | None = None,
    rate_hz: float | None = None,
) -> ActuatorLimits:
    """See the module docstring for the rules. Overrides are SI (m or rad based).

    ``rate_hz``: the frame rate, for controllers whose limits depend on it (an EasySmc frame
    is a move that must ramp up and down within one period); None gives the limits that hold
    at any rate.
    """
    n = int(platform.n_actuators)
    kinds = tuple(platform.actuator_kinds)
    q_min = np.array(platform.q_min, dtype=float)
    q_max = np.array(platform.q_max, dtype=float)
    sources: dict[str, str] = {"stroke": f"platform {getattr(platform, 'name', '?')} usable stroke"}
    margin = _per_axis("stroke_margin", stroke_margin, n)
    if margin is not None:
        if np.any(margin < 0):
            raise ConfigError(f"stroke_margin = {stroke_margin!r} is invalid; allowed: >= 0")
        q_min, q_max = q_min + margin, q_max - margin
        sources["stroke"] += f" minus extra margin {margin.tolist()}"

    drives = platform.drives
    ppu = np.abs(np.asarray(drives.pulses_per_unit, dtype=float))
    v_cands: list[tuple[np.ndarray, str]] = []
    a_cands: list[tuple[np.ndarray, str]] = []
    catch_up = 1.0

    if controller is not None:
        who = f"controller {getattr(controller, 'name', '?')!r}"
        n_axes = int(controller.n_axes)
        if n_axes != n:
            raise ConfigError(
                f"{who} drives {n_axes} axes; platform {getattr(platform, 'name', '?')!r} has "
                f"{n} actuators"
            )
        _check_drives(platform, controller.drive_expectations(), who)
        catch_up = float(controller.catch_up_factor)
        if not (np.isfinite(catch_up) and catch_up >= 1.0):
            raise ConfigError(f"{who}: catch_up_factor = {catch_up!r}; allowed: >= 1")
        pl = controller.pulse_limits(rate_hz)
        if pl.has_stroke:
            q_min, q_max = _within_stroke(drives, pl, q_min, q_max)
            sources["stroke"] += f" within {pl.sources.get('stroke', who + ' stroke')}"
        if pl.has_speed:
            v_cands.append((pl.max_speed_pulses_s / ppu, pl.sources.get("v_max", who)))
        if pl.has_accel:
            a_cands.append((pl.max_accel_pulses_s2 / ppu, pl.sources.get("a_max", who)))

    # a platform description may carry its own actuator limits (SI arrays v_max / a_max /
    # j_max), e.g. the servo's rated speed; they take part like any other source
    for attr, cands in (("v_max", v_cands), ("a_max", a_cands)):
        own = getattr(platform, attr, None)
        if own is not None:
            arr = _per_axis(f"platform {attr}", own, n)
            if arr is not None:
                cands.append((arr, "platform config"))
    ov_v = _per_axis("v_max", v_max, n)
    ov_a = _per_axis("a_max", a_max, n)
    if ov_v is not None:
        v_cands.append((ov_v, "given"))
    if ov_a is not None:
        a_cands.append((ov_a, "given"))
    if not v_cands:
        raise ConfigError(
            "no maximum speed known: give v_max (--max-speed; m/s or rad/s) or a controller"
        )
    if not a_cands:
        raise ConfigError(
            "no maximum acceleration known: give a_max (--max-accel; m/s^2 or rad/s^2), a "
            "[limits] table in the platform config, or a controller that sets one"
        )
    v = np.min(np.stack([c for c, _ in v_cands]), axis=0)
    a = np.min(np.stack([c for c, _ in a_cands]), axis=0)
    sources["v_max"] = "min of: " + "; ".join(s for _, s in v_cands)
    sources["a_max"] = "min of: " + "; ".join(s for _, s in a_cands)
    j_cands: list[tuple[np.ndarray, str]] = []
    own_j = getattr(platform, "j_max", None)
    if own_j is not None:
        arr = _per_axis("platform j_max", own_j, n)
        if arr is not None:
            j_cands.append((arr, "platform config"))
    ov_j = _per_axis("j_max", j_max, n)
    if ov_j is not None:
        j_cands.append((ov_j, "given"))
    j = None
    if j_cands:
        j = np.min(np.stack([c for c, _ in j_cands]), axis=0)
        sources["j_max"] = "min of: " + "; ".join(s for _, s in j_cands)
    if catch_up != 1.0:
        v, a = v / catch_up, a / catch_up**2
        note = (
            f"; divided by the controller's catch-up factor {catch_up:g} (speed), "
            f"{catch_up:g}^2 (acceleration): it may play frames that much faster than stamped"
        )
        sources["v_max"] += note
        sources["a_max"] += note
        if j is not None:
            j = j / catch_up**3
            sources["j_max"] += f"; divided by {catch_up:g}^3 (catch-up)"
    sources["catch_up"] = f"{catch_up:g}"
    return ActuatorLimits(q_min, q_max, v, a, j, tuple(platform.actuator_names), kinds, sources)


def _check_drives(platform: Platform, expect: DriveExpectations, who: str) -> None:
    """Refuse a platform drive that disagrees with what the controller's parameters say."""
    drives = platform.drives
    kinds = tuple(platform.actuator_kinds)
    ppr = np.asarray(drives.pulses_per_rev, dtype=float).reshape(-1)
    lead = np.abs(np.asarray(drives.units_per_rev, dtype=float).reshape(-1))
    pname = getattr(platform, "name", "?")
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
    IMAX stroke_mm / PA40), as :func:`limits_from_platform` builds it.

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
    pulse_limits = getattr(controller, "pulse_limits", None)
    if pulse_limits is None:
        return limits, None
    pl = pulse_limits(rate_hz)
    if not pl.has_stroke:
        return limits, None
    q_min, q_max = _within_stroke(platform.drives, pl, limits.q_min, limits.q_max)
    if np.array_equal(q_min, limits.q_min) and np.array_equal(q_max, limits.q_max):
        return limits, None
    name = getattr(controller, "name", "?")
    where = pl.sources.get("stroke", f"controller {name} stroke")
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
