"""The cueing preset of a command: ``--preset`` if given, else the platform's default."""

from __future__ import annotations

import argparse
import math
import shlex
from collections.abc import Sequence
from typing import TYPE_CHECKING

from .._errors import ConfigError

if TYPE_CHECKING:
    from ..cueing import CueingParams
    from ..kinematics import Platform
    from ..pipeline import Ride

__all__ = [
    "add_intensity_option",
    "add_vestibular_option",
    "apply_intensity",
    "check_play_intensity",
    "choose_preset",
    "cueing_note",
    "presets_with_intensity",
]


def choose_preset(
    preset: str | None,
    platform: Platform | None,
    platform_label: str | None,
    overrides: Sequence[str] | None = None,
    *,
    ride: bool = False,
) -> tuple[CueingParams, str]:
    """Load the cueing preset a command runs with, and say where it came from.

    Parameters
    ----------
    preset : str or None
        The ``--preset`` argument (a name or a path), ``None`` when not given.
    platform : motioncue.kinematics.Platform or None
        Its ``default_preset`` is used when ``preset`` is ``None``.
    platform_label : str or None
        How the user named the platform (for the message).
    overrides : sequence of str, optional
        ``--set`` items; the ``preset.SECTION.KEY=VALUE`` ones are applied to the preset.
    ride : bool
        The command knows the whole recording before its first frame (``generate``,
        ``cue``): the platform's ``ride_preset`` is used before its ``default_preset``.

    Returns
    -------
    params : motioncue.cueing.CueingParams
    source : str
        ``"NAME (--preset)"``, ``"NAME (ride-file default of platform P)"``, ``"NAME
        (default of platform P)"`` or ``"NAME (fallback: platform P names no
        default_preset)"``.

    Raises
    ------
    ConfigError
        No preset and no platform, or the preset cannot be loaded.
    """
    from ..cueing import FALLBACK_PRESET
    from ._common import load_preset_arg

    def load_cueing(name: str) -> CueingParams:
        return load_preset_arg(name, overrides)

    if preset is not None:
        params = load_cueing(preset)
        return params, f"{params.name} (--preset)"
    if platform is None:
        raise ConfigError(
            "no cueing preset: give --preset NAME, or --platform P to use its default"
        )
    label = platform_label or platform.name
    chosen = platform.cueing_preset(ride)
    if chosen:
        params = load_cueing(chosen)
        which = "ride-file default" if chosen != platform.default_preset else "default"
        return params, f"{params.name} ({which} of platform {label})"
    params = load_cueing(FALLBACK_PRESET)
    return params, f"{params.name} (fallback: platform {label} names no default_preset)"


def add_intensity_option(parser: argparse.ArgumentParser) -> None:
    """``--intensity PCT``: a point of the preset's tuned intensity range (one definition for
    every verb that runs a preset)."""
    parser.add_argument(
        "--intensity",
        type=float,
        default=None,
        metavar="PCT",
        help="0-100: a point of the preset's tuned range from gentle (0) to the strongest "
        "within its false-cue budget (100, the preset as it is); not a plain gain, every "
        "frame still within the limits. Needs a preset with an [intensity] table "
        "(the bundled hexapod's default racing-hexapod-auto among the bundled ones; the error "
        "lists them)",
    )


def apply_intensity(
    params: CueingParams, percent: float | None, source: str
) -> tuple[CueingParams, str]:
    """The preset at ``percent`` (:func:`motioncue.cueing.at_intensity`) and its source
    label with the intensity; unchanged when ``percent`` is ``None``."""
    if percent is None:
        return params, source
    from ..cueing import at_intensity

    if params.intensity_gentle is None and _valid_percent(percent):
        # the preset has no range: say which do (the platform's default may be the one)
        have = presets_with_intensity()
        raise ConfigError(
            f"preset {source} has no tuned intensity range (no [intensity] table), so "
            f"intensity {percent:g} % has nothing to choose from; give --preset NAME with one"
            f"{' (' + ', '.join(have) + ')' if have else ''}, or leave out the intensity"
        )
    return at_intensity(params, percent), f"{source} at intensity {percent:g} %"


def _valid_percent(percent: float) -> bool:
    return not isinstance(percent, bool) and math.isfinite(percent) and 0.0 <= percent <= 100.0


def presets_with_intensity() -> list[str]:
    """Names of the bundled cueing presets with a tuned intensity range (an ``[intensity]``
    table), sorted; presets that do not load are left out."""
    from .._config import bundled_names
    from ..cueing import load_cueing

    names = []
    for name in bundled_names("cueing"):
        try:
            if load_cueing(name).intensity_gentle is not None:
                names.append(name)
        except ConfigError:
            continue
    return names


def cueing_note(
    base: CueingParams, percent: float | None, overrides: Sequence[str] | None = None
) -> dict[str, object]:
    """What a ride records of its cueing (``notes["cueing"]`` of the ride header, covered
    by its digest): the preset's name and the intensity in percent (``None`` for a preset
    without a tuned range; ``100`` for one with a range when no intensity was asked for: the
    preset as tuned is its 100 % point). Not how the preset was chosen: the same preset
    makes the same ride whether named or taken as the platform's default.

    Parameters
    ----------
    base : CueingParams
        The preset before :func:`apply_intensity`.
    percent : float or None
        The ``--intensity`` asked for.
    overrides : sequence of str, optional
        ``--set`` items; the ``preset.`` ones changed the preset and are recorded as
        ``preset_set`` (left out when there are none).
    """
    if percent is None and base.intensity_gentle is not None:
        percent = 100.0
    note: dict[str, object] = {
        "preset": base.name,
        "intensity_percent": None if percent is None else float(percent),
    }
    sets = [str(o) for o in overrides or () if str(o).startswith("preset.")]
    if sets:
        note["preset_set"] = sets
    return note


def check_play_intensity(ride: Ride, percent: float, ride_name: str) -> str:
    """``play --intensity PCT``: a ride's frames are fixed when ``generate`` makes them, so
    the intensity can only be checked, not changed (no frame is sent that the ride's digest
    and ``generate``'s checks did not cover).

    Parameters
    ----------
    ride : motioncue.pipeline.Ride
        The ride about to be played (its ``notes["cueing"]``, its source, rig).
    percent : float
        The ``--intensity`` asked for.
    ride_name : str
        How the user named the ride file.

    Returns
    -------
    str
        A note for the player when the ride was made at ``percent``.

    Raises
    ------
    ConfigError
        ``percent`` outside 0..100, or a ride made at another intensity or with none
        recorded; the message gives the ``generate --intensity`` command that makes the ride
        asked for.
    """
    from ..viewer._cueing import ride_cueing

    if not _valid_percent(percent):
        raise ConfigError(f"--intensity {percent!r} % is invalid; allowed: 0 to 100")
    preset, pct, recorded = ride_cueing(ride.notes)
    words = ["motioncue", "generate", "--input", ride.source or "REC", "--platform",
             ride.platform, "--controller", ride.controller, "--preset",
             preset if preset is not None and pct is not None else "NAME"]  # fmt: skip
    sets = ride.notes["cueing"].get("preset_set") if recorded else None
    if pct is not None and isinstance(sets, list) and all(isinstance(x, str) for x in sets):
        for item in sets:
            words += ["--set", item]
    words += ["--intensity", f"{percent:g}", "--out", "NEW.ride"]
    fix = f"make one with '{shlex.join(words)}' (a ride's frames are fixed when it is made)"
    if not recorded:
        raise ConfigError(
            f"{ride_name} records no intensity (a keyframe ride, or one made before rides "
            f"recorded their cueing); {fix}"
        )
    if pct is None:
        raise ConfigError(
            f"{ride_name} was made with preset {preset}, which has no tuned intensity range; "
            f"{fix} with a preset that has one"
        )
    if abs(pct - percent) > 1e-9:
        raise ConfigError(f"{ride_name} was made at intensity {pct:g} %, not {percent:g} %; {fix}")
    return f"{ride_name} was made at intensity {pct:g} % (preset {preset})"


def add_vestibular_option(parser: argparse.ArgumentParser) -> None:
    """``--vestibular SET``: the vestibular model set of the evaluation (one definition for
    every verb that evaluates cues; the names are those of ``cueing._vestibular``'s
    ``MODEL_SETS``, written here so that building the parser imports nothing heavy)."""
    parser.add_argument(
        "--vestibular",
        default="telban-cardullo-2005",
        metavar="SET",
        help="vestibular model set for the evaluation: telban-cardullo-2005 (default) or "
        "reid-nahon-zacharias",
    )
