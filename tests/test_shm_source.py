"""Telemetry decoded in a child process and read through shared memory (issue 13, item 2).

Oracles: the F1 decoder run in this process on the same datagrams (values must be equal),
a writer process hammering the block with self-consistent samples (no torn read), and the
bridge's own parking when the child dies or its parent dies.
"""

from __future__ import annotations

import math
import multiprocessing as mp
import os
import signal
import subprocess
import sys
import textwrap
import time
from multiprocessing import shared_memory
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.cueing import load_cueing
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.telemetry import GAMES, TelemetrySample, decoder_for
from motioncue.telemetry._shm import _SIZE, SharedMemorySource, _publish, _read

SRC = Path(__file__).resolve().parents[1] / "src"
sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_bridge import F1Stream, ListTransport, _mbox_setup, lap_motion  # noqa: E402


def _wait_for(cond: Any, timeout_s: float = 5.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.005)
    return bool(cond())


def test_samples_equal_the_decoder_run_in_this_process() -> None:
    import socket

    stream = F1Stream(2024)
    oracle = decoder_for("f1")
    with (
        SharedMemorySource("f1:127.0.0.1:0") as src,
        socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx,
    ):
        assert src.latest() is None
        for k in range(1, 40):
            g_lat, g_lon, g_vert, w = lap_motion(k / 60.0)
            ex, motion = stream.frame(k, g_lat, g_lon, g_vert, w)
            t_before = time.perf_counter()
            for pkt in (ex, motion):
                tx.sendto(pkt, ("127.0.0.1", src.port))
            want = None
            for pkt in (ex, motion):
                want = oracle.feed(pkt, 0.0) or want
            assert want is not None
            assert _wait_for(lambda t0=t_before: (s := src.latest()) is not None and s.t_s >= t0)
            got = src.latest()
            assert got is not None
            assert got.f == want.f and got.w == want.w  # bit for bit
            assert got.paused == want.paused and got.game == "f1"
            assert t_before <= got.t_s <= time.perf_counter()
        tx.sendto(motion[:40], ("127.0.0.1", src.port))  # truncated: counted, skipped
        assert _wait_for(lambda: src.stats.get("skipped: truncated", 0) >= 1, 3.0)
        st = src.stats
        assert st["datagrams"] == 2 * 39 + 1 and st["samples"] == 39
        assert st["receive errors"] == 0


def _hammer(name: str, seconds: float) -> None:
    shm = shared_memory.SharedMemory(name=name)
    games = sorted(GAMES)
    seq, k = 0, 0
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        k += 1
        x = float(k)
        seq = _publish(
            shm.buf, seq, TelemetrySample(x, (x, x, x), (x, x, x), k % 2 == 1, "f1"), games
        )
    shm.close()


def test_no_torn_read_while_another_process_writes_as_fast_as_it_can() -> None:
    shm = shared_memory.SharedMemory(create=True, size=_SIZE)
    try:
        shm.buf[:_SIZE] = bytes(_SIZE)
        games = sorted(GAMES)
        proc = mp.get_context("spawn").Process(target=_hammer, args=(shm.name, 1.5))
        proc.start()
        seen, last, seq = 0, 0.0, 0
        while proc.is_alive() or seen == 0:
            got = _read(shm.buf, seq, games)
            if got is None:
                continue
            seq, s = got
            x = s.t_s
            assert s.f == (x, x, x) and s.w == (x, x, x) and s.paused == (int(x) % 2 == 1)
            assert x >= last  # never back in time
            last = x
            seen += 1
        proc.join(10)
        assert proc.exitcode == 0 and seen > 20
        assert _read(shm.buf, 0, games) is not None  # the final sample is readable
    finally:
        shm.close()
        shm.unlink()


def test_a_bad_spec_is_one_clear_error_and_leaves_no_process() -> None:
    with pytest.raises(ConfigError, match="unknown game"):
        SharedMemorySource("nosuchgame:0")
    with pytest.raises(ConfigError, match="start_timeout_s"):
        SharedMemorySource("f1:0", start_timeout_s=math.nan)
    assert not [p for p in mp.active_children() if p.name == "motioncue-telemetry"]


def test_the_bridge_parks_when_the_telemetry_process_dies() -> None:
    """A lost link: the child is killed mid-drive; the gate times out, the bridge parks and
    stats say why."""
    import socket
    import threading

    platform, ctrl, lim = _mbox_setup()
    gate = GateConfig(timeout_s=0.1, fade_out_s=0.2, fade_in_s=0.2)
    src = SharedMemorySource("f1:127.0.0.1:0")
    tr = ListTransport()
    stop = threading.Event()

    def send() -> None:
        stream = F1Stream(2024)
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            k = 0
            while not stop.is_set():
                k += 1
                for pkt in stream.frame(k, *lap_motion(k / 60.0)):
                    tx.sendto(pkt, ("127.0.0.1", src.port))
                time.sleep(1 / 60)

    th = threading.Thread(target=send, daemon=True)
    th.start()
    bridge = Bridge(platform, ctrl, load_cueing("racing"), src, tr, lim, BridgeConfig(100.0, gate))
    try:
        bridge.start()
        assert _wait_for(lambda: bridge.stats.state == "live", 10.0)
        os.kill(src._proc.pid, signal.SIGKILL)
        assert _wait_for(lambda: bridge.stats.state == "parked", 10.0)
        st = bridge.stats
        assert "note: telemetry process ended" in st.packet_reasons
        assert any("telemetry process ended" in n for n in st.notes)
        assert st.fade_outs >= 1 and st.error is None
    finally:
        stop.set()
        final = bridge.stop()
        src.close()
    assert final.state == "stopped"
    q = np.asarray(bridge.stage.q)
    np.testing.assert_array_equal(q, platform.q_park)


def test_the_child_ends_when_its_parent_dies() -> None:
    code = textwrap.dedent(
        """
        import os, sys
        from motioncue.telemetry._shm import SharedMemorySource
        src = SharedMemorySource("f1:127.0.0.1:0")
        print(src._proc.pid, flush=True)
        os._exit(0)
        """
    )
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=60
    )
    pid = int(out.stdout.split()[0])

    def gone() -> bool:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        # a zombie of an orphan is reaped by init; look at its state
        try:
            return Path(f"/proc/{pid}/stat").read_text().split()[2] == "Z"
        except OSError:
            return True

    assert _wait_for(gone, 5.0)


def test_cli_port_in_use_is_one_line_error_of_the_right_kind(
    capsys: pytest.CaptureFixture[str],
) -> None:
    """The child's TransportError (port taken) reaches the CLI as the same one-line error."""
    import socket

    from motioncue import TransportError
    from motioncue.cli import main

    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        with pytest.raises(TransportError):
            SharedMemorySource(f"f1:127.0.0.1:{port}")
        base = ["bridge", "--platform", "seat3", "--controller", "imax3"]
        code = main([*base, "--target", "file:/dev/null", "--source", f"f1:127.0.0.1:{port}"])
    err = capsys.readouterr().err
    assert code == 2
    lines = [ln for ln in err.splitlines() if "error" in ln]
    assert len(lines) == 1 and lines[0].startswith("motioncue bridge: error: "), err
    assert "Traceback" not in err
