"""Vehicle-motion recordings: the CSV format, and resampling to a uniform rate.

A recording CSV has a header row naming the columns ``t, fx, fy, fz, wx, wy, wz`` (any
order; extra columns are ignored): time (s), specific force (m/s^2) and angular velocity
(rad/s) in the vehicle body frame of conventions.md (x forward, y left, z up; at rest and
level ``f = [0, 0, +9.80665]``).
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from .._frozen import set_fields

__all__ = [
    "MAX_RESAMPLED_FRAMES",
    "RECORDING_COLUMNS",
    "Recording",
    "csv_read_error",
    "read_recording_csv",
    "resample",
    "write_recording_csv",
]

RECORDING_COLUMNS: tuple[str, ...] = ("t", "fx", "fy", "fz", "wx", "wy", "wz")
MAX_RESAMPLED_FRAMES = 2_000_000
"""Most samples :func:`resample` makes (about 5.5 h at 100 Hz): a longer grid comes from a
damaged or absurd recording (a time gap of 1e6 s) and would exhaust memory."""


def csv_read_error(path: str | Path, exc: OSError | UnicodeDecodeError | csv.Error) -> ConfigError:
    """The one-line error for a CSV file that could not be read, by what went wrong.

    Parameters
    ----------
    path : str or Path
        The file, named in the message.
    exc : OSError, UnicodeDecodeError or csv.Error
        What reading it raised.
    """
    if isinstance(exc, UnicodeDecodeError):  # a ValueError: tested before OSError for clarity
        return ConfigError(f"{path}: not a text (UTF-8) CSV file: {exc}")
    if isinstance(exc, OSError):
        return ConfigError(f"{path}: cannot read: {exc}")
    return ConfigError(f"{path}: not a readable CSV file: {exc}")


@dataclass(frozen=True, eq=False)
class Recording:
    """Vehicle motion over time.

    Attributes
    ----------
    t_s : (N,) array
        Sample times (s), finite (not necessarily sorted or uniform; see :func:`resample`).
    f : (N, 3) array
        Specific force (m/s^2), body frame; non-finite values are NaN (bad samples).
    w : (N, 3) array
        Angular velocity (rad/s), body frame; non-finite values are NaN.
    """

    t_s: NDArray[np.float64]
    f: NDArray[np.float64]
    w: NDArray[np.float64]

    def __init__(self, t_s: ArrayLike, f: ArrayLike, w: ArrayLike) -> None:
        t = np.array(t_s, dtype=float)
        fa = np.array(f, dtype=float)
        wa = np.array(w, dtype=float)
        n = t.shape[0] if t.ndim == 1 else -1
        if t.ndim != 1 or fa.shape != (n, 3) or wa.shape != (n, 3):
            raise ConfigError(
                f"Recording needs t (N,), f (N, 3), w (N, 3); got {t.shape}, {fa.shape}, {wa.shape}"
            )
        if not np.isfinite(t).all():
            raise ConfigError("Recording: sample times must be finite")
        fa[~np.isfinite(fa)] = np.nan
        wa[~np.isfinite(wa)] = np.nan
        for a in (t, fa, wa):
            a.flags.writeable = False
        set_fields(self, t_s=t, f=fa, w=wa)

    def __len__(self) -> int:
        return int(self.t_s.shape[0])


def _parse(cell: str, where: str, column: str) -> float:
    text = cell.strip()
    if text == "":
        return math.nan
    try:
        return float(text)
    except ValueError:
        raise ConfigError(f"{where}: column {column!r}: {cell!r} is not a number") from None


def read_recording_csv(path: str | Path) -> Recording:
    """Read a recording CSV.

    Parameters
    ----------
    path
        CSV with a header row containing at least ``t, fx, fy, fz, wx, wy, wz``.

    Returns
    -------
    Recording

    Raises
    ------
    ConfigError
        Unreadable file, missing column (named), a row with too few fields or an unparsable
        number (line and column named), or a non-finite time. Empty cells, ``nan`` and
        ``inf`` in the motion columns are kept as NaN: they are bad samples the washout holds
        and counts.
    """
    p = Path(path)
    try:
        with open(p, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            try:
                header = next(reader)
            except StopIteration:
                raise ConfigError(f"{p}: empty file, expected a header row") from None
            names = [h.strip() for h in header]
            missing = [c for c in RECORDING_COLUMNS if c not in names]
            if missing:
                raise ConfigError(
                    f"{p}: missing column(s) {', '.join(missing)}; header has {', '.join(names)}"
                )
            cols = [names.index(c) for c in RECORDING_COLUMNS]
            need = max(cols) + 1
            rows: list[list[float]] = []
            for row in reader:
                if len(row) >= need:
                    try:  # the common row: seven numbers (float() ignores the spaces _parse strips)
                        values = [float(row[i]) for i in cols]
                    except ValueError:  # an empty cell (NaN) or a bad number: _parse tells which
                        values = []
                    if values and math.isfinite(values[0]):
                        rows.append(values)
                        continue
                line = reader.line_num
                if not row or all(not c.strip() for c in row):
                    continue
                where = f"{p}:{line}"
                if len(row) < need:
                    raise ConfigError(f"{where}: {len(row)} fields, need at least {need}")
                values = [
                    _parse(row[i], where, c) for i, c in zip(cols, RECORDING_COLUMNS, strict=True)
                ]
                if not math.isfinite(values[0]):
                    raise ConfigError(f"{where}: time {row[cols[0]]!r} is not a finite number")
                rows.append(values)
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise csv_read_error(p, exc) from exc
    data = np.array(rows, dtype=float).reshape(-1, 7)
    return Recording(data[:, 0], data[:, 1:4], data[:, 4:7])


def write_recording_csv(path: str | Path, rec: Recording) -> None:
    """Write ``rec`` as a recording CSV (header ``t,fx,fy,fz,wx,wy,wz``; NaN as ``nan``),
    atomically (a temporary name renamed on success).

    Floats are written with ``repr`` precision, so :func:`read_recording_csv` returns the
    same numbers.
    """
    from .._atomic import atomic_write_bytes
    from .._errors import TransportError

    p = Path(path)
    data = np.column_stack([rec.t_s, rec.f, rec.w])
    lines = [",".join(RECORDING_COLUMNS)]
    lines += [",".join(repr(v) for v in row) for row in data.tolist()]
    try:
        atomic_write_bytes(p, ("\n".join(lines) + "\n").encode("utf-8"), "recording CSV")
    except TransportError as exc:
        raise ConfigError(f"{p}: cannot write: {exc.__cause__ or exc}") from exc


def resample(rec: Recording, fs_hz: float, max_frames: int = MAX_RESAMPLED_FRAMES) -> Recording:
    """Resample to a uniform grid by linear interpolation.

    Rule: samples are sorted by time (stable); of several samples with the same time the
    last one in the file wins (a later packet supersedes an earlier one). The grid starts at
    the earliest time, ``t_k = t_0 + k / fs``, and ends at the last grid point not after the
    latest time. Each grid value interpolates linearly between the two samples around it; a
    grid point on a sample (within a millionth of the grid period, absorbing rounding of
    the times) takes that sample's values, and one strictly between two
    samples of which one is NaN is NaN (left for the washout to hold and count). A
    recording of one sample gives one sample; an empty one gives an empty one.

    Parameters
    ----------
    rec : Recording
    fs_hz : float
        Target rate, > 0.
    max_frames : int
        Refuse a grid of more samples than this (:class:`ConfigError` naming the span, the
        count and the largest gap) instead of exhausting memory.

    Returns
    -------
    Recording
        Uniformly sampled at ``fs_hz``.
    """
    if (
        isinstance(fs_hz, bool)
        or not isinstance(fs_hz, int | float)
        or not math.isfinite(fs_hz)
        or fs_hz <= 0
    ):
        raise ConfigError(f"fs_hz = {fs_hz!r} is invalid; allowed: a finite number > 0")
    n = len(rec)
    if n == 0:
        return rec
    order = np.argsort(rec.t_s, kind="stable")
    t = rec.t_s[order]
    data = np.column_stack([rec.f, rec.w])[order]
    # keep the last of each run of equal times
    last = np.ones(n, dtype=bool)
    last[:-1] = t[1:] != t[:-1]
    t = t[last]
    data = data[last]
    span = float(t[-1] - t[0])
    frames = span * fs_hz * (1.0 + 1e-12) + 1e-9
    if not frames < max_frames:
        gaps = np.diff(t)
        k = int(np.argmax(gaps)) if gaps.size else 0
        gap = f"; its largest gap is {gaps[k]:.6g} s (samples {k} and {k + 1})" if gaps.size else ""
        raise ConfigError(
            f"the recording spans {span:.6g} s: {frames:.6g} samples at {fs_hz:g} Hz, more than "
            f"the {max_frames} allowed{gap}"
        )
    count = math.floor(frames) + 1
    grid = t[0] + np.arange(count) / fs_hz
    if t.shape[0] == 1:
        out = np.repeat(data, count, axis=0)
    else:
        j = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, t.shape[0] - 2)
        t0 = t[j]
        t1 = t[j + 1]
        frac = np.clip((grid - t0) / (t1 - t0), 0.0, 1.0)[:, None]
        d0 = data[j]
        d1 = data[j + 1]
        out = d0 + frac * (d1 - d0)
        bad = ~(np.isfinite(d0) & np.isfinite(d1))
        out[bad] = np.nan
        # on a sample (within 1e-6 of a grid period): exactly that sample, even if its
        # neighbour is NaN
        tol = 1e-6 / fs_hz
        on0 = (grid - t0) <= tol
        on1 = ~on0 & ((t1 - grid) <= tol)
        out[on0] = d0[on0]
        out[on1] = d1[on1]
    return Recording(grid, out[:, :3], out[:, 3:])
