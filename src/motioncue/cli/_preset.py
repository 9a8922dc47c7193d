"""The cueing preset of a command: ``--preset`` if given, else the platform's default."""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from typing import TYPE_CHECKING

from .._errors import ConfigError

if TYPE_CHECKING:
    from ..cueing import CueingParams
    from ..kinematics import Platform

__all__ = [
    "FALLBACK_PRESET",
    "add_intensity_option",
    "add_vestibular_option",
    "apply_intensity",
    "choose_preset",
]

FALLBACK_PRESET = "racing"
"""Used when neither ``--preset`` nor the platform file names a preset."""


def choose_preset(
    preset: str | None,
    platform: Platform | None,
    platform_label: str | None,
    overrides: Sequence[str] | None = None,
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

    Returns
    -------
    params : motioncue.cueing.CueingParams
    source : str
        ``"NAME (--preset)"``, ``"NAME (default of platform P)"`` or
        ``"NAME (fallback: platform P names no default_preset)"``.

    Raises
    ------
    ConfigError
        No preset and no platform, or the preset cannot be loaded.
    """
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
    default = getattr(platform, "default_preset", None)
    if default:
        params = load_cueing(default)
        return params, f"{params.name} (default of platform {label})"
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
        "(racing-hexapod)",
    )


def apply_intensity(
    params: CueingParams, percent: float | None, source: str
) -> tuple[CueingParams, str]:
    """The preset at ``percent`` (:func:`motioncue.cueing.at_intensity`) and its source
    label with the intensity; unchanged when ``percent`` is ``None``."""
    if percent is None:
        return params, source
    from ..cueing import at_intensity

    return at_intensity(params, percent), f"{source} at intensity {percent:g} %"


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
