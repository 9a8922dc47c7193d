"""The monitor's snapshot slot in shared memory (``viewer/_monitor_slot.py``): a reader never
gets a torn snapshot while a writer in another process writes throughout, and a bridge whose
monitor server is dead goes on sending and parks."""

from __future__ import annotations

import json
import os
import signal
import struct
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import pytest

from motioncue.viewer._monitor import BridgeSource, Monitor
from motioncue.viewer._monitor_slot import SnapshotSlot, TornSlot
from test_bridge_stats import _bridge

SLOT_PY = Path(__file__).resolve().parents[1] / "src" / "motioncue" / "viewer" / "_monitor_slot.py"

# the writer: the slot module alone (stdlib only, no package import), publishing snapshot k
# as k's 8 bytes repeated 1 + k % 500 times until the reader's first request
_WRITER = """
import importlib.util, struct, sys
spec = importlib.util.spec_from_file_location("slot", sys.argv[1])
mod = importlib.util.module_from_spec(spec)
spec.loader.exec_module(mod)
slot = mod.SnapshotSlot(int(sys.argv[2]), int(sys.argv[3]))
k = 0
while slot.requested() == 0:
    k += 1
    slot.publish(k, struct.pack("<Q", k) * (1 + k % 500))
print(k)
"""


def _wait_for(cond: Callable[[], bool], timeout_s: float = 30.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return bool(cond())


def test_a_reader_never_gets_a_torn_snapshot_while_another_process_writes() -> None:
    slot = SnapshotSlot.create(capacity_b=8 * 500)
    writer = subprocess.Popen(
        [sys.executable, "-c", _WRITER, str(SLOT_PY), str(slot.fileno()), str(slot.capacity_b)],
        pass_fds=[slot.fileno()],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert _wait_for(lambda: slot.read()[0] > 0), "the writer never published"
        seen: set[int] = set()
        reads = torn = 0
        end = time.monotonic() + 0.5
        while time.monotonic() < end or len(seen) < 50:
            try:
                k, data = slot.read(tries=50)
            except TornSlot:  # the writer kept writing through 50 tries: no snapshot, no harm
                torn += 1
                continue
            reads += 1
            # the payload itself says which snapshot it is: every word is k, k's own length
            assert len(data) == 8 * (1 + k % 500), (k, len(data))
            words = set(struct.unpack(f"<{len(data) // 8}Q", data))
            assert words == {k}, (k, sorted(words)[:5])
            seen.add(k)
        slot.request()  # the writer stops on the first request
        out, _ = writer.communicate(timeout=30)
    finally:
        if writer.poll() is None:
            writer.kill()
            writer.wait()
        slot.close()
    written = int(out)
    # the writer wrote throughout (many more snapshots than the reader kept), the reader saw
    # many of them, each one whole
    assert len(seen) >= 50 and written > len(seen), (written, len(seen), reads, torn)


def test_the_checksum_refuses_a_snapshot_changed_behind_the_sequence_counter() -> None:
    slot = SnapshotSlot.create(capacity_b=64)
    try:
        slot.publish(7, b"abcdefgh")
        assert slot.read() == (7, b"abcdefgh")
        # one payload byte changed without the writer's sequence counter (a store the reader
        # saw early on a weakly ordered processor looks like this): never returned
        slot._map[64 + 3] ^= 0x01
        with pytest.raises(TornSlot):
            slot.read(tries=3)
        slot.publish(8, b"xy")  # the next whole write is read again
        assert slot.read() == (8, b"xy")
        # a write under way (odd counter): no snapshot until it is done
        seq = struct.unpack_from("<Q", slot._map, 0)[0]
        struct.pack_into("<Q", slot._map, 0, seq + 1)
        with pytest.raises(TornSlot):
            slot.read(tries=3)
        with pytest.raises(ValueError, match="holds 64"):
            slot.publish(9, b"z" * 65)
    finally:
        slot.close()


class _Recording(BridgeSource):
    """A bridge's source that records which threads read it."""

    def __init__(self, bridge: Any) -> None:
        super().__init__(bridge)
        self.readers: list[str] = []

    def snapshot(self) -> Mapping[str, Any]:
        self.readers.append(threading.current_thread().name)
        return super().snapshot()


def _get_snapshot(mon: Monitor) -> dict[str, Any]:
    with urllib.request.urlopen(f"http://127.0.0.1:{mon.port}/snapshot", timeout=30) as r:
        snap: dict[str, Any] = json.loads(r.read())
    return snap


@pytest.mark.parametrize("frame_clock", ["fixed", "arrival"])
def test_a_running_bridge_answers_from_its_loop_and_its_final_state_comes_after_it(
    frame_clock: str,
) -> None:
    bridge, _ = _bridge(rate_hz=100.0, frame_clock=frame_clock)
    src = _Recording(bridge)
    with Monitor(src, bridge.platform, bridge.limits, port=0) as mon:
        assert bridge.after_frame is not None  # attached before the loop starts
        bridge.start()
        try:
            assert _wait_for(lambda: mon._slot is not None and mon._slot.live)
            n0 = len(src.readers)
            for _ in range(3):
                assert _get_snapshot(mon)["state"] in ("parked", "parking")
            # while the loop runs, only the loop's own thread reads the source: nothing else
            # in the job's process wakes for a request
            assert src.readers[n0:] == ["motioncue-bridge"] * 3
        finally:
            final = bridge.stop()
        assert final.state == "stopped" and final.park_q_error <= 1e-9
        assert not mon._slot.live  # the ended loop said so
        snap = _get_snapshot(mon)  # the final state, read by the job's reader thread
        assert snap["state"] == "parked" and "error" not in snap
        assert src.readers[-1] == "motioncue-monitor-source"
    assert bridge.after_frame is None  # a stopped monitor is detached from the loop
    assert mon.snapshots >= 4 and mon.errors == 0


def test_a_dead_server_never_blocks_the_bridge_which_parks() -> None:
    bridge, _ = _bridge(rate_hz=100.0)
    src = _Recording(bridge)
    mon = Monitor(src, bridge.platform, bridge.limits, port=0).start()
    try:
        bridge.start()
        assert _wait_for(lambda: mon._slot is not None and mon._slot.live)
        _get_snapshot(mon)
        served = len(src.readers)
        assert mon._proc is not None and mon._slot is not None
        mon._slot.request()  # a request the dead server will never read
        os.kill(mon._proc.pid, signal.SIGKILL)
        mon._proc.wait(10)
        # the loop answers the pending request into the slot nobody reads, and goes on
        assert _wait_for(lambda: len(src.readers) > served)
        sent = bridge.stats.frames_sent
        assert _wait_for(lambda: bridge.stats.frames_sent >= sent + 20)
        assert bridge.running and bridge.stats.error is None
    finally:
        final = bridge.stop()
        mon.stop()  # returns although its server is gone
    assert final.state == "stopped" and final.error is None and final.park_q_error <= 1e-9
    assert bridge.after_frame is None
