"""EasySmc 2300 command set: one table, two framings (serial ASCII and USB 16-byte).

Manual: ``/work/shared/seeds/002_bc662b73892c38ba.txt`` (chapters 5, 6, 7, 8).

Payload
    A command is ``(addr, code, words, start)``. A *word* is the manual's 7-digit data field
    ("DAT"), an integer in ``[0, 0x0FFFFFFF]``: on the serial link 7 upper-case ASCII hex digits,
    on USB 4 bytes (first digit as one byte, then the other 6 digits as 3 bytes; manual 6.2.4.1
    and 7.1.8.6: ``6000001`` -> ``06 00 00 01``). Moves and positions are sign-magnitude words:
    first digit 0 = positive, 1 = negative, then 6 hex digits of magnitude (<= 16 777 215).

Framing
    Serial (manual ch. 5): ``STX addr(2) cmd(2) data(7 x n) start(1) ETX checksum(2)``; the
    checksum is the low byte of the sum of every byte from ``addr`` through ``ETX``, as two
    upper-case hex digits (5.1.1.1: ``00 01 00007D0 0`` -> 0x25F -> ``5F``).
    USB (manual 6.2.4): 16-byte write ``01 addr cmd DAT1 DAT2 DAT3 start``; 20-byte write
    reply; reads are DLL calls ``recdata(cmd, rdat1, rdat2)`` answered by a 16-byte reply.

Decisions where the manual contradicts itself are listed in ``MANUAL_DECISIONS``.
"""

from __future__ import annotations

import enum
import struct
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Any

from ..._errors import ProtocolError
from ..._frozen import set_fields

__all__ = [
    "COMMANDS",
    "ETX",
    "MANUAL_DECISIONS",
    "MAX_MAGNITUDE",
    "MAX_WORD",
    "STX",
    "USB_READ_REPLY_SIZE",
    "USB_WRITE_REPLY_SIZE",
    "USB_WRITE_SIZE",
    "Command",
    "CommandSpec",
    "ErrorCode",
    "ErrorReply",
    "ExecStatus",
    "ReadReply",
    "Start",
    "UsbReadReply",
    "UsbReadRequest",
    "UsbWriteReply",
    "WordKind",
    "WriteReply",
    "checksum",
    "decode_command",
    "decode_reply",
    "decode_usb_read_reply",
    "decode_usb_write",
    "decode_usb_write_reply",
    "encode_command",
    "encode_reply",
    "encode_usb_read_reply",
    "encode_usb_write",
    "encode_usb_write_reply",
    "serial_frame_size",
    "signed_from_word",
    "split_serial_frames",
    "word_from_signed",
]

STX = 0x02
ETX = 0x03
MAX_WORD = 0x0FFFFFFF  # 7 hex digits
MAX_MAGNITUDE = 0xFFFFFF  # 6 hex digits of a sign-magnitude word (manual 5.5.1)
_HEX = b"0123456789ABCDEF"
_HEX_VALUE = {c: i for i, c in enumerate(_HEX)}


class Start(enum.IntEnum):
    """Start condition ("启动条件", manual ch. 5): how a buffered command is executed."""

    IMMEDIATE = 0  # 30H/31H: at once, interlock ignored
    IMMEDIATE_ALT = 1
    IMMEDIATE_LEVEL = 2  # at once, external interlock level-triggered
    IMMEDIATE_PULSE = 3
    SEQUENCE = 4  # 34H/35H: in sequence, interlock ignored (used for frames)
    SEQUENCE_ALT = 5
    SEQUENCE_LEVEL = 6
    SEQUENCE_PULSE = 7
    OUT_OF_BAND = 8  # 38H: brake / clear buffer / loop test, not buffered


class ErrorCode(enum.IntEnum):
    """Error codes of a command-99 reply (manual ch. 5 and 6.2.4.2)."""

    NO_SUCH_COMMAND = 1
    MANUAL_MODE = 2
    BUFFER_FULL = 3
    CHECKSUM = 4


class WordKind(enum.Enum):
    """How a data word is read."""

    UNSIGNED = "unsigned"  # a plain 7-digit number (Hz, Hz/s, ms, register values)
    SIGNED = "signed"  # sign digit 0/1 + 6-digit magnitude (moves, positions, limits)
    CODE = "code"  # a sub-command word validated by the command (19, 18, 41...)
    ANGLE = "angle"  # arc angle: direction digit 0 = ccw / 1 = cw + 6 digits of 0.01 deg


@dataclass(frozen=True)
class CommandSpec:
    """One row of the command table.

    Attributes
    ----------
    code : int
        Command code (the two hex digits after the address).
    name : str
        Identifier used in messages and by the CLI.
    words : tuple of (name, WordKind)
        Meaning of DAT1..DATn; the number of words is fixed per command.
    kind : str
        ``"write"`` (buffered or out-of-band, write reply) or ``"query"`` (read reply, never
        buffered).
    section : str
        Manual section.
    """

    code: int
    name: str
    words: tuple[tuple[str, WordKind], ...]
    kind: str
    section: str

    @property
    def n_words(self) -> int:
        return len(self.words)


def _table() -> dict[int, CommandSpec]:
    """The command table, declared as data in ``commands.toml`` beside this module."""
    text = resources.files(__package__).joinpath("commands.toml").read_text(encoding="utf-8")
    data = tomllib.loads(text)
    layouts: dict[str, list[str]] = data["words"]

    def words(row: dict[str, Any]) -> tuple[tuple[str, WordKind], ...]:
        named = row["words"]
        listed = layouts[named] if isinstance(named, str) else named
        return tuple((name, WordKind(kind)) for name, kind in map(str.split, listed))

    rows = (
        CommandSpec(row["code"], name, words(row), row.get("kind", "write"), row["section"])
        for name, row in data["commands"].items()
    )
    return {r.code: r for r in rows}


COMMANDS: Mapping[int, CommandSpec] = _table()
"""The command table: code -> :class:`CommandSpec` (manual chapter 5)."""

_BY_NAME = {spec.name: spec for spec in COMMANDS.values()}

# Sub-command words -----------------------------------------------------------------------

_BRAKE_CODES = {
    0x00: "emergency brake all axes",
    0x01: "release emergency brake all axes",
    0x02: "emergency brake X",
    0x03: "release emergency brake X",
    0x04: "emergency brake Y",
    0x05: "release emergency brake Y",
    0x06: "emergency brake Z",
    0x07: "release emergency brake Z",
    0x12: "emergency brake U",
    0x13: "release emergency brake U",
    0x08: "smooth brake all axes",
    0x09: "smooth brake X",
    0x0A: "smooth brake Y",
    0x0B: "smooth brake Z",
    0x19: "smooth brake U",
    0x0C: "release smooth brake all axes",
    0x0D: "release smooth brake X",
    0x0E: "release smooth brake Y",
    0x0F: "release smooth brake Z",
    0x1D: "release smooth brake U",
}


def describe_control(word: int) -> str:
    """Meaning of a command-19 word; raises ProtocolError when the manual has none."""
    lead, rest = word >> 24, word & 0xFFFFFF
    if lead == 0x1:
        return f"wait {rest} ms"
    if lead == 0x3 and rest in (0, 1, 2):
        return ("reset command numbering", "standard mode", "small-segment mode")[rest]
    if lead == 0x4 and rest == 0:
        return "clear command buffer"
    if lead == 0x5 and rest == 0:
        return "loop test"
    if lead in (0x6, 0x7, 0x8) and (1 <= rest <= 0x18 or (lead == 6 and 0x21 <= rest <= 0x38)):
        signal = {6: "FREE" if rest <= 0x18 else "ECLR", 7: "CP", 8: "DIR"}[lead]
        return f"{signal} as I/O, item {rest:#x}"
    if lead == 0x9 and (rest >> 16) in (1, 2) and (rest & 0xFFFF) <= 0xFFFF:
        return f"set counter {rest >> 16} = {rest & 0xFFFF}"
    if lead == 0xA and (rest >> 16) in (1, 2) and (rest & 0xFFFF) in (0, 1):
        return f"counter {rest >> 16} {'+1' if (rest & 0xFFFF) == 0 else '-1'}"
    if lead == 0xB and (rest <= 8 or rest == 0xFF):
        return "download control"
    if lead in (0xC, 0xD) and rest <= 0xF:
        return f"output {_OUTPUT_NAMES[rest]} {'low' if lead == 0xC else 'high'}"
    if lead == 0xE:
        return "spline synchronous output"
    raise ProtocolError(f"command 19: word {word:07X} has no meaning in the manual (5.1.8)")


_OUTPUT_NAMES = tuple(f"{a}0-{i}" for a in "XYZU" for i in range(1, 5))


def _check_code_word(spec: CommandSpec, word: int) -> None:
    code = spec.code
    if code == 0x19:
        describe_control(word)
    elif code == 0x18:
        if word not in _BRAKE_CODES:
            raise ProtocolError(f"command 18: brake code {word:07X} unknown (manual 5.1.7)")
    elif code == 0x17:
        if word not in (1, 2):
            raise ProtocolError(f"command 17: word {word:07X} must be 0000001 or 0000002")
    elif code == 0x16:
        if not 1 <= (word >> 24) <= 9:
            raise ProtocolError(f"command 16: selector digit {word >> 24:X} not in 1..9 (5.1.5)")
    elif code in (0x2A, 0x2B, 0x2C, 0x2D):
        if word != 0:
            raise ProtocolError(f"command {code:02X}: word must be 0000000, got {word:07X}")
    elif code in (0x41, 0x42, 0x43, 0x47):
        if not 1 <= word <= 7:
            raise ProtocolError(f"command {code:02X}: homing mode {word:07X} not in 1..7 (5.4)")
    # query items (31..38) are validated by the responder: an unknown item is answered there.


def _check_word(spec: CommandSpec, index: int, word: int) -> None:
    name, kind = spec.words[index]
    if not 0 <= word <= MAX_WORD:
        raise ProtocolError(f"command {spec.code:02X} {name}: word {word} outside 0..0xFFFFFFF")
    if kind in (WordKind.SIGNED, WordKind.ANGLE) and (word >> 24) > 1:
        raise ProtocolError(
            f"command {spec.code:02X} {name}: first digit {word >> 24:X} must be 0 or 1 "
            "(sign / direction)"
        )
    if kind is WordKind.CODE:
        _check_code_word(spec, word)


def word_from_signed(value: int) -> int:
    """Sign-magnitude word of a signed pulse count (``-1000`` -> ``0x10003E8``)."""
    if not -MAX_MAGNITUDE <= value <= MAX_MAGNITUDE:
        raise ProtocolError(
            f"{value} pulses outside the word's range +-{MAX_MAGNITUDE} (6 hex digits)"
        )
    return (1 << 24) | -value if value < 0 else value


def signed_from_word(word: int) -> int:
    """Signed pulses of a sign-magnitude word; first digit must be 0 or 1."""
    sign = word >> 24
    if sign > 1 or word < 0:
        raise ProtocolError(f"word {word:07X}: sign digit {sign:X} is neither 0 nor 1")
    return -(word & MAX_MAGNITUDE) if sign else word & MAX_MAGNITUDE


# Messages --------------------------------------------------------------------------------


@dataclass(frozen=True)
class Command:
    """A host -> controller command (both links).

    Attributes
    ----------
    code : int
        Command code, a key of :data:`COMMANDS`.
    words : tuple of int
        DAT1..DATn as 7-digit words; n fixed by the command.
    start : Start
        Start condition.
    addr : int
        Controller address 0..3 (DIP switch; USB always 0).
    """

    code: int
    words: tuple[int, ...] = ()
    start: Start = Start.IMMEDIATE
    addr: int = 0

    def __post_init__(self) -> None:
        spec = COMMANDS.get(self.code)
        if spec is None:
            raise ProtocolError(f"unknown command code {self.code:#04x}")
        if not 0 <= self.addr <= 0xFF:
            raise ProtocolError(f"address {self.addr} outside 0..255")
        if len(self.words) != spec.n_words:
            raise ProtocolError(
                f"command {self.code:02X} ({spec.name}) takes {spec.n_words} data words, "
                f"got {len(self.words)}"
            )
        set_fields(self, words=tuple(int(w) for w in self.words))
        try:
            set_fields(self, start=Start(self.start))
        except ValueError as exc:
            raise ProtocolError(f"start condition {self.start!r} not in 0..8") from exc
        for i, w in enumerate(self.words):
            _check_word(spec, i, w)

    @property
    def spec(self) -> CommandSpec:
        return COMMANDS[self.code]

    @classmethod
    def named(
        cls, name: str, *words: int, start: Start = Start.IMMEDIATE, addr: int = 0
    ) -> Command:
        """Build by table name: ``Command.named("xyz_linear", w1, w2, w3, start=4)``."""
        if name not in _BY_NAME:
            raise ProtocolError(f"unknown command name {name!r}")
        return cls(_BY_NAME[name].code, tuple(words), start, addr)

    @classmethod
    def move(
        cls, code: int, pulses: Sequence[int], start: Start = Start.SEQUENCE, addr: int = 0
    ) -> Command:
        """A relative move (44..4A, 51..5C) from signed pulse counts."""
        return cls(code, tuple(word_from_signed(int(p)) for p in pulses), start, addr)

    def fields(self) -> dict[str, int]:
        """Word values by their table names; signed words as signed integers."""
        out: dict[str, int] = {}
        for (name, kind), w in zip(self.spec.words, self.words, strict=True):
            out[name] = signed_from_word(w) if kind is WordKind.SIGNED else w
        return out

    def describe(self) -> str:
        """One line for people (``inspect``)."""
        spec = self.spec
        parts = []
        for (name, kind), w in zip(spec.words, self.words, strict=True):
            if kind is WordKind.SIGNED:
                parts.append(f"{name}={signed_from_word(w)}")
            elif kind is WordKind.ANGLE:
                parts.append(f"{name}={'cw' if w >> 24 else 'ccw'} {(w & MAX_MAGNITUDE) / 100}")
            elif self.code == 0x19:
                parts.append(describe_control(w))
            elif self.code == 0x18:
                parts.append(_BRAKE_CODES[w])
            else:
                parts.append(f"{name}={w}" if kind is WordKind.UNSIGNED else f"{name}={w:07X}")
        return (
            f"addr {self.addr:02X} cmd {self.code:02X} {spec.name} [{', '.join(parts)}] "
            f"start {int(self.start)}"
        )


@dataclass(frozen=True)
class WriteReply:
    """Controller answer to a write command: ``STX addr cmd start ETX checksum``."""

    code: int
    start: int = 0
    addr: int = 0


@dataclass(frozen=True)
class ReadReply:
    """Controller answer to a query: ``STX addr cmd data start ETX checksum`` (1..3 words)."""

    code: int
    words: tuple[int, ...]
    start: int = 0
    addr: int = 0

    def __post_init__(self) -> None:
        if not 1 <= len(self.words) <= 3:
            raise ProtocolError(f"a read reply carries 1..3 words, got {len(self.words)}")
        for w in self.words:
            if not 0 <= w <= MAX_WORD:
                raise ProtocolError(f"read reply word {w} outside 0..0xFFFFFFF")


@dataclass(frozen=True)
class ErrorReply:
    """Command-99 reply carrying an :class:`ErrorCode` in its data word."""

    error: ErrorCode
    start: int = 0
    addr: int = 0


Reply = WriteReply | ReadReply | ErrorReply


@dataclass(frozen=True)
class ExecStatus:
    """Query 38 item 0 (manual 5.3.8.0 / 8.8.0), interpreted.

    Attributes
    ----------
    state : int
        First digit of DAT1: 0 = running normally, 1..6 limit faults, 7 = emergency stop
        (codes of the USB table 8.8.0, which the serial text only calls "brake state").
    executing : int
        Number of the command executing (or last executed), 6 hex digits of DAT1.
    received : int
        Valid commands received (DAT2).
    axis_faults : tuple of int
        X, Y, Z, U fault digits of DAT3 (1 hard high, 2 hard low, 4 soft +, 8 soft -).
    """

    state: int
    executing: int
    received: int
    axis_faults: tuple[int, int, int, int] = (0, 0, 0, 0)

    @classmethod
    def from_reply(cls, reply: ReadReply) -> ExecStatus:
        if reply.code != 0x38 or len(reply.words) != 3:
            raise ProtocolError(f"not a query-38 status reply: {reply}")
        w1, w2, w3 = reply.words
        f = [(w3 >> (4 * (5 - i))) & 0xF for i in range(4)]
        return cls(w1 >> 24, w1 & MAX_MAGNITUDE, w2, (f[0], f[1], f[2], f[3]))

    def words(self) -> tuple[int, int, int]:
        w3 = sum((f & 0xF) << (4 * (5 - i)) for i, f in enumerate(self.axis_faults))
        return ((self.state << 24) | self.executing, self.received, w3)


# Serial framing ---------------------------------------------------------------------------


def checksum(body: bytes) -> bytes:
    """Two upper-case hex digits of the low byte of ``sum(body)`` (body = addr..ETX)."""
    s = sum(body) & 0xFF
    return bytes((_HEX[s >> 4], _HEX[s & 0xF]))


def _hex(value: int, digits: int) -> bytes:
    return f"{value:0{digits}X}".encode("ascii")


def serial_frame_size(n_words: int) -> int:
    """Bytes of a serial frame with ``n_words`` data words: ``9 + 7 n``."""
    return 9 + 7 * n_words


def _frame(addr: int, code: int, words: Sequence[int], start: int) -> bytes:
    if not 0 <= addr <= 0xFF or not 0 <= code <= 0xFF or not 0 <= start <= 9:
        raise ProtocolError(f"cannot frame addr={addr} code={code} start={start}")
    body = _hex(addr, 2) + _hex(code, 2) + b"".join(_hex(w, 7) for w in words)
    body += bytes((0x30 + start, ETX))
    return bytes((STX,)) + body + checksum(body)


def encode_command(cmd: Command) -> bytes:
    """Serial ASCII frame of a command."""
    return _frame(cmd.addr, cmd.code, cmd.words, int(cmd.start))


def encode_reply(reply: Reply) -> bytes:
    """Serial ASCII frame of a controller reply."""
    if isinstance(reply, WriteReply):
        return _frame(reply.addr, reply.code, (), reply.start)
    if isinstance(reply, ReadReply):
        return _frame(reply.addr, reply.code, reply.words, reply.start)
    return _frame(reply.addr, 0x99, (int(reply.error),), reply.start)


def _parse_hex(data: bytes, what: str) -> int:
    value = 0
    for c in data:
        v = _HEX_VALUE.get(c)
        if v is None:
            raise ProtocolError(f"{what}: byte {c:#04x} is not an upper-case hex digit")
        value = value * 16 + v
    return value


@dataclass(frozen=True)
class _RawFrame:
    addr: int
    code: int
    words: tuple[int, ...]
    start: int


def _unframe(frame: bytes) -> _RawFrame:
    n = len(frame)
    if n < 9 or (n - 9) % 7 or n > serial_frame_size(3):
        raise ProtocolError(f"serial frame of {n} bytes; expected 9, 16, 23 or 30 (9 + 7 x words)")
    if frame[0] != STX:
        raise ProtocolError(f"frame starts with {frame[0]:#04x}, expected STX 0x02")
    if frame[-3] != ETX:
        raise ProtocolError(f"byte {n - 3} is {frame[-3]:#04x}, expected ETX 0x03")
    body = frame[1:-2]
    expected = checksum(body)
    if frame[-2:] != expected:
        raise ProtocolError(
            f"checksum {frame[-2:]!r} does not match {expected!r} (sum of addr..ETX)"
        )
    addr = _parse_hex(frame[1:3], "address")
    code = _parse_hex(frame[3:5], "command code")
    words = tuple(
        _parse_hex(frame[5 + 7 * i : 12 + 7 * i], f"DAT{i + 1}") for i in range((n - 9) // 7)
    )
    start_byte = frame[-4]
    if not 0x30 <= start_byte <= 0x39:
        raise ProtocolError(f"start condition byte {start_byte:#04x} is not an ASCII digit")
    return _RawFrame(addr, code, words, start_byte - 0x30)


def decode_command(frame: bytes) -> Command:
    """Decode one serial host -> controller frame; raises ProtocolError on anything wrong."""
    raw = _unframe(bytes(frame))
    if raw.code not in COMMANDS:
        raise ProtocolError(f"unknown command code {raw.code:02X}")
    if raw.start > 8:
        raise ProtocolError(f"start condition {raw.start} not in 0..8")
    return Command(raw.code, raw.words, Start(raw.start), raw.addr)


def decode_reply(frame: bytes) -> Reply:
    """Decode one serial controller -> host frame (write, read or error-99 reply)."""
    raw = _unframe(bytes(frame))
    if raw.code == 0x99:
        if len(raw.words) != 1:
            raise ProtocolError(f"error reply (99) with {len(raw.words)} words, expected 1")
        try:
            err = ErrorCode(raw.words[0])
        except ValueError as exc:
            raise ProtocolError(f"error reply code {raw.words[0]:07X} not in 1..4") from exc
        return ErrorReply(err, raw.start, raw.addr)
    if raw.code not in COMMANDS:
        raise ProtocolError(f"reply to unknown command code {raw.code:02X}")
    if not raw.words:
        return WriteReply(raw.code, raw.start, raw.addr)
    return ReadReply(raw.code, raw.words, raw.start, raw.addr)


def split_serial_frames(buffer: bytes) -> tuple[list[bytes], bytes, int]:
    """Cut complete ``STX .. ETX cc`` frames out of a byte stream.

    Returns
    -------
    frames : list of bytes
        Complete candidate frames (still to be decoded and checked).
    rest : bytes
        Trailing bytes of an incomplete frame.
    skipped : int
        Bytes discarded before an STX (noise), so that they are counted, not silent.
    """
    frames: list[bytes] = []
    skipped = 0
    i = 0
    n = len(buffer)
    while i < n:
        if buffer[i] != STX:
            skipped += 1
            i += 1
            continue
        j = buffer.find(bytes((ETX,)), i + 1)
        if j < 0:
            if n - i > serial_frame_size(3):  # no ETX within a maximal frame: noise
                skipped += 1
                i += 1
                continue
            break
        if j + 2 >= n:
            break
        if j - i + 3 > serial_frame_size(3):
            skipped += 1
            i += 1
            continue
        frames.append(bytes(buffer[i : j + 3]))
        i = j + 3
    return frames, bytes(buffer[i:]), skipped


# USB framing (manual 6.2.4) ---------------------------------------------------------------

# One layout per USB message; a data word travels as a u32 whose first byte is its top
# hex digit (0..0x0F) and the next three its low 24 bits, i.e. the word big-endian.
USB_WRITE = struct.Struct(">BBB3IB")  # 0x01, addr, cmd, DAT1..DAT3, start
USB_WRITE_REPLY = struct.Struct(">BBBBI3I")  # addr, cmd, error, busy, state|executing, X Y Z
USB_READ_REPLY = struct.Struct(">BB3IBB")  # addr, cmd, DAT1..DAT3, start, valid DATs
USB_WRITE_SIZE = USB_WRITE.size  # 16
USB_WRITE_REPLY_SIZE = USB_WRITE_REPLY.size  # 20
USB_READ_REPLY_SIZE = USB_READ_REPLY.size  # 16


def _usb_digit_word(word: int, what: str) -> int:
    """A USB data word (its first byte one hex digit), else :class:`ProtocolError`."""
    if word >> 24 > 0x0F:
        raise ProtocolError(f"{what}: first byte {word >> 24:#04x} is not one hex digit (0..0x0F)")
    return word


def _pack(layout: struct.Struct, what: str, *fields: int) -> bytes:
    try:
        return layout.pack(*fields)
    except struct.error as exc:
        raise ProtocolError(f"{what} field out of range: {exc}") from None


def encode_usb_write(cmd: Command) -> bytes:
    """16-byte ``senddata`` buffer: ``01 addr cmd DAT1 DAT2 DAT3 start`` (unused DATs zero)."""
    words = (*cmd.words, 0, 0, 0)[:3]
    return _pack(USB_WRITE, "USB write", 0x01, cmd.addr, cmd.code, *words, int(cmd.start))


def decode_usb_write(data: bytes) -> Command:
    """Decode a 16-byte USB write buffer (the manual: unused DATs are "don't care")."""
    data = bytes(data)
    if len(data) != USB_WRITE_SIZE:
        raise ProtocolError(f"USB write of {len(data)} bytes, expected {USB_WRITE_SIZE}")
    if data[0] != 0x01:
        raise ProtocolError(f"USB write code {data[0]:#04x}, expected 0x01")
    spec = COMMANDS.get(data[2])
    if spec is None:
        raise ProtocolError(f"unknown command code {data[2]:02X}")
    if spec.kind == "query":
        raise ProtocolError(f"command {data[2]:02X} is a query; USB reads go through recdata")
    _one, addr, _code, *dats, start = USB_WRITE.unpack(data)
    words = tuple(_usb_digit_word(dats[i], f"DAT{i + 1}") for i in range(spec.n_words))
    if start > 8:
        raise ProtocolError(f"USB start code {start:#04x} not in 0..8")
    return Command(spec.code, words, Start(start), addr)


@dataclass(frozen=True)
class UsbWriteReply:
    """20-byte reply to ``senddata`` (manual 6.2.4.2).

    Attributes
    ----------
    code : int
        Echoed command code, 0x99 on error.
    error : int
        Error code (2 manual mode, 3 buffer full); 0 when ``code`` is not 0x99.
    busy : int
        Bit 3 X, bit 2 Y, bit 1 Z, bit 0 U.
    state : int
        First byte of the executing-number field (0 normal, 1..7 fault as in 8.8.0).
    executing : int
        Executing command number (3 bytes).
    positions : tuple of int
        X, Y, Z logical positions (sign byte + 3 bytes each).
    """

    code: int
    error: int = 0
    busy: int = 0
    state: int = 0
    executing: int = 0
    positions: tuple[int, int, int] = (0, 0, 0)
    addr: int = 0


def encode_usb_write_reply(r: UsbWriteReply) -> bytes:
    if not (
        0 <= r.busy <= 0x0F
        and 0 <= r.state <= 0xFF
        and 0 <= r.executing <= MAX_MAGNITUDE
        and 0 <= r.error <= 0xFF
        and 0 <= r.code <= 0xFF
    ):
        raise ProtocolError(f"USB write reply field out of range: {r}")
    positions = (word_from_signed(p) for p in r.positions)
    state_executing = r.state << 24 | r.executing
    return _pack(
        USB_WRITE_REPLY, "USB write reply", r.addr, r.code, r.error, r.busy, state_executing,
        *positions,
    )  # fmt: skip


def decode_usb_write_reply(data: bytes) -> UsbWriteReply:
    data = bytes(data)
    if len(data) != USB_WRITE_REPLY_SIZE:
        raise ProtocolError(
            f"USB write reply of {len(data)} bytes, expected {USB_WRITE_REPLY_SIZE}"
        )
    if data[1] == 0x99 and data[2] not in (1, 2, 3, 4):
        raise ProtocolError(f"USB error reply with error code {data[2]} (expected 1..4)")
    if data[3] > 0x0F:
        raise ProtocolError(f"USB busy byte {data[3]:#04x} uses bits above bit 3")
    addr, code, error, busy, state_executing, *words = USB_WRITE_REPLY.unpack(data)
    x, y, z = (
        signed_from_word(_usb_digit_word(w, f"{axis} position"))
        for w, axis in zip(words, "XYZ", strict=True)
    )
    return UsbWriteReply(
        code, error, busy, state_executing >> 24, state_executing & 0xFFFFFF, (x, y, z), addr
    )


@dataclass(frozen=True)
class UsbReadRequest:
    """Arguments of ``recdata(prec, addr, cmd, rdat1, rdat2)`` (manual 6.2, ch. 8)."""

    code: int
    rdat1: int
    rdat2: int = 0

    def __post_init__(self) -> None:
        spec = COMMANDS.get(self.code)
        if spec is None or spec.kind != "query":
            raise ProtocolError(f"recdata command {self.code:#04x} is not a query (31..38)")
        if not 0 <= self.rdat1 <= 0xFF or not -(2**31) <= self.rdat2 < 2**31:
            raise ProtocolError(f"recdata rdat1={self.rdat1} / rdat2={self.rdat2} out of range")

    def serial_word(self) -> int:
        """The equivalent serial query word (5.3): 38 puts the item in the first digit."""
        if self.code == 0x38:
            if self.rdat1 > 0xF:
                raise ProtocolError(f"query 38 item {self.rdat1} has no serial form")
            low = self.rdat2 & 0xFF if self.rdat1 == 3 else 0
            return (self.rdat1 << 24) | (low << 16)
        if self.code == 0x31 and self.rdat1 == 0x06:
            return 0x42  # decision D5: serial 5.3.1.6 writes 0000042 for USB rdat1 = 6
        return self.rdat1


@dataclass(frozen=True)
class UsbReadReply:
    """16-byte reply of ``recdata`` (manual 6.2.4.3): addr cmd DAT1..3 start n_valid."""

    code: int
    words: tuple[int, int, int] = (0, 0, 0)
    start: int = 0
    n_valid: int = 3
    addr: int = 0


def encode_usb_read_reply(r: UsbReadReply) -> bytes:
    if not 0 <= r.n_valid <= 3 or not 0 <= r.start <= 0xFF or len(r.words) != 3:
        raise ProtocolError(f"USB read reply field out of range: {r}")
    return _pack(USB_READ_REPLY, "USB read reply", r.addr, r.code, *r.words, r.start, r.n_valid)


def decode_usb_read_reply(data: bytes) -> UsbReadReply:
    data = bytes(data)
    if len(data) != USB_READ_REPLY_SIZE:
        raise ProtocolError(f"USB read reply of {len(data)} bytes, expected 16")
    if data[15] > 3:
        raise ProtocolError(f"USB read reply: {data[15]} valid DATs (expected 0..3)")
    addr, code, *dats, start, n_valid = USB_READ_REPLY.unpack(data)
    w1, w2, w3 = (_usb_digit_word(w, f"DAT{i + 1}") for i, w in enumerate(dats))
    return UsbReadReply(code, (w1, w2, w3), start, n_valid, addr)


@dataclass(frozen=True)
class _Decision:
    topic: str
    manual_says: str
    decision: str


MANUAL_DECISIONS: tuple[_Decision, ...] = (
    _Decision(
        "read / error reply framing",
        "ch. 5 summary omits ETX from the read and error reply formats",
        "ETX present in every reply, as in the worked replies of 5.3.1.1 and 5.3.4.1",
    ),
    _Decision(
        "USB start code byte",
        "7.1.7/7.1.8.4 say start condition 38H; the worked USB example sends $00",
        "USB byte 15 carries the numeric start condition 0..8 (like the DAT digits)",
    ),
    _Decision(
        "small-segment mode word",
        "USB 7.1.8.3 gives 03 00 00 01 for both standard and small-segment mode",
        "serial 5.1.8.3: 3000001 standard, 3000002 small-segment, on both links",
    ),
    _Decision(
        "brake code 7",
        "5.1.7 and 7.1.7: code 0000007 'release Y brake' (Y appears twice, Z never)",
        "0000007 releases the Z emergency brake",
    ),
    _Decision(
        "query U inputs",
        "serial 5.3.1.6 sends 0000042, USB 8.1.6 uses rdat1 = $06",
        "serial uses 0000042 as printed; the USB read request maps rdat1 6 to it",
    ),
    _Decision(
        "buffer depth",
        "ch. 5: 63 commands; 5.8.2.2 (download): 62, the 63rd is 'buffer full'",
        "63 pending commands in normal operation (the download mode is not used)",
    ),
    _Decision(
        "per-command move range",
        "ch. 2: single-axis range +-134 217 727; 5.5.1: 6 hex digits, max 16 777 215",
        "the wire carries at most 16 777 215 pulses per word; larger is refused",
    ),
    _Decision(
        "negative soft-limit default",
        "appendix: negative soft limits default 16 777 215 (FFFFFF) without sign",
        "read as -16 777 215 (no limit); U current-position default FFFFFF read as 0",
    ),
    _Decision(
        "query 38 item 0 layout",
        "serial: DAT1 first digit brake state, rest number; USB 8.8.0: byte 02 fault "
        "0..7 then says both 03-05 and 02-04 hold the number",
        "DAT1 = state digit (0 normal, 1..6 limit faults, 7 e-stop) + 6-digit number",
    ),
    _Decision(
        "USB write-reply busy bits",
        "6.2.4.2 lists lsb1 twice (Z and Y) and X at lsb2",
        "bit0 U, bit1 Z, bit2 Y, bit3 X (serial 5.3.1.3 order U X Y Z by nibble)",
    ),
    _Decision(
        "USB write-reply executing number",
        "6.2.4.2: bytes 04..07 'executing line number' without layout",
        "byte 04 = state as in 8.8.0, bytes 05..07 = number (24-bit big-endian)",
    ),
    _Decision(
        "Z start frequencies",
        "serial 5.1.3.2: command 14 takes DAT1..3; USB 7.1.3.2 lists only DAT1",
        "three words, as for X (02) and Y (09) and the query reply 5.3.6.2",
    ),
    _Decision(
        "work-mode soft-limit bit",
        "5.2.17: 'Bit3=0 soft limit off; Bit4=1 soft limit on'",
        "bit 3 of the 6th digit enables the soft limits",
    ),
    _Decision(
        "command numbering reset",
        "5.1.8.3: the numbering restarts when 19 3000000 *executes*",
        "the emulator renumbers when it is received (identical when sent first into an "
        "empty buffer, which is how the streamer uses it)",
    ),
    _Decision(
        "interpolation feed reference",
        "5.1.1.10: 'XYZ linear interpolation constant frequency' without saying of which axis",
        "the feed is the pulse rate of the axis with the longest move; the start "
        "frequency is the linear-interpolation start frequency of the first axis "
        "(02 DAT2 for X...); a move whose feed is at or below the start frequency runs "
        "at constant feed. To be confirmed on hardware.",
    ),
    _Decision(
        "arc example word width",
        "5.6.1's worked arc example prints 8 ASCII bytes per DAT (31H 30H 30H 30H 30H 31H 39H 30H)",
        "7 digits, as the frame format, 5.5.1's identical example and USB 7.5.1 say",
    ),
    _Decision(
        "online-state reply",
        "5.3.7.0 prints the reply DAT1 with 6 digits (30H x5 + 30H/31H)",
        "a 7-digit word: 0000000 manual, 0000001 online (USB 8.7.0: 00 00 00 00 / 01)",
    ),
    _Decision(
        "start conditions",
        "0 and 1 (and 4 and 5) are described identically; 2/3/6/7 wait for an interlock",
        "frames use 4; the emulator runs 0..7 in sequence and treats the interlock as "
        "satisfied (it has no interlock inputs); 8 only for brakes, clear buffer, loop test",
    ),
    _Decision(
        "cross-references and titles",
        "ch. 5 points to '5.1.11' for the checksum example; 7.3.4 is titled Z homing for "
        "command 47; appendix 1 lists Z start frequency / Z equivalent under 5.1.4.1 (AC)",
        "read as 5.1.1.1, U homing (47) and U parameters (AC DAT2, DAT3)",
    ),
    _Decision(
        "received-command count",
        "5.3.8.0 DAT2 / 8.8.1: 'valid commands received' without saying since when",
        "counted since the last numbering reset (19 3000000), i.e. the last number given",
    ),
    _Decision(
        "emergency-brake release",
        "5.1.7: after release the controller 'continues the buffered commands'",
        "the interrupted move completes its remaining distance, then the queue resumes",
    ),
)
"""Every place the manual contradicts itself or is silent, and the decision taken."""
