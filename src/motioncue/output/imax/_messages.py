"""IMAX / SMC UDP messages (IMAX manual chapter 2), each declared once.

Every message is a frozen dataclass with its ``struct.Struct`` layout beside it; ``encode``,
``decode`` and ``size`` derive from it. :func:`decode` reads a datagram of either direction
and returns the typed message or raises :class:`~motioncue.ProtocolError`.

Replies: the last hex digit of the function code is the status ``x`` (2 running normally,
3 error, 4 e-stop active, 5 command error or controller fault); when ``x`` is not 2 the
channel field holds the controller's error code (2.2.2.2, 2.2.2.4, 2.2.2.6).

Decisions where the manual is ambiguous or contradicts itself:

* PortOut's width is configuration (``port_out_bytes`` of the controller, 2 or 4; default
  2), passed to every frame message and to :func:`decode`. The manual prints it two ways:
  2 bytes (``$.$``) in the 0x1301 absolute-time frame (2.2.2.5), 4 bytes (``L*``) in the
  0x1401 relative-time frame (2.2.2.7), in every frame reply (2.2.2.6, 2.2.2.8) and in the
  vibration frames and replies (2.2.2.9-2.2.2.12). The two frames are otherwise the same
  layout and a controller is unlikely to differ between them, so one width is used for all
  frames and replies of a controller: 2 (0x1301's table; the 12 outputs fit in 2 bytes and
  the ``L*`` elsewhere copied from the neighbouring columns) or 4 (the majority of the
  tables; 0x1301's ``$.$`` the slip). The frame lengths tell the two apart (26 + 4 n or
  28 + 4 n bytes for n axes, vibration 22 + 8 n or 24 + 8 n), so :func:`decode` without a
  width accepts either (for tools such as ``inspect``); the emulator and the replies use
  the configured width only.
* Frame replies repeat the frame layout, PortOut carrying the input states; their axis
  count follows from the length because error replies overwrite the channel.
* Channel 0 = 3 axes, 1 = 6 axes, n = n axes (2..12); the 0x1401 table's "2: x axes" is
  read as "x: x axes". Vibration frames use the same coding (their tables list 0 and 1).
* 0x1801 is absolute time (function table, "绝对时间" row) although its header row says
  "Relative Time"; 0x1902/0x1903 are the relative-time vibration replies (2.2.2.12's title
  says absolute).
* The read request's Extra Data is ``count`` zero words; servo replies 0x21xx / 0x22xx
  (not printed) are taken to mirror the register replies under ConfirmCode 0x33CC.
* Status report 0x3101 (2.2.2.15) has no Who fields: ControlID u16, ServoNum u16, then
  ServoNum x position i32, ServoNum x torque i16, ServoNum x alarm u16, controller alarm
  u16, outputs u16, inputs u16 (the width row of the table is garbled; columns in order).
* 0x1001 appears in the function table ("report status") without a layout; it is refused
  as unknown, 0x3101 being the documented report.
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from functools import cache
from itertools import chain
from typing import TYPE_CHECKING, ClassVar, Self, cast

from ..._errors import ProtocolError
from ..._frozen import set_fields
from .._udp_common import (
    AXES_OF_CHANNEL,
    CHANNEL_OF_AXES,
    CONFIRM_MAIN,
    CONFIRM_SERVO,
    F_ABS,
    F_REL,
    PASSCODE,
    REG_HEAD,
    WHO_ALL,
    WHO_NONE,
    Header,
    check_length,
    decode_header,
    pack_timed_frame,
    timed_frame_struct,
    u16_tuple,
)
from .._udp_registers import (
    RegisterReadShape,
    RegisterWire,
    RegisterWriteShape,
    check_u16_fields,
    unpack_values,
)

__all__ = [  # what the package exports from here
    "CHANNEL_DP",
    "CHANNEL_DPF",
    "CHANNEL_PA",
    "PORT_OUT_BYTES",
    "MotionFrame",
    "MotionFrameReply",
    "RegisterRead",
    "RegisterReply",
    "RegisterWrite",
    "ReplyStatus",
    "ServoRead",
    "ServoReply",
    "ServoWrite",
    "StatusReport",
    "VibrationFrame",
    "VibrationFrameReply",
    "axes_of_channel",
    "channel_of_axes",
    "decode",
    "frame_size",
]

F_READ, F_WRITE = 0x1101, 0x1201
F_VIB_ABS, F_VIB_REL = 0x1801, 0x1901
F_SERVO_READ, F_SERVO_WRITE = 0x2101, 0x2201
F_STATUS = 0x3101

CHANNEL_DP, CHANNEL_PA, CHANNEL_DPF = 0, 1, 2
MAX_AXES = 12
MAX_SERVO_REGS = 6
PORT_OUT_BYTES = (2, 4)
"""The two readings of the manual for PortOut's width in frames and replies (module notes)."""
_FRAME_FUNCTIONS = frozenset(
    base - 1 + x for base in (0x1301, 0x1401, 0x1801, 0x1901) for x in (1, 2, 3, 4, 5)
)


class ReplyStatus(enum.IntEnum):
    """``x`` in a reply's function code 0x....x (IMAX 2.2.1)."""

    OK = 2
    ERROR = 3
    ESTOP = 4
    COMMAND_ERROR = 5


FUNCTION_NAMES = {
    F_READ: "read registers",
    F_WRITE: "write registers",
    F_ABS: "frame abs-time",
    F_REL: "frame rel-time",
    F_VIB_ABS: "vibration frame abs-time",
    F_VIB_REL: "vibration frame rel-time",
    F_SERVO_READ: "servo read",
    F_SERVO_WRITE: "servo write",
    F_STATUS: "status report",
}


def axes_of_channel(channel: int) -> int:
    """Axis count of a frame channel: 0 -> 3, 1 -> 6, n -> n (2..12)."""
    if 0 <= channel <= MAX_AXES:
        return AXES_OF_CHANNEL.get(channel, channel)
    raise ProtocolError(f"frame channel {channel}: allowed 0 (3 axes), 1 (6 axes), 2..12 (n)")


def channel_of_axes(n_axes: int) -> int:
    """Frame channel of an axis count: 3 -> 0, 6 -> 1, n -> n (2..12)."""
    if 2 <= n_axes <= MAX_AXES:
        return CHANNEL_OF_AXES.get(n_axes, n_axes)
    raise ProtocolError(f"{n_axes} axes: an IMAX frame carries 2..12 axes")


# -- register access ------------------------------------------------------------------------
@dataclass(frozen=True, slots=True)
class RegisterRead(RegisterReadShape):
    """Host -> IMAX 0x1101: read ``count`` registers of channel 0 (DP) or 1 (PA).

    Layout: header, StartAddress u16, Count u16, ``count`` zero words (Extra Data).
    """

    FUNCTION: ClassVar[int] = F_READ
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_DP, CHANNEL_PA)


class _Servo:
    """What the servo-parameter messages 0x2101 / 0x2201 change in the register layout:
    ConfirmCode 0x33CC, the channel field is the servo id, at most 6 parameters."""

    __slots__ = ()

    CONFIRM: ClassVar[int] = CONFIRM_SERVO
    CHANNELS: ClassVar[Sequence[int]] = range(0x10000)
    MAX_COUNT: ClassVar[int] = MAX_SERVO_REGS


@dataclass(frozen=True, slots=True)
class ServoRead(_Servo, RegisterRead):
    """Host -> IMAX 0x2101: read parameters of the servo drive ``channel``; PA508 is
    address 0x01FC (2.2.2.13)."""

    FUNCTION: ClassVar[int] = F_SERVO_READ


@dataclass(frozen=True, slots=True)
class RegisterWrite(RegisterWriteShape):
    """Host -> IMAX 0x1201: write ``values`` to channel 0 (DP), 1 (PA) or 2 (DPF0..DPFF)."""

    FUNCTION: ClassVar[int] = F_WRITE
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_DP, CHANNEL_PA, CHANNEL_DPF)


@dataclass(frozen=True, slots=True)
class ServoWrite(_Servo, RegisterWrite):
    """Host -> IMAX 0x2201: write parameters of servo ``channel`` (2.2.2.14)."""

    FUNCTION: ClassVar[int] = F_SERVO_WRITE


@dataclass(frozen=True, slots=True)
class RegisterReply(RegisterWire):
    """IMAX -> host 0x110x (read) / 0x120x (write) reply, x = :class:`ReplyStatus`.

    Layout: header (channel, or error code when x != 2), StartAddress u16, Count u16,
    Count x u16 (the values read / written). Unlike the MBOX's, the function code is a
    field: its last digit carries the status, and the channel the error code.
    """

    LAYOUT: ClassVar[struct.Struct] = REG_HEAD
    CONFIRM: ClassVar[int] = CONFIRM_MAIN
    BASES: ClassVar[tuple[int, int]] = (F_READ, F_WRITE)

    function: int
    channel: int
    start: int
    values: tuple[int, ...]
    who_accept: int = WHO_NONE
    who_reply: int = WHO_NONE

    def __post_init__(self) -> None:
        if (self.function & 0xFFF0) | 1 not in self.BASES or self.function & 0xF not in (
            2,
            3,
            4,
            5,
        ):
            raise ProtocolError(f"{type(self).__name__}: function 0x{self.function:04X}")
        check_u16_fields(self, "channel", "start", "who_accept", "who_reply")
        set_fields(self, values=u16_tuple(self.values, type(self).__name__))
        if len(self.values) > 256:
            raise ProtocolError(f"{type(self).__name__}: {len(self.values)} values")

    @property
    def status(self) -> ReplyStatus:
        return ReplyStatus(self.function & 0xF)

    @property
    def error_code(self) -> int | None:
        """The controller's error code (channel field), ``None`` for an OK reply."""
        return None if self.status == ReplyStatus.OK else self.channel

    def _function_code(self) -> int:
        return self.function

    def _count_and_words(self) -> tuple[int, Sequence[int]]:
        return len(self.values), self.values

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> Self:
        start, values = unpack_values(data, cls.__name__)
        return cls(h.function, h.channel, start, values, h.who_accept, h.who_reply)


@dataclass(frozen=True, slots=True)
class ServoReply(RegisterReply):
    """IMAX -> host 0x210x / 0x220x servo-parameter reply (ConfirmCode 0x33CC)."""

    CONFIRM: ClassVar[int] = CONFIRM_SERVO
    BASES: ClassVar[tuple[int, int]] = (F_SERVO_READ, F_SERVO_WRITE)


# -- frames -----------------------------------------------------------------------------------
def check_port_out_bytes(port_out_bytes: object) -> int:
    """``port_out_bytes`` if it is 2 or 4, else :class:`ProtocolError`."""
    if type(port_out_bytes) is not int or port_out_bytes not in PORT_OUT_BYTES:
        raise ProtocolError(
            f"PortOut width {port_out_bytes!r} bytes; allowed: 2 or 4 (see the IMAX notes)"
        )
    return port_out_bytes


def _port_code(port_out_bytes: int) -> str:
    return "H" if check_port_out_bytes(port_out_bytes) == 2 else "I"


@cache
def _frame_struct(n_axes: int, relative: bool, port_out_bytes: int = 2) -> struct.Struct:
    # header, Frame u32, Time u32 / i32, n x i32 positions, PortOut u16 / u32, Extend u32
    return timed_frame_struct(n_axes, relative, f"{_port_code(port_out_bytes)}I")


@cache
def _vib_struct(n_axes: int, relative: bool, port_out_bytes: int = 2) -> struct.Struct:
    # header, Frame u32, Time, n x i32, PortOut u16 / u32, n x (period u16 0.125 ms,
    # amplitude u16)
    return timed_frame_struct(n_axes, relative, f"{_port_code(port_out_bytes)}{2 * n_axes}H")


def frame_size(n_axes: int, port_out_bytes: int = 2) -> int:
    """Bytes of a motion frame: 12 + 8 + 4 n + PortOut (2 or 4) + 4."""
    return _frame_struct(n_axes, False, port_out_bytes).size


def vibration_frame_size(n_axes: int, port_out_bytes: int = 2) -> int:
    """Bytes of a vibration frame: 12 + 8 + 4 n + PortOut (2 or 4) + 4 n."""
    return _vib_struct(n_axes, False, port_out_bytes).size


def _width_of(size: int, sizes: dict[int, int], port_out_bytes: int | None, what: str) -> int:
    """The PortOut width of a ``size``-byte message whose size per width is ``sizes``:
    the given width (checked), or, for ``None``, the one the length fits."""
    if port_out_bytes is not None:
        expected = sizes[check_port_out_bytes(port_out_bytes)]
        if size != expected:
            raise ProtocolError(
                f"{what}: length {size} bytes, expected {expected} (PortOut {port_out_bytes} bytes)"
            )
        return port_out_bytes
    for width, expected in sizes.items():
        if size == expected:
            return width
    raise ProtocolError(
        f"{what}: length {size} bytes, expected {sizes[2]} (PortOut 2 bytes) or "
        f"{sizes[4]} (4 bytes)"
    )


def _reply_axes(
    size: int, fixed: int, per_axis: int, port_out_bytes: int | None, what: str
) -> tuple[int, int]:
    """``(n_axes, width)`` of a reply of ``size`` bytes = ``fixed`` + PortOut + ``per_axis``
    x n: the given width, or for ``None`` the one whose n is a whole 2..12."""
    widths = PORT_OUT_BYTES if port_out_bytes is None else (check_port_out_bytes(port_out_bytes),)
    for width in widths:
        n, rest = divmod(size - fixed - width, per_axis)
        if not rest and 2 <= n <= MAX_AXES:
            return n, width
    forms = " or ".join(f"{fixed + w} + {per_axis} n" for w in widths)
    raise ProtocolError(f"{what}: length {size} bytes is not {forms} for 2..12 axes")


_Pairs = tuple[tuple[int, int], ...]
_Tail = tuple[int, int | _Pairs]
"""A frame's fields after the positions: PortOut, then Extend (plain frames) or the
vibration (period, amplitude) pairs."""


@dataclass(frozen=True)
class _FrameKind:
    """What tells the four IMAX frame messages apart, beyond their head fields.

    Attributes
    ----------
    vibration : bool
        The layout's tail after PortOut is n (period, amplitude) u16 pairs, not Extend u32.
    bases : tuple[int, int]
        The (absolute, relative) request function codes.
    what : str
        The message's name in errors.
    tail : tuple[str, str]
        The names of its two trailing fields: PortOut (the request's outputs, the reply's
        inputs), then Extend or the vibration pairs.
    """

    vibration: bool
    bases: tuple[int, int]
    what: str
    tail: tuple[str, str]


class _TimedFrame:
    """Encoder, decoder and size of the four IMAX frame messages, derived from one
    declaration per message: its :class:`_FrameKind` (``KIND``), whether it is a request
    or a reply (:class:`_TimedRequest`, :class:`_TimedReply`) and its fields."""

    __slots__ = ()

    KIND: ClassVar[_FrameKind]

    absolute: bool
    frame: int
    time_ms: int
    positions: tuple[int, ...]
    port_out_bytes: int

    if TYPE_CHECKING:  # the dataclass subclasses' constructors, in field order

        def __init__(self, *fields: object) -> None: ...

    @classmethod
    def _STRUCT(cls, n_axes: int, relative: bool, port_out_bytes: int) -> struct.Struct:
        layout = _vib_struct if cls.KIND.vibration else _frame_struct
        return layout(n_axes, relative, port_out_bytes)

    def _head(self) -> tuple[int, int, int, int]:
        raise NotImplementedError

    def _tail_fields(self) -> _Tail:
        """PortOut, then Extend or the pairs (the fields ``KIND.tail`` names)."""
        port, last = self.KIND.tail
        return (getattr(self, port), getattr(self, last))

    def _tail(self) -> Iterable[int]:
        port, last = self._tail_fields()
        if self.KIND.vibration:
            pairs = cast(_Pairs, last)
            return chain((port,), (v for pair in pairs for v in pair))
        return (port, cast(int, last))

    @classmethod
    def _parse_tail(cls, rest: tuple[int, ...]) -> _Tail:
        """:meth:`_tail_fields` from the layout's values after the positions."""
        return (rest[0], _pairs(rest[1:])) if cls.KIND.vibration else (rest[0], rest[1])

    @classmethod
    def _from_tail(cls, h: Header, relative: bool, f: tuple[int, ...], n: int, width: int) -> Self:
        raise NotImplementedError

    @classmethod
    def _axes_and_width(cls, h: Header, size: int, port_out_bytes: int | None) -> tuple[int, int]:
        """Axis count and PortOut width of a ``size``-byte message with header ``h``."""
        raise NotImplementedError

    def _pair_count(self) -> int | None:
        """Vibration pairs the message carries (None: a plain frame)."""
        return len(cast(_Pairs, self._tail_fields()[1])) if self.KIND.vibration else None

    def __post_init__(self) -> None:
        n = len(self.positions)
        channel_of_axes(n)
        check_port_out_bytes(self.port_out_bytes)
        pairs = self._pair_count()
        if pairs is not None and pairs != n:
            raise ProtocolError(f"{pairs} vibration pairs for {n} axes")
        self.encode()

    @property
    def size(self) -> int:
        return type(self)._STRUCT(len(self.positions), False, self.port_out_bytes).size

    def encode(self) -> bytes:
        layout = type(self)._STRUCT(len(self.positions), not self.absolute, self.port_out_bytes)
        return pack_timed_frame(
            layout,
            self._head(),
            self.frame,
            self.time_ms,
            self.positions,
            self._tail(),
            f"IMAX {self.KIND.what}",
        )

    @classmethod
    def decode_parts(cls, h: Header, data: bytes, port_out_bytes: int | None = None) -> Self:
        """The message in ``data`` (PortOut ``port_out_bytes`` wide; ``None``: either)."""
        relative = (h.function & 0xFFF0) == (cls.KIND.bases[1] & 0xFFF0)
        n, width = cls._axes_and_width(h, len(data), port_out_bytes)
        return cls._from_tail(h, relative, cls._STRUCT(n, relative, width).unpack(data), n, width)


class _TimedRequest(_TimedFrame):
    """Host -> IMAX frame: function from the time mode, channel from the axis count,
    axis count from the channel."""

    __slots__ = ()

    who_accept: int
    who_reply: int

    @property
    def function(self) -> int:
        return self.KIND.bases[0] if self.absolute else self.KIND.bases[1]

    @property
    def n_axes(self) -> int:
        return len(self.positions)

    def _head(self) -> tuple[int, int, int, int]:
        n = channel_of_axes(len(self.positions))
        return self.function, n, self.who_accept, self.who_reply

    @classmethod
    def _from_tail(cls, h: Header, relative: bool, f: tuple[int, ...], n: int, width: int) -> Self:
        return cls(
            not relative, f[6], f[7], f[8 : 8 + n], *cls._parse_tail(f[8 + n :]),
            h.who_accept, h.who_reply, width,
        )  # fmt: skip

    @classmethod
    def _axes_and_width(cls, h: Header, size: int, port_out_bytes: int | None) -> tuple[int, int]:
        n = axes_of_channel(h.channel)
        sizes = {w: cls._STRUCT(n, False, w).size for w in PORT_OUT_BYTES}
        what = f"{n}-axis {cls.KIND.what} 0x{h.function:04X}"
        return n, _width_of(size, sizes, port_out_bytes, what)


@dataclass(frozen=True, slots=True)
class _RequestHead(_TimedRequest):
    """The fields every frame request starts with; a request adds its tail, Who fields
    and ``port_out_bytes``."""

    absolute: bool
    frame: int
    time_ms: int
    positions: tuple[int, ...]


class _TimedReply(_TimedFrame):
    """IMAX -> host frame reply: status in the function's last digit, the channel field
    kept (axis channel, or the error code), Who 0, axis count from the length."""

    __slots__ = ()

    status: ReplyStatus
    channel: int

    @property
    def function(self) -> int:
        bases = self.KIND.bases
        return (bases[0] if self.absolute else bases[1]) - 1 + int(self.status)

    def _head(self) -> tuple[int, int, int, int]:
        return self.function, self.channel, WHO_NONE, WHO_NONE

    @classmethod
    def _from_tail(cls, h: Header, relative: bool, f: tuple[int, ...], n: int, width: int) -> Self:
        return cls(
            ReplyStatus(h.function & 0xF), not relative, h.channel, f[6], f[7], f[8 : 8 + n],
            *cls._parse_tail(f[8 + n :]), width,
        )  # fmt: skip

    @classmethod
    def _axes_and_width(cls, h: Header, size: int, port_out_bytes: int | None) -> tuple[int, int]:
        fixed = cls._STRUCT(0, False, 2).size - 2
        per_axis = cls._STRUCT(1, False, 2).size - cls._STRUCT(0, False, 2).size
        what = f"{cls.KIND.what} 0x{h.function:04X}"
        return _reply_axes(size, fixed, per_axis, port_out_bytes, what)


@dataclass(frozen=True, slots=True)
class _ReplyHead(_TimedReply):
    """The fields every frame reply starts with; a reply adds its tail and
    ``port_out_bytes``."""

    status: ReplyStatus
    absolute: bool
    channel: int
    frame: int
    time_ms: int
    positions: tuple[int, ...]


def _pairs(flat: Sequence[int]) -> tuple[tuple[int, int], ...]:
    return tuple(zip(flat[0::2], flat[1::2], strict=True))


_FRAME = (False, (F_ABS, F_REL))
_VIB_FRAME = (True, (F_VIB_ABS, F_VIB_REL))


@dataclass(frozen=True, slots=True)
class MotionFrame(_RequestHead):
    """Host -> IMAX timed frame, 0x1301 (absolute ms since the first frame, u32) or 0x1401
    (ms since the previous frame, i32) (2.2.2.5, 2.2.2.7).

    ``positions``: 2..12 absolute motor positions, int32 pulses (0 = mechanical zero + lift
    PA40/PA41). ``port_out``: Y01..Y12 effect outputs (ignored when PA9d = 1).
    ``extend``: reserved u32. ``port_out_bytes``: PortOut's width on the wire, 2 or 4 (the
    manual prints both; module notes).
    """

    KIND = _FrameKind(*_FRAME, "frame", ("port_out", "extend"))

    port_out: int = 0
    extend: int = 0
    who_accept: int = WHO_ALL
    who_reply: int = WHO_ALL
    port_out_bytes: int = 2


@dataclass(frozen=True, slots=True)
class MotionFrameReply(_ReplyHead):
    """IMAX -> host 0x130x / 0x140x: the frame echoed, ``port`` = input states,
    ``channel`` = axis channel (x = 2) or error code (x != 2) (2.2.2.6, 2.2.2.8)."""

    KIND = _FrameKind(*_FRAME, "frame reply", ("port", "extend"))

    port: int = 0
    extend: int = 0
    port_out_bytes: int = 2


@dataclass(frozen=True, slots=True)
class VibrationFrame(_RequestHead):
    """Host -> IMAX 0x1801 (absolute time) / 0x1901 (relative time) frame with per-axis
    vibration: ``vibration[i] = (period in 0.125 ms, amplitude in pulses)`` (2.2.2.9,
    2.2.2.11)."""

    KIND = _FrameKind(*_VIB_FRAME, "vibration frame", ("port_out", "vibration"))

    port_out: int
    vibration: tuple[tuple[int, int], ...]
    who_accept: int = WHO_ALL
    who_reply: int = WHO_ALL
    port_out_bytes: int = 2


@dataclass(frozen=True, slots=True)
class VibrationFrameReply(_ReplyHead):
    """IMAX -> host 0x180x / 0x190x: the vibration frame echoed (``port`` = inputs)."""

    KIND = _FrameKind(*_VIB_FRAME, "vibration reply", ("port", "vibration"))

    port: int
    vibration: tuple[tuple[int, int], ...]
    port_out_bytes: int = 2


# -- status report ----------------------------------------------------------------------------
STATUS_HEAD = struct.Struct(">3HHH")  # confirm, pass, function, control id, servo count


@cache
def _status_struct(n: int) -> struct.Struct:
    return struct.Struct(f">3HHH{n}i{n}h{n}H3H")


@dataclass(frozen=True, slots=True)
class StatusReport:
    """IMAX -> host 0x3101 (ConfirmCode 0x33CC), sent per PA1e / PA1f (2.2.2.15, 5.11).

    Attributes
    ----------
    control_id : int
        PA12 << 8 | PA13 (the last two bytes of the controller's IP).
    positions : tuple[int, ...]
        Servo positions (pulses, i32), one per servo.
    torques : tuple[int, ...]
        Servo torques (i16).
    alarms : tuple[int, ...]
        Servo alarm codes (u16).
    control_alarm, outputs, inputs : int
        Controller alarm code (the display's Err number), Y outputs, X inputs.
    """

    control_id: int
    positions: tuple[int, ...]
    torques: tuple[int, ...]
    alarms: tuple[int, ...]
    control_alarm: int = 0
    outputs: int = 0
    inputs: int = 0

    def __post_init__(self) -> None:
        n = len(self.positions)
        if not 0 <= n <= MAX_AXES or len(self.torques) != n or len(self.alarms) != n:
            raise ProtocolError(
                "status report: one position, torque and alarm per servo (at most 12)"
            )
        self.encode()

    @property
    def size(self) -> int:
        return _status_struct(len(self.positions)).size

    def encode(self) -> bytes:
        n = len(self.positions)
        try:
            return _status_struct(n).pack(
                CONFIRM_SERVO,
                PASSCODE,
                F_STATUS,
                self.control_id,
                n,
                *self.positions,
                *self.torques,
                *self.alarms,
                self.control_alarm,
                self.outputs,
                self.inputs,
            )
        except struct.error as exc:
            raise ProtocolError(f"status report field out of range: {exc}") from None

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> StatusReport:
        if len(data) < STATUS_HEAD.size:
            raise ProtocolError(f"status report: length {len(data)} bytes, at least 10 needed")
        n = STATUS_HEAD.unpack_from(data)[4]
        if n > MAX_AXES:
            raise ProtocolError(f"status report: {n} servos, at most 12")
        layout = _status_struct(n)
        check_length(data, layout.size, f"status report of {n} servos")
        f = layout.unpack(data)
        return cls(
            f[3], f[5 : 5 + n], f[5 + n : 5 + 2 * n], f[5 + 2 * n : 5 + 3 * n], *f[5 + 3 * n :]
        )


ImaxMessage = (
    RegisterRead
    | RegisterWrite
    | RegisterReply
    | ServoRead
    | ServoWrite
    | ServoReply
    | MotionFrame
    | MotionFrameReply
    | VibrationFrame
    | VibrationFrameReply
    | StatusReport
)

_DECODERS: dict[tuple[int, int], Callable[..., ImaxMessage]] = {
    (CONFIRM_MAIN, F_READ): RegisterRead.decode_parts,
    (CONFIRM_MAIN, F_WRITE): RegisterWrite.decode_parts,
    (CONFIRM_MAIN, F_ABS): MotionFrame.decode_parts,
    (CONFIRM_MAIN, F_REL): MotionFrame.decode_parts,
    (CONFIRM_MAIN, F_VIB_ABS): VibrationFrame.decode_parts,
    (CONFIRM_MAIN, F_VIB_REL): VibrationFrame.decode_parts,
    (CONFIRM_SERVO, F_SERVO_READ): ServoRead.decode_parts,
    (CONFIRM_SERVO, F_SERVO_WRITE): ServoWrite.decode_parts,
    (CONFIRM_SERVO, F_STATUS): StatusReport.decode_parts,
}
for _x in ReplyStatus:
    _DECODERS[(CONFIRM_MAIN, F_READ - 1 + _x)] = RegisterReply.decode_parts
    _DECODERS[(CONFIRM_MAIN, F_WRITE - 1 + _x)] = RegisterReply.decode_parts
    _DECODERS[(CONFIRM_MAIN, F_ABS - 1 + _x)] = MotionFrameReply.decode_parts
    _DECODERS[(CONFIRM_MAIN, F_REL - 1 + _x)] = MotionFrameReply.decode_parts
    _DECODERS[(CONFIRM_MAIN, F_VIB_ABS - 1 + _x)] = VibrationFrameReply.decode_parts
    _DECODERS[(CONFIRM_MAIN, F_VIB_REL - 1 + _x)] = VibrationFrameReply.decode_parts
    _DECODERS[(CONFIRM_SERVO, F_SERVO_READ - 1 + _x)] = ServoReply.decode_parts
    _DECODERS[(CONFIRM_SERVO, F_SERVO_WRITE - 1 + _x)] = ServoReply.decode_parts


def decode(data: bytes, port_out_bytes: int | None = None) -> ImaxMessage:
    """Decode one IMAX datagram (either direction) into its typed message.

    ``port_out_bytes``: PortOut's width in frames and frame replies, 2 or 4 (the
    controller's ``port_out_bytes``); ``None`` accepts either, telling them apart by the
    length (module notes). Other messages have no PortOut.

    Raises
    ------
    ProtocolError
        Short datagram, confirm code not 0x55AA / 0x33CC (or the wrong one for the
        function), pass code not 0, unknown function, wrong channel, length or padding,
        a frame of the other PortOut width than ``port_out_bytes``.
    """
    if port_out_bytes is not None:
        check_port_out_bytes(port_out_bytes)
    if len(data) >= 6 and data[:2] == b"\x33\xcc" and data[4:6] == b"\x31\x01":
        passcode, function = struct.unpack_from(">HH", data, 2)
        h = Header(CONFIRM_SERVO, passcode, function, 0, 0, 0)
        if h.passcode != PASSCODE:
            raise ProtocolError(f"pass code 0x{h.passcode:04X}, expected 0x0000")
    else:
        h = decode_header(data)
    decoder = _DECODERS.get((h.confirm, h.function))
    if decoder is None:
        raise ProtocolError(
            f"unknown IMAX function code 0x{h.function:04X} with confirm code 0x{h.confirm:04X}"
        )
    try:
        if h.confirm == CONFIRM_MAIN and h.function in _FRAME_FUNCTIONS:
            return decoder(h, data, port_out_bytes)
        return decoder(h, data)
    except (struct.error, ValueError) as exc:
        if isinstance(exc, ProtocolError):
            raise
        raise ProtocolError(f"function 0x{h.function:04X}: {exc}") from None
