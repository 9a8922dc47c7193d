"""The demo plays to an emulator in its own process: a held-up emulator thread is no dead
controller (a fresh clone's run with one core busy stopped the demo as 'controller silent
for 762 ms'). A real link keeps its 0.5 s limit (tests/test_liveness.py)."""

from __future__ import annotations

import os
import subprocess
import threading
from pathlib import Path

import pytest

from motioncue.output import _udp_emulator


def test_the_demo_rides_through_an_emulator_held_up_for_a_second(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from motioncue.pipeline import run_demo

    handle = _udp_emulator.ControllerEmulator.handle
    held = threading.Event()
    seen = [0]

    def slow_handle(self, data, now_s):  # type: ignore[no-untyped-def]
        seen[0] += 1
        if seen[0] == 300 and not held.is_set():
            held.set()  # this whole process held up for 1 s mid-ride, as a busy machine does
            pid = os.getpid()
            subprocess.Popen(["sh", "-c", f"kill -STOP {pid}; sleep 1; kill -CONT {pid}"])
        return handle(self, data, now_s)

    monkeypatch.setattr(_udp_emulator.ControllerEmulator, "handle", slow_handle)
    # the report's plots (about 3 s of CPU; tests/test_pipeline.py checks them) are not what
    # is held up here: not drawn
    from motioncue.pipeline import _report

    drawn: list[object] = []
    monkeypatch.setattr(_report, "write_report", lambda d, *_a: drawn.append(d))
    demo = run_demo(tmp_path / "demo", log=lambda s: None)
    assert drawn == [demo.report_dir]  # the report writer was the one replaced
    assert held.is_set()  # the hold-up happened during the ride
    assert demo.comparison.ok, demo.comparison  # every frame traced, on time, in the limits
