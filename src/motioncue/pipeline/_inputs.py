"""What ``generate`` accepts, recognised by content: vehicle-motion recordings (CSV), raw
telemetry recordings (``motioncue record`` files) and pose keyframes (CSV).

Pose-keyframe CSV: a header row with ``x, y, z, roll, pitch, yaw`` (m, rad; or ``x_mm ...``
and ``roll_deg ...`` columns in human units) and optionally ``t`` (s; an empty cell means the
timing of that keyframe is free), ``dout`` (effect output bits, held from that keyframe on),
``dac1`` and ``dac2``.

What ``generate`` refuses or warns about (nothing half-understood becomes a ride):

- a recording with no samples (a header-only CSV), or with fewer than two valid samples
  (all six motion columns finite): refused;
- in a recording CSV, a time not after the previous one (duplicated or decreasing times),
  or a gap over ``MAX_GAP_S``: refused, naming the samples;
- an input that would make more than ``MAX_GENERATE_FRAMES`` frames at the chosen rate
  (a recording's span, or the last keyframe time): refused with the numbers;
- a recording of which more than ``HELD_WARNING_FRACTION`` of the samples were held by the
  washout (non-finite, spikes): the ride is made, with a loud warning giving the fraction
  (:func:`held_warning`);
- keyframe times that are negative or not increasing: refused;
- a CSV larger than ``MAX_CSV_BYTES``: refused by its size, before anything is read (a
  ``motioncue record`` file has its own limit, checked after its magic).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import ConfigError
from ..telemetry import decode_recording, samples_to_arrays
from ..telemetry._motion import is_datagram_recording
from ..telemetry._recording import Recording, csv_read_error, read_recording_csv

__all__ = [
    "HELD_WARNING_FRACTION",
    "MAX_CSV_BYTES",
    "MAX_GAP_S",
    "MAX_GENERATE_FRAMES",
    "Keyframes",
    "check_generate_size",
    "check_recording",
    "held_warning",
    "load_generate_input",
    "read_keyframes_csv",
]

MAX_GAP_S = 60.0
"""Largest time between two samples of a recording CSV (a longer gap is missing data)."""
MAX_GENERATE_FRAMES = 2_000_000
"""Most frames ``generate`` makes (about 5.5 h at 100 Hz)."""
MAX_CSV_BYTES = 256 << 20
"""Largest CSV input ``generate`` reads (256 MiB: over 2 million rows of seven numbers)."""
_MAX_HEADER_CHARS = 64 << 10
HELD_WARNING_FRACTION = 0.2
"""Warn when more than this fraction of the input samples were held by the washout."""

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
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = list(csv.reader(fh))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise csv_read_error(path, exc) from exc
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
    if np.any(given < 0):
        raise ConfigError(f"{path}: keyframe time {float(given[given < 0][0])!r} s is negative")
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
        ``"recording"`` (a :class:`~motioncue.telemetry.Recording`) or
        ``"keyframes"`` (:class:`Keyframes`).
    data
    counters : dict
        Decoder counters for telemetry recordings (skipped packets by reason), else empty.
    """
    path = Path(path)
    if not path.is_file():
        raise ConfigError(f"input {str(path)!r} does not exist")
    if is_datagram_recording(path):
        return "recording", *_telemetry_recording(path)
    size = path.stat().st_size
    if size > MAX_CSV_BYTES:
        raise ConfigError(
            f"{path}: {size} bytes is larger than the {MAX_CSV_BYTES} bytes of CSV generate "
            "reads; split the recording"
        )
    try:
        with open(path, newline="", errors="replace") as fh:
            # the header row only, however long the first line of a foreign file is
            first = next(csv.reader([fh.readline(_MAX_HEADER_CHARS)]), [])
    except (OSError, csv.Error) as exc:
        raise csv_read_error(path, exc) from exc
    names = {h.strip() for h in first}
    if {"fx", "fy", "fz", "wx", "wy", "wz"} <= names:
        rec = read_recording_csv(path)
        check_recording(rec, str(path), csv_times=True)
        return "recording", rec, {}
    if {"roll", "pitch"} <= names or {"roll_deg", "pitch_deg"} <= names:
        return "keyframes", read_keyframes_csv(path), {}
    raise ConfigError(
        f"{path}: not a recording CSV (t,fx,fy,fz,wx,wy,wz), a pose-keyframe CSV "
        "(t,x,y,z,roll,pitch,yaw) or a motioncue telemetry recording"
    )


def _telemetry_recording(path: Path) -> tuple[Recording, dict[str, int]]:
    """Decode a ``motioncue record`` file. Paused stretches become rest (the vehicle is not
    moving while the game is paused), so the cue washes out there instead of interpolating
    across the pause."""
    samples, stats = decode_recording(path)
    if not samples:
        raise ConfigError(f"{path}: no usable telemetry samples ({stats})")
    a = samples_to_arrays(samples)
    f, w = a.f.copy(), a.w.copy()
    f[a.paused] = (0.0, 0.0, 9.80665)
    w[a.paused] = 0.0
    rec = Recording(a.t_s - a.t_s[0], f, w)
    check_recording(rec, str(path), csv_times=False)
    return rec, stats


def check_recording(rec: Recording, where: str, *, csv_times: bool = True) -> None:
    """Refuse a recording ``generate`` cannot make a meaningful ride from.

    Parameters
    ----------
    rec : motioncue.telemetry.Recording
    where : str
        The file, for messages.
    csv_times : bool
        Also refuse times that do not increase and gaps over :data:`MAX_GAP_S` (for
        recording CSVs; telemetry recordings are ordered by their receive times, and a pause
        without packets is no error there).

    Raises
    ------
    ConfigError
        No samples, fewer than two valid ones, or (``csv_times``) bad times; the message
        names the counts or the samples (numbered from 0, in file order).
    """
    n = len(rec)
    if n == 0:
        raise ConfigError(f"{where}: the recording has no samples (only a header?)")
    valid = np.all(np.isfinite(rec.f), axis=1) & np.all(np.isfinite(rec.w), axis=1)
    n_valid = int(np.count_nonzero(valid))
    if n_valid < 2:
        raise ConfigError(
            f"{where}: {n_valid} of {n} samples are valid (all of fx, fy, fz, wx, wy, wz "
            "finite); a ride needs at least 2"
        )
    if csv_times:
        t = np.asarray(rec.t_s, dtype=float)
        dt = np.diff(t)
        if np.any(dt <= 0):
            k = int(np.flatnonzero(dt <= 0)[0])
            what = "repeats" if dt[k] == 0 else "goes back to"
            raise ConfigError(
                f"{where}: time {what} {float(t[k + 1])!r} s at sample {k + 1} after "
                f"{float(t[k])!r} s at sample {k}; recording times must increase"
            )
        if np.any(dt > MAX_GAP_S):
            k = int(np.argmax(dt))
            raise ConfigError(
                f"{where}: a gap of {dt[k]:.6g} s between samples {k} (t = {float(t[k])!r} s) and "
                f"{k + 1} (t = {float(t[k + 1])!r} s); at most {MAX_GAP_S:g} s allowed (split the "
                "recording)"
            )


def check_generate_size(kind: str, data: Recording | Keyframes, rate_hz: float, where: str) -> None:
    """Refuse an input that would make more than :data:`MAX_GENERATE_FRAMES` frames."""
    if kind == "recording":
        t = np.asarray(data.t_s, dtype=float)
        span = float(t.max() - t.min()) if t.size else 0.0
        what = f"the recording spans {span:.6g} s"
    else:
        t = np.asarray(data.t_s, dtype=float)
        given = t[np.isfinite(t)]
        span = float(given.max()) if given.size else 0.0
        what = f"the last keyframe is at {span:.6g} s"
    frames = span * rate_hz
    if not frames <= MAX_GENERATE_FRAMES:
        raise ConfigError(
            f"{where}: {what}: {frames:.6g} frames at {rate_hz:g} Hz, more than the "
            f"{MAX_GENERATE_FRAMES} generate makes"
        )


def held_warning(bad_samples: int, n_samples: int) -> str | None:
    """The warning for a recording of which many samples were held, or None."""
    if n_samples <= 0:
        return None
    frac = bad_samples / n_samples
    if frac <= HELD_WARNING_FRACTION:
        return None
    return (
        f"WARNING: {frac:.0%} of the input samples ({bad_samples} of {n_samples}) were "
        "non-finite or spikes and were held by the washout: much of this ride follows held "
        "values, not the recording"
    )
