"""Frames on arrival: an output stage whose frames may come at any whole millisecond.

The SC-MBOX and IMAX play each frame at its own time stamp (whole ms, absolute or relative;
``docs/controllers.md``), so a frame need not wait for a fixed slot: the bridge can send one
as soon as a telemetry sample arrives (issue 13, item 1) and keep the nominal period between
samples. :class:`ArrivalOutputStage` makes such frames safe on the controller's clock.

How the limits hold for any intervals ``h >= min_interval_ms``
--------------------------------------------------------------
The actuator limiter runs on a fine grid of 1 ms (the controller's time resolution), always,
whatever the frame intervals: a frame ``m`` ms after the previous one is ``m`` limiter steps
towards targets interpolated linearly from the previous frame's target to this one's, and
only the last of those positions is sent. On the controller's clock a frame's speed is then
the mean of ``m`` fine-grid speeds (each within ``v_max``), and the change of speed between
two frames, over the mean of their durations (the controller's and the emulators'
definition), is the mean of the fine-grid speed differences over pairs of 1 ms steps apart
by ``(h1 + h2) / 2`` on average, each within ``a_max`` per ms: so within ``a_max``. Positions
are fine-grid positions, within the stroke. Rounding to whole pulses moves a speed by at most
``1 / h`` and an acceleration by at most ``2 / (h1 h2)`` pulses, so the limits are tightened
for the shortest interval, ``min_interval_ms`` (:func:`~motioncue.trajectory._derive.
pulse_rounding_limits`). A jerk limit is not supported here (refused).

Everything else is :class:`~motioncue.pipeline._stream.OutputStage`: atomic frames, the
held first frame, transient send retries, the park (at the nominal period).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .._errors import ConfigError, LimitError
from ..trajectory import RealtimeLimiter
from ..trajectory._derive import pulse_rounding_limits
from ._stream import OutputStage

__all__ = ["ArrivalOutputStage"]

TICK_S = 1e-3  # the controller's time resolution


@dataclass
class ArrivalOutputStage(OutputStage):
    """An :class:`OutputStage` whose frames come ``ticks`` whole ms after the previous one.

    Parameters
    ----------
    min_interval_ms : int
        Shortest interval between frames (ms), in [1, period]; the limits are tightened for
        the pulse rounding at this interval.

    Other parameters as :class:`OutputStage`; ``rate_hz`` sets the nominal period, which
    must be a whole number of ms (``period_ms``), and the controller must stamp whole ms
    frames (SC-MBOX, IMAX), not be fed through a command stream.
    """

    min_interval_ms: int = 2
    period_ms: int = 0
    last_stamp_ms: int = -1
    frame_intervals_ms: list[int] | None = None

    def __post_init__(self) -> None:
        if self.controller.time_resolution_s != TICK_S:
            raise ConfigError(
                "frames on arrival need a controller that stamps whole-ms frames (SC-MBOX, IMAX)"
            )
        period = 1000.0 / self.rate_hz
        self.period_ms = round(period)
        if abs(period - self.period_ms) > 1e-9 or self.period_ms < 1:
            raise ConfigError(
                f"rate_hz = {self.rate_hz!r} is invalid for frames on arrival; allowed: a "
                "whole-ms period (1000 / k Hz)"
            )
        m = self.min_interval_ms
        if not (isinstance(m, int) and 1 <= m <= self.period_ms):
            raise ConfigError(
                f"min_interval_ms = {m!r} is invalid; allowed: 1..{self.period_ms} ms"
            )
        if self.limits.j_max is not None:
            raise ConfigError("frames on arrival do not support a jerk limit; use fixed frames")
        super().__post_init__()
        if self._streamer is not None:
            raise ConfigError("frames on arrival need time-stamped frames, not a command stream")
        q0 = list(self._state.q)
        tight = pulse_rounding_limits(self.limits, self.platform, m * TICK_S)
        self._start_limiter(RealtimeLimiter(tight, TICK_S), q0)
        self._target = [float(v) for v in q0]
        self._still = True  # the last frame is where the one before it was
        self.frame_intervals_ms = []

    @property
    def at_rest(self) -> bool:
        """At rest on the controller's clock: no speed on the fine grid and the last frame
        where the one before it was (no speed over the last interval either)."""
        return self._still and super().at_rest

    def emit(
        self,
        q_target: Sequence[float] | np.ndarray,
        dout: int = 0,
        dacs: tuple[int, int] = (0, 0),
        *,
        ticks: int | None = None,
    ) -> np.ndarray:
        """Limit, encode and send one frame ``ticks`` ms after the previous one (default:
        the nominal period); atomic as :meth:`OutputStage.emit`. Returns the pulses.

        The first frame of a run is preceded by a frame at the start position, at rest,
        stamped 0.
        """
        self._supervise()  # a silent or refusing controller stops the job (OutputStage)
        m = self.period_ms if ticks is None else int(ticks)
        if m < self.min_interval_ms:
            raise LimitError(
                f"frame {m} ms after the previous one; allowed: >= {self.min_interval_ms} ms"
            )
        state = self._state
        saved = self._saver.save(state)
        clock = self._encoder.clock  # declared: None for an encoder without one
        saved_clock = None if clock is None else clock.snapshot()
        saved_frames, saved_t, saved_stamp = self.frames, self.t_s, self.last_stamp_ms
        target = [float(v) for v in np.asarray(q_target, dtype=float).reshape(-1)]
        prev = self._target
        q_before = list(state.q)
        try:
            if self.last_stamp_ms < 0:  # the run opens at the start position, at rest
                self.t_s = 0.0
                for msg in self._encoder.encode(0.0, [int(p) for p in self.last_pulses], 0, (0, 0)):
                    self._send(msg)
                self.frames += 1
                self.last_stamp_ms = 0
                if clock is not None:
                    saved_clock = clock.snapshot()
                saved_frames, saved_stamp = self.frames, 0
            step = self._step
            q_out: list[float] = []
            for j in range(1, m + 1):
                r = j / m
                q_out = step([a + r * (b - a) for a, b in zip(prev, target, strict=True)])
            q_arr = np.asarray(q_out, dtype=float)
            if not np.all(np.isfinite(q_arr)):
                raise LimitError("limiter produced a non-finite position; frame not sent")
            pulses = self.platform.drives.to_pulses(q_arr)
            stamp = self.last_stamp_ms + m
            self.t_s = stamp * TICK_S
            for msg in self._encoder.encode(self.t_s, [int(p) for p in pulses], dout, dacs):
                self._send(msg)
        except BaseException:
            self._saver.restore(state, saved)
            if saved_clock is not None and clock is not None:
                clock.restore(saved_clock)
            self.frames, self.t_s, self.last_stamp_ms = saved_frames, saved_t, saved_stamp
            raise
        if not np.array_equal(q_arr, np.asarray(target, dtype=float)):
            self.clamped_frames += 1
        self._target = [v if v == v else p for v, p in zip(target, prev, strict=True)]
        self._still = q_out == q_before
        self.last_pulses = pulses
        self.frames += 1
        self.last_stamp_ms = stamp
        assert self.frame_intervals_ms is not None
        self.frame_intervals_ms.append(m)
        if len(self.frame_intervals_ms) > 100_000:
            del self.frame_intervals_ms[:50_000]
        return pulses

    def park_frames_bound(self) -> int:
        """Frames of the nominal period :meth:`park_step` needs at most (from any state)."""
        lim = self.limits
        span = float(np.max(lim.q_max - lim.q_min))
        v, a = float(np.min(lim.v_max)), float(np.min(lim.a_max))
        return int(np.ceil((span / v + 2 * v / a) / (self.period_ms * TICK_S))) + 10
