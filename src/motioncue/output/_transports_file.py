"""``file:PATH`` (raw bytes) and ``pcap:PATH`` (a Wireshark-readable capture).

The pcap holds each datagram as it would cross the wire: Ethernet II, IPv4 (header
checksum computed), UDP (checksum computed), in the classic libpcap format (microsecond
time stamps, link type 1). Time stamps are ``epoch_s + t_s`` where ``t_s`` is the frame
time given to :meth:`PcapTransport.send` (offline generation), or the wall clock when no
time is given.

Both write atomically (:mod:`motioncue._atomic`): the data goes to ``.NAME.partial-XXXX`` and
is renamed to ``NAME`` by :meth:`close` after a normal end. Leaving the ``with`` block on an
exception (or Ctrl-C), or calling :meth:`discard`, removes it: a refused or failed run leaves
no file, and a killed one leaves only the obviously unfinished temporary name.
"""

from __future__ import annotations

import ipaddress
import math
import struct
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._atomic import AtomicFile, AtomicFileWriter
from .._errors import ConfigError, ProtocolError, TransportError
from ._transport import Transport, TransportURL

__all__ = [
    "FileTransport",
    "PcapPacket",
    "PcapTransport",
    "ethernet_ipv4_udp",
    "internet_checksum",
    "read_pcap",
]

PCAP_GLOBAL = struct.Struct("<IHHiIII")  # magic, major, minor, thiszone, sigfigs, snaplen, link
PCAP_RECORD = struct.Struct("<IIII")  # ts_sec, ts_usec, incl_len, orig_len
ETHERNET = struct.Struct(">6s6sH")
IPV4 = struct.Struct(">BBHHHBBH4s4s")
UDP = struct.Struct(">HHHH")
LINKTYPE_ETHERNET = 1
SRC_MAC = bytes.fromhex("020000000001")  # locally administered


def internet_checksum(data: bytes) -> int:
    """RFC 1071 one's-complement sum of 16-bit words (odd length padded with zero)."""
    if len(data) % 2:
        data += b"\0"
    total: int = sum(struct.unpack(f">{len(data) // 2}H", data))
    while total >> 16:
        total = (total & 0xFFFF) + (total >> 16)
    return ~total & 0xFFFF


def _mac_for(ip: bytes) -> bytes:
    if ip == b"\xff\xff\xff\xff":
        return b"\xff" * 6
    return b"\x02\x00" + ip  # locally administered, derived from the address


def ethernet_ipv4_udp(
    src: tuple[str, int], dst: tuple[str, int], payload: bytes, ident: int = 0, ttl: int = 64
) -> bytes:
    """One Ethernet II frame carrying ``payload`` in IPv4/UDP, checksums filled in."""
    sip = ipaddress.IPv4Address(src[0]).packed
    dip = ipaddress.IPv4Address(dst[0]).packed
    udp_len = UDP.size + len(payload)
    total = IPV4.size + udp_len
    if total > 0xFFFF:
        raise ProtocolError(f"datagram of {len(payload)} bytes does not fit in one IPv4 packet")
    ip = IPV4.pack(0x45, 0, total, ident & 0xFFFF, 0, ttl, 17, 0, sip, dip)
    ip = ip[:10] + struct.pack(">H", internet_checksum(ip)) + ip[12:]
    pseudo = sip + dip + struct.pack(">BBH", 0, 17, udp_len)
    udp = UDP.pack(src[1], dst[1], udp_len, 0) + payload
    csum = internet_checksum(pseudo + udp) or 0xFFFF
    udp = udp[:6] + struct.pack(">H", csum) + udp[8:]
    return ETHERNET.pack(_mac_for(dip), SRC_MAC if sip != dip else _mac_for(sip), 0x0800) + ip + udp


class _AtomicFileTransport(AtomicFileWriter, Transport):
    """A transport writing one file atomically: published by :meth:`close`, removed by
    :meth:`discard` or by leaving the ``with`` block on an exception."""


class FileTransport(_AtomicFileTransport):
    """Raw bytes, one message after the other, no framing (``file:PATH``)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._out = AtomicFile(self.path, "file")

    @classmethod
    def from_url(cls, url: TransportURL, **options: Any) -> FileTransport:
        return cls(url.path, **options)

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self._out.write(data)


def _address(value: tuple[str, int] | str, what: str) -> tuple[str, int]:
    if isinstance(value, str):
        host, _, port = value.rpartition(":")
        try:
            value = (host, int(port))
        except ValueError as exc:
            raise ConfigError(f"{what} = {value!r}; expected IP:PORT") from exc
    try:
        ipaddress.IPv4Address(value[0])
    except ValueError as exc:
        raise ConfigError(f"{what} = {value!r}; expected an IPv4 address") from exc
    if not 0 <= value[1] <= 0xFFFF:
        raise ConfigError(f"{what} port {value[1]}; allowed 0..65535")
    return value


class PcapTransport(_AtomicFileTransport):
    """Datagrams written as a libpcap capture (``pcap:PATH``).

    Parameters
    ----------
    path : path
    src, dst : (ip, port) or "ip:port"
        Addresses written in the packets (defaults: the manuals' factory host
        192.168.15.101:8410 and controller 192.168.15.201:7408).
    epoch_s : float or None
        Time stamp of ``t_s = 0`` (default: the wall clock when the file is opened).
    """

    def __init__(
        self,
        path: str | Path,
        *,
        src: tuple[str, int] | str = ("192.168.15.101", 8410),
        dst: tuple[str, int] | str = ("192.168.15.201", 7408),
        epoch_s: float | None = None,
    ) -> None:
        self.path = Path(path)
        self.src = _address(src, "pcap source")
        self.dst = _address(dst, "pcap destination")
        self.epoch_s = time.time() if epoch_s is None else float(epoch_s)
        self._ident = 0
        self._out = AtomicFile(self.path, "pcap")
        self._out.write(PCAP_GLOBAL.pack(0xA1B2C3D4, 2, 4, 0, 0, 65535, LINKTYPE_ETHERNET))

    @classmethod
    def from_url(cls, url: TransportURL, **options: Any) -> PcapTransport:
        return cls(url.path, **options)

    def send(
        self,
        data: bytes,
        *,
        t_s: float | None = None,
        src: tuple[str, int] | None = None,
        dst: tuple[str, int] | None = None,
    ) -> None:
        """Append one packet, stamped ``epoch_s + t_s`` (or now)."""
        ts = time.time() if t_s is None else self.epoch_s + t_s
        if not math.isfinite(ts) or ts < 0:
            raise ProtocolError(f"pcap time stamp {ts!r} s is not a finite time after 1970")
        frame = ethernet_ipv4_udp(src or self.src, dst or self.dst, data, self._ident)
        self._ident = (self._ident + 1) & 0xFFFF
        sec = int(ts)
        usec = min(999_999, round((ts - sec) * 1e6))
        try:
            record = PCAP_RECORD.pack(sec, usec, len(frame), len(frame))
        except struct.error as exc:
            raise ProtocolError(f"pcap time stamp {ts!r} s does not fit the format") from exc
        self._out.write(record + frame)


@dataclass(frozen=True)
class PcapPacket:
    """A UDP datagram found in a capture."""

    t_s: float
    src: tuple[str, int]
    dst: tuple[str, int]
    payload: bytes


def read_pcap(path: str | Path) -> Iterator[PcapPacket]:
    """UDP datagrams of a classic pcap (Ethernet, Linux cooked or raw IPv4 link types).

    Non-UDP packets are skipped; a damaged file raises :class:`ProtocolError`.
    """
    try:
        blob = Path(path).read_bytes()
    except OSError as exc:
        raise TransportError(f"cannot read {path}: {exc}") from exc
    if len(blob) < PCAP_GLOBAL.size:
        raise ProtocolError(f"{path}: too short for a pcap file")
    magic = blob[:4]
    if magic in (b"\xd4\xc3\xb2\xa1", b"\x4d\x3c\xb2\xa1"):
        endian = "<"
    elif magic in (b"\xa1\xb2\xc3\xd4", b"\xa1\xb2\x3c\x4d"):
        endian = ">"
    else:
        raise ProtocolError(f"{path}: not a classic pcap file (magic {magic.hex()})")
    nano = magic in (b"\x4d\x3c\xb2\xa1", b"\xa1\xb2\x3c\x4d")
    link = struct.unpack_from(endian + "I", blob, 20)[0]
    rec = struct.Struct(endian + "IIII")
    off = PCAP_GLOBAL.size
    while off < len(blob):
        if off + rec.size > len(blob):
            raise ProtocolError(f"{path}: truncated record header at byte {off}")
        sec, frac, incl, _orig = rec.unpack_from(blob, off)
        off += rec.size
        pkt = blob[off : off + incl]
        if len(pkt) != incl:
            raise ProtocolError(f"{path}: truncated packet at byte {off}")
        off += incl
        t = sec + frac * (1e-9 if nano else 1e-6)
        if link == LINKTYPE_ETHERNET:
            if len(pkt) < 14 or struct.unpack_from(">H", pkt, 12)[0] != 0x0800:
                continue
            ip = pkt[14:]
        elif link == 113:  # Linux cooked
            if len(pkt) < 16 or struct.unpack_from(">H", pkt, 14)[0] != 0x0800:
                continue
            ip = pkt[16:]
        elif link in (101, 228):  # raw IPv4
            ip = pkt
        else:
            raise ProtocolError(f"{path}: link type {link} not supported")
        if len(ip) < 20 or ip[0] >> 4 != 4 or ip[9] != 17:
            continue
        ihl = (ip[0] & 0xF) * 4
        total = struct.unpack_from(">H", ip, 2)[0]
        udp = ip[ihl:total]
        if len(udp) < 8:
            continue
        sport, dport, ulen, _ = UDP.unpack_from(udp)
        yield PcapPacket(
            t,
            (str(ipaddress.IPv4Address(ip[12:16])), sport),
            (str(ipaddress.IPv4Address(ip[16:20])), dport),
            bytes(udp[8:ulen]),
        )
