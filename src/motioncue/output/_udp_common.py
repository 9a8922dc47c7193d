"""What the IMAX and SC-MBOX UDP protocols share: the 12-byte header, Who addressing,
register blocks, and the frame-encoder state both kinds use.

Every UDP datagram of both controllers starts with the same 12 bytes (IMAX manual 2.2.1,
SC-MBOX manual 4.2.2), all big-endian:

======  ====  ==============================================================
offset  size  field
======  ====  ==============================================================
0       2     ConfirmCode (``0x55AA``; IMAX servo/status messages ``0x33CC``)
2       2     PassCode (``0x0000``)
4       2     FunctionCode
6       2     ObjectChannel (error code / servo id in some messages)
8       2     WhoAccept
10      2     WhoReply
======  ====  ==============================================================

The layouts that follow the header are declared in each kind's ``_messages`` module.
"""

from __future__ import annotations

import math
import numbers
import re
import struct
import tomllib
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Protocol

from .._errors import ConfigError, ProtocolError

__all__ = [
    "AXES_OF_CHANNEL",
    "CHANNEL_OF_AXES",
    "CONFIRM_MAIN",
    "CONFIRM_SERVO",
    "F_ABS",
    "F_REL",
    "HEADER",
    "PASSCODE",
    "REG_HEAD",
    "WHO_ALL",
    "WHO_NONE",
    "FrameClock",
    "Header",
    "HexNames",
    "ParameterTable",
    "WireMessage",
    "check_int32",
    "check_length",
    "decode_header",
    "format_who",
    "pack_timed_frame",
    "param_lookup",
    "parse_node",
    "timed_frame_struct",
    "u16_tuple",
]

CONFIRM_MAIN = 0x55AA
CONFIRM_SERVO = 0x33CC
PASSCODE = 0x0000
WHO_ALL = 0xFFFF
WHO_NONE = 0x0000
F_ABS, F_REL = 0x1301, 0x1401
"""Timed frame, absolute / relative time: the same function codes in both manuals."""
AXES_OF_CHANNEL = {0: 3, 1: 6}
"""A frame's ObjectChannel in both manuals: 0 = 3 axes, 1 = 6 axes (IMAX also n = n)."""
CHANNEL_OF_AXES = {n: channel for channel, n in AXES_OF_CHANNEL.items()}

HEADER = struct.Struct(">6H")
REG_HEAD = struct.Struct(">HH")


@cache
def timed_frame_struct(n_axes: int, relative: bool, tail: str) -> struct.Struct:
    """Layout of a timed motion frame (0x1301 / 0x1401 in both manuals, IMAX 0x1801 / 0x1901).

    Header, frame number u32, time u32 (absolute) or i32 (relative), ``n_axes`` x i32
    positions, then ``tail`` (struct codes of the kind's outputs: MBOX ``"4H"`` BaseDout,
    DAC1, DAC2, ExtDout; IMAX ``"HI"`` PortOut, Extend).
    """
    return struct.Struct(f">6HI{'i' if relative else 'I'}{n_axes}i{tail}")


def pack_timed_frame(
    layout: struct.Struct,
    head: tuple[int, int, int, int],
    number: int,
    time_ms: int,
    positions: Sequence[int],
    tail: Iterable[int],
    what: str,
) -> bytes:
    """Encode a timed frame of :func:`timed_frame_struct` ``layout``.

    ``head`` = (function, channel, who_accept, who_reply); ``tail`` the kind's trailing
    fields (unpacked inside the guard, so a malformed one is reported too). A field out of
    its range raises :class:`ProtocolError` naming ``what``.
    """
    try:
        return layout.pack(CONFIRM_MAIN, PASSCODE, *head, number, time_ms, *positions, *tail)
    except (struct.error, TypeError) as exc:
        raise ProtocolError(f"{what} field out of range: {exc}") from None


class WireMessage(Protocol):
    """A decoded message of a UDP kind: it encodes back to its datagram."""

    def encode(self) -> bytes: ...


@dataclass(frozen=True, slots=True)
class Header:
    """The 12 header bytes, as integers."""

    confirm: int
    passcode: int
    function: int
    channel: int
    who_accept: int
    who_reply: int


def decode_header(data: bytes) -> Header:
    """Read the 12-byte header; raise :class:`ProtocolError` if it is short or mis-coded."""
    if len(data) < HEADER.size:
        raise ProtocolError(f"datagram of {len(data)} bytes is shorter than the 12-byte header")
    header = Header(*HEADER.unpack_from(data))
    if header.confirm not in (CONFIRM_MAIN, CONFIRM_SERVO):
        raise ProtocolError(f"confirm code 0x{header.confirm:04X} is neither 0x55AA nor 0x33CC")
    if header.passcode != PASSCODE:
        raise ProtocolError(f"pass code 0x{header.passcode:04X}, expected 0x0000")
    return header


def check_length(data: bytes, expected: int, what: str) -> None:
    """Raise :class:`ProtocolError` unless ``len(data) == expected``."""
    if len(data) != expected:
        raise ProtocolError(f"{what}: length {len(data)} bytes, expected {expected}")


def parse_node(text: str) -> tuple[int, int]:
    """Who fields for ``--node``: ``all`` (0xFFFF), ``XX.YY`` hexadecimal bytes (one node,
    ``XX.FF`` a column, ``FF.YY`` a row). Returns ``(who_accept, who_reply)``.
    """
    text = text.strip().lower()
    if text == "all":
        return WHO_ALL, WHO_ALL
    parts = text.split(".")
    try:
        if len(parts) != 2 or not all(1 <= len(p) <= 2 for p in parts):
            raise ValueError
        value = (int(parts[0], 16) << 8) | int(parts[1], 16)
    except ValueError as exc:
        raise ConfigError(
            f"node {text!r} is invalid; allowed: 'all' or XX.YY with hexadecimal XX, YY "
            "(FF = whole row/column), e.g. 01.02"
        ) from exc
    if value == 0:
        raise ConfigError("node 00.00 means 'nobody'; give a node, a row, a column or 'all'")
    return value, value


def format_who(value: int) -> str:
    """``0xFFFF`` -> ``all``, ``0`` -> ``none``/host, else ``XX.YY``."""
    if value == WHO_ALL:
        return "all"
    if value == WHO_NONE:
        return "0"
    return f"{value >> 8:02X}.{value & 0xFF:02X}"


def u16_tuple(values: Sequence[int], what: str) -> tuple[int, ...]:
    """Validate register values as 16-bit words; negative values are two's complement."""
    out = []
    for v in values:
        if isinstance(v, bool) or not isinstance(v, int) or not -0x8000 <= v <= 0xFFFF:
            raise ProtocolError(f"{what}: value {v!r} is not a 16-bit register value")
        out.append(v & 0xFFFF)
    return tuple(out)


def check_int32(values: Sequence[object], n_axes: int, what: str = "positions") -> tuple[int, ...]:
    """Validate motor positions: ``n_axes`` finite integers within int32.

    Integral floats (``1000.0``) and numpy integers are accepted; NaN, inf, fractions and
    anything out of int32 raise :class:`ProtocolError` so nothing bad reaches the wire.
    """
    if len(values) != n_axes:
        raise ProtocolError(f"{what}: {len(values)} values given, the controller has {n_axes} axes")
    out = []
    for i, v in enumerate(values):
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise ProtocolError(f"{what}[{i}] = {v!r} is not a number")
        if isinstance(v, int):
            iv = v
        else:
            try:
                fv = float(v)
            except (TypeError, ValueError) as exc:
                raise ProtocolError(f"{what}[{i}] = {v!r} is not a number") from exc
            if not math.isfinite(fv) or fv != int(fv):
                raise ProtocolError(f"{what}[{i}] = {v!r} is not a finite whole number of pulses")
            iv = int(fv)
        if not -0x80000000 <= iv <= 0x7FFFFFFF:
            raise ProtocolError(f"{what}[{i}] = {iv} pulses is outside int32")
        out.append(iv)
    return tuple(out)


class FrameClock:
    """Frame numbering and time stamps of one run (explicit state, stepped by each frame).

    Parameters
    ----------
    absolute_time : bool
        ``True``: time field = ms since the run's origin (function 0x1301);
        ``False``: ms since the previous frame (0x1401).
    t0_s : float or None
        Time origin of the run in seconds. ``None`` takes the first frame's time, so the
        first frame carries time 0 (for relative time, 0 means the controller's jog time).
    first_frame : int
        Number of the first frame (u32, wraps).

    Times are rounded once to whole ms on the absolute scale, so relative time stamps do not
    drift: the sum of the deltas is always the rounded absolute time.
    """

    __slots__ = ("_prev_ms", "absolute_time", "frame", "t0_s")

    def __init__(self, absolute_time: bool, t0_s: float | None = None, first_frame: int = 0):
        if t0_s is not None and not math.isfinite(t0_s):
            raise ConfigError(f"t0_s = {t0_s!r} is invalid; allowed: a finite number or None")
        self.absolute_time = bool(absolute_time)
        self.t0_s = t0_s
        self.frame = int(first_frame) & 0xFFFFFFFF
        self._prev_ms: int | None = None

    def stamp(self, t_s: float) -> tuple[int, int, int]:
        """``(frame_number, time_field, abs_ms)`` for a frame at ``t_s``, without advancing.

        Raises :class:`ProtocolError` for a non-finite time, a time before the origin or
        beyond u32 ms, and a time earlier than the previous frame's.
        """
        if isinstance(t_s, bool) or not isinstance(t_s, int | float) or not math.isfinite(t_s):
            raise ProtocolError(f"frame time t_s = {t_s!r} is not a finite number")
        t0 = float(t_s) if self.t0_s is None else self.t0_s
        abs_ms = round((t_s - t0) * 1000.0)
        if abs_ms < 0 or abs_ms > 0xFFFFFFFF:
            raise ProtocolError(
                f"frame time {t_s} s is {abs_ms} ms from the run origin {t0} s; "
                "allowed: 0 .. 2**32-1 ms"
            )
        prev = self._prev_ms
        if prev is not None and abs_ms < prev:
            raise ProtocolError(
                f"frame time went backwards: {abs_ms} ms after {prev} ms (the controller would "
                "treat it as a rewind); start a new encoder for a new run"
            )
        field = abs_ms if self.absolute_time else abs_ms - (0 if prev is None else prev)
        return self.frame, field, abs_ms

    def commit(self, t_s: float, abs_ms: int) -> None:
        """Advance past the frame :meth:`stamp` described."""
        if self.t0_s is None:
            self.t0_s = float(t_s)
        self.frame = (self.frame + 1) & 0xFFFFFFFF
        self._prev_ms = abs_ms

    def snapshot(self) -> tuple[int, int | None, float | None]:
        """The clock's state, for :meth:`restore` (a frame encoded but never sent)."""
        return (self.frame, self._prev_ms, self.t0_s)

    def restore(self, state: tuple[int, int | None, float | None]) -> None:
        """Go back to a :meth:`snapshot`."""
        self.frame, self._prev_ms, self.t0_s = state

    def step(self, t_s: float) -> tuple[int, int]:
        """Return ``(frame_number, time_field)`` for a frame at ``t_s`` and advance."""
        frame, field, abs_ms = self.stamp(t_s)
        self.commit(t_s, abs_ms)
        return frame, field


def param_lookup(parameters: Mapping[str, int], name: str, default: int | None = None) -> int:
    """A parameter value by manual name, with a clear error when absent."""
    if name in parameters:
        return parameters[name]
    if default is not None:
        return default
    raise ConfigError(f"controller parameter {name} is not set")


Decoder = Callable[[Header, bytes], WireMessage]


@dataclass(frozen=True)
class HexNames:
    """The names of one family of registers or parameters: a prefix and hexadecimal digits.

    Attributes
    ----------
    pattern : re.Pattern
        Matches an accepted spelling; its first group holds the hexadecimal digits.
    fmt : str
        The canonical form of an address (``"PA{:02x}"``).
    what : str
        The allowed form, for the error message (``"an IMAX parameter name (PAxx, ...)"``).
    """

    pattern: re.Pattern[str]
    fmt: str
    what: str

    def name(self, text: str) -> str:
        """The canonical name of ``text``; :class:`ConfigError` naming the allowed form."""
        return self.fmt.format(self.address(text))

    def address(self, text: str) -> int:
        """The register address of the name ``text`` (any accepted spelling)."""
        m = self.pattern.match(text.strip())
        if not m:
            raise ConfigError(f"{text!r} is not {self.what}")
        return int(m.group(1), 16)


ParamSpec = tuple[int, int, int, str]
"""A parameter's ``(lo, hi, default, meaning)``."""


@dataclass(frozen=True)
class ParameterTable:
    """A controller's parameter table, declared as data: one TOML file in the kind's
    package, its names' spelling in ``[names]`` and, in ``[parameters]``, a line
    ``NAME = [lo, hi, default, "meaning"]`` per parameter in address order.

    Attributes
    ----------
    names : HexNames
        The parameters' names (every name in the file is canonical).
    spec : dict[str, tuple[int, int, int, str]]
        ``name: (lo, hi, default, meaning)`` in the file's order.
    by_address : dict[int, str]
        Register address -> name.
    """

    names: HexNames
    spec: dict[str, ParamSpec]
    by_address: dict[int, str]

    @classmethod
    def load(cls, package: str, resource: str = "params.toml") -> ParameterTable:
        """Read ``resource`` of ``package``: a table ``[names]`` (``pattern`` of the accepted
        spellings, case-insensitive, its first group the hexadecimal digits; ``canonical``,
        the format of a name; ``what``, the form an error message names) and a table
        ``[parameters]``. :class:`ConfigError` naming a malformed row."""
        text = resources.files(package).joinpath(resource).read_text(encoding="utf-8")
        data = tomllib.loads(text)
        form = data["names"]
        names = HexNames(
            re.compile(form["pattern"], re.IGNORECASE), form["canonical"], form["what"]
        )
        spec: dict[str, ParamSpec] = {}
        for name, row in data["parameters"].items():
            ints = row[:3] if isinstance(row, list) and len(row) == 4 else ()
            if (
                len(ints) != 3
                or not all(type(v) is int for v in ints)
                or not isinstance(row[3], str)
                or not ints[0] <= ints[2] <= ints[1]
                or names.name(name) != name
            ):
                raise ConfigError(
                    f"{package}/{resource}: {name} = {row!r}: expected a canonical name = "
                    "[lo, hi, default, meaning] with lo <= default <= hi"
                )
            spec[name] = (row[0], row[1], row[2], row[3])
        return cls(names, spec, {names.address(name): name for name in spec})
