"""Register-access messages, the same wire structure in the IMAX and SC-MBOX manuals.

Both manuals (IMAX 2.2.2.1-2.2.2.4, SC-MBOX 4.2.3-4.2.5) lay a register message out as

======  ============  ==================================================================
offset  size          field
======  ============  ==================================================================
0       12            header (:data:`~._udp_common.HEADER`)
12      2             StartAddress u16
14      2             Count u16
16      2 x n         n u16 words: the values, or ``Count`` zero words in a read request
======  ============  ==================================================================

:func:`register_struct` is that declaration; the two message shapes below derive their
encoder, decoder and size from it. What differs between the manuals stays data in each
kind's ``_messages``: function and confirm codes, the channels allowed and what they mean,
the register count limit, where an error code goes (IMAX: channel field of the reply;
MBOX: a separate 0x1103 / 0x1203 layout).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import ClassVar, Self

from .._errors import ProtocolError
from .._frozen import set_fields
from ._udp_common import CONFIRM_MAIN, PASSCODE, REG_HEAD, WHO_ALL, WHO_NONE, Header, u16_tuple

__all__ = [
    "REGISTER_MIN_SIZE",
    "RegisterReadShape",
    "RegisterValuesShape",
    "RegisterWire",
    "RegisterWriteShape",
    "check_u16",
    "check_u16_fields",
    "pack_registers",
    "register_struct",
    "unpack_registers",
    "unpack_values",
]


@lru_cache(maxsize=64)
def register_struct(n_words: int) -> struct.Struct:
    """Header, StartAddress u16, Count u16, then ``n_words`` u16 words."""
    return struct.Struct(f">6H2H{n_words}H")


REGISTER_MIN_SIZE = register_struct(0).size  # 16: header, StartAddress, Count


def check_u16(value: int, what: str) -> None:
    """Raise :class:`ProtocolError` unless ``value`` is an int in [0, 0xFFFF]."""
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFFFF:
        raise ProtocolError(f"{what} = {value!r} is not in [0, 0xFFFF]")


def check_u16_fields(msg: object, *names: str) -> None:
    """Raise :class:`ProtocolError` unless each field ``names`` of ``msg`` is a u16 (a
    message's header and register fields, checked in the order given)."""
    for name in names:
        check_u16(getattr(msg, name), name)


def _allowed(channels: Sequence[int]) -> str:
    if isinstance(channels, range):
        return f"{channels.start}..{channels.stop - 1}"
    return str(tuple(channels))


def _check_address(msg: RegisterReadShape | RegisterValuesShape) -> None:
    """Channel among the message's CHANNELS; StartAddress and Who fields u16."""
    if msg.channel not in msg.CHANNELS:
        raise ProtocolError(
            f"{type(msg).__name__}: channel {msg.channel}, allowed {_allowed(msg.CHANNELS)}"
        )
    check_u16_fields(msg, "start", "who_accept", "who_reply")


def pack_registers(
    confirm: int,
    function: int,
    channel: int,
    who_accept: int,
    who_reply: int,
    start: int,
    count: int,
    words: Sequence[int],
) -> bytes:
    """One register datagram (``count`` is the Count field, ``words`` what follows it)."""
    return register_struct(len(words)).pack(
        confirm, PASSCODE, function, channel, who_accept, who_reply, start, count, *words
    )


def unpack_registers(data: bytes) -> tuple[int, int, tuple[int, ...]]:
    """StartAddress, Count and the words after them (header already checked)."""
    if len(data) < REGISTER_MIN_SIZE or len(data) % 2:
        raise ProtocolError(
            f"register message: length {len(data)} bytes, expected an even length >= 16"
        )
    f = register_struct((len(data) - REGISTER_MIN_SIZE) // 2).unpack(data)
    return f[6], f[7], f[8:]


def unpack_values(data: bytes, what: str) -> tuple[int, tuple[int, ...]]:
    """StartAddress and the values of a message whose Count must match its length."""
    start, count, values = unpack_registers(data)
    if count != len(values):
        raise ProtocolError(
            f"{what}: Count says {count} registers, the datagram carries "
            f"{len(values)} (length {len(data)} bytes, expected {16 + 2 * count})"
        )
    return start, values


class RegisterWire:
    """Encoder and size of every register message, derived from :func:`register_struct`:
    a message gives its confirm code, function (``_function_code``), channel,
    StartAddress, Who fields, and (``_count_and_words``) its Count field and the words
    after it."""

    __slots__ = ()

    CONFIRM: ClassVar[int] = CONFIRM_MAIN
    channel: int
    start: int
    who_accept: int
    who_reply: int

    def _function_code(self) -> int:
        raise NotImplementedError

    def _count_and_words(self) -> tuple[int, Sequence[int]]:
        raise NotImplementedError

    @property
    def size(self) -> int:
        return register_struct(len(self._count_and_words()[1])).size

    def encode(self) -> bytes:
        count, words = self._count_and_words()
        return pack_registers(
            self.CONFIRM,
            self._function_code(),
            self.channel,
            self.who_accept,
            self.who_reply,
            self.start,
            count,
            words,
        )


class _FixedFunction(RegisterWire):
    """A register message whose function code is class data (``FUNCTION``), with the
    channels it may address and the most registers it may carry."""

    __slots__ = ()

    LAYOUT: ClassVar[struct.Struct] = REG_HEAD
    FUNCTION: ClassVar[int] = 0
    CHANNELS: ClassVar[Sequence[int]] = ()
    MAX_COUNT: ClassVar[int] = 256

    @property
    def function(self) -> int:
        return self.FUNCTION

    def _function_code(self) -> int:
        return self.FUNCTION


@dataclass(frozen=True, slots=True)
class RegisterReadShape(_FixedFunction):
    """Read request: header, StartAddress u16, Count u16, ``count`` zero words (Extra Data).

    A subclass names its function, confirm code, the channels it may read and the most
    registers one request may ask for.
    """

    channel: int
    start: int
    count: int
    who_accept: int = WHO_ALL
    who_reply: int = WHO_ALL

    def __post_init__(self) -> None:
        _check_address(self)
        if not 1 <= self.count <= self.MAX_COUNT:
            raise ProtocolError(
                f"{type(self).__name__}: count {self.count}, allowed 1..{self.MAX_COUNT}"
            )

    def _count_and_words(self) -> tuple[int, Sequence[int]]:
        return self.count, (0,) * self.count

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> Self:
        start, count, pad = unpack_registers(data)
        if any(pad):
            raise ProtocolError(f"{cls.__name__}: Extra Data after Count must be zero")
        return cls(h.channel, start, count, h.who_accept, h.who_reply)


@dataclass(frozen=True, slots=True)
class RegisterValuesShape(_FixedFunction):
    """Header, StartAddress u16, Count u16 (= ``len(values)``), the values u16 each.

    The write request and (MBOX) the OK replies and status report. Negative values are
    stored as two's complement words. A subclass names its function, confirm code,
    channels and maximum count; requests override the Who defaults with ``WHO_ALL``.
    """

    channel: int
    start: int
    values: tuple[int, ...]
    who_accept: int = WHO_NONE
    who_reply: int = WHO_NONE

    def __post_init__(self) -> None:
        _check_address(self)
        set_fields(self, values=u16_tuple(self.values, type(self).__name__))
        if not 1 <= len(self.values) <= self.MAX_COUNT:
            raise ProtocolError(
                f"{type(self).__name__}: {len(self.values)} values, allowed 1..{self.MAX_COUNT}"
            )

    def _count_and_words(self) -> tuple[int, Sequence[int]]:
        return len(self.values), self.values

    @classmethod
    def decode_parts(cls, h: Header, data: bytes) -> Self:
        start, values = unpack_values(data, cls.__name__)
        return cls(h.channel, start, values, h.who_accept, h.who_reply)


@dataclass(frozen=True, slots=True)
class RegisterWriteShape(RegisterValuesShape):
    """The write request (IMAX 0x1201 / 0x2201, MBOX 0x1201): the values layout, sent to
    every node and asking every node to reply (Who fields ``WHO_ALL``) unless told."""

    who_accept: int = WHO_ALL
    who_reply: int = WHO_ALL
