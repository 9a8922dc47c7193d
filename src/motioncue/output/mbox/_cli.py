"""Hooks the ``emulate`` / ``send`` / ``inspect`` verbs call for an SC-MBOX."""

from __future__ import annotations

import re
from typing import TextIO

from ..._errors import ConfigError, ProtocolError
from .._transport import Transport, TransportURL
from .._udp_cli import (
    VERBS,
    RegisterLink,
    describe,
    need_args,
    park,
    parse_bits,
    parse_value,
    positions_from_words,
    require_request,
    split_datagrams,
)
from .._udp_cli import transport_options as _transport_options
from .._udp_common import HEADER, WHO_ALL, decode_header
from ._controller import MboxController
from ._messages import (
    CHANNEL_CX,
    CHANNEL_DX,
    CHANNEL_FX,
    CHANNEL_FXM,
    F_ABS,
    F_READ,
    F_READ_ERR,
    F_REL,
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

__all__ = [
    "VERBS",
    "inspect_decode",
    "send_verb",
    "split_stream",
    "transport_options",
]

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


def send_verb(
    controller: MboxController,
    transport: Transport,
    verb: str,
    args: list[str],
    *,
    who: tuple[int, int] = (WHO_ALL, WHO_ALL),
    save: bool = False,
    out: TextIO,
) -> int:
    """Run one ``motioncue send`` verb; returns the exit status (0 ok, 1 error reply)."""
    link = RegisterLink(transport, decode, RegisterRead, RegisterWrite, who, out)
    write, read = link.write, link.read

    def nargs(n: int) -> None:
        need_args(verb, args, n)

    if verb == "estop":
        nargs(1)
        if args[0] not in ("on", "off"):
            raise ConfigError(f"send estop {args[0]!r}: allowed on | off")
        # manual 4.5.2: Fn090 = 1 through FXm (channel 0, not saved)
        reply = write(CHANNEL_FXM, 0x090, (1 if args[0] == "on" else 0,))
    elif verb == "reset":
        nargs(0)
        reply = write(CHANNEL_CX, 0, (0x0001,))  # RST: leave the fault state; SON = 0 re-homes
    elif verb == "home":
        nargs(0)
        reply = write(CHANNEL_CX, 0, (0x0000,))  # manual 4.5.1: play control word 0 re-homes
    elif verb == "outputs":
        nargs(1)
        bits = parse_bits(args[0], 24)
        reply = write(CHANNEL_CX, 1, (bits & 0xFFF,))
        if bits >> 12:
            reply = write(CHANNEL_CX, 4, (bits >> 12,))
    elif verb == "read":
        if len(args) not in (1, 2):
            raise ConfigError("send read REG [COUNT]")
        channel, start, _label = register(args[0], for_write=False)
        count = parse_value(args[1], "count") if len(args) == 2 else 1
        reply = read(channel, start, count)
        if isinstance(reply, RegisterReadReply):
            for i, v in enumerate(reply.values):
                name = f"Dn{start + i:02X}" if channel == CHANNEL_DX else f"Fn{start + i:03X}"
                print(f"{name} = {v} (0x{v:04X})", file=out)
    elif verb == "write":
        if len(args) < 2:
            raise ConfigError("send write REG VALUE...")
        channel, start, _label = register(args[0], for_write=True, save=save)
        values = tuple(parse_value(v) & 0xFFFF for v in args[1:])
        reply = write(channel, start, values)
    elif verb == "park":
        nargs(0)
        require_request(transport)
        reply = read(CHANNEL_DX, 0, 0x30)
        if not isinstance(reply, RegisterReadReply):
            return 1
        positions = positions_from_words(reply.values, DX_COMMAND[: controller.n_axes])
        park(controller, transport, positions, out)
        return 0
    else:
        raise ConfigError(f"send {verb!r}: allowed {', '.join(VERBS)}")
    if isinstance(reply, RegisterError) and reply.function in (F_READ_ERR, F_WRITE_ERR):
        print(f"error reply: code {reply.error_code}", file=out)
        return 1
    return 0


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
