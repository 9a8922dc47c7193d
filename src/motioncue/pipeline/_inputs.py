"""What ``generate`` accepts, recognised by content: vehicle-motion recordings (CSV), raw
telemetry recordings (``motioncue record`` files) and pose keyframes (CSV).

Pose-keyframe CSV: a header row with ``x, y, z, roll, pitch, yaw`` (m, rad; or ``x_mm ...``
and ``roll_deg ...`` columns in human units) and optionally ``t`` (s; an empty cell means the
timing of that keyframe is free), ``dout`` (effect output bits, held from that keyframe on),
``dac1`` and ``dac2``.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import ConfigError

__all__ = ["Keyframes", "load_generate_input", "read_keyframes_csv"]

_POSE = ("x", "y", "z", "roll", "pitch", "yaw")
_HUMAN = {"x_mm": 1e-3, "y_mm": 1e-3, "z_mm": 1e-3}
_HUMAN.update({f"{a}_deg": math.pi / 180 for a in ("roll", "pitch", "yaw")})


@dataclass(frozen=True, eq=False)
class Keyframes:
    """Authored poses with optional times and effect outputs.

    Attributes
    ----------
    poses : ndarray, (K, 6)
        Poses (m, rad) from neutral.
    t_s : ndarray, (K,)
        Keyframe times (s); NaN where the timing is free.
    dout : ndarray, (K,) int
        Effect output bits from each keyframe on.
    dacs : ndarray, (K, 2) int
        Analogue outputs from each keyframe on.
    """

    poses: np.ndarray
    t_s: np.ndarray
    dout: np.ndarray
    dacs: np.ndarray


def read_keyframes_csv(path: str | Path) -> Keyframes:
    """Read a pose-keyframe CSV (see the module docstring); errors name line and column."""
    path = Path(path)
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    if not rows:
        raise ConfigError(f"{path}: empty file")
    header = [h.strip() for h in rows[0]]
    cols: dict[str, tuple[int, float]] = {}
    for axis in _POSE:
        for name, scale in (
            (axis, 1.0),
            *((k, v) for k, v in _HUMAN.items() if k.startswith(axis + "_")),
        ):
            if name in header:
                cols[axis] = (header.index(name), scale)
                break
        else:
            raise ConfigError(f"{path}: keyframes need a column {axis!r} (or its _mm/_deg form)")
    poses, times, dout, dacs = [], [], [], []

    def cell(row: list[str], name: str, line: int, allow_empty: bool) -> float:
        if name not in header:
            return math.nan if allow_empty else 0.0
        text = row[header.index(name)].strip() if header.index(name) < len(row) else ""
        if text == "" and allow_empty:
            return math.nan
        try:
            value = float(text)
        except ValueError as exc:
            raise ConfigError(f"{path}:{line}: column {name!r}: {text!r} is not a number") from exc
        if not math.isfinite(value):
            raise ConfigError(f"{path}:{line}: column {name!r}: {text!r} is not finite")
        return value

    for line, row in enumerate(rows[1:], start=2):
        if not row or all(not c.strip() for c in row):
            continue
        pose = []
        for axis in _POSE:
            idx, scale = cols[axis]
            pose.append(cell(row, header[idx], line, False) * scale)
        poses.append(pose)
        times.append(cell(row, "t", line, True))
        dout.append(cell(row, "dout", line, False))
        dacs.append((cell(row, "dac1", line, False), cell(row, "dac2", line, False)))
    if not poses:
        raise ConfigError(f"{path}: no keyframes")
    t = np.asarray(times, dtype=float)
    given = t[np.isfinite(t)]
    if np.any(np.diff(given) <= 0):
        raise ConfigError(f"{path}: keyframe times must increase")
    out_bits = np.asarray(dout, dtype=float)
    dac_arr = np.asarray(dacs, dtype=float)
    for name, arr in (("dout", out_bits), ("dac", dac_arr)):
        if np.any(arr != np.round(arr)) or np.any(arr < 0) or np.any(arr > 0xFFFFFF):
            raise ConfigError(f"{path}: {name} values must be whole numbers >= 0")
    return Keyframes(np.asarray(poses), t, out_bits.astype(np.int64), dac_arr.astype(np.int64))


def load_generate_input(path: str | Path) -> tuple[str, Any, dict[str, int]]:
    """Recognise and read an input for ``generate``.

    Returns
    -------
    kind : str
        ``"recording"`` (a :class:`~motioncue.telemetry._recording.Recording`) or
        ``"keyframes"`` (:class:`Keyframes`).
    data
    counters : dict
        Decoder counters for telemetry recordings (skipped packets by reason), else empty.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"input {str(path)!r} does not exist")
    from motioncue.telemetry._motion import is_datagram_recording

    if is_datagram_recording(path):
        return "recording", *_telemetry_recording(path)
    with open(path, newline="", errors="replace") as fh:
        first = next(csv.reader(fh), [])
    names = {h.strip() for h in first}
    if {"fx", "fy", "fz", "wx", "wy", "wz"} <= names:
        from motioncue.telemetry._recording import read_recording_csv

        return "recording", read_recording_csv(path), {}
    if {"roll", "pitch"} <= names or {"roll_deg", "pitch_deg"} <= names:
        return "keyframes", read_keyframes_csv(path), {}
    raise ConfigError(
        f"{path}: not a recording CSV (t,fx,fy,fz,wx,wy,wz), a pose-keyframe CSV "
        "(t,x,y,z,roll,pitch,yaw) or a motioncue telemetry recording"
    )


def _telemetry_recording(path: Path) -> tuple[Any, dict[str, int]]:
    """Decode a ``motioncue record`` file. Paused stretches become rest (the vehicle is not
    moving while the game is paused), so the cue washes out there instead of interpolating
    across the pause."""
    from motioncue.telemetry import decode_recording, samples_to_arrays
    from motioncue.telemetry._recording import Recording

    samples, stats = decode_recording(path)
    if not samples:
        raise ConfigError(f"{path}: no usable telemetry samples ({stats})")
    a = samples_to_arrays(samples)
    f, w = a.f.copy(), a.w.copy()
    f[a.paused] = (0.0, 0.0, 9.80665)
    w[a.paused] = 0.0
    return Recording(a.t_s - a.t_s[0], f, w), stats
