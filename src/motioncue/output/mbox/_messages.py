"""SC-MBOX UDP messages (SC-MBOX manual chapter 4), each declared once.

Every message is a frozen dataclass with its ``struct.Struct`` layout beside it; ``encode``,
``decode`` and ``size`` are derived from that layout. :func:`decode` reads any datagram a
host or an MBOX sends and returns the typed message, or raises
:class:`~motioncue.ProtocolError` naming what is wrong (confirm code, length, channel,
unknown function).

Decisions where the manual is ambiguous (see docs in the package ``__init__``):

* 6-axis frames use channel 1 (4.2.7's sentence says 0, its table and 4.2.9 say 1).
* A read request carries ``count`` zero words of "Extra Data" (the manual prints zero
  padding of unstated length); any even number of zero bytes is accepted when decoding.
* Error replies 0x1103/0x1203 carry StartAddress, Count and one u16 error code (4.2.4-4.2.5).
* Frame replies (0x1302/3/4, 0x1402/3/4) repeat the frame layout (the manual prints it).
"""

from __future__ import annotations

import enum
import struct
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache
from typing import ClassVar

from ..._errors import ProtocolError
from ..._frozen import set_fields
from .._udp_common import (
    AXES_OF_CHANNEL,
    CHANNEL_OF_AXES,
    CONFIRM_MAIN,
    F_ABS,
    F_REL,
    HEADER,
    PASSCODE,
    WHO_ALL,
    WHO_NONE,
    Header,
    check_length,
    decode_header,
    pack_timed_frame,
    timed_frame_struct,
)
from .._udp_registers import (
    RegisterReadShape,
    RegisterValuesShape,
    RegisterWriteShape,
    check_u16_fields,
)

__all__ = [  # what the package exports from here
    "CHANNEL_CX",
    "CHANNEL_DX",
    "CHANNEL_FX",
    "CHANNEL_FXM",
    "FrameStatus",
    "MotionFrame",
    "MotionFrameReply",
    "RegisterError",
    "RegisterRead",
    "RegisterReadReply",
    "RegisterWrite",
    "RegisterWriteReply",
    "StatusReport",
    "decode",
    "frame_size",
]

# Function codes (4.2.2-4.2.9).
F_STATUS = 0x1001
F_READ, F_READ_OK, F_READ_ERR = 0x1101, 0x1102, 0x1103
F_WRITE, F_WRITE_OK, F_WRITE_ERR = 0x1201, 0x1202, 0x1203

# Object channels.
CHANNEL_DX = 0  # read: status registers Dn
CHANNEL_FX = 1  # read/write: parameters Fn (write: saved)
CHANNEL_FXM = 0  # write: parameters Fn, not saved
CHANNEL_CX = 2  # write: control registers Cn

FUNCTION_NAMES = {
    F_STATUS: "status report",
    F_READ: "read registers",
    F_READ_OK: "read reply",
    F_READ_ERR: "read error",
    F_WRITE: "write registers",
    F_WRITE_OK: "write reply",
    F_WRITE_ERR: "write error",
    F_ABS: "frame abs-time",
    F_ABS + 1: "frame reply",
    F_ABS + 2: "frame reply buffer-full",
    F_ABS + 3: "frame reply short-frame",
    F_REL: "frame rel-time",
    F_REL + 1: "frame reply",
    F_REL + 2: "frame reply buffer-full",
    F_REL + 3: "frame reply short-frame",
}

_HEAD4 = struct.Struct(">4H")


@dataclass(frozen=True, slots=True)
class RegisterRead(RegisterReadShape):
    """Host -> MBOX 0x1101: read ``count`` registers of ``channel`` (0 DX, 1 FX) from ``start``.

    Layout: header, StartAddress u16, Count u16, ``count`` zero words (Extra Data).
    """

    FUNCTION: ClassVar[int] = F_READ
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_DX, CHANNEL_FX)


@dataclass(frozen=True, slots=True)
class RegisterReadReply(RegisterValuesShape):
    """MBOX -> host 0x1102: the values read (channel 0 DX, 1 FX)."""

    FUNCTION: ClassVar[int] = F_READ_OK
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_DX, CHANNEL_FX)


@dataclass(frozen=True, slots=True)
class RegisterWrite(RegisterWriteShape):
    """Host -> MBOX 0x1201: write ``values`` to channel 0 FXm (not saved), 1 FX, 2 CX."""

    FUNCTION: ClassVar[int] = F_WRITE
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_FXM, CHANNEL_FX, CHANNEL_CX)


@dataclass(frozen=True, slots=True)
class RegisterWriteReply(RegisterValuesShape):
    """MBOX -> host 0x1202: the write was done; echoes the values written."""

    FUNCTION: ClassVar[int] = F_WRITE_OK
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_FXM, CHANNEL_FX, CHANNEL_CX)


@dataclass(frozen=True, slots=True)
class StatusReport(RegisterValuesShape):
    """MBOX -> host 0x1001 (4.2.3): DX registers from Fn042, Fn043 of them, sent when
    Fn040 asks for reports. Channel 0 (DX)."""

    FUNCTION: ClassVar[int] = F_STATUS
    CHANNELS: ClassVar[Sequence[int]] = (CHANNEL_DX,)


@dataclass(frozen=True, slots=True)
class RegisterError:
    """MBOX -> host 0x1103 (read) or 0x1203 (write) error reply.

    Layout: header, StartAddress u16, Count u16, ErrorCode u16.
    """

    LAYOUT: ClassVar[struct.Struct] = struct.Struct(">HHH")

    function: int
    channel: int
    start: int
    count: int
    error_code: int
    who_accept: int = WHO_NONE
    who_reply: int = WHO_NONE

    def __post_init__(self) -> None:
        if self.function not in (F_READ_ERR, F_WRITE_ERR):
            raise ProtocolError(f"error reply function 0x{self.function:04X}: 0x1103 or 0x1203")
        check_u16_fields(self, "channel", "start", "count", "error_code", "who_accept", "who_reply")

    size: ClassVar[int] = HEADER.size + 6

    def encode(self) -> bytes:
        return HEADER.pack(
            CONFIRM_MAIN, PASSCODE, self.function, self.channel, self.who_accept, self.who_reply
        ) + self.LAYOUT.pack(self.start, self.count, self.error_code)

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> RegisterError:
        check_length(data, cls.size, f"error reply 0x{h.function:04X}")
        start, count, code = cls.LAYOUT.unpack_from(data, HEADER.size)
        return cls(h.function, h.channel, start, count, code, h.who_accept, h.who_reply)


class FrameStatus(enum.IntEnum):
    """Last hex digit of a frame reply's function code (4.2.6-4.2.9)."""

    OK = 2
    BUFFER_FULL = 3
    SHORT_FRAME = 4


@cache
def _frame_struct(n_axes: int, relative: bool) -> struct.Struct:
    # header, Line u32, Time u32 (abs) / i32 (delta), n x i32 positions,
    # BaseDout u16, DAC1 u16, DAC2 u16, ExtDout u16
    return timed_frame_struct(n_axes, relative, "4H")


def frame_size(n_axes: int) -> int:
    """Bytes of a frame datagram: 40 for 3 axes, 52 for 6 axes."""
    return _frame_struct(n_axes, False).size


@dataclass(frozen=True, slots=True)
class MotionFrame:
    """Host -> MBOX timed frame, 0x1301 (absolute time) or 0x1401 (relative time).

    Attributes
    ----------
    absolute : bool
        ``True`` for 0x1301 (ms since the run's first frame, u32), ``False`` for 0x1401
        (ms since the previous frame, i32: 0 = jog over Fn013, < 0 = rewind over Fn014).
    line : int
        Frame number (u32).
    time_ms : int
        Time field.
    positions : tuple[int, ...]
        3 (channel 0) or 6 (channel 1) motor positions in encoder pulses, int32, X Y Z (U V W);
        0 is the homed origin.
    base_dout : int
        12 digital outputs (used when Fn010 = 1).
    dac1, dac2 : int
        Analogue outputs, 0 .. Fn078/Fn079 full scale (u16).
    ext_dout : int
        12 extended digital outputs.
    """

    absolute: bool
    line: int
    time_ms: int
    positions: tuple[int, ...]
    base_dout: int = 0
    dac1: int = 0
    dac2: int = 0
    ext_dout: int = 0
    who_accept: int = WHO_ALL
    who_reply: int = WHO_ALL

    FUNCTIONS: ClassVar[tuple[int, int]] = (F_ABS, F_REL)

    def __post_init__(self) -> None:
        if len(self.positions) not in CHANNEL_OF_AXES:
            raise ProtocolError(f"an MBOX frame has 3 or 6 positions, not {len(self.positions)}")
        try:
            self.encode()
        except ProtocolError as exc:
            raise ProtocolError(f"MotionFrame: {exc}") from None

    @property
    def function(self) -> int:
        return F_ABS if self.absolute else F_REL

    @property
    def n_axes(self) -> int:
        return len(self.positions)

    @property
    def size(self) -> int:
        return frame_size(len(self.positions))

    def encode(self) -> bytes:
        n = len(self.positions)
        return pack_timed_frame(
            _frame_struct(n, not self.absolute),
            (self.function, CHANNEL_OF_AXES[n], self.who_accept, self.who_reply),
            self.line,
            self.time_ms,
            self.positions,
            (self.base_dout, self.dac1, self.dac2, self.ext_dout),
            "frame",
        )

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> MotionFrame:
        return cls._from_wire(data, h.function, h.channel)

    @classmethod
    def _from_wire(cls, data: bytes, function: int, channel: int) -> MotionFrame:
        n = AXES_OF_CHANNEL.get(channel)
        if n is None:
            raise ProtocolError(f"frame channel {channel}: allowed 0 (3 axes), 1 (6 axes)")
        relative = function == F_REL
        layout = _frame_struct(n, relative)
        if len(data) != layout.size:
            check_length(data, layout.size, f"{n}-axis frame 0x{function:04X}")
        f = layout.unpack(data)
        # every field came out of the layout, so it is in range: skip the re-validation
        obj = object.__new__(cls)
        # per-frame decode (emulator, inspect): object.__setattr__ bound once is ~3 us a
        # frame faster than set_fields' keyword packing
        setattr_ = object.__setattr__
        setattr_(obj, "absolute", not relative)
        setattr_(obj, "line", f[6])
        setattr_(obj, "time_ms", f[7])
        setattr_(obj, "positions", f[8 : 8 + n])
        setattr_(obj, "base_dout", f[8 + n])
        setattr_(obj, "dac1", f[9 + n])
        setattr_(obj, "dac2", f[10 + n])
        setattr_(obj, "ext_dout", f[11 + n])
        setattr_(obj, "who_accept", f[4])
        setattr_(obj, "who_reply", f[5])
        return obj


@dataclass(frozen=True, slots=True)
class MotionFrameReply:
    """MBOX -> host frame reply: 0x1302/0x1402 accepted, 0x1303/0x1403 internal buffer
    full, 0x1304/0x1404 frame shorter than required. Same layout as the frame."""

    status: FrameStatus
    frame: MotionFrame

    @property
    def function(self) -> int:
        return self.frame.function + int(self.status) - 1

    @property
    def size(self) -> int:
        return self.frame.size

    def encode(self) -> bytes:
        raw = bytearray(self.frame.encode())
        struct.pack_into(">H", raw, 4, self.function)
        struct.pack_into(">HH", raw, 8, WHO_NONE, WHO_NONE)
        return bytes(raw)

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> MotionFrameReply:
        status = FrameStatus(h.function & 0xF)
        frame = MotionFrame._from_wire(data, (h.function & 0xFFF0) | 1, h.channel)
        # replies address the host (Who = 0); other values are accepted and not kept
        set_fields(frame, who_accept=WHO_NONE, who_reply=WHO_NONE)
        return cls(status, frame)


MboxMessage = (
    RegisterRead
    | RegisterReadReply
    | RegisterWrite
    | RegisterWriteReply
    | RegisterError
    | StatusReport
    | MotionFrame
    | MotionFrameReply
)

_DECODERS: dict[int, Callable[[Header, bytes], MboxMessage]] = {
    F_STATUS: StatusReport.decode_parts,
    F_READ: RegisterRead.decode_parts,
    F_READ_OK: RegisterReadReply.decode_parts,
    F_READ_ERR: RegisterError.decode_parts,
    F_WRITE: RegisterWrite.decode_parts,
    F_WRITE_OK: RegisterWriteReply.decode_parts,
    F_WRITE_ERR: RegisterError.decode_parts,
    F_ABS: MotionFrame.decode_parts,
    F_REL: MotionFrame.decode_parts,
}
for _base in (F_ABS, F_REL):
    for _s in FrameStatus:
        _DECODERS[_base + int(_s) - 1] = MotionFrameReply.decode_parts


def decode(data: bytes) -> MboxMessage:
    """Decode one MBOX datagram (either direction) into its typed message.

    Raises
    ------
    ProtocolError
        Short header, confirm code not 0x55AA, pass code not 0, unknown function, wrong
        channel or length, non-zero padding.
    """
    if len(data) >= HEADER.size:  # fast path for frames, the bulk of the traffic
        confirm, passcode, function, channel = _HEAD4.unpack_from(data)
        if (function == F_ABS or function == F_REL) and confirm == CONFIRM_MAIN and not passcode:
            return MotionFrame._from_wire(data, function, channel)
    h = decode_header(data)
    if h.confirm != CONFIRM_MAIN:
        raise ProtocolError(f"confirm code 0x{h.confirm:04X}: the MBOX uses 0x55AA")
    decoder = _DECODERS.get(h.function)
    if decoder is None:
        raise ProtocolError(f"unknown MBOX function code 0x{h.function:04X}")
    try:
        return decoder(h, data)
    except (struct.error, ValueError) as exc:
        if isinstance(exc, ProtocolError):
            raise
        raise ProtocolError(f"function 0x{h.function:04X}: {exc}") from None
