"""A snapshot slot in memory shared by the job's process and the monitor's server process.

The job's frame loop publishes the monitor's snapshot here at the end of a frame, in its own
time (:meth:`SnapshotSlot.publish`), when the server has asked for one
(:meth:`SnapshotSlot.request`); the server polls the slot (:meth:`SnapshotSlot.read`). So
nothing in the job's process wakes when a page asks: a thread woken by a request would take
the interpreter lock at any moment, also just before a frame's deadline (measured: such a
frame goes out about 0.3-1.1 ms late; ``benchmarks/bench_monitor.py``).

One writer per field, no lock: the job writes the snapshot under a sequence counter (odd
while it writes, the *seqlock*), and with it a CRC-32 of the answered request number, the
length and the bytes. A reader copies the snapshot and keeps it only when the counter was
even and unchanged around the copy *and* the checksum matches, else it tries again: a torn
snapshot is never returned, even where the processor reorders stores (the checksum). The
writer never waits for the reader, so a dead or stopped server cannot hold up the loop.

The memory is an anonymous file (``memfd`` on Linux, else an unlinked temporary file) whose
descriptor is passed to the server process like the monitor's sockets. Not
:mod:`multiprocessing.shared_memory`: it needs a name, and on Python < 3.13 a process that
attaches registers the segment with a resource tracker of its own, which unlinks it when that
process ends (python/cpython#82300). The kernel frees an anonymous file once both processes
have closed it, also after a kill.

Layout (little-endian unsigned 64-bit words, then the payload):

====  =========================================  ==========
word  meaning                                    written by
====  =========================================  ==========
0     sequence counter (odd: a write under way)   job
1     the request number the snapshot answers     job
2     payload length (bytes)                      job
3     CRC-32 of words 1-2 and the payload         job
4     1 while a loop publishes, else 0            job
5     the newest request number                   server
6, 7  the server's snapshot and error counters    server
====  =========================================  ==========
"""

from __future__ import annotations

import mmap
import os
import struct
import tempfile
import time
import zlib

__all__ = ["SnapshotSlot", "TornSlot"]

_HEADER_B = 64
_WORD = struct.Struct("<Q")
_BODY = struct.Struct("<QQQ")  # answers, length, checksum
_COUNTS = struct.Struct("<QQ")
_SEQ, _ANSWERS, _LIVE, _REQUEST, _COUNTS_AT = 0, 8, 32, 40, 48
DEFAULT_CAPACITY_B = 1 << 16
"""Payload bytes a slot holds (a monitor snapshot pickles to about 1 kB)."""


class TornSlot(Exception):
    """No consistent snapshot could be read within the tries (the writer kept writing)."""


def _checksum(answers: int, data: bytes | memoryview) -> int:
    return zlib.crc32(data, zlib.crc32(_COUNTS.pack(answers, len(data))))


class SnapshotSlot:
    """One snapshot (bytes) in shared memory; see the module docstring for the protocol.

    Parameters
    ----------
    fd : int
        An open file descriptor of the shared file (this object owns it).
    capacity_b : int
        Payload bytes the slot holds (the file is ``64 + capacity_b`` bytes).
    """

    def __init__(self, fd: int, capacity_b: int) -> None:
        if capacity_b < 1:
            raise ValueError(f"capacity_b = {capacity_b!r} is invalid; allowed: >= 1")
        self._fd = fd
        self.capacity_b = int(capacity_b)
        self._map = mmap.mmap(fd, _HEADER_B + self.capacity_b)
        self._seq = _WORD.unpack_from(self._map, _SEQ)[0] & ~1

    @classmethod
    def create(cls, capacity_b: int = DEFAULT_CAPACITY_B) -> SnapshotSlot:
        """A new, zeroed slot (no snapshot, no request, not live)."""
        if capacity_b < 1:
            raise ValueError(f"capacity_b = {capacity_b!r} is invalid; allowed: >= 1")
        memfd = getattr(os, "memfd_create", None)
        if memfd is not None:
            fd = memfd("motioncue-monitor")
        else:  # pragma: no cover - not Linux
            f = tempfile.TemporaryFile()
            fd = os.dup(f.fileno())
            f.close()
        os.ftruncate(fd, _HEADER_B + capacity_b)
        slot = cls(fd, capacity_b)
        slot.publish(0, b"")  # a valid empty snapshot: a reader never sees zeroed memory as torn
        return slot

    def fileno(self) -> int:
        return self._fd

    def close(self) -> None:
        """Unmap and close the descriptor (idempotent; a write after this raises ValueError)."""
        if not self._map.closed:
            self._map.close()
        if self._fd >= 0:
            os.close(self._fd)
            self._fd = -1

    # ------------------------------------------------------------------ the job (writer)
    def publish(self, answers: int, data: bytes) -> None:
        """Write ``data`` as the answer to request ``answers``; never waits.

        Raises
        ------
        ValueError
            ``data`` is longer than :attr:`capacity_b` (nothing written), or the slot is closed.
        """
        n = len(data)
        if n > self.capacity_b:
            raise ValueError(f"snapshot of {n} bytes; the slot holds {self.capacity_b}")
        m = self._map
        seq = self._seq + 1
        _WORD.pack_into(m, _SEQ, seq)  # odd: a reader now retries
        m[_HEADER_B : _HEADER_B + n] = data
        _BODY.pack_into(m, _ANSWERS, answers, n, _checksum(answers, data))
        _WORD.pack_into(m, _SEQ, seq + 1)
        self._seq = seq + 1

    def set_live(self, live: bool) -> None:
        """Say whether a loop answers requests through the slot (the server asks over its
        pipe otherwise)."""
        _WORD.pack_into(self._map, _LIVE, 1 if live else 0)

    def requested(self) -> int:
        """The newest request number the server wrote (0: none yet)."""
        return int(_WORD.unpack_from(self._map, _REQUEST)[0])

    def server_counts(self) -> tuple[int, int]:
        """The server's counters ``(snapshots made, errors)`` as of its newest request."""
        s, e = _COUNTS.unpack_from(self._map, _COUNTS_AT)
        return int(s), int(e)

    # ------------------------------------------------------------------ the server (reader)
    @property
    def live(self) -> bool:
        return bool(_WORD.unpack_from(self._map, _LIVE)[0])

    def request(self, snapshots: int = 0, errors: int = 0) -> int:
        """Ask for a snapshot (the counters go with it); returns the request's number."""
        m = self._map
        _COUNTS.pack_into(m, _COUNTS_AT, snapshots, errors)
        req = int(_WORD.unpack_from(m, _REQUEST)[0]) + 1
        _WORD.pack_into(m, _REQUEST, req)
        return req

    def read(self, tries: int = 1000) -> tuple[int, bytes]:
        """The newest snapshot as ``(request number it answers, bytes)``; ``(0, b"")``
        before the first.

        Raises
        ------
        TornSlot
            Every one of ``tries`` copies was torn (the writer wrote throughout).
        """
        m = self._map
        for _ in range(tries):
            s1 = _WORD.unpack_from(m, _SEQ)[0]
            if not s1 & 1:
                answers, n, crc = _BODY.unpack_from(m, _ANSWERS)
                if n <= self.capacity_b:
                    data = m[_HEADER_B : _HEADER_B + n]
                    if _WORD.unpack_from(m, _SEQ)[0] == s1 and _checksum(answers, data) == crc:
                        return int(answers), data
            time.sleep(0)  # let the writer finish
        raise TornSlot(f"no consistent snapshot in {tries} reads")
