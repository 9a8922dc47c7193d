"""Effective actuator limits from platform + drive + controller parameters (+ overrides).

Rules, each recorded in :attr:`ActuatorLimits.sources`:

Stroke
    The platform's usable stroke ``[q_min, q_max]`` (its config already keeps ``margin_mm``
    from each end stop), shrunk by ``stroke_margin`` (SI, optional extra margin), and
    intersected with the controller's own stroke where it defines one:

    * SC-MBOX: ``Fn0C0`` is the stroke in 0.1 mm from the homed origin (pulse 0) and
      ``Fn0C1`` the pulses per mm; allowed pulses ``[0, Fn0C0/10 * Fn0C1]`` (Fn0C0 = 0: no
      limit). ``Fn0C1`` must agree with the platform's drive (pulses per mm), otherwise the
      positions sent would be wrong and a :class:`~motioncue.ConfigError` is raised.
    * IMAX: the manual defines no stroke parameter (PA42 is called "maximum stroke" in 5.7
      but "axis-1 lift" in the parameter table), so none is taken from it.
    * EasySmc 2300: the per-axis soft limits (commands 21..23/27..29, AF), in pulses.

Speed (``v_max``)
    The smallest of: the override ``v_max``; IMAX ``PA07`` (global, rpm), ``PA8x`` (per axis,
    rpm, 0 = none), ``PAax x PAbx`` (per axis; 5.10: their product is the axis' maximum
    speed in rpm); MBOX ``max_motor_speed_rpm`` when the controller description has it;
    EasySmc: the ``A3_feed_hz`` / ``A6_feed_hz`` cap (pulses/s; a necessary bound only, as
    each frame's move also ramps at the controller's accelerations from its start frequency).
    rpm become SI through the platform's drive: ``rpm / 60 * units_per_rev`` (the screw lead
    for a cylinder, ``2 pi / gear_ratio`` for a crank). IMAX ``PA41`` (lead, 0.1 mm) must
    agree with the platform's lead for linear actuators.

Acceleration (``a_max``)
    The smallest of: the override ``a_max``; IMAX ``PAbx`` read as the speed change in rpm
    per control period (5.10: the speed ramps up in ``PAax`` steps of ``PAbx`` rpm); the
    manual does not state the control period, taken as ``IMAX_RAMP_PERIOD_S`` = 1 ms (an
    assumption, stated in ``sources``). With the manual's example (PAa0 = 2, PAb0 = 1500) and
    a 5 mm lead that is 125 m/s^2: the controller's ramp is no practical limit and a rider
    limit should be given as an override.

Jerk (``j_max``)
    Only from the override or the platform (no controller parameter defines it).

Platform
    A platform description that carries ``v_max`` / ``a_max`` / ``j_max`` (SI, per actuator;
    the platform config's optional ``[limits]`` table) takes part in the minimum like any
    other source.

A quantity with no source raises :class:`~motioncue.ConfigError` naming what to give.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .._errors import ConfigError
from ._limits import ActuatorLimits

__all__ = ["IMAX_RAMP_PERIOD_S", "limits_from_platform"]

IMAX_RAMP_PERIOD_S = 1e-3


def _per_axis(name: str, value: float | Sequence[float] | None, n: int) -> np.ndarray | None:
    if value is None:
        return None
    arr = np.array(value, dtype=float).reshape(-1)
    if arr.size == 1:
        arr = np.full(n, float(arr[0]))
    if arr.shape != (n,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: one number or {n} numbers")
    return arr


def _param(params: Any, name: str) -> int | None:
    try:
        return int(params[name]) if name in params else None
    except (TypeError, KeyError):
        return None


def limits_from_platform(
    platform: Any,
    controller: Any = None,
    *,
    stroke_margin: float | Sequence[float] | None = None,
    v_max: float | Sequence[float] | None = None,
    a_max: float | Sequence[float] | None = None,
    j_max: float | Sequence[float] | None = None,
) -> ActuatorLimits:
    """See the module docstring for the rules. Overrides are SI (m or rad based)."""
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
    units_per_rev = np.abs(np.asarray(drives.units_per_rev, dtype=float))
    v_cands: list[tuple[np.ndarray, str]] = []
    a_cands: list[tuple[np.ndarray, str]] = []

    if controller is not None:
        kind = getattr(controller, "kind", None)
        params = getattr(controller, "parameters", {}) or {}
        n_axes = int(getattr(controller, "n_axes", n))
        if n_axes != n:
            raise ConfigError(
                f"controller {getattr(controller, 'name', kind)!r} drives {n_axes} axes; "
                f"platform {getattr(platform, 'name', '?')!r} has {n} actuators"
            )
        if kind == "imax":
            lead = _param(params, "PA41")
            for i in range(n):
                if kinds[i] == "linear" and lead:
                    ours = units_per_rev[i] * 1e4  # 0.1 mm
                    if abs(ours - lead) > 1e-6 * max(lead, 1):
                        raise ConfigError(
                            f"IMAX PA41 = {lead} (0.1 mm) disagrees with the platform's lead "
                            f"{units_per_rev[i] * 1e3:g} mm on actuator {i + 1}"
                        )
            rpm = np.full(n, np.inf)
            acc_rpm_s = np.full(n, np.inf)
            pa07 = _param(params, "PA07")
            if pa07:
                rpm = np.minimum(rpm, pa07)
            for i in range(min(n, 6)):
                p8 = _param(params, f"PA8{i:x}")
                if p8:
                    rpm[i] = min(rpm[i], p8)
                fa, fb = _param(params, f"PAa{i:x}"), _param(params, f"PAb{i:x}")
                if fa and fb:
                    rpm[i] = min(rpm[i], fa * fb)
                    acc_rpm_s[i] = fb / IMAX_RAMP_PERIOD_S
            if np.all(np.isfinite(rpm)):
                v_cands.append((rpm / 60.0 * units_per_rev, "IMAX min(PA07, PA8x, PAax*PAbx) rpm"))
            if np.all(np.isfinite(acc_rpm_s)):
                a_cands.append(
                    (
                        acc_rpm_s / 60.0 * units_per_rev,
                        f"IMAX PAbx rpm per {IMAX_RAMP_PERIOD_S * 1e3:g} ms ramp step (assumed)",
                    )
                )
        elif kind == "mbox":
            c0 = _param(params, "Fn0C0")
            c1 = _param(params, "Fn0C1")
            c1 = 2000 if c1 is None else c1  # factory default
            ppu = np.abs(np.asarray(drives.pulses_per_unit, dtype=float))
            for i in range(n):
                if kinds[i] == "linear" and abs(ppu[i] / 1000.0 - c1) > 1e-6 * c1:
                    raise ConfigError(
                        f"MBOX Fn0C1 = {c1} pulses/mm disagrees with the platform's drive "
                        f"({ppu[i] / 1000.0:g} pulses/mm) on actuator {i + 1}"
                    )
            if c0:
                pulses = np.zeros((2, n), dtype=np.int64)
                pulses[1] = round(c0 / 10.0 * c1)
                ends = np.asarray(drives.from_pulses(pulses), dtype=float)
                lo, hi = np.minimum(ends[0], ends[1]), np.maximum(ends[0], ends[1])
                q_min, q_max = np.maximum(q_min, lo), np.minimum(q_max, hi)
                sources["stroke"] += f" within MBOX Fn0C0 = {c0} (0.1 mm), Fn0C1 = {c1}"
            rpm_m = getattr(controller, "max_motor_speed_rpm", None)
            if rpm_m:
                v_cands.append(
                    (np.full(n, float(rpm_m)) / 60.0 * units_per_rev, "MBOX max_motor_speed_rpm")
                )
        elif kind == "easysmc":
            ppu = np.abs(np.asarray(drives.pulses_per_unit, dtype=float))
            soft = getattr(controller, "soft_limits", None)
            if callable(soft):
                pulses = np.array(soft(), dtype=np.int64).T  # (2, n): negative, positive
                ends = np.asarray(drives.from_pulses(pulses), dtype=float)
                lo, hi = np.minimum(ends[0], ends[1]), np.maximum(ends[0], ends[1])
                q_min, q_max = np.maximum(q_min, lo), np.minimum(q_max, hi)
                sources["stroke"] += " within EasySmc soft limits (21..29, AF)"
            units = getattr(controller, "units", ())
            caps = [
                float(params[f"{'A3' if u.axes == 'XYZ' else 'A6'}_feed_hz"])
                for u in units
                for _ in u.axes
                if f"{'A3' if u.axes == 'XYZ' else 'A6'}_feed_hz" in params
            ]
            if len(caps) == n:
                v_cands.append(
                    (
                        np.asarray(caps) / ppu,
                        "EasySmc A3/A6 feed cap, pulses/s (necessary only: each frame's move "
                        "also ramps at the A3/A6 accelerations from the start frequency)",
                    )
                )
        elif kind is not None:
            raise ConfigError(
                f"controller kind {kind!r} is unknown; allowed: imax | mbox | easysmc"
            )

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
            "no maximum acceleration known: give a_max (--max-accel; m/s^2 or rad/s^2) "
            "or an IMAX controller"
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
    return ActuatorLimits(q_min, q_max, v, a, j, tuple(platform.actuator_names), kinds, sources)
