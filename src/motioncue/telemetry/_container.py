"""Raw datagram recordings: the ``.mctr`` container, its writer, reader and the recorder.

File layout (little-endian), version 1::

    magic     8 bytes   b"MCTLMREC"
    version   uint16    1
    meta_len  uint32    length of the metadata that follows
    meta      meta_len bytes of UTF-8 JSON: {"game": "f1", "port": 20777,
              "created_utc": "2026-11-21T11:00:00Z", "writer": "motioncue 0.1.0"}
    records   until end of file, each:
        t_s     float64   receive time, seconds since the recording started
                          (time.perf_counter() differences)
        length  uint32    datagram length in bytes (at most 65507, the UDP payload limit)
        data    length bytes, exactly as received

The datagrams are stored undecoded, so a recording replays through any decoder version and
keeps the packets a decoder skipped. The writer is atomic (:mod:`motioncue._atomic`): it
writes ``.NAME.partial-XXXX`` and renames it to ``NAME`` when the recording ends normally
(Ctrl-C ends a recording normally); an error discards it. A recorder killed by SIGKILL leaves
the partial file, whose last record may be short: the reader (given that file) keeps every
complete record and reports ``truncated_tail``.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import os
import platform
import socket
import struct
import sys
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

from .._atomic import AtomicFile, AtomicFileWriter, StopSignalRecorder
from .._config import read_capped
from .._errors import ConfigError, ProtocolError, TransportError
from ._registry import game_info
from ._sample import TelemetrySample

__all__ = [
    "FILE_HEADER",
    "MAGIC",
    "MAX_DATAGRAM",
    "MAX_RECORDING_BYTES",
    "RECORD_HEADER",
    "VERSION",
    "DatagramRecording",
    "RecordSummary",
    "RecordingWriter",
    "decode_recording",
    "iter_recording_samples",
    "read_recording_file",
    "record",
]

MAGIC = b"MCTLMREC"
VERSION = 1
FILE_HEADER = struct.Struct("<8sHI")
"""magic, version, metadata length."""
RECORD_HEADER = struct.Struct("<dI")
"""receive time (s since start), datagram length."""
MAX_DATAGRAM = 65507
_MAX_META = 1 << 20
MAX_RECORDING_BYTES = 1 << 30
"""Largest recording file :func:`read_recording_file` reads (1 GiB, checked before reading)."""


@dataclass(frozen=True)
class DatagramRecording:
    """A recording file read back.

    Attributes
    ----------
    game : str
        Registered game name the datagrams came from.
    port : int
        UDP port they were received on.
    meta : dict
        The whole metadata header.
    t_s : list of float
        Receive times (s since the recording started), one per datagram.
    datagrams : list of bytes
        The datagrams, as received.
    truncated_tail : bool
        True if the file ended inside a record (recorder killed); that record is dropped.
    """

    game: str
    port: int
    meta: dict[str, object]
    t_s: list[float]
    datagrams: list[bytes]
    truncated_tail: bool = False

    def __len__(self) -> int:
        return len(self.datagrams)


class RecordingWriter(AtomicFileWriter):
    """Write a recording file record by record (context manager; atomic: published by
    :meth:`close` or a normal exit, discarded by :meth:`discard` or an exception).

    Parameters
    ----------
    path : str or os.PathLike
        File to create (overwritten).
    game : str
        Registered game name.
    port : int
        Port the datagrams are received on (metadata only).
    """

    def __init__(self, path: str | os.PathLike[str], game: str, port: int) -> None:
        game_info(game)  # a registered game, else ConfigError naming the registered ones
        from .. import __version__

        meta = {
            "game": game,
            "port": int(port),
            "created_utc": _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%dT%H:%M:%SZ"),
            "writer": f"motioncue {__version__}",
        }
        blob = json.dumps(meta, sort_keys=True).encode()
        self._out = AtomicFile(path, "recording")
        self._out.write(FILE_HEADER.pack(MAGIC, VERSION, len(blob)) + blob)
        self.count = 0
        self.nbytes = 0

    def write(self, t_s: float, datagram: bytes) -> None:
        """Append one datagram received ``t_s`` seconds after the recording started."""
        if len(datagram) > MAX_DATAGRAM:
            raise ProtocolError(f"datagram of {len(datagram)} bytes exceeds {MAX_DATAGRAM}")
        if not math.isfinite(t_s):
            raise ProtocolError(f"receive time {t_s!r} is not finite")
        self._out.write(RECORD_HEADER.pack(t_s, len(datagram)) + datagram)
        self.count += 1
        self.nbytes += len(datagram)


def read_recording_file(path: str | os.PathLike[str]) -> DatagramRecording:
    """Read a recording written by :func:`record` / :class:`RecordingWriter`.

    Raises
    ------
    ProtocolError
        Wrong magic, unsupported version, bad metadata or an impossible record length.
    TransportError
        The file cannot be read.
    """
    name = os.fspath(path)

    def check_head(head: bytes) -> None:
        if len(head) < len(MAGIC):
            raise ProtocolError(f"{name}: {len(head)} bytes is too short for a recording header")
        if head != MAGIC:
            raise ProtocolError(f"{name}: not a motioncue recording (magic {head!r})")

    try:
        blob = read_capped(
            path,
            MAX_RECORDING_BYTES,
            "a recording",
            error=ProtocolError,
            where=name,
            advice="; split it (motioncue record --duration)",
            check_head=check_head,
            head_size=len(MAGIC),
        )
    except OSError as exc:
        raise TransportError(f"cannot read recording {name!r}: {exc}") from exc
    if len(blob) < FILE_HEADER.size:
        raise ProtocolError(f"{name}: {len(blob)} bytes is too short for a recording header")
    magic, version, meta_len = FILE_HEADER.unpack_from(blob)
    if magic != MAGIC:
        raise ProtocolError(f"{name}: not a motioncue recording (magic {magic!r})")
    if version != VERSION:
        raise ProtocolError(f"{name}: recording version {version} unsupported (reads {VERSION})")
    if meta_len > _MAX_META or FILE_HEADER.size + meta_len > len(blob):
        raise ProtocolError(f"{name}: metadata length {meta_len} exceeds the file")
    pos = FILE_HEADER.size
    try:
        meta = json.loads(blob[pos : pos + meta_len].decode())
        game = str(meta["game"])
        port = int(meta["port"])
    except (ValueError, KeyError, TypeError) as exc:
        raise ProtocolError(f"{name}: bad metadata: {exc}") from exc
    pos += meta_len
    times: list[float] = []
    datagrams: list[bytes] = []
    truncated = False
    end = len(blob)
    while pos < end:
        if pos + RECORD_HEADER.size > end:
            truncated = True
            break
        t_s, n = RECORD_HEADER.unpack_from(blob, pos)
        if n > MAX_DATAGRAM or not math.isfinite(t_s):
            raise ProtocolError(f"{name}: corrupt record at byte {pos} (length {n}, t {t_s})")
        pos += RECORD_HEADER.size
        if pos + n > end:
            truncated = True
            break
        times.append(t_s)
        datagrams.append(blob[pos : pos + n])
        pos += n
    return DatagramRecording(game, port, meta, times, datagrams, truncated)


def decode_recording(
    rec: DatagramRecording | str | os.PathLike[str],
) -> tuple[list[TelemetrySample], dict[str, int]]:
    """Decode a whole recording as fast as possible, with the recorded receive times.

    Returns
    -------
    samples : list of TelemetrySample
        The samples in order; ``t_s`` is the recorded receive time.
    stats : dict of str to int
        The decoder's outcome counters.
    """
    from ._registry import decoder_for

    if not isinstance(rec, DatagramRecording):
        rec = read_recording_file(rec)
    dec = decoder_for(rec.game)
    samples = []
    for t_s, data in zip(rec.t_s, rec.datagrams, strict=True):
        s = dec.feed(data, t_s)
        if s is not None:
            samples.append(s)
    return samples, dict(dec.stats)


def iter_recording_samples(rec: DatagramRecording) -> Iterator[TelemetrySample]:
    """Yield the samples of a recording lazily (recorded receive times)."""
    from ._registry import decoder_for

    dec = decoder_for(rec.game)
    for t_s, data in zip(rec.t_s, rec.datagrams, strict=True):
        s = dec.feed(data, t_s)
        if s is not None:
            yield s


@dataclass
class RecordSummary:
    """What :func:`record` did."""

    path: str
    game: str
    host: str
    port: int
    datagrams: int = 0
    nbytes: int = 0
    duration_s: float = 0.0
    stats: dict[str, int] = field(default_factory=dict)


def record(
    source: str,
    out: str | os.PathLike[str],
    seconds: float | None = None,
    *,
    should_stop: Callable[[], bool] | None = None,
    on_ready: Callable[[int], None] | None = None,
    peer_port: int | None = None,
) -> RecordSummary:
    """Record raw datagrams of a game's UDP stream to a file.

    Parameters
    ----------
    source : str
        ``GAME``, ``GAME:PORT`` or ``GAME:HOST:PORT`` (default host 127.0.0.1; use
        ``0.0.0.0`` to receive from another machine or a console).
    out : str or os.PathLike
        Recording file to create.
    seconds : float, optional
        Stop after this long; None records until ``should_stop()`` or a stop signal (Ctrl-C,
        SIGTERM, SIGHUP, SIGQUIT: in the main thread they only end the loop, and the
        recording is published).
    should_stop : callable, optional
        Polled about every 0.1 s; True ends the recording.
    on_ready : callable, optional
        Called with the bound port once the socket listens (port 0 binds a free port).
    peer_port : int, optional
        For a game that must be asked (``ac``, ``gt7``: ``GAME@ADDRESS`` specs): its port,
        default the game's own (tests use stand-in games). The requests are sent from the
        recording socket, as a live source does; they are not recorded.

    Returns
    -------
    RecordSummary
        Datagram count, bytes, duration and the decoder's counters (each datagram is also
        decoded, to report what the recording holds; the file keeps every datagram).
    """
    from ._registry import decoder_for
    from ._source import AUTO, TALK_PERIOD_S, Requester, parse_live_spec, split_peer

    game, host, port = parse_live_spec(source)
    if game == AUTO:
        raise ConfigError(f"source {source!r}: a recording is of one game; name it")
    if seconds is not None and not (math.isfinite(seconds) and seconds > 0):
        raise ConfigError(f"seconds = {seconds!r} must be > 0")
    dec = decoder_for(game)
    asker = dec if isinstance(dec, Requester) else None
    dest = None
    if asker is not None:
        dest = (split_peer(source)[1] or "127.0.0.1",
                int(asker.PEER_PORT if peer_port is None else peer_port))  # fmt: skip
    sock = _bind_udp(host, port)

    def talk(datagrams: list[bytes]) -> None:
        assert dest is not None
        for d in datagrams:
            try:
                sock.sendto(d, dest)
            except OSError:
                pass  # the game is not there yet: asked again on the next round

    bound_port = sock.getsockname()[1]
    receive = _arrival_receiver(sock)  # before anyone is told the port: stamps from the first
    summary = RecordSummary(os.fspath(out), game, host, bound_port)
    buf = bytearray(MAX_DATAGRAM + 1)
    try:
        # a stop signal (Ctrl-C, SIGTERM, a closed terminal) only sets a flag and the loop
        # ends at its top: a handler raising between a record's write and its count
        # published a file with a record more than the summary said
        with StopSignalRecorder() as stops, RecordingWriter(out, game, bound_port) as writer:
            if on_ready is not None:
                on_ready(bound_port)
            t0 = time.perf_counter()
            t_last = t0
            deadline = math.inf if seconds is None else t0 + seconds
            next_talk = t0
            try:
                while not stops.event.is_set():
                    now = time.perf_counter()
                    if now >= deadline or (should_stop is not None and should_stop()):
                        break
                    if asker is not None and now >= next_talk:
                        next_talk = now + TALK_PERIOD_S
                        talk(asker.requests(now - t0))
                    wait = min(0.1 if asker is None else TALK_PERIOD_S, deadline - now)
                    sock.settimeout(max(wait, 1e-3))
                    try:
                        n, t = receive(buf)
                    except TimeoutError:
                        continue
                    t = max(t, t_last)  # stamps never go back (a clock step, mixed sources)
                    t_last = t
                    data = bytes(buf[:n])
                    writer.write(t - t0, data)
                    dec.feed(data, t - t0)
            except KeyboardInterrupt:
                pass
            if asker is not None:
                talk(asker.farewell())
            summary.datagrams = writer.count
            summary.nbytes = writer.nbytes
            summary.duration_s = time.perf_counter() - t0
    finally:
        sock.close()
    summary.stats = dict(dec.stats)
    return summary


# SO_TIMESTAMPNS / SCM_TIMESTAMPNS (Linux's asm-generic value; Python's socket module does
# not name it). Only on the machines whose kernels use the generic value.
_SO_TIMESTAMPNS = 35
_GENERIC_SOCKET_ABI = {"x86_64", "amd64", "i386", "i686", "aarch64", "arm64", "armv7l", "riscv64"}
_TIMESPEC = struct.Struct("@qq")


def _arrival_receiver(sock: socket.socket) -> Callable[[bytearray], tuple[int, float]]:
    """A ``receive(buf) -> (nbytes, t)`` for ``sock``: ``t`` is when the datagram arrived, on
    the :func:`time.perf_counter` clock.

    On Linux the kernel stamps each datagram as it arrives (``SO_TIMESTAMPNS``), so a recorder
    that a busy machine holds up still records the game's own timing; elsewhere, or if the
    kernel gives no stamp, the time the datagram was read. A stamp more than 1 s old or from
    the future (the wall clock stepped) falls back to the read time.
    """
    stamped = False
    if sys.platform == "linux" and platform.machine().lower() in _GENERIC_SOCKET_ABI:
        try:
            sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
            stamped = True
        except OSError:
            stamped = False
    if not stamped:

        def read(buf: bytearray) -> tuple[int, float]:
            n = sock.recv_into(buf)
            return n, time.perf_counter()

        return read

    anc = socket.CMSG_SPACE(_TIMESPEC.size)

    def read_stamped(buf: bytearray) -> tuple[int, float]:
        n, ancdata, _flags, _addr = sock.recvmsg_into([buf], anc)
        now = time.perf_counter()
        now_wall_ns = time.time_ns()
        for level, kind, data in ancdata:
            if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(data) >= 16:
                sec, nsec = _TIMESPEC.unpack_from(data)
                age_s = (now_wall_ns - (sec * 1_000_000_000 + nsec)) / 1e9
                if 0.0 <= age_s <= 1.0:
                    return n, now - age_s
        return n, now

    return read_stamped


def _bind_udp(host: str, port: int) -> socket.socket:
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 20)
        sock.bind((host, port))
    except OSError as exc:
        sock.close()
        raise TransportError(f"cannot listen on udp://{host}:{port}: {exc}") from exc
    return sock
