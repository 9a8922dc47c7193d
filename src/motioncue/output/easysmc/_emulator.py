"""An EasySmc 2300 emulator: the manual's state machine behind a pseudo-terminal.

:class:`ControllerModel` is one controller with time passed explicitly (pure, testable):
63-command buffer, command numbering, sequential playback whose timing follows each move's
feed and accelerations (:mod:`._profile`), homing, emergency / smooth brakes, clear buffer,
outputs, counters, and the query replies of manual 5.3. It records a trace of the logical
position of every axis at the end of every move and flags violations (moves before homing,
outside the soft limits, above 2 MHz, a ``5B`` not followed by ``5C``...).

:class:`EasySmcEmulator` puts one or more models (an RS485 bus, addresses 00..03) behind a
pseudo-terminal: it prints / exposes ``path`` for pyserial, decodes and validates every byte
it receives and answers as the manual says (write, read, and error-99 replies: no such command,
manual mode, buffer full, checksum).

Given the controller description (and the frame rate), the emulator also checks frames with
the description's own numbers (:func:`frame_limits`, from ``controller.pulse_limits``): each
frame move's feed within the A3/A6 cap, each axis's step within the per-frame bound, and each
move ending within its frame's period on the controller's clock.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import time
from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..._errors import ConfigError, ProtocolError, TransportError
from ._profile import move_duration_s, move_progress
from ._protocol import (
    MAX_MAGNITUDE,
    Command,
    ErrorCode,
    ErrorReply,
    ExecStatus,
    ReadReply,
    Start,
    WordKind,
    WriteReply,
    _unframe,
    encode_reply,
    signed_from_word,
    split_serial_frames,
    word_from_signed,
)

if TYPE_CHECKING:
    from ._controller import EasySmcController

__all__ = [
    "BUFFER_DEPTH",
    "ControllerModel",
    "EasySmcEmulator",
    "FrameLimits",
    "TraceEntry",
    "Violation",
    "frame_limits",
]

BUFFER_DEPTH = 63
MAX_PULSE_HZ = 2_000_000  # manual ch. 2 item 3
_AXES = "XYZU"

# Interpolation speed command and leading axis of each move command.
_MOVE_SPEED = {
    0x44: (0x03, "X"),
    0x45: (0x10, "Y"),
    0x46: (0x15, "Z"),
    0x4A: (0xAD, "U"),
    0x51: (0x04, "XY"),
    0x52: (0x05, "XZ"),
    0x53: (0x11, "YZ"),
    0x54: (0xA1, "XU"),
    0x55: (0xA7, "YU"),
    0x56: (0xAA, "ZU"),
    0x57: (0xA3, "XYZ"),
    0x58: (0xA4, "XYU"),
    0x59: (0xA5, "XZU"),
    0x5A: (0xA9, "YZU"),
    0x5B: (0xA6, "XY"),
    0x5C: (0xA6, "ZU"),
}
_ARC = {0x61: (0x06, "XY"), 0x62: (0x07, "XZ"), 0x63: (0x12, "YZ")}
_START_CODE = {"X": 0x02, "Y": 0x09, "Z": 0x14}

# Parameter reads (5.3.4 .. 5.3.6): (query code, item) -> parameter command code.
_PARAM_READ = {
    **{
        (0x34, i): c
        for i, c in (
            (1, 0x01),
            (2, 0x02),
            (3, 0x03),
            (4, 0x04),
            (5, 0x05),
            (6, 0x06),
            (7, 0x07),
            (8, 0xA1),
            (9, 0xA2),
            (0xA, 0xA3),
            (0xB, 0xA4),
            (0xC, 0xA5),
            (0xD, 0xA6),
            (0x80, 0xAC),
            (0x81, 0xAD),
            (0x82, 0xAE),
            (0xFE, 0xFE),
            (0xFF, 0xFF),
        )
    },
    **{
        (0x35, i): c
        for i, c in (
            (1, 0x08),
            (2, 0x09),
            (3, 0x10),
            (4, 0x11),
            (5, 0x12),
            (6, 0xA7),
            (7, 0xA8),
            (8, 0xA9),
        )
    },
    **{(0x36, i): c for i, c in ((1, 0x13), (2, 0x14), (3, 0x15), (4, 0xAA), (5, 0xAB))},
}


def _factory_params() -> dict[int, list[int]]:
    """Appendix 1 of the manual (factory defaults)."""
    p: dict[int, list[int]] = {}
    for c in (0x01, 0x08, 0x13):
        p[c] = [2000]
    for c in (0x02, 0x09, 0x14, 0xAC):
        p[c] = [2000, 2000, 2000]
    for c in (
        0x03,
        0x04,
        0x05,
        0x06,
        0x07,
        0xA1,
        0xA2,
        0xA3,
        0xA4,
        0xA5,
        0xA6,
        0x10,
        0x11,
        0x12,
        0xA7,
        0xA8,
        0xA9,
        0x15,
        0xAA,
        0xAB,
        0xAD,
    ):
        p[c] = [20000, 20000, 20000]
    p[0xAE] = [1000, 1000, 1000]
    p[0xFC] = [2000, 20000, 1]
    p[0xFD] = [20000, 20000, 20000]
    p[0xFE] = [0, 0, 0]
    p[0xFF] = [0, 0, 0]
    return p


@dataclass(frozen=True)
class Violation:
    """Something the host sent that a real controller would not like.

    Attributes
    ----------
    t_s : float
        Emulator time of the command (s).
    addr : int
        Controller address.
    kind : str
        ``homing``, ``soft-limit``, ``feed``, ``pairing``, ``start-condition``, ``arc``.
    axis : str or None
        Axis letter when one axis is concerned.
    detail : str
        What happened.
    """

    t_s: float
    addr: int
    kind: str
    axis: str | None
    detail: str

    def __str__(self) -> str:
        return f"{self.t_s:.3f} s addr {self.addr:02X} {self.kind}: {self.detail}"


@dataclass(frozen=True)
class FrameLimits:
    """What a controller description allows the frame moves of one unit.

    Attributes
    ----------
    speed_code : int
        The unit's frame speed command (``0xA3`` XYZ, ``0xA6`` XYZU); moves run at its feed
        are frame moves.
    feed_cap_hz : float
        Largest feed a frame may set (``pulse_limits(None)``: the A3/A6 feed cap).
    max_frame_pulses : Mapping[str, float] or None
        Largest step of each axis (letter) in one frame (``pulse_limits(rate)`` x period);
        None when the frame rate is not known.
    period_s : float or None
        Frame period; each frame (move or wait) must end within it on the controller's clock
        (time the controller sat idle between frames excepted). None: not checked.
    """

    speed_code: int
    feed_cap_hz: float
    max_frame_pulses: Mapping[str, float] | None = None
    period_s: float | None = None


def frame_limits(
    controller: EasySmcController, frame_rate_hz: float | None = None
) -> dict[int, FrameLimits]:
    """Per unit address, the limits of frame moves as the controller description states
    them: ``controller.pulse_limits(None)`` (feed cap) and ``controller.pulse_limits(rate)``
    (per-frame step), the same numbers the limits of a ride are derived from."""
    cap = controller.pulse_limits(None).max_speed_pulses_s
    step = None
    period = None
    if frame_rate_hz is not None:
        period = 1.0 / float(frame_rate_hz)
        step = controller.pulse_limits(frame_rate_hz).max_speed_pulses_s * period
    out: dict[int, FrameLimits] = {}
    i = 0
    for u in controller.units:
        n = len(u.axes)
        per_axis = None if step is None else {a: float(step[i + j]) for j, a in enumerate(u.axes)}
        out[u.address] = FrameLimits(
            0xA3 if u.axes == "XYZ" else 0xA6, float(min(cap[i : i + n])), per_axis, period
        )
        i += n
    return out


@dataclass(frozen=True)
class TraceEntry:
    """Logical positions (pulses, X Y Z U) of one controller at a time (s since start)."""

    t_s: float
    addr: int
    positions: tuple[int, ...]
    number: int  # command number that ended here


@dataclass
class _Job:
    number: int
    cmd: Command
    start_s: float
    end_s: float
    deltas: tuple[int, ...]
    dist: int
    profile: tuple[float, float, float, float]  # feed, f0, a, b
    origin: tuple[int, ...]
    end: tuple[int, ...]  # logical positions once done

    def rest_from(self, t_s: float, origin: tuple[int, ...], deltas: tuple[int, ...]) -> _Job:
        """What is left of this move: ``deltas`` (pulses) from ``origin``, started at ``t_s``
        (s) at the job's own profile, ending where the job ends."""
        dist = max(abs(d) for d in deltas)
        t_end = t_s + move_duration_s(dist, *self.profile)
        return _Job(self.number, self.cmd, t_s, t_end, deltas, dist, self.profile, origin, self.end)


@dataclass
class _Halt:
    at_s: float
    axes: set[str] = field(default_factory=set)  # braked axes (emergency)
    smooth: set[str] = field(default_factory=set)


class ControllerModel:
    """One EasySmc 2300, driven by decoded commands and explicit times (seconds).

    Parameters
    ----------
    address : int
        DIP address 0..3.
    physical_offset : sequence of int
        Distance of each axis from its home switch at power-up (pulses), for homing time.
    limits : FrameLimits, optional
        Check frame moves against a controller description (:func:`frame_limits`):
        violations ``feed`` (above the configured cap), ``speed`` (an axis steps more in one
        frame than the description allows) and ``late`` (a frame ends after its period).
    """

    def __init__(
        self,
        address: int = 0,
        physical_offset: Sequence[int] = (0, 0, 0, 0),
        limits: FrameLimits | None = None,
    ) -> None:
        self.address = address
        self.limits = limits
        # frame schedule on the controller's clock: each frame job (frame move or timed
        # wait) is due one period after the previous one's due time, plus any time the
        # controller spent idle or on other jobs in between
        self._frame_due_s: float | None = None
        self._frame_end_s = 0.0
        self.params = _factory_params()
        self.soft = {a: [MAX_MAGNITUDE, -MAX_MAGNITUDE] for a in _AXES}
        self.manual_params = {i: (2000 if i <= 3 else 1000) for i in range(1, 10)}
        self.position = [0, 0, 0, 0]  # logical, after the last finished job
        self.physical = [int(v) for v in physical_offset]  # relative to home switch
        self.homed = [False] * 4
        self.queue: deque[_Job] = deque()
        self.pending_5b: tuple[int, Command] | None = None
        self.next_number = 1
        self.last_done = 0
        self.received = 0
        self.halt: _Halt | None = None
        self.manual_mode = False
        self.small_segment = False
        self.outputs = 0
        self.counters = [0, 0, 0]
        self.trace: list[TraceEntry] = []
        self.violations: list[Violation] = []
        self._now = 0.0
        self.stats = {"underflows": 0, "buffer_full": 0, "max_depth": 0}
        self._flagged: set[str] = set()
        self._last_end_s = 0.0
        self._moves_seen = False

    # -- time ------------------------------------------------------------------------------
    def _flag(self, kind: str, msg: str, axis: str | None = None, once: str | None = None) -> None:
        if once is not None:
            if once in self._flagged:
                return
            self._flagged.add(once)
        self.violations.append(Violation(self._now, self.address, kind, axis, msg))

    def advance(self, now_s: float) -> None:
        """Finish every job whose end time has passed (applies positions, trace)."""
        eff = now_s if self.halt is None else min(now_s, self.halt.at_s)
        while self.queue and self.queue[0].end_s <= eff:
            job = self.queue.popleft()
            self._finish(job, job.end_s)

    def _finish(self, job: _Job, t_s: float) -> None:
        code = job.cmd.code
        for i in range(4):
            self.physical[i] += job.deltas[i]
        self.position = list(job.end)
        if code in (0x41, 0x42, 0x43, 0x47):
            i = (0x41, 0x42, 0x43, 0x47).index(code)
            self.physical[i] = 0
            self.homed[i] = True
        elif code == 0x19:
            self._control_done(job.cmd.words[0])
        self.last_done = job.number
        self._last_end_s = t_s
        paired_5b = code == 0x5B and not any(job.deltas)  # its 5C records the pair
        if (
            (code in _MOVE_SPEED and not paired_5b)
            or code in _ARC
            or code in (0x24, 0x25, 0x26, 0xAF)
            or (code == 0x19 and job.cmd.words[0] >> 24 == 1)
        ):
            self.trace.append(TraceEntry(t_s, self.address, tuple(self.position), job.number))

    def _control_done(self, word: int) -> None:
        lead, rest = word >> 24, word & 0xFFFFFF
        if lead == 0x3 and rest == 1:
            self.small_segment = False
        elif lead == 0x3 and rest == 2:
            self.small_segment = True
        elif lead in (0xC, 0xD):
            bit = 1 << rest
            self.outputs = (self.outputs | bit) if lead == 0xD else (self.outputs & ~bit)
        elif lead == 0x9:
            self.counters[rest >> 16] = rest & 0xFFFF
        elif lead == 0xA:
            c = rest >> 16
            self.counters[c] = (self.counters[c] + (1 if rest & 0xF == 0 else -1)) & 0xFFFF

    def position_at(self, now_s: float) -> tuple[int, ...]:
        """Logical positions now, including the part of the executing move done."""
        self.advance(now_s)
        eff = now_s if self.halt is None else min(now_s, self.halt.at_s)
        if self.queue and self.queue[0].start_s < eff and self.queue[0].dist:
            job = self.queue[0]
            done, _ = move_progress(job.dist, *job.profile, eff - job.start_s)
            frac = done / job.dist
            return tuple(o + int(d * frac) for o, d in zip(job.origin, job.deltas, strict=True))
        if self.queue:
            return self.queue[0].origin
        return tuple(self.position)

    def _planned_position(self) -> list[int]:
        return list(self.queue[-1].end) if self.queue else list(self.position)

    def busy_axes(self, now_s: float) -> set[str]:
        self.advance(now_s)
        if self.queue and self.queue[0].start_s <= now_s and any(self.queue[0].deltas):
            return {a for a, d in zip(_AXES, self.queue[0].deltas, strict=True) if d}
        return set()

    # -- commands ----------------------------------------------------------------------------
    def handle(self, cmd: Command, now_s: float) -> WriteReply | ReadReply | ErrorReply:
        """Apply one valid command received at ``now_s``; returns the reply."""
        self._now = now_s
        self.advance(now_s)
        spec = cmd.spec
        if spec.kind == "query":
            return self._query(cmd, now_s)
        if self.manual_mode:
            return ErrorReply(ErrorCode.MANUAL_MODE, int(cmd.start), self.address)
        oob = cmd.code == 0x18 or (cmd.code == 0x19 and cmd.words[0] >> 24 in (4, 5))
        if oob:
            if cmd.start != Start.OUT_OF_BAND:
                self._flag(
                    "start-condition",
                    f"command {cmd.code:02X} {cmd.words[0]:07X} needs start condition 8 "
                    f"(got {int(cmd.start)}); executed out of band anyway",
                )
            self._out_of_band(cmd, now_s)
            return WriteReply(cmd.code, int(cmd.start), self.address)
        if cmd.start == Start.OUT_OF_BAND:
            self._flag(
                "start-condition",
                f"start condition 8 on command {cmd.code:02X}, which the manual allows "
                "only for brakes, clear buffer and loop test; queued",
            )
        if len(self.queue) + (self.pending_5b is not None) >= BUFFER_DEPTH:
            self.stats["buffer_full"] += 1
            return ErrorReply(ErrorCode.BUFFER_FULL, int(cmd.start), self.address)
        if cmd.code == 0x19 and cmd.words[0] == 0x3000000:
            self.next_number = 1  # decision: renumber on receipt (MANUAL_DECISIONS)
        number = self.next_number
        self.next_number += 1
        self.received = number
        self._enqueue(number, cmd, now_s)
        depth = len(self.queue) + (self.pending_5b is not None)
        self.stats["max_depth"] = max(self.stats["max_depth"], depth)
        return WriteReply(cmd.code, int(cmd.start), self.address)

    def _set_param(self, cmd: Command) -> None:
        c, w = cmd.code, cmd.words
        if c in (0x21, 0x22, 0x23):
            self.soft[_AXES[c - 0x21]][0] = signed_from_word(w[0])
        elif c in (0x27, 0x28, 0x29):
            self.soft[_AXES[c - 0x27]][1] = signed_from_word(w[0])
        elif c == 0xAF:
            self.soft["U"] = [signed_from_word(w[0]), signed_from_word(w[1])]
        elif c == 0x16:
            self.manual_params[w[0] >> 24] = w[0] & 0xFFFFFF
        elif c == 0x17 and w[0] == 1:
            self.params = _factory_params()
        elif all(k is WordKind.UNSIGNED for _, k in cmd.spec.words):
            self.params[c] = list(w)

    def _enqueue(self, number: int, cmd: Command, now_s: float) -> None:
        code = cmd.code
        if self.pending_5b is not None and code != 0x5C:
            self._flag(
                "pairing", f"5B (command {self.pending_5b[0]}) not followed by 5C; run as XY"
            )
            n5b, c5b = self.pending_5b
            self.pending_5b = None
            self._enqueue_move(
                n5b,
                c5b,
                now_s,
                [signed_from_word(c5b.words[0]), signed_from_word(c5b.words[1]), 0, 0],
            )
        if code == 0x5B:
            self.pending_5b = (number, cmd)
            return
        if code == 0x5C:
            if self.pending_5b is None:
                self._flag("pairing", f"5C (command {number}) without a preceding 5B; run as ZU")
                xy = [0, 0]
                first = number
            else:
                first, c5b = self.pending_5b
                xy = [signed_from_word(c5b.words[0]), signed_from_word(c5b.words[1])]
                self.pending_5b = None
                # the 5B and 5C pair is one move; give the 5B its (zero-length) slot
                self._enqueue_plain(first, c5b, now_s)
            deltas = [*xy, signed_from_word(cmd.words[0]), signed_from_word(cmd.words[1])]
            # the pair is one XYZU move: its start frequency is its first axis's (X, 02
            # DAT2; MANUAL_DECISIONS "interpolation feed reference"); a lone 5C is a ZU move
            self._enqueue_move(number, cmd, now_s, deltas, "Z" if first == number else "X")
            return
        if code in _MOVE_SPEED:
            axes = _MOVE_SPEED[code][1]
            deltas = [0, 0, 0, 0]
            for a, w in zip(axes, cmd.words, strict=True):
                deltas[_AXES.index(a)] = signed_from_word(w)
            self._enqueue_move(number, cmd, now_s, deltas)
            return
        if code in _ARC:
            self._enqueue_arc(number, cmd, now_s)
            return
        if spec_is_param(cmd):
            self._set_param(cmd)
        self._enqueue_plain(number, cmd, now_s)

    def _start_time(self, now_s: float) -> float:
        if self.queue:
            return self.queue[-1].end_s
        if self._moves_seen and now_s > self._last_end_s + 1e-9 and self.halt is None:
            self.stats["underflows"] += 1
        return max(now_s, self._last_end_s)

    def _enqueue_plain(self, number: int, cmd: Command, now_s: float) -> None:
        start = self._start_time(now_s)
        duration = 0.0
        code = cmd.code
        if code == 0x19 and cmd.words[0] >> 24 == 1:
            duration = (cmd.words[0] & 0xFFFFFF) / 1e3
        elif code in (0x41, 0x42, 0x43, 0x47):
            i = (0x41, 0x42, 0x43, 0x47).index(code)
            speed = self.params[(0x01, 0x08, 0x13, 0xAC)[i]][0]
            duration = abs(self.physical[i]) / max(speed, 1)
        timed_wait = code == 0x19 and cmd.words[0] >> 24 == 1
        if timed_wait or duration > 0:
            self._frame_schedule(number, start, start + duration, timed_wait)
        origin = tuple(self._planned_position())
        end = list(origin)
        if code in (0x24, 0x25, 0x26):
            end[code - 0x24] = signed_from_word(cmd.words[0])
        elif code == 0xAF:
            end[3] = signed_from_word(cmd.words[2])
        self._queue_job(number, cmd, start, duration, origin, end)

    def _frame_schedule(self, number: int, start_s: float, end_s: float, frame: bool) -> None:
        """Check that a frame job ends within its period (``limits.period_s``).

        A frame is due one period after the previous frame's due time; time between the end
        of the previous frame and this one's start (idle, homing...) moves the schedule on by
        as much. Non-frame timed jobs only make such a gap.
        """
        lim = self.limits
        if lim is None or lim.period_s is None:
            return
        if not frame:
            self._frame_end_s = max(self._frame_end_s, end_s)
            return
        gap = max(0.0, start_s - self._frame_end_s)
        if self._frame_due_s is None:
            due = start_s + lim.period_s
        else:
            due = self._frame_due_s + gap + lim.period_s
        if end_s > due + 1e-6:
            self._flag(
                "late",
                f"command {number}: frame ends {(end_s - due) * 1e3:.3f} ms after its "
                f"{lim.period_s * 1e3:.2f} ms period",
            )
        self._frame_due_s = due
        self._frame_end_s = end_s

    def _check_frame_move(self, number: int, speed_code: int, feed: int, deltas: list[int]) -> None:
        lim = self.limits
        if lim is None or speed_code != lim.speed_code:
            return
        if feed > lim.feed_cap_hz:
            self._flag(
                "feed",
                f"command {number}: feed {feed} Hz above the configured cap "
                f"{lim.feed_cap_hz:g} Hz (pulse_limits)",
            )
        if lim.max_frame_pulses is None:
            return
        for i, a in enumerate(_AXES):
            most = lim.max_frame_pulses.get(a)
            if most is not None and abs(deltas[i]) > most * (1 + 1e-9):
                self._flag(
                    "speed",
                    f"command {number}: axis {a} steps {abs(deltas[i])} pulses in one frame, "
                    f"above {most:g} (pulse_limits at {1.0 / (lim.period_s or 1.0):g} Hz)",
                    a,
                )

    def _enqueue_move(
        self, number: int, cmd: Command, now_s: float, deltas: list[int], lead: str = ""
    ) -> None:
        self._moves_seen = True
        speed_code, axes = _MOVE_SPEED[cmd.code]
        lead = lead or axes[0]
        acc_a, feed, acc_b = self.params[speed_code]
        if lead == "U":
            f0 = self.params[0xAC][1]
        else:
            f0 = self.params[_START_CODE[lead]][0 if len(axes) == 1 else 1]
        origin = self._planned_position()
        end = [o + d for o, d in zip(origin, deltas, strict=True)]
        for i, a in enumerate(_AXES):
            if deltas[i] and not self.homed[i]:
                self._flag("homing", f"axis {a} moved before homing", a, once=f"home{a}")
            pos, neg = self.soft[a]
            if deltas[i] and not neg <= end[i] <= pos:
                self._flag(
                    "soft-limit",
                    f"command {number}: axis {a} to {end[i]} outside soft limits [{neg}, {pos}]",
                    a,
                )
        if self.small_segment:
            acc_a, feed, acc_b = self.params[0xFD]
            f0 = self.params[0xFC][0]
        dist = max(abs(d) for d in deltas)
        if feed > MAX_PULSE_HZ:
            self._flag("feed", f"command {number}: feed {feed} Hz above the controller's 2 MHz")
        if dist and (feed <= 0 or (feed > f0 and (acc_a <= 0 or acc_b <= 0))):
            self._flag(
                "feed",
                f"command {number}: feed {feed} Hz / accelerations {acc_a}, {acc_b} "
                "cannot run a move; skipped",
            )
            deltas = [0, 0, 0, 0]
            dist = 0
        if not self.small_segment:
            self._check_frame_move(number, speed_code, feed, deltas)
        duration = move_duration_s(dist, feed, f0, acc_a, acc_b)
        start = self._start_time(now_s)
        if dist:
            frame = self.limits is not None and speed_code == self.limits.speed_code
            self._frame_schedule(number, start, start + duration, frame and not self.small_segment)
        self._queue_job(
            number, cmd, start, duration, origin, deltas=deltas, dist=dist,
            profile=(feed, f0, acc_a, acc_b),
        )  # fmt: skip

    def _enqueue_arc(self, number: int, cmd: Command, now_s: float) -> None:
        import math

        speed_code, axes = _ARC[cmd.code]
        acc_a, feed, acc_b = self.params[speed_code]
        f0 = self.params[_START_CODE[axes[0]]][2]
        cx, cy = signed_from_word(cmd.words[0]), signed_from_word(cmd.words[1])
        w = cmd.words[2]
        angle_deg = (w & 0xFFFFFF) / 100.0
        if angle_deg == 0:
            self._flag("arc", f"command {number}: endless arc (angle 0); emulated as one turn")
            angle_deg = 360.0
        sign = -1.0 if w >> 24 else 1.0  # 0 = counter-clockwise
        r = math.hypot(cx, cy)
        phi0 = math.atan2(-cy, -cx)
        phi1 = phi0 + sign * math.radians(angle_deg)
        dx = round(cx + r * math.cos(phi1))
        dy = round(cy + r * math.sin(phi1))
        deltas = [0, 0, 0, 0]
        deltas[_AXES.index(axes[0])] = dx
        deltas[_AXES.index(axes[1])] = dy
        dist = max(1, round(r * math.radians(angle_deg)))
        origin = self._planned_position()
        start = self._start_time(now_s)
        duration = move_duration_s(dist, max(feed, 1), f0, max(acc_a, 1), max(acc_b, 1))
        self._frame_schedule(number, start, start + duration, False)
        self._queue_job(
            number, cmd, start, duration, origin, deltas=deltas, dist=dist,
            profile=(max(feed, 1), f0, max(acc_a, 1), max(acc_b, 1)),
        )  # fmt: skip

    def _queue_job(
        self,
        number: int,
        cmd: Command,
        start: float,
        duration: float,
        origin: Sequence[int],
        end: Sequence[int] | None = None,
        *,
        deltas: Sequence[int] = (0, 0, 0, 0),
        dist: int = 0,
        profile: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0),
    ) -> None:
        """Queue ``cmd`` from ``start`` to + ``duration`` (s), taking the logical positions
        (pulses) from ``origin`` to ``end`` (default ``origin`` + ``deltas``).

        A move gives its ``deltas`` (pulses), step count ``dist`` and rate profile (feed Hz,
        start frequency Hz, acceleration and deceleration Hz/s); a job that moves no axis (a
        timed wait, a position set) gives none.
        """
        if end is None:
            end = [o + d for o, d in zip(origin, deltas, strict=True)]
        self.queue.append(
            _Job(number, cmd, start, start + duration, tuple(deltas), dist, profile,
                 tuple(origin), tuple(end))
        )  # fmt: skip

    def _stop_now(self, t_s: float) -> None:
        """Cut the executing move at ``t_s`` (position truncated) and keep the rest queued."""
        if self.queue and self.queue[0].start_s < t_s:
            job = self.queue[0]
            pos = self.position_at(t_s)
            rest = tuple(o + d - p for o, d, p in zip(job.origin, job.deltas, pos, strict=True))
            self.queue[0] = job.rest_from(t_s, pos, rest)
            self.trace.append(TraceEntry(t_s, self.address, pos, job.number))

    def _smooth_split(self, now_s: float) -> float:
        """Smooth brake: decelerate at B from the current rate to the start frequency.

        The executing move is split into a deceleration segment, which runs, and the
        remainder, which waits for the release. Returns the time the axes stop.
        """
        if not self.queue or self.queue[0].start_s >= now_s or not self.queue[0].dist:
            return now_s
        job = self.queue[0]
        _, rate = move_progress(job.dist, *job.profile, now_s - job.start_s)
        self._stop_now(now_s)
        rest = self.queue[0]
        _, f0, _, b = job.profile
        if rate <= f0 or not rest.dist:
            return now_s
        d_dec = min(rest.dist, (rate * rate - f0 * f0) / (2.0 * b))
        frac = d_dec / rest.dist
        seg = tuple(round(d * frac) for d in rest.deltas)
        seg_dist = max(abs(d) for d in seg)
        profile = (rate, f0, 1e12, b)  # already at speed: only the deceleration remains
        t_end = now_s + move_duration_s(seg_dist, *profile)
        mid = tuple(o + d for o, d in zip(rest.origin, seg, strict=True))
        first = _Job(job.number, job.cmd, now_s, t_end, seg, seg_dist, profile, rest.origin, mid)
        second = rest.rest_from(
            t_end, mid, tuple(d - s for d, s in zip(rest.deltas, seg, strict=True))
        )
        self.queue.popleft()
        self.queue.appendleft(second)
        self.queue.appendleft(first)
        return t_end

    def _out_of_band(self, cmd: Command, now_s: float) -> None:
        if cmd.code == 0x19:
            if cmd.words[0] >> 24 == 4:  # clear buffer: stop now and drop everything
                pos = self.position_at(now_s)
                if self.queue:
                    self.last_done = self.queue[0].number
                    self.trace.append(TraceEntry(now_s, self.address, pos, self.last_done))
                self.position = list(pos)
                self.queue.clear()
                self.pending_5b = None
                self.halt = None
                self._last_end_s = now_s
                self._moves_seen = False
                self._frame_due_s = None  # the next frame starts a new schedule
                self._frame_end_s = now_s
            return  # loop test: nothing but the reply
        code = cmd.words[0]
        brake_axes = {0x00: "XYZU", 0x02: "X", 0x04: "Y", 0x06: "Z", 0x12: "U"}
        release_axes = {0x01: "XYZU", 0x03: "X", 0x05: "Y", 0x07: "Z", 0x13: "U"}
        smooth_axes = {0x08: "XYZU", 0x09: "X", 0x0A: "Y", 0x0B: "Z", 0x19: "U"}
        smooth_release = {0x0C: "XYZU", 0x0D: "X", 0x0E: "Y", 0x0F: "Z", 0x1D: "U"}
        if code in brake_axes or code in smooth_axes:
            self.advance(now_s)
            if self.halt is None:
                t_stop = now_s
                if code in smooth_axes:
                    t_stop = self._smooth_split(now_s)
                else:
                    self._stop_now(now_s)
                self.halt = _Halt(t_stop)
            target = self.halt.axes if code in brake_axes else self.halt.smooth
            target.update((brake_axes | smooth_axes)[code])
        elif code in release_axes or code in smooth_release:
            if self.halt is None:
                return
            if code in release_axes:
                self.halt.axes -= set(release_axes[code])
            else:
                self.halt.smooth -= set(smooth_release[code])
            if not self.halt.axes and not self.halt.smooth:
                self.advance(self.halt.at_s)
                shift = max(now_s - self.halt.at_s, 0.0)
                for job in self.queue:
                    job.start_s += shift
                    job.end_s += shift
                self._last_end_s = max(self._last_end_s, now_s)
                self.halt = None

    # -- queries ----------------------------------------------------------------------------
    def _query(self, cmd: Command, now_s: float) -> ReadReply | ErrorReply:
        words = self.query_words(cmd.code, cmd.words[0], now_s)
        if words is None:
            return ErrorReply(ErrorCode.NO_SUCH_COMMAND, int(cmd.start), self.address)
        return ReadReply(cmd.code, words, int(cmd.start), self.address)

    def exec_status(self, now_s: float) -> ExecStatus:
        self.advance(now_s)
        eff = now_s if self.halt is None else min(now_s, self.halt.at_s)
        executing = self.last_done
        if self.queue and self.queue[0].start_s <= eff:
            executing = self.queue[0].number
        state = 7 if self.halt is not None and self.halt.axes else 0
        return ExecStatus(state, executing & MAX_MAGNITUDE, self.received, (0, 0, 0, 0))

    def query_words(self, code: int, item: int, now_s: float) -> tuple[int, ...] | None:
        """Data words of the read reply to query ``code`` with word ``item`` (None: unknown)."""
        pos = self.position_at(now_s)
        sw = word_from_signed
        if code in (0x31, 0x32, 0x33):
            i = code - 0x31
            if item == 1:
                return (sw(pos[i]),)
            if item == 2:
                return (sw(pos[i]), 0, 0)
            if item == 3:
                busy = self.busy_axes(now_s)
                return (
                    (("U" in busy) << 12)
                    | (("X" in busy) << 8)
                    | (("Y" in busy) << 4)
                    | ("Z" in busy),
                )
            if item == 4 and code == 0x31:
                return (sw(pos[0]), sw(pos[1]), sw(pos[2]))
            if item == 5 and code == 0x31:
                return (sw(pos[3]), 0, 0)
            if item == 0x42 and code == 0x31:
                return (sw(pos[3]), 0, 0)
            return None
        if (code, item) in _PARAM_READ:
            return tuple(self.params[_PARAM_READ[(code, item)]])
        if code == 0x34 and item == 0x83:
            up, un = self.soft["U"]
            return (sw(up), sw(un), sw(pos[3]))
        if code == 0x34 and item in (0xFC, 0xFD):
            return (sw(pos[0]), sw(pos[1]), sw(pos[2])) if item == 0xFC else (sw(pos[3]), 0, 0)
        if code == 0x37:
            if item == 0:
                return (0 if self.manual_mode else 1,)
            if 1 <= item <= 9:
                return (self.manual_params[item],)
            if 0xA <= item <= 0xF:
                axis = "XYZ"[(item - 0xA) // 2]
                return (sw(self.soft[axis][(item - 0xA) % 2]),)
            return None
        if code == 0x38:
            sub = item >> 24
            if sub == 0 and item == 0:
                return self.exec_status(now_s).words()
            if sub == 1 and item == 0x1000000:
                return (self.received,)
            if sub == 3 and (item >> 16) & 0xFF in (1, 2):
                c = (item >> 16) & 0xFF
                return ((3 << 24) | (c << 16) | self.counters[c],)
            if sub == 4:
                return ((4 << 24) | (1 << 20),)  # not in download state
            return None
        return None


def spec_is_param(cmd: Command) -> bool:
    """Commands that set parameters (sections 5.1 and 5.2, except moves and controls)."""
    return cmd.code not in (0x18, 0x19) and cmd.spec.section.startswith(("5.1", "5.2"))


class EasySmcEmulator:
    """Controllers on one serial bus behind a pseudo-terminal.

    Parameters
    ----------
    addresses : sequence of int
        Controller addresses on the bus (``(0,)``; ``(0, 1)`` for two on RS485).
    clock : callable
        Time source in seconds (``time.monotonic``).
    line_baud : int, optional
        Simulate the serial line: every byte received and sent occupies the line for
        10 bits at this rate (8N1), so a host cannot push more than the real link carries.
        None (default): bytes pass as fast as the pseudo-terminal moves them.
    controller : EasySmcController, optional
        Check frames with this description's numbers (:func:`frame_limits`): feed cap
        always; per-frame steps and frame periods when ``frame_rate_hz`` is given too.
    frame_rate_hz : float, optional
        The frame rate the host streams at (needs ``controller``).

    Use ``start()`` (thread), ``path`` (give it to pyserial), ``trace``, ``violations``,
    ``stop()``; or call :meth:`feed` with bytes directly (no pty).
    """

    def __init__(
        self,
        addresses: Sequence[int] = (0,),
        clock: Callable[[], float] = time.monotonic,
        line_baud: int | None = None,
        *,
        controller: EasySmcController | None = None,
        frame_rate_hz: float | None = None,
    ) -> None:
        if not addresses or len(set(addresses)) != len(addresses):
            raise ConfigError(f"addresses {addresses!r} must be distinct and non-empty")
        if line_baud is not None and line_baud <= 0:
            raise ConfigError(f"line_baud {line_baud} must be positive")
        if frame_rate_hz is not None and controller is None:
            raise ConfigError("frame_rate_hz needs the controller description (controller=)")
        limits = {} if controller is None else frame_limits(controller, frame_rate_hz)
        self.line_baud = line_baud
        self._line_free = 0.0
        self.models = {a: ControllerModel(a, limits=limits.get(a)) for a in addresses}
        self._clock = clock
        self._epoch = clock()
        self._buffer = b""
        self.stats = {
            "frames": 0,
            "checksum_errors": 0,
            "unknown": 0,
            "foreign_address": 0,
            "noise_bytes": 0,
        }
        self._lock = threading.Lock()
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self._master: int | None = None
        self._slave: int | None = None
        self.path = ""
        self.log: list[str] = []

    def now_s(self) -> float:
        return self._clock() - self._epoch

    # -- bytes in, bytes out ---------------------------------------------------------------
    def feed(self, data: bytes, now_s: float | None = None) -> bytes:
        """Take received bytes, return the reply bytes (thread-safe)."""
        with self._lock:
            t = self.now_s() if now_s is None else now_s
            frames, self._buffer, skipped = split_serial_frames(self._buffer + data)
            self.stats["noise_bytes"] += skipped
            out = b""
            for frame in frames:
                out += self._frame(frame, t)
            return out

    def _frame(self, frame: bytes, t: float) -> bytes:
        first = next(iter(self.models.values()))
        try:
            raw = _unframe(frame)
        except ProtocolError as exc:
            self.stats["checksum_errors"] += 1
            self.log.append(f"{t:.3f} bad frame {frame!r}: {exc}")
            return encode_reply(ErrorReply(ErrorCode.CHECKSUM, 0, first.address))
        model = self.models.get(raw.addr)
        if model is None:
            self.stats["foreign_address"] += 1
            return b""
        try:
            if raw.start > 8:
                raise ProtocolError(f"start condition {raw.start} not in 0..8")
            cmd = Command(raw.code, raw.words, Start(raw.start), raw.addr)
        except ProtocolError as exc:
            self.stats["unknown"] += 1
            self.log.append(f"{t:.3f} addr {raw.addr:02X}: {exc}")
            return encode_reply(ErrorReply(ErrorCode.NO_SUCH_COMMAND, min(raw.start, 9), raw.addr))
        self.stats["frames"] += 1
        return encode_reply(model.handle(cmd, t))

    # -- state ------------------------------------------------------------------------------
    def sync(self) -> None:
        with self._lock:
            t = self.now_s()
            for m in self.models.values():
                m.advance(t)

    @property
    def trace(self) -> list[TraceEntry]:
        self.sync()
        return sorted((e for m in self.models.values() for e in m.trace), key=lambda e: e.t_s)

    @property
    def violations(self) -> list[Violation]:
        return sorted((v for m in self.models.values() for v in m.violations), key=lambda v: v.t_s)

    @property
    def received(self) -> int:
        """Valid frames received (any address on the bus)."""
        return self.stats["frames"]

    @property
    def frames_received(self) -> int:
        """The same as :attr:`received`: every frame on the bus is a frame."""
        return self.received

    def set_manual(self, manual: bool) -> None:
        """Close / open the A/M jumper (manual mode answers writes with error 2)."""
        with self._lock:
            for m in self.models.values():
                m.manual_mode = manual

    # -- pseudo-terminal ---------------------------------------------------------------------
    def start(self) -> EasySmcEmulator:
        """Open a pseudo-terminal and serve it from a thread; ``path`` is the device."""
        import tty

        try:
            self._master, self._slave = os.openpty()
            tty.setraw(self._slave)
            self.path = os.ttyname(self._slave)
        except OSError as exc:
            raise TransportError(f"cannot open a pseudo-terminal: {exc}") from exc
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name="easysmc-emulator", daemon=True)
        self._thread.start()
        return self

    def _serve(self) -> None:
        assert self._master is not None
        fd = self._master
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([fd], [], [], 0.02)
            except (OSError, ValueError):
                return
            if not ready:
                continue
            try:
                data = os.read(fd, 4096)
            except OSError:  # the other side closed: wait for a new open
                time.sleep(0.01)
                continue
            if not data:
                continue
            self._occupy_line(len(data))  # the command arrives once it is on the line
            reply = self.feed(data)
            if reply:
                self._occupy_line(len(reply))
                with contextlib.suppress(OSError):
                    os.write(fd, reply)

    def _occupy_line(self, n_bytes: int) -> None:
        """Wait while ``n_bytes`` cross the simulated line (absolute schedule, no drift)."""
        if self.line_baud is None:
            return
        now = time.monotonic()
        self._line_free = max(self._line_free, now) + n_bytes * 10 / self.line_baud
        delay = self._line_free - now
        if delay > 0:
            time.sleep(delay)

    def stop(self) -> None:
        """Stop serving and close the pseudo-terminal."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=2.0)
            self._thread = None
        for fd in (self._master, self._slave):
            if fd is not None:
                with contextlib.suppress(OSError):
                    os.close(fd)
        self._master = self._slave = None
        self.sync()

    def __enter__(self) -> EasySmcEmulator:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
