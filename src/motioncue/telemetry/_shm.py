"""Telemetry received and decoded in its own process, read through shared memory.

The bridge's frame loop is a Python thread: while another thread of its process holds the
GIL (the telemetry receiver decoding a 1.3 kB F1 packet, a recorder writing a file) the loop
cannot run, whatever its deadline. :class:`SharedMemorySource` moves the receiver and the
decoder into a child process; the newest sample crosses over in a
:mod:`multiprocessing.shared_memory` block guarded by a sequence counter (a seqlock: the
writer makes the counter odd, writes, makes it even; a reader retries while the counter is
odd or changed under it), so the loop's :meth:`~SharedMemorySource.latest` never blocks and
never waits for the child.

Signals: a closing terminal sends SIGHUP (Ctrl-\\ SIGQUIT, Ctrl-C SIGINT; ``kill -TERM -PGID``
SIGTERM) to the whole process group. The parent parks and then closes the child, so the
child ignores these four,
and the :mod:`multiprocessing` resource tracker (a helper process that would otherwise die
of SIGHUP and, relaunched, print a warning and a ``KeyError`` traceback per shared object)
is started with them blocked (:func:`_shielded`). :meth:`SharedMemorySource.close` kills a
child that does not stop by itself (SIGKILL).

Failure handling: the child ends when the parent process ends (it polls its parent every
50 ms) or on :meth:`~SharedMemorySource.close`; if the child dies, ``latest()`` keeps the
last sample, whose age grows until the bridge's gate fades out and parks (a lost link), and
``stats`` reports ``note: telemetry process ended`` and ``receive errors``.

Block layout (native order, float64 / int64 words): ``[seq, t_s, f0, f1, f2, w0, w1, w2,
paused, game index, datagrams, samples, receive errors, stats seq, stats length]`` then a
2 KiB JSON object of the decoder's counters, refreshed about 5 times a second.
"""

from __future__ import annotations

import contextlib
import json
import math
import multiprocessing as mp
import os
import signal
import struct
import time
from collections.abc import Iterator
from multiprocessing import resource_tracker, shared_memory
from multiprocessing.connection import Connection
from multiprocessing.synchronize import Event

from .._atomic import STOP_SIGNALS
from .._errors import ConfigError, MotioncueError
from ._sample import TelemetrySample

__all__ = ["SharedMemorySource"]

_WORDS = struct.Struct("=q7dqqqqqqq")  # seq, t, f(3), w(3), paused, game, d, s, e, sseq, slen
_JSON_AT = _WORDS.size
_JSON_MAX = 2048
_SIZE = _JSON_AT + _JSON_MAX
_SAMPLE = struct.Struct("=q7dqq")  # the sample part: seq .. game
_FIELDS = struct.Struct("=7dqq")  # the sample after seq: t, f, w, paused, game


_GROUP_SIGNALS: tuple[signal.Signals, ...] = STOP_SIGNALS
"""Signals a terminal sends to the whole process group; the helper processes ignore them."""


@contextlib.contextmanager
def _shielded() -> Iterator[None]:
    """Block :data:`_GROUP_SIGNALS` in this thread while the block runs, so that a process
    started in it is born with them blocked (the mask survives ``exec``); a signal arriving
    meanwhile is delivered to this process when the block ends."""
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _GROUP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


def _view(shm: shared_memory.SharedMemory) -> memoryview:
    buf = shm.buf
    if buf is None:  # closed
        raise MotioncueError("the telemetry shared-memory block is closed")
    return buf


def _publish(buf: memoryview, seq: int, s: TelemetrySample, games: list[str]) -> int:
    """Write sample ``s`` into the block under the sequence counter; returns the new (even)
    counter. ``seq`` is the current (even) counter; only one writer may call this."""
    struct.pack_into("=q", buf, 0, seq + 1)  # odd: writing
    g = games.index(s.game) if s.game in games else -1
    _FIELDS.pack_into(buf, 8, s.t_s, *s.f, *s.w, int(s.paused), g)
    struct.pack_into("=q", buf, 0, seq + 2)  # even: done
    return seq + 2


def _read(buf: memoryview, known_seq: int, games: list[str]) -> tuple[int, TelemetrySample] | None:
    """The sample in the block if its counter is even and differs from ``known_seq``;
    None when nothing new or when written meanwhile (a torn read is never returned)."""
    seq = struct.unpack_from("=q", buf, 0)[0]
    if seq == known_seq or seq & 1:
        return None
    v = _FIELDS.unpack_from(buf, 8)
    if struct.unpack_from("=q", buf, 0)[0] != seq:
        return None
    g = int(v[8])
    game = games[g] if 0 <= g < len(games) else "unknown"
    return seq, TelemetrySample(v[0], (v[1], v[2], v[3]), (v[4], v[5], v[6]), bool(v[7]), game)


def _child(
    spec: str,
    name: str,
    port_conn: Connection,
    stop: Event,
    parent_pid: int,
    games: list[str],
    modules: list[str],
) -> None:
    """Receive and decode in this process; publish the newest sample and the counters.

    ``games`` is the parent's list of registered games (the block carries a sample's game as
    an index in it); ``modules`` are the modules that registered them, imported here first,
    so that a game registered outside the package (a plugin) decodes in this process too.
    """
    import importlib

    from . import open_source

    # Ctrl-C, a closed terminal (SIGHUP), Ctrl-\\ and a group SIGTERM reach this child: the
    # parent parks and then closes this child. Born with them blocked (_shielded): ignore,
    # then unblock (a pending one is dropped).
    for sig in _GROUP_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, _GROUP_SIGNALS)
    shm = shared_memory.SharedMemory(name=name)
    buf = _view(shm)
    try:
        try:
            for module in modules:  # a spawned child starts with the package's games only
                importlib.import_module(module)
            src = open_source(spec)
        except MotioncueError as exc:
            port_conn.send(("error", (type(exc).__name__, str(exc))))
            return
        except ImportError as exc:
            port_conn.send(("error", ("ConfigError", f"cannot import a game's module: {exc}")))
            return
        port_conn.send(("port", src.port))  # 0 for a replay or a source on several ports
        seq = [0]
        view = [buf]  # emptied before the block is closed

        def publish(sample: TelemetrySample) -> None:  # on the receiver thread, at once
            if view:
                seq[0] = _publish(view[0], seq[0], sample, games)

        src.on_sample = publish
        first = src.latest()  # one that came before the hook (published twice at worst)
        if first is not None:
            publish(first)
        next_stats = 0.0
        sseq = 0
        try:
            # the samples are published by the receiver thread as they come; this loop only
            # refreshes the counters (20 Hz) and the stats text (5 Hz), so the child wakes
            # rarely and leaves the cores to the frame loop
            while not stop.is_set() and os.getppid() == parent_pid:
                now = time.perf_counter()
                st = src.stats
                struct.pack_into(
                    "=qqq", buf, _SAMPLE.size, st["datagrams"], st["samples"],
                    st["receive errors"],
                )  # fmt: skip
                if now >= next_stats:
                    next_stats = now + 0.2
                    blob = json.dumps(st).encode()[:_JSON_MAX]
                    sseq += 1
                    struct.pack_into("=q", buf, _SAMPLE.size + 24, sseq)
                    buf[_JSON_AT : _JSON_AT + len(blob)] = blob
                    sseq += 1
                    struct.pack_into("=qq", buf, _SAMPLE.size + 24, sseq, len(blob))
                # not stop.wait(): a child killed while waiting on the Event would leave its
                # condition expecting a waker, and the parent's stop.set() would hang
                time.sleep(0.05)
        finally:
            src.close()
            src.on_sample = None
            view.clear()
    finally:
        del buf
        shm.close()


class SharedMemorySource:
    """A telemetry source (``open_source`` spec) running in a child process.

    Same reading interface as :class:`~motioncue.telemetry.TelemetrySource`: ``latest()``,
    ``stats``, ``port``, ``finished``, ``close()``. The child's receiver thread publishes
    each sample as soon as it is decoded (no polling: the child does not wake 5000 times a
    second beside the frame loop); the counters and ``stats`` are refreshed at 20 Hz.

    Parameters
    ----------
    spec : str
        As for :func:`motioncue.telemetry.open_source` (``"f1:127.0.0.1:0"``...).
    start_timeout_s : float
        How long to wait for the child to bind its socket, in (0, 60].
    """

    def __init__(self, spec: str, *, start_timeout_s: float = 20.0) -> None:
        if not (math.isfinite(start_timeout_s) and 0 < start_timeout_s <= 60):
            raise ConfigError(
                f"start_timeout_s = {start_timeout_s!r} is invalid; allowed: (0, 60] s"
            )
        from . import GAMES

        self._games = sorted(GAMES)
        modules = sorted({getattr(GAMES[g].decoder, "__module__", "") for g in self._games} - {""})
        with _shielded():  # the tracker keeps the blocked mask: a closed terminal spares it
            resource_tracker.ensure_running()
        self._shm = shared_memory.SharedMemory(create=True, size=_SIZE)
        self._buf = _view(self._shm)
        self._buf[:_SIZE] = bytes(_SIZE)
        ctx = mp.get_context("spawn")
        self._stop = ctx.Event()
        parent, child = ctx.Pipe(duplex=False)
        self._proc = ctx.Process(
            target=_child,
            args=(spec, self._shm.name, child, self._stop, os.getpid(), self._games, modules),
            name="motioncue-telemetry",
            daemon=True,
        )
        with _shielded():
            self._proc.start()
        child.close()
        self._last: TelemetrySample | None = None
        self._seq = 0
        self._stats: dict[str, int] = {}
        self._closed = False
        try:
            if not parent.poll(start_timeout_s):
                raise MotioncueError(
                    f"telemetry process for {spec!r} did not start within {start_timeout_s} s"
                )
            kind, value = parent.recv()
        except (EOFError, OSError) as exc:
            self.close()
            raise MotioncueError(f"telemetry process for {spec!r} ended at start") from exc
        except BaseException:
            self.close()
            raise
        if kind == "error":
            self.close()
            from .. import _errors

            cls_name, message = value
            cls = getattr(_errors, cls_name, MotioncueError)
            if not (isinstance(cls, type) and issubclass(cls, MotioncueError)):
                cls = MotioncueError
            raise cls(message)
        self.port: int = int(value)
        from ._source import parse_live_spec

        self.game, self.host = parse_live_spec(spec)[:2]

    def latest(self) -> TelemetrySample | None:
        """The newest sample (or None); never blocks (a torn read keeps the previous one)."""
        if self._closed:
            return self._last
        for _ in range(3):
            got = _read(self._buf, self._seq, self._games)
            if got is not None:
                self._seq, self._last = got
                break
            if struct.unpack_from("=q", self._buf, 0)[0] == self._seq:
                break  # nothing new
        return self._last

    @property
    def stats(self) -> dict[str, int]:
        """The child's counters (``datagrams``, ``samples``, ``receive errors``, the decoder's)."""
        if self._closed:
            return dict(self._stats)
        buf = self._buf
        d, s, e, sseq, slen = struct.unpack_from("=qqqqq", buf, _SAMPLE.size)
        if not sseq & 1 and 0 < slen <= _JSON_MAX:
            try:
                blob = json.loads(bytes(buf[_JSON_AT : _JSON_AT + slen]))
                if struct.unpack_from("=q", buf, _SAMPLE.size + 24)[0] == sseq:
                    self._stats = {str(k): int(v) for k, v in blob.items()}
            except (ValueError, TypeError):
                pass
        self._stats.update({"datagrams": d, "samples": s, "receive errors": e})
        out = dict(self._stats)
        if not self._closed and not self._proc.is_alive():
            out["note: telemetry process ended"] = 1
            out["receive errors"] = e + 1
        return out

    @property
    def running(self) -> bool:
        return self._proc.is_alive()

    @property
    def finished(self) -> bool:
        """Always False: a live receiver may get datagrams at any time."""
        return False

    def close(self) -> None:
        """Stop the child and free the shared memory. Idempotent."""
        if self._closed:
            return
        self._closed = True
        self._stop.set()
        self._proc.join(3.0)
        if self._proc.is_alive():
            self._proc.kill()  # it ignores SIGTERM (a group signal is the parent's to act on)
            self._proc.join(2.0)
        del self._buf
        self._shm.close()
        try:
            self._shm.unlink()
        except FileNotFoundError:
            pass

    def __enter__(self) -> SharedMemorySource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def __repr__(self) -> str:
        return (
            f"SharedMemorySource({self.game!r}, udp://{self.host}:{self.port}, "
            f"running={self.running})"
        )
