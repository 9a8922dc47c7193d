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
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from .._errors import MotioncueError, ProtocolError

__all__ = [
    "FrameReplies",
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


PositionQuery = tuple[bytes, Callable[[bytes], "ReportedPosition | None"]]
"""A request datagram and the parser of its reply (``None`` for a datagram that is not it)."""


def register_position_query(
    request: bytes,
    decode: Callable[[bytes], Any],
    registers: Callable[[Any], Sequence[int] | None],
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
    controller: Any, transport: Any, *, timeout_s: float = 0.2, settle_s: float = 1.0
) -> ReportedPosition | None:
    """Ask the controller where its motors are; ``None`` if it cannot or does not say.

    Parameters
    ----------
    controller
        A controller description; one whose ``position_query()`` gives None (or that has
        none) gives ``None``.
    transport
        The link; one without ``request`` (``pcap:``, ``file:``, serial) gives ``None``.
    timeout_s : float
        How long to wait for each reply (s).
    settle_s : float
        While the controller reports it is still playing frames, ask again for up to this
        long (s); the last answer is returned (``moving`` tells whether it settled).

    Returns
    -------
    ReportedPosition or None
    """
    query = getattr(controller, "position_query", None)
    if query is None or getattr(transport, "request", None) is None:
        return None
    asked = query()
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
        Anything with ``recv(timeout_s)``; a link without it counts nothing.

    Attributes
    ----------
    accepted, refused : int
        Frame replies that said the frame was taken / not taken.
    refused_codes : dict[int, int]
        Refusals by reply function code (``0x1303`` MBOX buffer full, IMAX error...).
    last_refused_frame : int or None
        Number of the newest refused frame.
    """

    def __init__(self, transport: Any) -> None:
        recv = getattr(transport, "recv", None)
        self._recv = recv
        self.accepted = 0
        self.refused = 0
        self.refused_codes: dict[int, int] = {}
        self.last_refused_frame: int | None = None
        self.last_accepted_frame: int | None = None

    @property
    def replies(self) -> int:
        return self.accepted + self.refused

    def poll(self, wait_s: float = 0.0, until_frame: int | None = None) -> None:
        """Read every reply already waiting; with ``wait_s``, keep reading for up to that
        long (stopping early once frame ``until_frame`` has been answered)."""
        recv = self._recv
        if recv is None:
            return
        deadline = time.monotonic() + wait_s
        while True:
            try:
                data = recv(max(0.0, deadline - time.monotonic()))
            except (OSError, MotioncueError):
                return
            if data is None:  # nothing more within the wait
                return
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
            self.last_refused_frame = number
        return number
