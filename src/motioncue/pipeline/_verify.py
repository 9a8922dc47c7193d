"""Independent check that timed frames respect a limits table, by finite differences.

This is the check users can repeat with a spreadsheet: on frame times ``t`` and pulses ``p``,

- speed ``v[k] = (p[k] - p[k-1]) / (t[k] - t[k-1])``;
- acceleration ``a[k] = (v[k] - v[k-1]) / ((t[k] - t[k-2]) / 2)``, the change of speed
  over the mean of the two intervals, as the controllers (and their emulators) judge it; on
  a uniform grid this is ``(p[k] - 2 p[k-1] + p[k-2]) / dt^2``, the definition the limiters
  enforce, and frames on arrival (whole-ms intervals that vary) are judged the same way.

It deliberately shares no code with the limiters it checks.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["FrameCheck", "check_frames", "limits_arrays"]


@dataclass(frozen=True)
class FrameCheck:
    """Worst use of each limit, per actuator, as a fraction of the limit (<= 1 is inside).

    Attributes
    ----------
    stroke_use, speed_use, accel_use : ndarray, shape (n,)
        ``max |value| / limit``; for the stroke, ``max |p - mid| / half stroke`` (> 1 is
        beyond a stroke end).
    worst_frame : dict[str, int]
        Frame index of the worst speed and acceleration.
    ok : bool
        Every frame within every limit (with ``slack``).
    """

    stroke_use: np.ndarray
    speed_use: np.ndarray
    accel_use: np.ndarray
    worst_frame: dict[str, int]
    ok: bool

    def summary(self) -> str:
        return (
            f"stroke {self.stroke_use.max():.3f}, speed {self.speed_use.max():.3f}, "
            f"accel {self.accel_use.max():.3f} of the limits ({'OK' if self.ok else 'VIOLATED'})"
        )


def limits_arrays(table: Mapping[str, Any] | Sequence[Mapping[str, Any]]) -> dict[str, np.ndarray]:
    """Per-actuator arrays from a limits table as ``motioncue limits --json`` prints it."""
    rows = table["actuators"] if isinstance(table, Mapping) else table
    return {
        "lo": np.array([r["stroke_pulses"][0] for r in rows], dtype=float),
        "hi": np.array([r["stroke_pulses"][1] for r in rows], dtype=float),
        "v": np.array([r["max_speed_pulses_s"] for r in rows], dtype=float),
        "a": np.array([r["max_accel_pulses_s2"] for r in rows], dtype=float),
    }


def check_frames(
    t_s: np.ndarray,
    pulses: np.ndarray,
    table: Mapping[str, Any] | Sequence[Mapping[str, Any]],
    slack: float = 1e-9,
    start_at_rest: bool = False,
) -> FrameCheck:
    """Check frames ``pulses (N, n)`` at ``t_s (N,)`` against a limits table.

    Parameters
    ----------
    slack : float
        Relative tolerance on speed and acceleration (the pulse rounding of the wire format
        is already inside the limiters' margins, so the default is tight).
    start_at_rest : bool
        Also count the acceleration from rest into the first frame.
    """
    lim = limits_arrays(table)
    p = np.asarray(pulses, dtype=float)
    t = np.asarray(t_s, dtype=float)
    mid = 0.5 * (lim["hi"] + lim["lo"])
    half_span = np.maximum(0.5 * (lim["hi"] - lim["lo"]), 0.5)
    stroke_use = np.abs(p - mid).max(axis=0, initial=0.0) / half_span
    dt = np.diff(t)[:, None]
    v = np.diff(p, axis=0) / dt if len(t) > 1 else np.zeros((0, p.shape[1]))
    if start_at_rest and len(v):
        # at rest before the first frame, for as long as the first interval
        v_prev = np.vstack([np.zeros((1, p.shape[1])), v])
        dt_prev = np.vstack([dt[:1], dt])
        a = np.diff(v_prev, axis=0) / (0.5 * (dt_prev[1:] + dt_prev[:-1]))
    else:
        a = (
            np.diff(v, axis=0) / (0.5 * (dt[1:] + dt[:-1]))
            if len(v) > 1
            else np.zeros((0, p.shape[1]))
        )
    speed_use = np.abs(v).max(axis=0, initial=0.0) / lim["v"]
    accel_use = np.abs(a).max(axis=0, initial=0.0) / lim["a"]
    worst = {
        "speed": int(np.argmax(np.abs(v).max(axis=1)) + 1) if len(v) else 0,
        "accel": int(np.argmax(np.abs(a).max(axis=1)) + 2) if len(a) else 0,
    }
    ok = bool(
        np.all(stroke_use <= 1.0)
        and np.all(speed_use <= 1.0 + slack)
        and np.all(accel_use <= 1.0 + slack)
        and np.all(np.isfinite(p))
    )
    return FrameCheck(stroke_use, speed_use, accel_use, worst, ok)
