"""Transports: pcap read back by an independent reader (dpkt), raw files, UDP request/reply."""

from __future__ import annotations

import socket
import struct
import threading

import dpkt
import pytest

from motioncue import ConfigError, MotioncueError, TransportError
from motioncue.output import (
    FileTransport,
    PcapTransport,
    UdpTransport,
    load_controller,
    mbox,
    open_transport,
    read_pcap,
)
from motioncue.output._transports_file import internet_checksum


def _frames(n=5):
    enc = load_controller("mbox6").frame_encoder()
    return [(0.02 * k, enc.encode(0.02 * k, [k, -k, 2 * k, 3, 4, 5])[0]) for k in range(n)]


def test_pcap_opens_in_dpkt_with_correct_headers_and_frame_times(tmp_path):
    path = tmp_path / "run.pcap"
    frames = _frames()
    with open_transport(f"pcap:{path}", epoch_s=1_700_000_000.0) as tr:
        for t, data in frames:
            tr.send(data, t_s=t)
    with open(path, "rb") as fh:
        reader = dpkt.pcap.Reader(fh)
        assert reader.datalink() == dpkt.pcap.DLT_EN10MB
        packets = list(reader)
    assert len(packets) == len(frames)
    for (ts, buf), (t, data) in zip(packets, frames, strict=True):
        assert ts == pytest.approx(1_700_000_000.0 + t, abs=1e-6)
        eth = dpkt.ethernet.Ethernet(buf)
        ip = eth.data
        assert isinstance(ip, dpkt.ip.IP) and ip.p == dpkt.ip.IP_PROTO_UDP
        assert socket.inet_ntoa(ip.src) == "192.168.15.101"
        assert socket.inet_ntoa(ip.dst) == "192.168.15.201"
        udp = ip.data
        assert (udp.sport, udp.dport) == (8410, 7408)
        assert udp.data == data and udp.ulen == 8 + len(data) and ip.len == 28 + len(data)
        # dpkt recomputes the IPv4 header checksum when it is zeroed
        stored = ip.sum
        ip.sum = 0
        assert dpkt.ip.IP(bytes(ip)).sum == stored
        # and the UDP checksum over the pseudo-header
        pseudo = ip.src + ip.dst + struct.pack(">BBH", 0, 17, udp.ulen)
        assert internet_checksum(pseudo + bytes(udp)) == 0


def test_our_reader_reads_what_dpkt_writes(tmp_path):
    path = tmp_path / "dpkt.pcap"
    payload = mbox.RegisterWrite(0, 0x90, (1,)).encode()
    udp = dpkt.udp.UDP(sport=8410, dport=7408, data=payload)
    udp.ulen = 8 + len(payload)
    ip = dpkt.ip.IP(
        src=socket.inet_aton("10.0.0.1"),
        dst=socket.inet_aton("10.0.0.2"),
        p=dpkt.ip.IP_PROTO_UDP,
        data=udp,
    )
    ip.len = 20 + udp.ulen
    eth = dpkt.ethernet.Ethernet(src=b"\x02" * 6, dst=b"\x04" * 6, type=0x0800, data=ip)
    with open(path, "wb") as fh:
        w = dpkt.pcap.Writer(fh)
        w.writepkt(bytes(eth), ts=12.5)
    (pkt,) = list(read_pcap(path))
    assert pkt.payload == payload and pkt.src == ("10.0.0.1", 8410) and pkt.t_s == 12.5


def test_pcap_addresses_can_be_set(tmp_path):
    path = tmp_path / "b.pcap"
    with PcapTransport(
        path, src="169.254.88.22:8410", dst=("255.255.255.255", 7408), epoch_s=0.0
    ) as tr:
        tr.send(b"\x55\xaa" + bytes(16), t_s=1.5)
    (pkt,) = list(read_pcap(path))
    assert pkt.dst == ("255.255.255.255", 7408) and pkt.t_s == 1.5
    with pytest.raises(ConfigError):
        PcapTransport(tmp_path / "c.pcap", dst="999.1.1.1:7")


def test_file_transport_writes_raw_bytes_and_splits_back(tmp_path):
    path = tmp_path / "raw.bin"
    frames = _frames(4)
    write = mbox.RegisterWrite(mbox.CHANNEL_CX, 1, (0x3,)).encode()
    with open_transport(f"file:{path}") as tr:
        assert isinstance(tr, FileTransport)
        for _, data in frames:
            tr.send(data)
        tr.send(write)
    blob = path.read_bytes()
    assert blob == b"".join(d for _, d in frames) + write
    assert mbox.split_stream(blob) == [d for _, d in frames] + [write]


def test_os_errors_become_transport_errors(tmp_path):
    with pytest.raises(TransportError) as info:
        open_transport(f"pcap:{tmp_path}/missing/dir/x.pcap")
    assert isinstance(info.value.__cause__, OSError)
    with pytest.raises(TransportError):
        open_transport(f"file:{tmp_path}/missing/x.bin")
    with pytest.raises(TransportError):
        UdpTransport("127.0.0.1", 9, local_port=_busy_port())


def _busy_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("", 0))
    _busy_port.keep = s  # type: ignore[attr-defined]
    return s.getsockname()[1]


def test_bad_urls_are_config_errors():
    for url in ("tcp://x:1", "udp://nohost", "pcap:", "nothing"):
        with pytest.raises(ConfigError):
            open_transport(url)
    with pytest.raises(ConfigError, match="retries"):
        open_transport("udp://127.0.0.1:9?retries=x")
    # serial:// belongs to the EasySmc work: absent -> ConfigError, present -> no such port
    with pytest.raises(MotioncueError):
        open_transport("serial:///dev/motioncue-no-such-port?baud=19200")


class _Peer:
    """A UDP peer on loopback answering the n-th datagram it receives (0-based)."""

    def __init__(self, answer_from: int) -> None:
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.sock.bind(("127.0.0.1", 0))
        self.sock.settimeout(2.0)
        self.port = self.sock.getsockname()[1]
        self.got: list[bytes] = []
        self.answer_from = answer_from
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def run(self) -> None:
        try:
            while len(self.got) < 5:
                data, peer = self.sock.recvfrom(1024)
                self.got.append(data)
                if len(self.got) > self.answer_from:
                    self.sock.sendto(b"noise", peer)  # not accepted by the predicate
                    self.sock.sendto(b"reply:" + data, peer)
                    return
        except OSError:
            return


def test_request_retries_until_a_reply_is_accepted():
    peer = _Peer(answer_from=2)  # ignore the first two attempts
    with open_transport(f"udp://127.0.0.1:{peer.port}?timeout_ms=100&retries=3") as tr:
        reply = tr.request(b"ping", lambda r: r.startswith(b"reply:"))
    assert reply == b"reply:ping" and peer.got == [b"ping"] * 3


def test_request_gives_up_with_transport_error():
    peer = _Peer(answer_from=99)
    with UdpTransport("127.0.0.1", peer.port, timeout_s=0.05, retries=1) as tr:
        with pytest.raises(TransportError, match="after 2 attempt"):
            tr.request(b"ping", lambda r: True)
    peer.thread.join(0.5)
    assert peer.got == [b"ping", b"ping"]


def test_url_query_wins_over_keyword_options():
    with open_transport("udp://127.0.0.1:9?timeout_ms=40", timeout_s=2.0, retries=0) as tr:
        assert isinstance(tr, UdpTransport) and tr.timeout_s == 0.04 and tr.retries == 0
    with pytest.raises(ConfigError, match="unknown option"):
        open_transport("udp://127.0.0.1:9", colour="red")
