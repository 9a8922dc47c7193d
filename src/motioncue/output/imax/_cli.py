"""Hooks the ``emulate`` / ``send`` / ``inspect`` verbs call for an IMAX controller."""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence

from ..._errors import ConfigError, ProtocolError
from .._transport import TransportURL
from .._udp_cli import (
    SendWords,
    Write,
    describe,
    parse_bits,
    positions_from_words,
    split_datagrams,
)
from .._udp_cli import transport_options as _transport_options
from .._udp_common import CONFIRM_SERVO, F_ABS, F_REL, HEADER, WireMessage, decode_header
from ._controller import ImaxController
from ._messages import (
    CHANNEL_DP,
    CHANNEL_DPF,
    CHANNEL_PA,
    F_READ,
    F_STATUS,
    F_VIB_ABS,
    F_VIB_REL,
    F_WRITE,
    PORT_OUT_BYTES,
    RegisterRead,
    RegisterReply,
    RegisterWrite,
    ReplyStatus,
    axes_of_channel,
    decode,
    frame_size,
    vibration_frame_size,
)
from ._params import DP_POS, pa_name

__all__ = ["inspect_decode", "send_verb", "split_stream", "transport_options"]

_DP = re.compile(r"^dp[ _]?([0-9a-f]{1,2})$", re.IGNORECASE)
_DPF = re.compile(r"^dpf[ _]?([0-9a-f])$", re.IGNORECASE)


def register(name: str, *, for_write: bool) -> tuple[int, int, str]:
    """``(channel, address, label)``: ``PA80``, ``DP06``, ``DPF0`` (= DP F0)."""
    text = name.strip()
    m = _DPF.match(text)
    if m:
        a = int(m.group(1), 16)
        return (CHANNEL_DPF, a, f"DPF{a:X}") if for_write else (CHANNEL_DP, 0xF0 + a, f"DPF{a:X}")
    m = _DP.match(text)
    if m:
        a = int(m.group(1), 16)
        return CHANNEL_DP, a, f"DP{a:02x}"
    pa = pa_name(text)
    return CHANNEL_PA, int(pa[2:], 16), pa


def transport_options(controller: ImaxController, url: TransportURL) -> dict[str, object]:
    """``open_transport`` options for this controller: pcap addresses from the config;
    the IMAX only accepts commands sent from port PA24 (2.3.1), so a
    non-loopback ``udp://`` target sends from it."""
    return _transport_options(controller, url, fixed_source_port=True)


class _Words(SendWords):
    """The IMAX's registers behind the ``send`` words (manual 2.3, 5)."""

    PARK_READ = (CHANNEL_DP, 0x27)

    def estop(self, write: Write, args: Sequence[str]) -> WireMessage | None:
        raise ConfigError(
            "the IMAX has no e-stop command over UDP: its e-stop is wired to inputs "
            "X01..X12 (PA90 bit 0, PA91, PA92; manual 5.6). Stop streaming or send 'park'."
        )

    def reset(self, write: Write) -> WireMessage | None:
        return write(CHANNEL_PA, 0x08, (1,))  # PA08 = 1: manual reset (5.2, 5.13)

    def home(self, write: Write) -> WireMessage | None:
        return write(CHANNEL_DPF, 0, (0,))  # DPF0 = 0 homes; reads 2 when done (2.3.3)

    def outputs(self, write: Write, bits: str) -> WireMessage | None:
        return write(CHANNEL_DPF, 1, (parse_bits(bits, 12),))  # DPF1 (5.12)

    def register(self, name: str, *, for_write: bool, save: bool) -> tuple[int, int, str]:
        return register(name, for_write=for_write)

    def read_name(self, channel: int, address: int) -> str:
        return f"DP{address:02X}" if channel == CHANNEL_DP else f"PA{address:02x}"

    def values(self, reply: WireMessage | None) -> Sequence[int] | None:
        if isinstance(reply, RegisterReply) and reply.status == ReplyStatus.OK:
            return reply.values
        return None

    def error(self, reply: WireMessage | None) -> str | None:
        if isinstance(reply, RegisterReply) and reply.status != ReplyStatus.OK:
            return f"error reply: {reply.status.name}, code {reply.error_code}"
        return None

    def park_from(self, values: Sequence[int], n_axes: int) -> list[int]:
        return positions_from_words(values, DP_POS[:n_axes])

    def after_write(self, write: Write, channel: int, save: bool) -> None:
        if save and channel == CHANNEL_PA:
            write(CHANNEL_PA, 0x0F, (2,))  # PA0f = 2: save parameters


send_verb = _Words(decode, RegisterRead, RegisterWrite).run
"""Run one ``motioncue send`` verb; returns the exit status (0 ok, 1 error reply)."""


def inspect_decode(data: bytes) -> str:
    """One line describing an IMAX datagram (raises :class:`ProtocolError`); frames of
    either PortOut width are read (their lengths differ)."""
    return describe(decode(data))


def _size_at(blob: bytes, off: int, port_out_bytes: int = 2) -> int:
    """Size of the IMAX datagram at ``off`` of a capture, from its header, frames having
    a PortOut of ``port_out_bytes``."""
    if blob[off : off + 2] == b"\x33\xcc" and blob[off + 4 : off + 6] == b"\x31\x01":
        n = int.from_bytes(blob[off + 8 : off + 10], "big")
        return 16 + 8 * n
    h = decode_header(blob[off : off + HEADER.size])
    f = h.function
    if f in (F_ABS, F_REL):
        return frame_size(axes_of_channel(h.channel), port_out_bytes)
    if f in (F_VIB_ABS, F_VIB_REL):
        return vibration_frame_size(axes_of_channel(h.channel), port_out_bytes)
    if (f & 0xFFF0) in (F_READ & 0xFFF0, F_WRITE & 0xFFF0, 0x2100, 0x2200) and f & 0xF:
        count = int.from_bytes(blob[off + 14 : off + 16], "big")
        return HEADER.size + 4 + 2 * count
    if h.confirm == CONFIRM_SERVO and f == F_STATUS:
        raise ProtocolError(f"byte {off}: malformed status report")
    raise ProtocolError(f"byte {off}: cannot size IMAX function 0x{f:04X}")


def split_stream(blob: bytes, port_out_bytes: int | None = None) -> list[bytes]:
    """Cut a raw ``file:`` capture of host -> controller datagrams into datagrams.

    A raw capture does not say how wide PortOut is (``port_out_bytes``, 2 or 4); ``None``
    tries 2, then 4: with the wrong width the next message's header is misplaced and the
    split fails."""
    widths = PORT_OUT_BYTES if port_out_bytes is None else (port_out_bytes,)
    errors = []
    for width in widths:
        try:
            return split_datagrams(blob, functools.partial(_size_at, port_out_bytes=width))
        except ProtocolError as exc:
            errors.append(f"PortOut {width} bytes: {exc}")
    raise ProtocolError("; ".join(errors))
