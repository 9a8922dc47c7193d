"""What a ride says about the cueing that made it (``notes["cueing"]`` of its header).

``motioncue generate`` records the preset and the intensity there (covered by the ride's
digest); ``view``, the monitor and ``play --intensity`` read it. Older rides and keyframe
rides have none: read as "not recorded", never an error.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

__all__ = ["describe_cueing", "ride_cueing"]


def _valid_percent(value: object) -> bool:
    return (
        isinstance(value, int | float)
        and not isinstance(value, bool)
        and math.isfinite(float(value))
        and 0.0 <= float(value) <= 100.0
    )


def ride_cueing(notes: Mapping[str, Any]) -> tuple[str | None, float | None, bool]:
    """``(preset, intensity_percent, recorded)`` from a ride's notes, trusting nothing.

    Parameters
    ----------
    notes : mapping
        The ride's ``notes``.

    Returns
    -------
    preset : str or None
        The preset's name.
    intensity_percent : float or None
        0 to 100; ``None`` for a preset without a tuned intensity range.
    recorded : bool
        False when the note is missing or malformed (then ``(None, None, False)``).
    """
    note = notes.get("cueing") if isinstance(notes, Mapping) else None
    if not isinstance(note, Mapping):
        return None, None, False
    preset = note.get("preset")
    pct = note.get("intensity_percent")
    if not isinstance(preset, str) or not (pct is None or _valid_percent(pct)):
        return None, None, False
    return preset, None if pct is None else float(pct), True


def describe_cueing(notes: Mapping[str, Any]) -> str:
    """One line on a ride's cueing, for ``view`` and the monitor: ``"racing-hexapod-strong
    at intensity 50 %"``, ``"racing (no tuned intensity range)"`` or ``"not recorded (...)"``;
    a preset changed by ``--set`` items (``preset_set``) is named with them.
    """
    preset, pct, recorded = ride_cueing(notes)
    if not recorded:
        return "not recorded (a keyframe ride, or one made before rides recorded their cueing)"
    sets = notes["cueing"].get("preset_set")
    if isinstance(sets, list) and sets and all(isinstance(x, str) for x in sets):
        preset = f"{preset} (--set {' '.join(sets)})"
    if pct is None:
        return f"{preset} (no tuned intensity range)"
    return f"{preset} at intensity {pct:g} %"
