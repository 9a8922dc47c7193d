"""A stop signal during a write that must not be cut is handled right after it.

A stop signal's handler that raises (``KeyboardInterrupt``, :class:`Interrupted`) at an
arbitrary bytecode of a library that is not written for it (zipfile inside numpy's
``savez_compressed``, a file created but not yet armed for removal, a record written but not
yet counted) leaves a broken state behind: a ``ValueError`` traceback, a temporary file, a
count that disagrees with the file. While such a write runs, the handlers only record the
signal; it is raised again right after (:func:`motioncue._atomic.stop_signals_deferred`).

Blocking the signals in the writing thread (``pthread_sigmask``, tried before) is no such
guarantee in a process with more threads (a pytest-xdist worker, a BLAS pool): the kernel
hands a process-directed signal to a thread that has it unblocked and Python runs the handler
in the main thread all the same. Each test therefore sends the signal both to the process and
to another of its threads (what the kernel may do), deterministically.
"""

from __future__ import annotations

import os
import signal
import socket
import threading
import zipfile
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np
import pytest

import motioncue._atomic as atomic
from motioncue._atomic import (
    PARTIAL_MARK,
    Interrupted,
    atomic_write_bytes,
    interrupt_on_stop_signals,
)

WAYS = ["to the process", "to another thread"]


class SignalSender:
    """Sends a signal to this process (``os.kill``: on Linux the main thread takes it at once
    when it does not block it) or to a helper thread of it (``pthread_kill`` from that thread
    to itself: its C-level handler has run when :meth:`send` returns, and Python runs the
    signal's handler in the main thread at its next check, as it does for a process-directed
    signal the kernel handed to another thread)."""

    def __init__(self, way: str) -> None:
        self.way = way
        self.sent: list[int] = []
        self._todo: list[int] = []
        self._go = threading.Event()
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        if way == "to another thread":
            self._thread.start()  # before any section: it does not block the signals

    def _run(self) -> None:
        self._go.wait()
        if self._todo:
            signal.pthread_kill(threading.get_ident(), self._todo[0])
        self._done.set()

    def send(self, sig: int) -> None:
        self.sent.append(sig)
        if self.way == "to the process":
            os.kill(os.getpid(), sig)
            return
        assert not self._todo, "one signal per sender"
        self._todo.append(sig)
        self._go.set()
        assert self._done.wait(10.0), "the helper thread did not send the signal"

    def close(self) -> None:
        self._go.set()
        if self._thread.is_alive():
            self._thread.join(10.0)


@pytest.fixture(params=WAYS)
def sender(request: pytest.FixtureRequest) -> Iterator[SignalSender]:
    s = SignalSender(request.param)
    try:
        yield s
    finally:
        s.close()


@pytest.fixture()
def handler_log() -> Iterator[list[str]]:
    """SIGHUP raises :class:`Interrupted` (as under the command line) and logs that it ran;
    the previous handler is restored after the test."""
    log: list[str] = []

    def stop(signum: int, frame: FrameType | None) -> None:
        log.append("handler")
        raise Interrupted("SIGHUP")

    previous = signal.signal(signal.SIGHUP, stop)
    try:
        yield log
    finally:
        signal.signal(signal.SIGHUP, previous)


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_a_signal_while_the_temporary_file_is_created_leaves_nothing(
    sender: SignalSender, handler_log: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The temporary file exists once ``mkstemp`` returns, before anything that removes it on
    an exception is armed: a handler raising there left ``.x.partial-...`` behind."""
    real_mkstemp = atomic.tempfile.mkstemp

    def mkstemp_then_signal(*args: Any, **kw: Any) -> tuple[int, str]:
        made = real_mkstemp(*args, **kw)
        sender.send(signal.SIGHUP)
        return made

    monkeypatch.setattr(atomic.tempfile, "mkstemp", mkstemp_then_signal)
    with pytest.raises(Interrupted):
        atomic_write_bytes(tmp_path / "x", b"data")
    assert sender.sent == [signal.SIGHUP]
    assert handler_log == ["handler"]
    assert _leftovers(tmp_path) == []


def test_a_signal_while_a_file_is_written_discards_it_after_the_write(
    sender: SignalSender, handler_log: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    events: list[str] = []
    real_write = atomic.AtomicFile.write

    def write_with_signal(self: atomic.AtomicFile, data: bytes) -> None:
        sender.send(signal.SIGHUP)
        real_write(self, data)
        events.append("written")

    monkeypatch.setattr(atomic.AtomicFile, "write", write_with_signal)
    with pytest.raises(Interrupted):
        atomic_write_bytes(tmp_path / "x", b"data")
    assert events + handler_log == ["written", "handler"]
    assert _leftovers(tmp_path) == []


def test_a_flag_only_handler_gets_the_signal_and_the_file_is_written(
    sender: SignalSender, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Under a handler that only records (a park in progress), the signal reaches it after
    the write and the file is published whole."""
    from motioncue.pipeline._signals import SignalGuard

    real_write = atomic.AtomicFile.write

    def write_with_signal(self: atomic.AtomicFile, data: bytes) -> None:
        sender.send(signal.SIGTERM)
        real_write(self, data)

    monkeypatch.setattr(atomic.AtomicFile, "write", write_with_signal)
    with SignalGuard() as guard:
        atomic_write_bytes(tmp_path / "x", b"data")
        assert guard.received == [signal.SIGTERM]
    assert (tmp_path / "x").read_bytes() == b"data"
    assert _leftovers(tmp_path) == ["x"]


def test_an_ignored_signal_stays_ignored_and_handlers_come_back(
    sender: SignalSender, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``nohup`` ignores SIGHUP: a deferral must not turn it into a stop (nor lose the file),
    and every handler is the one before once the write is done."""
    real_write = atomic.AtomicFile.write

    def write_with_signal(self: atomic.AtomicFile, data: bytes) -> None:
        sender.send(signal.SIGHUP)
        real_write(self, data)

    monkeypatch.setattr(atomic.AtomicFile, "write", write_with_signal)
    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with interrupt_on_stop_signals():
            signal.signal(signal.SIGHUP, signal.SIG_IGN)
            before = {s: signal.getsignal(s) for s in atomic.STOP_SIGNALS}
            atomic_write_bytes(tmp_path / "x", b"data")
            assert {s: signal.getsignal(s) for s in atomic.STOP_SIGNALS} == before
    finally:
        signal.signal(signal.SIGHUP, previous)
    assert (tmp_path / "x").read_bytes() == b"data"


def test_a_deferred_signal_is_raised_again_in_the_order_received() -> None:
    """Signals received during a deferral reach the handlers in force before it, in order,
    right after it (not before: the block's last statement ran)."""
    log: list[str] = []

    def record(signum: int, frame: FrameType | None) -> None:
        log.append(signal.Signals(signum).name)

    old = {s: signal.signal(s, record) for s in (signal.SIGTERM, signal.SIGHUP)}
    try:
        with atomic.stop_signals_deferred() as held:
            os.kill(os.getpid(), signal.SIGTERM)
            os.kill(os.getpid(), signal.SIGHUP)
            log.append("block done")
        assert held.received == [signal.SIGTERM, signal.SIGHUP]
        assert log == ["block done", "SIGTERM", "SIGHUP"]
    finally:
        for s, h in old.items():
            signal.signal(s, h)


@pytest.mark.parametrize("when", ["entering", "leaving"])
def test_a_handler_raising_while_handlers_are_swapped_leaves_the_previous_ones(
    when: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``signal.signal`` first runs the handlers of pending signals, before it swaps: one that
    raises there (stood in for here) must not leave a recorder installed for good, which
    would swallow every later Ctrl-C."""
    real_signal = signal.signal
    armed = [when == "entering"]
    swaps: list[int] = []

    def pending_handler_raises(sig: int, handler: Any) -> Any:
        swaps.append(sig)
        if armed[0] and (when == "leaving" or len(swaps) == 2):
            armed[0] = False
            raise Interrupted("SIGTERM")  # as the pending signal's handler would, unswapped
        return real_signal(sig, handler)

    before = {s: signal.getsignal(s) for s in atomic.STOP_SIGNALS}
    monkeypatch.setattr(signal, "signal", pending_handler_raises)
    with pytest.raises(Interrupted):
        with atomic.stop_signals_deferred():
            armed[0] = True
    monkeypatch.undo()
    assert not armed[0]
    assert {s: signal.getsignal(s) for s in atomic.STOP_SIGNALS} == before


# --- record: a record and its count go together ----------------------------------------------


def test_a_stop_signal_while_record_writes_keeps_the_count_and_the_file_together(
    sender: SignalSender, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """SIGTERM ends a recording normally (as Ctrl-C does). One arriving while a datagram was
    written raised between the write and its count: the published file held a record more
    than the summary said. Now the signal ends the loop at its top."""
    from motioncue.telemetry._container import read_recording_file, record

    out = tmp_path / "r.mctr"
    real_write = atomic.AtomicFile.write
    writes: list[int] = []

    def write_then_signal(self: atomic.AtomicFile, data: bytes) -> None:
        real_write(self, data)
        writes.append(len(data))
        if len(writes) == 3:  # the header, then the first two datagrams
            sender.send(signal.SIGTERM)

    def send_datagrams(port: int) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            for k in range(4):
                s.sendto(bytes([k]) * 40, ("127.0.0.1", port))

    monkeypatch.setattr(atomic.AtomicFile, "write", write_then_signal)
    with interrupt_on_stop_signals():
        summary = record("f1:127.0.0.1:0", out, 30.0, on_ready=send_datagrams)
    assert sender.sent == [signal.SIGTERM]
    recording = read_recording_file(out)
    assert summary.datagrams == len(recording.datagrams) == 2
    assert recording.datagrams == [bytes([0]) * 40, bytes([1]) * 40]
    assert [p.name for p in tmp_path.iterdir()] == ["r.mctr"]


# --- the ride's zip ------------------------------------------------------------------------------


def _small_ride() -> Any:
    from motioncue.pipeline import Ride

    n = 50
    return Ride(
        platform="seat3", controller="mbox3", rate_hz=100.0, actuator_names=("a", "b", "c"),
        t_s=np.arange(n) / 100.0, pulses=np.zeros((n, 3), np.int32),
        dout=np.zeros(n, np.uint16), dacs=np.zeros((n, 2), np.uint16),
    )  # fmt: skip


def _signal_when_a_member_opens(
    monkeypatch: pytest.MonkeyPatch,
    send: Callable[[], None],
    events: list[str],
    opened: list[str] | None = None,
) -> None:
    """The first zip member opened for writing sends the signal (its handle open: the
    handler raising there left the archive unclosable, numpy's close raised ValueError).
    The names of the members opened for writing go to ``opened``."""
    real_open = zipfile.ZipFile.open
    real_close = zipfile.ZipFile.close

    def open_then_signal(self: zipfile.ZipFile, name: Any, *args: Any, **kw: Any) -> Any:
        handle = real_open(self, name, *args, **kw)
        if opened is not None and (args[:1] == ("w",) or kw.get("mode") == "w"):
            opened.append(str(name))
        if "signal sent" not in events:
            events.append("signal sent")
            send()
        return handle

    def close(self: zipfile.ZipFile) -> None:
        real_close(self)
        events.append("zip closed")

    monkeypatch.setattr(zipfile.ZipFile, "open", open_then_signal)
    monkeypatch.setattr(zipfile.ZipFile, "close", close)


def test_a_stop_signal_while_a_ride_is_encoded_is_handled_after_it(
    sender: SignalSender, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A SIGHUP while numpy writes the ride's zip member (handle open) used to raise inside
    zipfile, and numpy's close then raised ValueError over it: a traceback instead of
    "interrupted" (seen in a fresh clone's run). It is handled right after the archive is
    closed, with no ValueError."""
    from motioncue.pipeline._ridefile import ride_bytes

    events: list[str] = []

    def stop(signum: int, frame: FrameType | None) -> None:
        events.append("handler")
        raise KeyboardInterrupt

    opened: list[str] = []
    _signal_when_a_member_opens(monkeypatch, lambda: sender.send(signal.SIGHUP), events, opened)
    previous = signal.signal(signal.SIGHUP, stop)
    try:
        with pytest.raises(KeyboardInterrupt) as caught:
            ride_bytes(_small_ride())
    finally:
        signal.signal(signal.SIGHUP, previous)
    assert caught.type is KeyboardInterrupt  # not a ValueError over it
    assert opened == ["header.npy"]  # abandoned at the next chunk, not encoded to the end
    # the archive closed (numpy's close; ZipFile.__del__ closes again), then the handler, once
    assert events[:2] == ["signal sent", "zip closed"], events
    assert events[-1] == "handler" and events.count("handler") == 1, events


def test_a_signal_a_park_only_records_lets_the_ride_be_encoded_whole(
    sender: SignalSender, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """Under flag-only handlers (a park in progress) the abandoned encoding is done again,
    to the end: the ride file is whole and the guard has the signal."""
    from motioncue.pipeline import load_ride
    from motioncue.pipeline._ridefile import ride_bytes
    from motioncue.pipeline._signals import SignalGuard

    ride = _small_ride()
    events: list[str] = []
    opened: list[str] = []
    _signal_when_a_member_opens(monkeypatch, lambda: sender.send(signal.SIGHUP), events, opened)
    with SignalGuard() as guard:
        data = ride_bytes(ride)
    monkeypatch.undo()
    assert guard.received == [signal.SIGHUP]
    members = ["header", "t_s", "pulses", "dout", "dacs", "digest"]
    assert opened == ["header.npy"] + [m + ".npy" for m in members]
    path = tmp_path / "r.ride"
    path.write_bytes(data)
    back = load_ride(path)
    assert back.integrity == "intact"
    np.testing.assert_array_equal(back.pulses, ride.pulses)
    np.testing.assert_array_equal(back.t_s, ride.t_s)


def test_the_ride_archive_holds_what_numpy_savez_compressed_writes() -> None:
    """The archive is written member by member (to stop between chunks); its members are
    byte for byte those of ``np.savez_compressed`` of the same arrays (the oracle), also for
    an array of more than one 16 MiB chunk."""
    import io

    from motioncue.pipeline._ridefile import _npz_bytes

    members = {
        "small": np.arange(5, dtype=np.uint8),
        # 17.6 MB, two chunks; repetitive, so that deflate is quick
        "big": (np.arange(2_200_000, dtype=np.int64) % 7).reshape(1_100_000, 2),
        "empty": np.zeros((0, 3), np.int32),
    }
    ours = zipfile.ZipFile(io.BytesIO(_npz_bytes(members, lambda: False)))
    buf = io.BytesIO()
    np.savez_compressed(buf, **members)
    theirs = zipfile.ZipFile(io.BytesIO(buf.getvalue()))
    assert ours.namelist() == theirs.namelist() == [k + ".npy" for k in members]
    for name in theirs.namelist():
        assert ours.read(name) == theirs.read(name), name


def test_generate_says_interrupted_when_the_signal_comes_while_its_ride_is_encoded(
    sender: SignalSender,
    monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
    tmp_path: Path,
) -> None:
    """The failure as the user saw it (``test_stop_signal_while_generate_writes_leaves_no_file
    [SIGHUP]`` in a fresh clone): ``generate`` printed a ValueError traceback. It says
    "interrupted by SIGHUP", exits 130 and leaves no file, temporary or final."""
    from motioncue.cli import main

    keyframes = tmp_path / "kf.csv"
    keyframes.write_text(
        "t,x_mm,y_mm,z_mm,roll_deg,pitch_deg,yaw_deg\n0,0,0,0,0,0,0\n1,5,0,0,0,0,0\n"
    )
    out = tmp_path / "out"
    out.mkdir()
    events: list[str] = []
    _signal_when_a_member_opens(monkeypatch, lambda: sender.send(signal.SIGHUP), events)
    rc = main(["generate", "--input", str(keyframes), "--platform", "stewart6-linear",
               "--controller", "mbox6", "--rate", "100", "--out", str(out / "r.ride"),
               "--pcap", str(out / "r.pcap"), "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    assert "signal sent" in events
    assert rc == 130, err
    assert err.strip().splitlines()[-1] == "motioncue generate: interrupted by SIGHUP", err
    assert "Traceback" not in err and PARTIAL_MARK not in "".join(_leftovers(out))
    assert _leftovers(out) == []
