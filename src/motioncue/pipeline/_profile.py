"""Bridge profiles: one file binds a telemetry source, a cueing preset, cue gains and effects
for a game or a car (``configs/profiles/*.toml``; ``motioncue bridge --profile NAME``).

File layout (``source`` required, everything else optional; unknown keys are refused with
the key named)::

    description = "DiRT Rally 2.0, rally cars on gravel"   # optional
    car = "Renault 5 Turbo"            # optional, for the reader: the car the gains suit
    source = "dirt"                    # GAME[:[HOST:]PORT] or replay:FILE[?speed=X]
    intensity = 70                     # optional: % of the preset's tuned intensity range
                                       # (0 gentle, 100 strong; motioncue.cueing.at_intensity);
                                       # needs a preset with an [intensity] table
    [preset]                           # optional: a cueing preset (name or .toml path,
    stewart6-linear = "flight"         # relative to this file) for a named platform; every
    corner4 = "my-corner4-flight.toml" # other platform keeps its own default_preset
    [cue]
    f_gain = [1.0, 1.2, 0.8]           # multiplies the preset's f_scale (x, y, z); or one
    w_gain = 1.0                       # number for all three; w_gain multiplies w_scale
    [effects]                          # effect gains, 0..3 (motioncue.pipeline._effects)
    engine = 0.3
    road = 1.0
    shift = 0.5

The presets are tuned per platform (``default_preset`` in each platform file): a profile
keeps the platform's tuned preset unless its ``[preset]`` table names one for that platform
(keyed by the platform's name, the platform file's stem). A single ``preset = "NAME"`` string
is still read, for every platform, but the bridge says at the start when it replaces a
platform's own tuned preset.

Gains multiply the preset's scaling: ``f_gain`` 1.2 on y gives 20 % more lateral cue before
the preset's own smooth limit (``f_limit_m_s2``), which still bounds it; the workspace and
actuator limits bound everything after.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

from .._config import ConfigReader, bundled_names, find_config, load_toml
from .._errors import ConfigError
from ..cueing import load_cueing
from ..telemetry._source import parse_live_spec
from ._effects import EFFECT_NAMES, MAX_GAIN, EffectGains

if TYPE_CHECKING:
    from ..cueing import CueingParams

__all__ = ["MAX_CUE_GAIN", "Profile", "bundled_profiles", "load_profile"]

MAX_CUE_GAIN = 5.0
"""Largest cue gain a profile may set on one axis."""

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Profile:
    """A bridge profile (see the module docstring for the file layout).

    Attributes
    ----------
    name : str
        The file's stem.
    source : str
        Telemetry source spec (``motioncue.telemetry.open_source``).
    preset : str or None
        A cueing preset name or absolute path for every platform (the old single-string
        form); None: each platform's default unless ``presets`` names one.
    presets : dict of str to str
        Cueing preset (name or absolute path) by platform name; wins over ``preset``.
    f_gain, w_gain : tuple of 3 float
        Multipliers of the preset's ``f_scale`` and ``w_scale`` (x, y, z / roll, pitch, yaw).
    effects : EffectGains
        Effect layer gains.
    intensity : float or None
        Percent of the preset's tuned intensity range (:func:`motioncue.cueing.at_intensity`),
        applied before the gains; ``None``: the preset as it is.
    description, car : str
        Free text.
    """

    name: str
    source: str
    preset: str | None = None
    presets: Mapping[str, str] = field(default_factory=dict)
    f_gain: Vec3 = (1.0, 1.0, 1.0)
    w_gain: Vec3 = (1.0, 1.0, 1.0)
    effects: EffectGains = field(default_factory=EffectGains)
    intensity: float | None = None
    description: str = ""
    car: str = ""

    def preset_for(self, platform_name: str | None) -> str | None:
        """The preset this profile names for a platform, or None (the platform's own).

        Parameters
        ----------
        platform_name : str or None
            The platform's name (its file's stem); None: no platform.
        """
        if platform_name is not None and platform_name in self.presets:
            return self.presets[platform_name]
        return self.preset

    def apply(self, cueing: CueingParams) -> CueingParams:
        """The cueing parameters with this profile's gains applied (a new object)."""
        if self.f_gain == (1.0, 1.0, 1.0) and self.w_gain == (1.0, 1.0, 1.0):
            return cueing
        fs, fg, ws, wg = cueing.f_scale, self.f_gain, cueing.w_scale, self.w_gain
        f = (fs[0] * fg[0], fs[1] * fg[1], fs[2] * fg[2])
        w = (ws[0] * wg[0], ws[1] * wg[1], ws[2] * wg[2])
        return replace(cueing, f_scale=f, w_scale=w, name=f"{cueing.name}+{self.name}")


def bundled_profiles() -> list[str]:
    """Names of the bundled profiles."""
    return bundled_names("profiles")


def _gain3(table: ConfigReader, key: str) -> Vec3:
    if not table.has(key):
        return (1.0, 1.0, 1.0)
    raw = table.raw(key)
    allowed = f"a number or a list of 3 numbers in [0, {MAX_CUE_GAIN:g}]"
    vals = [raw] * 3 if isinstance(raw, int | float) and not isinstance(raw, bool) else raw
    if (
        not isinstance(vals, list)
        or len(vals) != 3
        or not all(
            isinstance(v, int | float)
            and not isinstance(v, bool)
            and math.isfinite(v)
            and 0.0 <= v <= MAX_CUE_GAIN
            for v in vals
        )
    ):
        raise table.error(key, raw, allowed)
    return (float(vals[0]), float(vals[1]), float(vals[2]))


def load_profile(name_or_path: str | Path) -> Profile:
    """Load a bundled profile by name (``dirt-rally2``) or from a TOML path.

    The source spec and the preset are checked here (an unknown game or preset is a
    :class:`ConfigError` naming the file), so that a bad profile fails before anything opens.

    Raises
    ------
    ConfigError
        Unknown profile, bad TOML, unknown or missing keys, values out of range, unknown
        game or preset.
    """
    path = find_config("profiles", name_or_path)
    where = path.name
    top = ConfigReader(load_toml(path), where)
    description = top.string("description", "")
    car = top.string("car", "")
    source = top.string("source")
    preset: str | None = None
    by_platform: dict[str, str] = {}
    if top.has("preset"):
        raw = top.raw("preset")
        if isinstance(raw, Mapping):
            table = top.table("preset")
            for key in table.keys():
                by_platform[key] = table.string(key)
            table.finish()
        else:
            preset = top.string("preset")
    intensity = top.number("intensity", lo=0.0, hi=100.0) if top.has("intensity") else None
    cue = top.table("cue", {})
    f_gain = _gain3(cue, "f_gain")
    w_gain = _gain3(cue, "w_gain")
    cue.finish()
    eff = top.table("effects", {})
    gains = {}
    for name in EFFECT_NAMES:
        if eff.has(name):
            gains[name] = eff.number(name, lo=0.0, hi=MAX_GAIN)
    eff.finish()
    top.finish()
    if source.startswith("replay:"):
        if source == "replay:":
            raise top.error("source", source, "GAME[:[HOST:]PORT] or replay:FILE")
    else:
        try:
            parse_live_spec(source)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None

    def resolve(value: str, label: str) -> str:
        candidate = Path(value)
        if candidate.suffix == ".toml" and not candidate.is_absolute():
            value = str((path.parent / candidate).resolve())
        try:
            load_cueing(value)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {label}: {exc}") from None
        return value

    if preset is not None:
        preset = resolve(preset, "preset")
    presets = {k: resolve(v, f"[preset] {k}") for k, v in by_platform.items()}
    return Profile(
        name=path.stem,
        source=source,
        preset=preset,
        presets=presets,
        f_gain=f_gain,
        w_gain=w_gain,
        effects=EffectGains(**gains),
        intensity=intensity,
        description=description,
        car=car,
    )
