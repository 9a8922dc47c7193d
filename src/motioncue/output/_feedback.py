"""What an IMAX or SC-MBOX tells the host back: where the platform is, and which frames it
refused.

* :func:`read_position` asks the controller for its motor positions with one register read
  (MBOX 0x1101 on channel 0, the Dn status registers: actual positions Dn06.., commanded
  positions Dn0C.., buffer depth Dn4B, manual 003 section 6.1; IMAX 0x1101 on channel 0, the
  DP registers: positions DP06.., receive / use pointers DP48 / DP49, manual 000 2.3.3).
  A link that cannot answer (``pcap:``, ``file:``, serial) or a controller that does not
  answer within the timeout gives ``None``: the caller then assumes the park position.
* :class:`FrameReplies` counts the frame replies waiting on a link without blocking: both
  kinds answer a frame 0x1301 / 0x1401 with 0x1x02 when it was taken and another last digit
  when it was not (MBOX 0x1x03 buffer full, 0x1x04 short frame; IMAX 0x1x03 error, e.g.
  Err21 buffer overflow, 0x1x04 e-stop active, 0x1x05 command error).
* :class:`LinkWatch` notices a controller that stops answering (power loss, a reset, the
  cable, nothing listening) or refuses the frames it is sent: every datagram the controller
  sends (frame replies, register replies, IMAX status reports 0x3101) counts as a sign of
  life; after ``probe_every_s`` without one the watch asks the controller's status (the
  register read of :func:`read_position`, which both kinds answer even when they do not
  answer frames), and after ``silence_s`` without one it raises
  :class:`~motioncue._errors.ControllerSilent`. Frames refused for a reason that does not go
  away by waiting (MBOX 0x1x04 frame shorter than required, i.e. a frame of the other axis
  mode; IMAX 0x1x04 e-stop, 0x1x05 command error, 0x1x03 other than Err21) stop the job at
  the ``refusals_stop``-th one with :class:`~motioncue._errors.FramesRefused`; a full buffer
  (MBOX 0x1x03, IMAX 0x1x03 with error 21) is flow control, counted and reported.
"""

from __future__ import annotations

import errno
import math
import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, TypeVar

from .._errors import ControllerSilent, FramesRefused, MotioncueError, ProtocolError

if TYPE_CHECKING:
    from ._controller_api import Controller
    from ._registry import Refusals
    from ._transport import Transport

__all__ = [
    "DEFAULT_SILENCE_S",
    "FrameReplies",
    "LinkWatch",
    "PositionQuery",
    "ReportedPosition",
    "read_position",
    "register_position_query",
    "words_to_positions",
]

_HEAD = struct.Struct(">HHHH")  # confirm, pass, function, channel
_FRAME_NO = struct.Struct(">I")  # frame number right after the 12-byte header
_CONFIRM_MAIN = 0x55AA
_FRAME_BASES = (0x1300, 0x1400, 0x1800, 0x1900)  # timed and vibration frames (and replies)
# what the host sends (an echo of our own broadcast is no sign of the controller's life):
# register read / write, servo parameter read / write
_REQUESTS = frozenset((0x1101, 0x1201, 0x2101, 0x2201))

DEFAULT_SILENCE_S = 0.5
"""How long a controller may stay silent before the job stops (s); ``udp://...?silence_ms=``
sets it per target (0: not watched, for a capture or a sniffer that never answers)."""


@dataclass(frozen=True)
class ReportedPosition:
    """Motor positions a controller reported.

    Attributes
    ----------
    pulses : tuple of int
        Actual motor positions (encoder pulses), one per axis.
    moving : bool
        The controller still had frames to play (buffer depth > 0, or actual and
        commanded positions differ) when it last answered.
    depth : int
        Frames in its buffer at that time.
    """

    pulses: tuple[int, ...]
    moving: bool
    depth: int


def _signed32(lo: int, hi: int) -> int:
    v = lo | hi << 16
    return v - (1 << 32) if v & 0x80000000 else v


def words_to_positions(values: Sequence[int], addresses: Sequence[int]) -> tuple[int, ...]:
    """32-bit signed positions from 16-bit registers (low word at each address, high word
    after it)."""
    return tuple(_signed32(values[a], values[a + 1]) for a in addresses)


MessageT = TypeVar("MessageT")

PositionQuery = tuple[bytes, Callable[[bytes], "ReportedPosition | None"]]
"""A request datagram and the parser of its reply (``None`` for a datagram that is not it)."""


def register_position_query(
    request: bytes,
    decode: Callable[[bytes], MessageT],
    registers: Callable[[MessageT], Sequence[int] | None],
    positions: Sequence[int],
    status: Callable[[Sequence[int], tuple[int, ...]], tuple[bool, int]],
) -> PositionQuery:
    """A :data:`PositionQuery` for a register read (MBOX Dn, IMAX DP).

    ``decode`` turns a datagram into a message (raising :class:`ProtocolError`),
    ``registers`` gives the values of the expected reply (None for anything else),
    ``positions`` the register of each axis' 32-bit position, and ``status(values,
    pulses)`` returns ``(moving, buffer depth)``.
    """

    def parse(data: bytes) -> ReportedPosition | None:
        try:
            values = registers(decode(data))
        except ProtocolError:
            return None
        if values is None:
            return None
        pulses = words_to_positions(values, positions)
        moving, depth = status(values, pulses)
        return ReportedPosition(pulses, moving, depth)

    return request, parse


def read_position(
    controller: Controller,
    transport: Transport,
    *,
    timeout_s: float = 0.2,
    settle_s: float = 1.0,
) -> ReportedPosition | None:
    """Ask the controller where its motors are; ``None`` if it cannot or does not say.

    Parameters
    ----------
    controller
        A controller description; one whose ``position_query()`` gives None gives ``None``.
    transport
        The link; one that does not answer (``pcap:``, ``file:``, serial) gives ``None``.
    timeout_s : float
        How long to wait for each reply (s).
    settle_s : float
        While the controller reports it is still playing frames, ask again for up to this
        long (s); the last answer is returned (``moving`` tells whether it settled).

    Returns
    -------
    ReportedPosition or None
    """
    if not transport.answers:
        return None
    asked = controller.position_query()
    if asked is None:
        return None
    request, parse = asked
    deadline = time.monotonic() + settle_s
    last: ReportedPosition | None = None
    while True:
        try:
            reply = transport.request(
                request, lambda d: parse(d) is not None, timeout_s=timeout_s, retries=0
            )
        except MotioncueError:
            return last
        last = parse(reply)
        if last is None or not last.moving or time.monotonic() >= deadline:
            return last
        time.sleep(0.02)


class FrameReplies:
    """Counts frame replies waiting on a link (never blocks).

    Parameters
    ----------
    transport
        The link (its ``recv(timeout_s)``; a send-only link's gives None: nothing counted).

    Attributes
    ----------
    accepted, refused : int
        Frame replies that said the frame was taken / not taken.
    refused_codes : dict[int, int]
        Refusals by reply function code (``0x1303`` MBOX buffer full, IMAX error...).
    last_refused_frame : int or None
        Number of the newest refused frame.
    refusals : dict[tuple[int, int], int]
        Refusals by (reply function code, channel field: the IMAX error code).
    heard : int
        Datagrams from the controller of any kind (frame and register replies, status
        reports); ``last_heard`` is the ``time.monotonic()`` of the newest (None: none yet).
    unreachable : int
        Receives that reported an ICMP "port unreachable" (nothing listens at the target).
    """

    def __init__(self, transport: Transport) -> None:
        self._recv = transport.recv
        self.accepted = 0
        self.refused = 0
        self.refused_codes: dict[int, int] = {}
        self.refusals: dict[tuple[int, int], int] = {}
        self.last_refused_frame: int | None = None
        self.last_refusal: tuple[int, int] | None = None
        self.last_accepted_frame: int | None = None
        self.heard = 0
        self.last_heard: float | None = None
        self.unreachable = 0

    @property
    def last_answered_frame(self) -> int:
        """Number of the newest frame answered (taken or refused); -1 before any."""
        a, r = self.last_accepted_frame, self.last_refused_frame
        return max(-1 if a is None else a, -1 if r is None else r)

    @property
    def replies(self) -> int:
        return self.accepted + self.refused

    def poll(self, wait_s: float = 0.0, until_frame: int | None = None) -> None:
        """Read every reply already waiting; with ``wait_s``, keep reading for up to that
        long (stopping early once frame ``until_frame`` has been answered)."""
        recv = self._recv
        deadline = time.monotonic() + wait_s
        while True:
            try:
                data = recv(max(0.0, deadline - time.monotonic()))
            except (OSError, MotioncueError) as exc:
                cause = exc.__cause__ if exc.__cause__ is not None else exc
                if isinstance(cause, OSError) and cause.errno == errno.ECONNREFUSED:
                    self.unreachable += 1
                    continue  # the pending ICMP error is consumed; read on
                return
            if data is None:  # nothing more within the wait
                return
            if len(data) >= 6 and int.from_bytes(data[4:6], "big") not in _REQUESTS:
                function = int.from_bytes(data[4:6], "big")
                if not (function & 0xFFF0 in _FRAME_BASES and function & 0xF == 1):
                    self.heard += 1
                    self.last_heard = time.monotonic()
            number = self._count(data)
            if until_frame is not None and number == until_frame:
                deadline = 0.0  # answered: only read what is already waiting

    def _count(self, data: bytes) -> int | None:
        if len(data) < 16:
            return None
        confirm, passcode, function, _channel = _HEAD.unpack_from(data)
        if confirm != _CONFIRM_MAIN or passcode or function & 0xFFF0 not in _FRAME_BASES:
            return None
        status = function & 0xF
        if status == 1:  # a frame, not a reply (our own broadcast echoed back)
            return None
        number = int(_FRAME_NO.unpack_from(data, 12)[0])
        if status == 2:
            self.accepted += 1
            self.last_accepted_frame = number
        else:
            self.refused += 1
            self.refused_codes[function] = self.refused_codes.get(function, 0) + 1
            key = (function, _channel)
            self.refusals[key] = self.refusals.get(key, 0) + 1
            self.last_refusal = key
            self.last_refused_frame = number
        return number


def _refusals(kind: str) -> Refusals | None:
    from ._registry import controller_kind

    return controller_kind(kind).refusals


def is_flow_control(kind: str, function: int, channel: int) -> bool:
    """A refusal that waiting cures (the controller's buffer was full: MBOX 0x1x03, IMAX
    0x1x03 with error 21), as the kind's registry entry declares."""
    refusals = _refusals(kind)
    return refusals is not None and refusals.is_flow_control(function, channel)


def describe_refusal(kind: str, function: int, channel: int) -> str:
    """What a frame refusal means, by the controller's manual (its kind's registry entry)."""
    refusals = _refusals(kind)
    return "refused" if refusals is None else refusals.describe(function, channel)


class LinkWatch:
    """Notices a controller that stops answering or refuses its frames (module docstring).

    Parameters
    ----------
    transport
        The link (``send`` and ``recv``).
    controller
        Its ``kind`` names the refusal codes; its ``position_query()`` gives the status
        request sent while the controller is silent.
    silence_s : float
        Longest time without any datagram from the controller while frames are sent (s).
    probe_every_s : float
        Without a sign of life for this long, ask the controller's status, and again each
        time this long passes (s).
    refusals_stop : int
        Refusals that waiting does not cure after which the job stops.

    Attributes
    ----------
    replies : FrameReplies
    armed : bool
        Whether :meth:`check` raises (the park disarms it: park frames are sent whatever
        the controller says, and the park is judged by :meth:`await_answer`).
    probes : int
        Status requests sent.
    """

    def __init__(
        self,
        transport: Transport,
        controller: Controller,
        silence_s: float = DEFAULT_SILENCE_S,
        *,
        probe_every_s: float = 0.2,
        refusals_stop: int = 3,
    ) -> None:
        if not (math.isfinite(silence_s) and silence_s > 0):
            raise ValueError(f"silence_s = {silence_s!r}; allowed: > 0 s")
        self.replies = FrameReplies(transport)
        self._send = transport.send
        self.address = transport.address
        self.silence_s = float(silence_s)
        self.probe_every_s = float(min(probe_every_s, silence_s / 2))
        self.refusals_stop = int(refusals_stop)
        self.kind = str(controller.kind)
        asked = controller.position_query()
        self._probe: bytes | None = None if asked is None else asked[0]
        self.armed = True
        self.probes = 0
        self.frames = 0
        self.t_first: float | None = None
        self._last_probe = -math.inf
        self._heard_at_frame = (0, 0)  # (heard count, frames sent) at the last sign of life
        self._waiting_since: float | None = None  # first send not answered yet

    def sent_frame(self) -> None:
        """Count one frame handed to the link."""
        now = time.monotonic()
        if self.t_first is None:
            self.t_first = now
        if self._waiting_since is None:
            self._waiting_since = now
        self.frames += 1

    def silent_s(self, now: float | None = None) -> float:
        """How long the controller has left unanswered what it was sent: from the first
        frame or status request sent after its last sign of life (0 when nothing waits for
        an answer). A host held up between frames (a stopped process) is not counted as
        the controller's silence: answers that came meanwhile are read first."""
        if self._waiting_since is None:
            return 0.0
        return (time.monotonic() if now is None else now) - self._waiting_since

    def hard_refusals(self) -> dict[tuple[int, int], int]:
        """Refusals waiting does not cure, by (function, channel)."""
        return {
            k: v for k, v in self.replies.refusals.items() if not is_flow_control(self.kind, *k)
        }

    def poll(self, wait_s: float = 0.0, until_frame: int | None = None) -> None:
        """Read what the controller sent; ask its status when it has been quiet too long."""
        replies = self.replies
        replies.poll(wait_s, until_frame)
        if replies.heard != self._heard_at_frame[0]:
            self._heard_at_frame = (replies.heard, self.frames)
            self._waiting_since = None  # it answered: what was sent counts as answered
        now = time.monotonic()
        if (
            self._probe is not None
            and self.t_first is not None
            and self.silent_s(now) >= self.probe_every_s
            and now - self._last_probe >= self.probe_every_s
        ):
            self._last_probe = now
            try:
                self._send(self._probe)
                self.probes += 1
            except OSError:
                pass  # the silence, not the send, is what stops the job
            if self._waiting_since is None:
                self._waiting_since = now

    def check(self) -> None:
        """Poll (never blocks); raise when the controller is silent or refuses frames.

        Raises
        ------
        ControllerSilent
            Nothing from the controller for longer than ``silence_s`` (armed only).
        FramesRefused
            ``refusals_stop`` frames refused for a reason waiting does not cure (armed only).
        """
        self.poll()
        if not self.armed:
            return
        silent = self.silent_s()
        if silent > self.silence_s:
            raise ControllerSilent(self.silence_message(silent))
        if self.replies.refused >= self.refusals_stop:  # cheap test first: rare
            hard = self.hard_refusals()
            if sum(hard.values()) >= self.refusals_stop:
                raise FramesRefused(self.refusal_message())

    def silence_message(self, silent_s: float) -> str:
        """``controller silent for N ms ...``: what was sent into the silence, and what
        the link said."""
        unanswered = self.frames - self._heard_at_frame[1]
        where = "" if self.address is None else f" at {self.address[0]}:{self.address[1]}"
        asked = f" and {self.probes} status requests" if self.probes else ""
        ever = "" if self.replies.heard else "; it never answered"
        icmp = (
            f"; the host answered 'port unreachable' {self.replies.unreachable} times: "
            "nothing listens there"
            if self.replies.unreachable
            else ""
        )
        return (
            f"controller silent for {1000 * silent_s:.0f} ms (limit {1000 * self.silence_s:.0f}"
            f" ms): no answer{where} to the last {unanswered} frames{asked}{ever}{icmp} "
            "(power, cable, a reset or nothing listening)"
        )

    def refusal_message(self) -> str:
        """Which frames were refused and why."""
        parts = [
            f"0x{f:04X} x{n}: {describe_refusal(self.kind, f, c)}"
            for (f, c), n in sorted(self.replies.refusals.items())
        ]
        taken = self.replies.accepted
        return (
            f"the controller refused {self.replies.refused} frames ({'; '.join(parts)}) and "
            f"took {taken}"
        )
