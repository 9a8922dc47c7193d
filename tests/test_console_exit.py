"""After ``main`` the ``motioncue`` command ends with its own status whatever stop signal
arrives while the interpreter shuts down, in whichever thread the kernel delivers it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"

# main() is replaced by one that returns 3 and leaves a non-daemon thread behind (as a
# library's worker may be); the interpreter waits for it at shutdown, and it signals the
# process then: the kernel delivers a process-directed signal to a thread that does not
# block it, so blocking the signals in the main thread alone would not keep the status
PROGRAM = """
import os, signal, sys, threading, time
import motioncue.cli as cli

def late(sig):
    time.sleep(0.3)
    os.kill(os.getpid(), sig)
    time.sleep(0.5)

def main():
    threading.Thread(target=late, args=(int(sys.argv[1]),)).start()
    return 3

cli.main = main
cli.console()
"""


@pytest.mark.parametrize(
    "sig", [signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGQUIT], ids=lambda s: s.name
)
def test_a_stop_signal_during_shutdown_keeps_the_exit_status(sig: int) -> None:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.run(
        [sys.executable, "-c", PROGRAM, str(int(sig))],
        env=env,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 3, (proc.returncode, proc.stderr)
    assert "Traceback" not in proc.stderr
