"""Issue 23 items 3, 4, 10 and 11, each with real processes where the item is about one.

* 11: SIGHUP / SIGQUIT to the process group of a live ``bridge`` (a closing terminal, Ctrl-\\)
  parks and leaves stderr clean (no resource_tracker warning, no ``KeyError`` tracebacks of
  the shared-memory telemetry helper processes).
"""

from __future__ import annotations

import os
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
ENV = {**os.environ, "PYTHONPATH": str(SRC)}


def _motioncue(*args: str) -> list[str]:
    return [sys.executable, "-m", "motioncue", *args]


def _wait_for_line(proc: subprocess.Popen[str], text: str, timeout_s: float) -> str:
    """Read stderr lines until one contains ``text``; returns what was read."""
    assert proc.stderr is not None
    seen = ""
    end = time.monotonic() + timeout_s
    while time.monotonic() < end and proc.poll() is None:
        ready, _, _ = select.select([proc.stderr], [], [], 0.2)
        if ready:
            line = proc.stderr.readline()
            seen += line
            if text in line:
                return seen
    raise AssertionError(f"no {text!r} within {timeout_s} s; stderr so far:\n{seen}")


# --- item 11: group signals to a live bridge -------------------------------------------------


@pytest.mark.parametrize("sig", [signal.SIGHUP, signal.SIGQUIT], ids=["SIGHUP", "SIGQUIT"])
def test_group_signal_to_live_bridge_parks_with_clean_stderr(sig: int, tmp_path: Path) -> None:
    """What a closing terminal does: the signal goes to every process of the group (the
    bridge, its telemetry child and multiprocessing's resource tracker)."""
    cmd = _motioncue(
        "bridge", "--source", "f1:127.0.0.1:0", "--platform", "stewart6-linear",
        "--controller", "mbox6", "--target", f"file:{tmp_path / 'frames.bin'}", "--quiet",
        "--fade", "0.3",
    )  # fmt: skip
    proc = subprocess.Popen(cmd, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True)  # fmt: skip
    try:
        head = _wait_for_line(proc, "Ctrl-C parks", 30.0)
        assert "SharedMemorySource" in head  # the telemetry runs in its own process
        time.sleep(0.3)
        os.killpg(proc.pid, sig)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    err = head + err
    name = signal.Signals(sig).name
    assert proc.returncode == 130, err
    assert f"stopped by {name}; parked at rest" in err, err
    tail = err.split("parked at rest", 1)[1]
    assert tail.strip() == "", f"output after the final line:\n{tail}"
    for bad in ("Traceback", "KeyError", "resource_tracker", "Warning", "telemetry process ended"):
        assert bad not in err, err
