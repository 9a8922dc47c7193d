"""Platform configuration files (TOML, human units in key names) -> frozen platform models.

Layout of a platform file::

    kind = "stewart6-linear"          # a registered platform kind (PLATFORM_KINDS): bundled
                                      # stewart6-linear | stewart6-rotary | seat3 | seat2-yaw
                                      # | corner4
    description = "..."
    actuators = ["1", "2", ...]       # controller order: the legs (then the yaw axis)
    spare_axes = ["5", "6"]           # optional: controller axes after the actuators that
                                      # drive nothing, held at pulse 0 (a 6-axis MBOX/IMAX
                                      # under a 4- or 5-actuator rig)
    default_preset = "racing-hexapod" # optional: the cueing preset used when a command is
                                      # given no --preset (a bundled name or a path)
    ride_preset = "optimal-hexapod"   # optional: the one generate and cue use instead (the
                                      # whole recording known: a plan that sees the ride)

    [geometry]                        # anchors: a symmetric ring layout (hexapods) or the
                                      # measured joint centres, one [x, y, z] per leg, in mm
                                      # (base_anchors_mm, platform_anchors_mm) or metres
                                      # (base_anchors_m, platform_anchors_m)
    [stroke]                          # linear legs: retracted_length_mm, stroke_mm, margin_mm
    [crank]                           # rotary legs: crank_mm, rod_mm, min_deg, max_deg
    [drive]                           # leg drives (screw lead or gear ratio, pulses, homing)
    [yaw]                             # seat2-yaw: min_deg, max_deg, gear_ratio, pulses...
    [traction_loss]                   # optional, any kind but seat2-yaw: a yaw slider on top,
                                      # one more linear actuator (see _traction_loss)

Every value is converted to SI once, here. Unknown keys, missing keys and impossible values
raise :class:`~motioncue.ConfigError` naming the file, the key and the value.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .._config import ConfigReader, find_config, load_toml
from .._errors import ConfigError
from ._drive import Drive
from ._kinds import (
    PLATFORM_KINDS,
    PlatformFile,
    PlatformKind,
    PlatformReader,
    register_platform_kind,
)
from ._legs import CrankLegs
from ._platform import (
    Corner4,
    LinearLegPlatform,
    Platform,
    Seat2Yaw,
    Seat3,
    Stewart6Linear,
    Stewart6Rotary,
)

__all__ = ["linear_legs_reader", "load_platform", "platform_from_dict"]

_MM = 1e-3


def load_platform(name_or_path: str | Path) -> Platform:
    """Load a platform: a bundled name (``"stewart6-linear"``) or a path to a ``.toml`` file.

    Parameters
    ----------
    name_or_path
        Bundled names: ``stewart6-linear``, ``stewart6-rotary``, ``seat3``, ``seat2-yaw``,
        ``corner4``, ``corner4-tl``.

    Returns
    -------
    Platform
        Frozen model (:class:`Stewart6Linear`, :class:`Stewart6Rotary`, :class:`Seat3`,
        :class:`Seat2Yaw` or :class:`Corner4`; a plain :class:`Platform` when the file adds a
        ``[traction_loss]`` slider or ``spare_axes``).

    Raises
    ------
    ConfigError
        Unknown name, unreadable file, unknown or missing key, impossible value.
    """
    path = find_config("platforms", name_or_path)
    return platform_from_dict(load_toml(path), where=path.name, name=path.stem)


def _ring(g: ConfigReader, which: str) -> np.ndarray:
    """Anchors of a symmetric ring: pairs centred at 0, 120, 240 deg (pair 1 at the front, +x),
    each pair at +-``pair_angle`` about its centre, first the clockwise one."""
    radius = g.number(f"{which}_radius_mm", lo=0.0, lo_open=True) * _MM
    half = g.number(f"{which}_pair_angle_deg", lo=0.0, hi=60.0, hi_open=True)
    z = g.number(f"{which}_z_mm", 0.0) * _MM
    out = []
    for centre in (0.0, 120.0, 240.0):
        for side in (-1.0, 1.0):
            a = math.radians(centre + side * half)
            out.append([radius * math.cos(a), radius * math.sin(a), z])
    return np.array(out)


def _anchor_list(g: ConfigReader, key: str, n: int) -> np.ndarray:
    """``key_mm`` or ``key_m``: ``n`` measured [x, y, z] joint centres, returned in metres."""
    unit = "m" if g.has(f"{key}_m") else "mm"
    if g.has(f"{key}_m") and g.has(f"{key}_mm"):
        raise ConfigError(f"{g.where}: give either '{key}_mm' or '{key}_m', not both")
    key = f"{key}_{unit}"
    value = g.raw(key)
    if (
        not isinstance(value, list)
        or len(value) != n
        or not all(
            isinstance(row, list)
            and len(row) == 3
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in row)
            and all(math.isfinite(v) for v in row)
            for row in value
        )
    ):
        raise g.error(key, value, f"a list of {n} [x, y, z] triples of finite numbers ({unit})")
    return np.array(value, dtype=float) * (1.0 if unit == "m" else _MM)


def _anchors(g: ConfigReader, n: int) -> tuple[np.ndarray, np.ndarray]:
    if any(g.has(f"{w}_anchors_{u}") for w in ("base", "platform") for u in ("mm", "m")):
        return _anchor_list(g, "base_anchors", n), _anchor_list(g, "platform_anchors", n)
    if n != 6:
        raise ConfigError(
            f"{g.where}: missing key 'base_anchors_mm' (and 'platform_anchors_mm'): "
            f"{n} [x, y, z] triples in mm (or base_anchors_m, platform_anchors_m in metres)"
        )
    return _ring(g, "base"), _ring(g, "platform")


def _per_actuator(
    r: ConfigReader,
    key: str,
    n: int,
    default: object,
    *,
    integer: bool = False,
    lo: float = -math.inf,
    lo_open: bool = False,
    hi: float = 1e12,
) -> np.ndarray:
    """A number, or a list of ``n`` numbers, one per actuator (``default`` None: required),
    each in ``[lo, hi]`` (``hi`` defaults to 1e12: no quantity of a motion platform in its
    config units is larger, and larger ones overflow the pulse arithmetic)."""
    if not r.has(key) and default is None:
        raise ConfigError(f"{r.where}: missing key {key!r}")
    if r.has(key) and isinstance(r.raw(key), list):
        vals = r.vector(key, n)
    elif integer:
        vals = (float(r.integer(key, default)),) * n
    else:
        vals = (r.number(key, default),) * n
    arr = np.array(vals, dtype=float)
    below = arr <= lo if lo_open else arr < lo
    if np.any(below) or np.any(arr > hi) or (integer and np.any(arr != np.round(arr))):
        what = "integers" if integer else "numbers"
        sign = ">" if lo_open else ">="
        raise r.error(key, r.raw(key), f"{what} {sign} {lo} and <= {hi:g}, one or a list of {n}")
    return arr


def _direction(r: ConfigReader, n: int) -> np.ndarray:
    arr = _per_actuator(r, "direction", n, 1, integer=True, lo=-1)
    if not np.all(np.isin(arr, (-1.0, 1.0))):
        raise r.error("direction", r.raw("direction"), f"+1 or -1, one or a list of {n}")
    return arr.astype(int)


def _pulses_per_rev(r: ConfigReader, n: int, travel_per_rev_mm: np.ndarray | None) -> np.ndarray:
    """``pulses_per_rev``, or for a screw ``pulses_per_mm`` (MBOX Fn0C1) times the lead."""
    if r.has("pulses_per_mm") and travel_per_rev_mm is not None:
        if r.has("pulses_per_rev"):
            raise ConfigError(
                f"{r.where}: give either 'pulses_per_rev' or 'pulses_per_mm', not both"
            )
        ppmm = _per_actuator(r, "pulses_per_mm", n, None, lo=0.0, lo_open=True)
        ppr = ppmm * travel_per_rev_mm
        if np.any(np.abs(ppr - np.round(ppr)) > 1e-9):
            raise r.error(
                "pulses_per_mm",
                r.raw("pulses_per_mm"),
                "a value giving a whole number of pulses per revolution with lead_mm",
            )
        return np.asarray(np.round(ppr), dtype=float)
    if not r.has("pulses_per_rev"):
        alt = " or 'pulses_per_mm'" if travel_per_rev_mm is not None else ""
        raise ConfigError(f"{r.where}: missing key 'pulses_per_rev'{alt}")
    return _per_actuator(r, "pulses_per_rev", n, None, integer=True, lo=1, hi=_INT32_MAX)


def _linear_stroke(cfg: ConfigReader, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(retracted, usable_min, usable_max) pin-to-pin lengths (m), per leg."""
    s = cfg.table("stroke")
    retracted = _per_actuator(s, "retracted_length_mm", n, None, lo=0.0, lo_open=True) * _MM
    stroke = _per_actuator(s, "stroke_mm", n, None, lo=0.0, lo_open=True) * _MM
    margin = _per_actuator(s, "margin_mm", n, 0.0, lo=0.0) * _MM
    if np.any(2 * margin >= stroke):
        raise s.error("margin_mm", s.raw("margin_mm"), "less than half of stroke_mm")
    s.finish()
    return retracted, retracted + margin, retracted + stroke - margin


def _linear_drive(
    cfg: ConfigReader,
    n: int,
    retracted: np.ndarray,
    neutral_length: np.ndarray,
    usable: tuple[np.ndarray, np.ndarray],
) -> Drive:
    d = cfg.table("drive")
    lead_mm = _per_actuator(d, "lead_mm", n, None, lo=0.0, lo_open=True)
    ppr = _pulses_per_rev(d, n, lead_mm)
    direction = _direction(d, n)
    lift = _per_actuator(d, "home_lift_mm", n, 0.0, lo=0.0) * _MM
    home_length = retracted + lift
    bad = (home_length < usable[0] - 1e-12) | (home_length > usable[1] + 1e-12)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise d.error(
            "home_lift_mm",
            d.raw("home_lift_mm"),
            "a lift keeping the homed length inside the usable stroke "
            f"[{(usable[0][i] - retracted[i]) / _MM:.6g}, "
            f"{(usable[1][i] - retracted[i]) / _MM:.6g}] mm above retracted (margin_mm)",
        )
    d.finish()
    return Drive.linear(lead_mm * _MM, ppr.astype(int), home_length - neutral_length, direction)


def _check_neutral(
    g: ConfigReader,
    lengths: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    names: tuple[str, ...],
) -> None:
    bad = (lengths <= lo) | (lengths >= hi)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise g.error(
            "neutral_height_mm",
            g.raw("neutral_height_mm"),
            f"a height (or anchors) putting every leg inside its usable stroke at neutral: "
            f"actuator {names[i]!r} (leg {i + 1}) cannot reach the neutral pose, its length "
            f"would be {lengths[i] / _MM:.6g} mm, usable {lo[i] / _MM:.6g}..{hi[i] / _MM:.6g} mm",
        )


def platform_from_dict(
    data: dict[str, object], where: str = "<dict>", name: str = "platform"
) -> Platform:
    """Build a platform from a parsed TOML table (see the module docstring for the layout).

    The ``kind`` names a registered platform kind (:data:`PLATFORM_KINDS`): this reads the
    keys every kind shares, then hands the rest to the kind's reader.
    """
    cfg = ConfigReader(data, where)
    kind_name = cfg.string("kind")
    if kind_name not in PLATFORM_KINDS:
        raise cfg.error(
            "kind",
            kind_name,
            f"{' | '.join(PLATFORM_KINDS)} (the registered platform kinds; a plugin module "
            "named in MOTIONCUE_PLUGINS registers more)",
        )
    kind = PLATFORM_KINDS[kind_name]
    description = cfg.string("description", "")
    presets: dict[str, str | None] = {}
    for key in ("default_preset", "ride_preset"):
        presets[key] = cfg.string(key, "") or None
        if presets[key] is not None:
            try:
                find_config("cueing", str(presets[key]))
            except ConfigError as exc:
                raise cfg.error(key, presets[key], f"a cueing preset ({exc})") from exc
    default_preset, ride_preset = presets["default_preset"], presets["ride_preset"]
    n_legs = kind.n_legs
    has_tl = cfg.has("traction_loss")
    if has_tl and kind.yaw_axis:
        raise cfg.error(
            "traction_loss", "...", f"no [traction_loss] on {kind.name} (its turntable is its yaw)"
        )
    n_act = kind.n_actuators + (1 if has_tl else 0)
    names_raw = cfg.raw("actuators")
    if (
        not isinstance(names_raw, list)
        or len(names_raw) != n_act
        or not all(isinstance(v, str) and v for v in names_raw)
        or len(set(names_raw)) != n_act
    ):
        raise cfg.error(
            "actuators", names_raw, f"{n_act} distinct non-empty names, controller order"
        )
    names = tuple(names_raw)
    spare = _spare_names(cfg, names)
    g = cfg.table("geometry")
    base, plat = _anchors(g, n_legs)
    height = g.number("neutral_height_mm", lo=0.0, lo_open=True) * _MM
    source = PlatformFile(cfg, g, base, plat, height, names[: kind.n_actuators], name, description)
    platform = kind.reader(source)
    _check_built(kind, platform, where)
    tl_limits: dict[str, float] = {}
    if has_tl:
        platform, tl_limits = _traction_loss(cfg.table("traction_loss"), platform, names[-1])
    if spare:
        platform = platform.with_spare_axes(spare)
    platform = _actuator_limits(cfg, platform, tl_limits)
    if default_preset is not None:
        platform = platform.with_default_preset(default_preset)
    if ride_preset is not None:
        platform = platform.with_ride_preset(ride_preset)
    cfg.finish()
    _check_pulse_range(platform, where)
    return platform


def _check_built(kind: PlatformKind, platform: Platform, where: str) -> None:
    """A kind's reader must return its class with its legs and actuators (a plugin's bug is
    named here, not found downstream)."""
    if (
        not isinstance(platform, kind.platform_class)
        or platform.legs.n != kind.n_legs
        or platform.n_actuators != kind.n_actuators
        or platform.has_yaw_axis != kind.yaw_axis
    ):
        raise ConfigError(
            f"{where}: the reader of platform kind {kind.name!r} returned {platform!r}; "
            f"expected a {kind.platform_class.__name__} with {kind.n_legs} legs and "
            f"{kind.n_actuators} actuators"
        )


def _linear_legs(f: PlatformFile) -> tuple[Drive, np.ndarray]:
    """The legs' drive and ``(n, 2)`` usable pin-to-pin lengths (m) from ``[stroke]`` and
    ``[drive]``, after the neutral pose is checked inside the stroke."""
    n = f.base_anchors_m.shape[0]
    f.geometry.finish()
    retracted, lo, hi = _linear_stroke(f.config, n)
    neutral = np.linalg.norm(
        f.platform_anchors_m + np.array([0.0, 0.0, f.neutral_height_m]) - f.base_anchors_m,
        axis=1,
    )
    _check_neutral(f.geometry, neutral, lo, hi, f.actuator_names[:n])
    drive = _linear_drive(f.config, n, retracted, neutral, (lo, hi))
    return drive, np.stack([lo, hi], axis=1)


def linear_legs_reader(cls: type[LinearLegPlatform]) -> PlatformReader:
    """The reader of a kind made of linear legs only (a :class:`LinearLegPlatform` subclass).

    It reads ``[stroke]`` (``retracted_length_mm``, ``stroke_mm``, ``margin_mm``) and
    ``[drive]`` (``lead_mm``, ``pulses_per_rev`` or ``pulses_per_mm``, ``direction``,
    ``home_lift_mm``), as for the bundled ``stewart6-linear``, ``seat3`` and ``corner4``.
    """

    def read(f: PlatformFile) -> Platform:
        drive, stroke = _linear_legs(f)
        return cls(
            f.base_anchors_m,
            f.platform_anchors_m,
            f.neutral_height_m,
            stroke,
            drives=drive,
            name=f.name,
            actuator_names=f.actuator_names,
            description=f.description,
        )

    return read


def _seat2_yaw(f: PlatformFile) -> Platform:
    """Two linear legs on a turntable: ``[stroke]``, ``[drive]`` and ``[yaw]``."""
    drive, stroke = _linear_legs(f)
    y = f.config.table("yaw")
    lo_deg = y.number("min_deg", lo=-360.0, hi=0.0, hi_open=True)
    hi_deg = y.number("max_deg", lo=0.0, hi=360.0, lo_open=True)
    gear = y.number("gear_ratio", lo=0.0, hi=1e12, lo_open=True)
    ppr = y.integer("pulses_per_rev", lo=1, hi=_INT32_MAX)
    direction = y.integer("direction", 1)
    if direction not in (-1, 1):
        raise y.error("direction", direction, "+1 or -1")
    home = y.number("home_deg", 0.0)
    if not lo_deg <= home <= hi_deg:
        raise y.error("home_deg", home, f"inside [min_deg, max_deg] = [{lo_deg}, {hi_deg}]")
    y.finish()
    yaw_drive = Drive.rotary(gear, ppr, [math.radians(home)], direction)
    return Seat2Yaw(
        f.base_anchors_m,
        f.platform_anchors_m,
        f.neutral_height_m,
        stroke,
        (math.radians(lo_deg), math.radians(hi_deg)),
        drives=Drive.concat(drive, yaw_drive),
        name=f.name,
        actuator_names=f.actuator_names,
        description=f.description,
    )


_INT32_MAX = 2**31 - 1


def _check_pulse_range(platform: Platform, where: str) -> None:
    """Every stroke position must be a pulse count the controllers' frames carry (int32):
    refuses absurd strokes, leads, gear ratios and pulse counts (``pulses_per_rev = 1e20``)
    with the numbers, before they overflow anywhere downstream."""
    drives = platform.drives
    ppu = np.asarray(drives.pulses_per_unit, dtype=float)
    with np.errstate(over="ignore", invalid="ignore"):
        ends = np.stack([platform.q_min, platform.q_max]) - drives.q_home
        pulses = ends * ppu
    bad = ~np.isfinite(pulses) | (np.abs(pulses) > _INT32_MAX)
    if np.any(bad):
        k, i = (int(x) for x in np.argwhere(bad)[0])
        raise ConfigError(
            f"{where}: actuator {platform.actuator_names[i]!r}: its stroke end is "
            f"{pulses[k, i]:.6g} pulses from the homed position (pulses per unit "
            f"{ppu[i]:.6g}); allowed: within the int32 positions of the controllers' frames "
            f"(|pulses| <= {_INT32_MAX}); check the stroke, lead / gear ratio and pulses"
        )


def _spare_names(cfg: ConfigReader, names: tuple[str, ...]) -> tuple[str, ...]:
    """The optional ``spare_axes`` list: names of controller axes held at pulse 0."""
    if not cfg.has("spare_axes"):
        return ()
    raw = cfg.raw("spare_axes")
    if (
        not isinstance(raw, list)
        or not 1 <= len(raw) <= 6
        or not all(isinstance(v, str) and v for v in raw)
        or len(set(raw) | set(names)) != len(raw) + len(names)
    ):
        raise cfg.error("spare_axes", raw, "1..6 distinct non-empty names, none an actuator's name")
    return tuple(raw)


def _traction_loss(
    t: ConfigReader, platform: Platform, name: str
) -> tuple[Platform, dict[str, float]]:
    """The ``[traction_loss]`` table: a yaw slider on top, one more linear actuator (the last
    name of ``actuators``).

    Keys: ``arm_mm`` (pivot to the pin the actuator pushes, > 0), ``stroke_mm``,
    ``margin_mm`` (kept free at each end), ``lead_mm``, ``pulses_per_rev`` or
    ``pulses_per_mm``, ``direction``, ``home_lift_mm`` (pulse 0 this far above the retracted
    end, as the legs' IMAX PA40), and its own limits ``max_speed_mm_s``, ``max_accel_mm_s2``,
    ``max_jerk_mm_s3`` (optional). The slider's travel is measured from its centre (the
    neutral pose, yaw 0).
    """
    arm = t.number("arm_mm", lo=0.0, hi=1e6, lo_open=True) * _MM
    stroke = t.number("stroke_mm", lo=0.0, hi=1e6, lo_open=True) * _MM
    margin = t.number("margin_mm", 0.0, lo=0.0) * _MM
    if 2 * margin >= stroke:
        raise t.error("margin_mm", margin / _MM, "less than half of stroke_mm")
    lead = t.number("lead_mm", lo=0.0, hi=1e6, lo_open=True)
    ppr = _pulses_per_rev(t, 1, np.array([lead]))
    direction = _direction(t, 1)
    lift = t.number("home_lift_mm", 0.0, lo=0.0) * _MM
    lo, hi = -stroke / 2 + margin, stroke / 2 - margin
    home = -stroke / 2 + lift
    if not lo <= home <= hi:
        raise t.error(
            "home_lift_mm",
            lift / _MM,
            f"a lift in [{margin / _MM:g}, {(stroke - margin) / _MM:g}] mm (inside the usable "
            "travel)",
        )
    limits: dict[str, float] = {}
    for key, what in (("v_max", "max_speed_mm_s"), ("a_max", "max_accel_mm_s2"),
                      ("j_max", "max_jerk_mm_s3")):  # fmt: skip
        if t.has(what):
            limits[key] = t.number(what, lo=0.0, hi=1e12, lo_open=True) * _MM
    t.finish()
    drive = Drive.linear(lead * _MM, ppr.astype(int), [home], direction)
    out = platform.with_traction_loss(name=name, arm_m=arm, q_min=lo, q_max=hi, drive=drive)
    return out, limits


def _actuator_limits(
    cfg: ConfigReader, platform: Platform, tl_limits: dict[str, float]
) -> Platform:
    """The optional ``[limits]`` table: the actuators' own speed/acceleration/jerk limits.

    Linear legs: ``max_speed_mm_s``, ``max_accel_mm_s2``, ``max_jerk_mm_s3``; crank legs:
    ``max_speed_deg_s``, ``max_accel_deg_s2``, ``max_jerk_deg_s3`` (each one number or one per
    leg). A turntable (the yaw axis of ``seat2-yaw``): ``yaw_max_speed_deg_s``,
    ``yaw_max_accel_deg_s2``, ``yaw_max_jerk_deg_s3``. A traction-loss slider takes its own
    from ``[traction_loss]``; spare axes (held at pulse 0) take the legs' smallest. A
    quantity is used when it is given for every moving actuator.
    """
    if not cfg.has("limits"):
        return platform
    lim = cfg.table("limits")
    n_legs = platform.legs.n
    rotary = platform.actuator_kinds[0] == "rotary"
    unit, scale = ("deg", math.pi / 180.0) if rotary else ("mm", _MM)
    turntable = platform.has_yaw_axis and platform.traction_loss_arm_m is None
    values: dict[str, np.ndarray | None] = {}
    for key, what, suffix in (("v_max", "speed", "s"), ("a_max", "accel", "s2"),
                              ("j_max", "jerk", "s3")):  # fmt: skip
        name = f"max_{what}_{unit}_{suffix}"
        legs = (
            _per_actuator(lim, name, n_legs, None, lo=0.0, lo_open=True) * scale
            if lim.has(name)
            else None
        )
        if turntable:
            yaw_name = f"yaw_max_{what}_deg_{suffix}"
            yaw = lim.number(yaw_name, lo=0.0, lo_open=True) if lim.has(yaw_name) else None
            if (legs is None) != (yaw is None):
                raise lim.error(
                    name if legs is None else yaw_name, None, f"both {name} and {yaw_name}"
                )
            if legs is not None and yaw is not None:
                legs = np.append(legs, math.radians(yaw))
        if platform.traction_loss_arm_m is not None and legs is not None:
            if key not in tl_limits:
                raise ConfigError(
                    f"{cfg.where} [traction_loss]: missing key "
                    f"'max_{what}_mm_{suffix}' (the slider's own limit, like [limits] {name})"
                )
            legs = np.append(legs, tl_limits[key])
        if legs is not None and platform.spare_axes:
            legs = np.append(legs, [float(np.min(legs))] * platform.spare_axes)
        values[key] = legs
    lim.finish()
    return platform.with_actuator_limits(**values)


def _rotary(f: PlatformFile) -> Platform:
    """Crank-and-rod hexapod: crank axes radial (horizontal), crank at angle 0 horizontal and
    tangential, pointing away from its pair's centre; positive angle lifts the crank tip.

    The crank directions follow from the pivots' angles about the base origin with legs in
    pairs, clockwise one first (as the ring layout orders them, and as explicit anchor lists
    must). Other crank arrangements: build :class:`Stewart6Rotary` in Python.
    """
    cfg, g, base, height = f.config, f.geometry, f.base_anchors_m, f.neutral_height_m
    g.finish()
    c = cfg.table("crank")
    crank = _per_actuator(c, "crank_mm", 6, None, lo=0.0, lo_open=True) * _MM
    rod = _per_actuator(c, "rod_mm", 6, None, lo=0.0, lo_open=True) * _MM
    lo_deg = c.number("min_deg", lo=-180.0, hi=180.0)
    hi_deg = c.number("max_deg", lo=-180.0, hi=180.0)
    if lo_deg >= hi_deg:
        raise c.error("max_deg", hi_deg, f"greater than min_deg = {lo_deg}")
    c.finish()
    angles = np.arctan2(base[:, 1], base[:, 0])
    side = np.array([-1.0, 1.0] * 3)
    zero_dirs = side[:, None] * np.stack([-np.sin(angles), np.cos(angles), np.zeros(6)], axis=1)
    axes = np.cross(zero_dirs, [0.0, 0.0, 1.0])
    d = cfg.table("drive")
    gear = _per_actuator(d, "gear_ratio", 6, None, lo=0.0, lo_open=True)
    ppr = _pulses_per_rev(d, 6, None)
    direction = _direction(d, 6)
    home_deg = _per_actuator(d, "home_deg", 6, None)
    if np.any((home_deg < lo_deg) | (home_deg > hi_deg)):
        raise d.error(
            "home_deg", d.raw("home_deg"), f"inside [min_deg, max_deg] = [{lo_deg}, {hi_deg}]"
        )
    d.finish()
    legs = CrankLegs(base, f.platform_anchors_m, height, axes, zero_dirs, crank, rod)
    if not np.all(legs.reachable0):
        raise c.error(
            "rod_mm",
            c.raw("rod_mm"),
            f"a rod that reaches its crank at the neutral pose (crank_mm = {c.raw('crank_mm')}, "
            f"[geometry] neutral_height_mm = {g.raw('neutral_height_mm')})",
        )
    theta0_deg = np.degrees(legs.theta0)
    if np.any((theta0_deg <= lo_deg) | (theta0_deg >= hi_deg)):
        raise g.error(
            "neutral_height_mm",
            g.raw("neutral_height_mm"),
            f"a height putting every crank inside [{lo_deg}, {hi_deg}] deg at neutral "
            f"(crank angles would be {np.round(theta0_deg, 2).tolist()} deg)",
        )
    drive = Drive.rotary(gear, ppr.astype(int), np.radians(home_deg) - legs.theta0, direction)
    return Stewart6Rotary(
        base,
        axes,
        zero_dirs,
        crank,
        rod,
        f.platform_anchors_m,
        height,
        (math.radians(lo_deg), math.radians(hi_deg)),
        drives=drive,
        name=f.name,
        actuator_names=f.actuator_names,
        description=f.description,
    )


# The bundled kinds; a new kind registers itself the same way from its own module.
for _cls, _title in (
    (Stewart6Linear, "6-DOF hexapod, linear legs (electric cylinders)"),
    (Seat3, "3-actuator heave/pitch/roll seat, linear legs"),
    (Corner4, "4-actuator corner rig (heave/pitch/roll), linear legs"),
):
    register_platform_kind(
        PlatformKind(_cls.DEFAULT_NAME, _cls, linear_legs_reader(_cls), _cls.N_LEGS, title=_title)
    )
register_platform_kind(
    PlatformKind(
        "stewart6-rotary", Stewart6Rotary, _rotary, 6, title="6-DOF hexapod, crank-and-rod legs"
    )
)
register_platform_kind(
    PlatformKind(
        "seat2-yaw", Seat2Yaw, _seat2_yaw, 2, yaw_axis=True,
        title="2 linear legs (pitch/roll) on a yaw turntable",
    )
)  # fmt: skip
del _cls, _title
