"""Hooks the ``emulate`` / ``send`` / ``inspect`` verbs call for an SC-MBOX."""

from __future__ import annotations

import re
from collections.abc import Sequence

from ..._errors import ConfigError, ProtocolError
from .._transport import TransportURL
from .._udp_cli import (
    SendWords,
    Write,
    describe,
    need_args,
    parse_bits,
    positions_from_words,
    split_datagrams,
)
from .._udp_cli import transport_options as _transport_options
from .._udp_common import F_ABS, F_REL, HEADER, WireMessage, decode_header
from ._controller import MboxController
from ._messages import (
    CHANNEL_CX,
    CHANNEL_DX,
    CHANNEL_FX,
    CHANNEL_FXM,
    F_READ,
    F_READ_ERR,
    F_STATUS,
    F_WRITE,
    F_WRITE_ERR,
    RegisterError,
    RegisterRead,
    RegisterReadReply,
    RegisterWrite,
    decode,
    frame_size,
)
from ._params import DX_COMMAND, fn_name

__all__ = ["inspect_decode", "send_verb", "split_stream", "transport_options"]

_DX = re.compile(r"^(?:dn|dx)[ _]?([0-9a-f]{1,2})$", re.IGNORECASE)
_CX = re.compile(r"^(?:cn|cx)[ _]?([0-7])$", re.IGNORECASE)


def register(name: str, *, for_write: bool, save: bool = False) -> tuple[int, int, str]:
    """``(channel, address, label)`` of a register name: ``Fn0C1``, ``Dn4B`` / ``DX4B``
    (read only), ``CX0`` / ``Cn0`` (write only)."""
    m = _DX.match(name.strip())
    if m:
        if for_write:
            raise ConfigError(f"{name}: DX status registers are read-only")
        a = int(m.group(1), 16)
        return CHANNEL_DX, a, f"Dn{a:02X}"
    m = _CX.match(name.strip())
    if m:
        if not for_write:
            raise ConfigError(f"{name}: CX control registers cannot be read over UDP")
        a = int(m.group(1))
        return CHANNEL_CX, a, f"CX{a}"
    fn = fn_name(name)
    channel = (CHANNEL_FX if save else CHANNEL_FXM) if for_write else CHANNEL_FX
    return channel, int(fn[2:], 16), fn


def transport_options(controller: MboxController, url: TransportURL) -> dict[str, object]:
    """``open_transport`` options for this controller: pcap addresses from the config;
    the MBOX accepts any source port."""
    return _transport_options(controller, url, fixed_source_port=False)


class _Words(SendWords):
    """The SC-MBOX's registers behind the ``send`` words (manual 4.5, 5)."""

    PARK_READ = (CHANNEL_DX, 0x30)

    def estop(self, write: Write, args: Sequence[str]) -> WireMessage | None:
        need_args("estop", args, 1)
        if args[0] not in ("on", "off"):
            raise ConfigError(f"send estop {args[0]!r}: allowed on | off")
        # manual 4.5.2: Fn090 = 1 through FXm (channel 0, not saved)
        return write(CHANNEL_FXM, 0x090, (1 if args[0] == "on" else 0,))

    def reset(self, write: Write) -> WireMessage | None:
        return write(CHANNEL_CX, 0, (0x0001,))  # RST: leave the fault state; SON = 0 re-homes

    def home(self, write: Write) -> WireMessage | None:
        return write(CHANNEL_CX, 0, (0x0000,))  # manual 4.5.1: play control word 0 re-homes

    def outputs(self, write: Write, bits: str) -> WireMessage | None:
        value = parse_bits(bits, 24)
        reply = write(CHANNEL_CX, 1, (value & 0xFFF,))
        if value >> 12:
            reply = write(CHANNEL_CX, 4, (value >> 12,))
        return reply

    def register(self, name: str, *, for_write: bool, save: bool) -> tuple[int, int, str]:
        return register(name, for_write=for_write, save=save)

    def read_name(self, channel: int, address: int) -> str:
        return f"Dn{address:02X}" if channel == CHANNEL_DX else f"Fn{address:03X}"

    def values(self, reply: WireMessage | None) -> Sequence[int] | None:
        return reply.values if isinstance(reply, RegisterReadReply) else None

    def error(self, reply: WireMessage | None) -> str | None:
        if isinstance(reply, RegisterError) and reply.function in (F_READ_ERR, F_WRITE_ERR):
            return f"error reply: code {reply.error_code}"
        return None

    def park_from(self, values: Sequence[int], n_axes: int) -> list[int]:
        return positions_from_words(values, DX_COMMAND[:n_axes])


send_verb = _Words(decode, RegisterRead, RegisterWrite).run
"""Run one ``motioncue send`` verb; returns the exit status (0 ok, 1 error reply)."""


def inspect_decode(data: bytes) -> str:
    """One line describing an MBOX datagram (raises :class:`ProtocolError`)."""
    return describe(decode(data))


def _size_at(blob: bytes, off: int) -> int:
    """Size of the MBOX datagram at ``off`` of a capture, from its header."""
    h = decode_header(blob[off : off + HEADER.size])
    f = h.function
    if f & 0xFFF0 in (F_ABS & 0xFFF0, F_REL & 0xFFF0):
        if h.channel not in (0, 1):
            raise ProtocolError(f"byte {off}: frame channel {h.channel}")
        return frame_size(3 if h.channel == 0 else 6)
    if f in (F_READ_ERR, F_WRITE_ERR):
        return HEADER.size + 6
    if f in (F_STATUS, F_READ, F_READ + 1, F_WRITE, F_WRITE + 1):
        if len(blob) < off + HEADER.size + 4:
            raise ProtocolError(f"byte {off}: truncated register message")
        count = int.from_bytes(blob[off + 14 : off + 16], "big")
        return HEADER.size + 4 + 2 * count
    raise ProtocolError(f"byte {off}: unknown MBOX function 0x{f:04X}")


def split_stream(blob: bytes) -> list[bytes]:
    """Cut a raw ``file:`` capture (datagrams back to back) into datagrams."""
    return split_datagrams(blob, _size_at)
