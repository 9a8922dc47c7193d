"""A started monitor serves from a process of its own: the job's process only reads its
source on request (a raw mapping over a pipe); forward kinematics, JSON and WebSocket I/O
happen in the server process, so they never hold the job's interpreter lock."""

from __future__ import annotations

import asyncio
import json
import os
import threading
from typing import Any

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.kinematics import load_platform
from motioncue.viewer._monitor import SERVER_NICE, Monitor


class _Job:
    """A job the test moves by hand; records which thread reads it."""

    def __init__(self, plat: Any, can_stop: bool = True) -> None:
        self.can_stop = can_stop
        self.q = np.asarray(plat.q_park, dtype=float).copy()
        self.readers: set[str] = set()
        self.stops = 0

    def snapshot(self) -> dict[str, Any]:
        self.readers.add(threading.current_thread().name)
        return {"q": self.q.tolist(), "v": [0.0] * self.q.size, "t_s": 0.0, "state": "running"}

    def request_stop(self) -> None:
        if not self.can_stop:
            raise ConfigError("this job cannot park")
        self.stops += 1


async def _client(url: str, n: int) -> tuple[list[dict[str, Any]], dict[str, Any]]:
    """``n`` snapshots from the page's WebSocket, then the reply to a stop request."""
    from tornado.websocket import websocket_connect

    conn = await websocket_connect(url)
    snaps: list[dict[str, Any]] = []
    while len(snaps) < n:
        msg = await asyncio.wait_for(conn.read_message(), 20.0)
        assert msg is not None
        snaps.append(json.loads(msg))
    conn.write_message("stop")
    while True:
        msg = await asyncio.wait_for(conn.read_message(), 20.0)
        assert msg is not None
        reply = json.loads(msg)
        if "stop" in reply:
            conn.close()
            return snaps, reply


@pytest.mark.parametrize("can_stop", [True, False])
def test_a_started_monitor_derives_and_serves_in_its_own_process(
    monkeypatch: pytest.MonkeyPatch, can_stop: bool
) -> None:
    plat = load_platform("stewart6-linear")
    job = _Job(plat, can_stop)
    pose = np.array([0.01, -0.02, 0.015, 0.04, -0.03, 0.05])
    job.q = plat.inverse(pose)

    def not_here(*args: object, **kwargs: object) -> dict[str, Any]:
        raise AssertionError("a snapshot was derived in the job's process")

    # the job's process must not derive: a spawned server process has the real method
    monkeypatch.setattr(Monitor, "_actuators", not_here)
    with Monitor(job, plat, port=0, rate_hz=20.0) as mon:
        assert mon._proc is not None and mon._proc.pid != os.getpid()
        # below the job's priority, so that it never holds a core the frame loop waits for
        job_nice = os.getpriority(os.PRIO_PROCESS, 0)
        assert os.getpriority(os.PRIO_PROCESS, mon._proc.pid) == min(job_nice + SERVER_NICE, 19)
        snaps, reply = asyncio.run(_client(f"ws://127.0.0.1:{mon.port}/ws", 3))
    assert mon._proc is None  # stopped: the server process has ended
    for snap in snaps:  # the forward kinematics of the server process found the pose
        assert "error" not in snap, snap
        np.testing.assert_allclose(snap["pose"][:3], pose[:3] * 1e3, atol=0.01)
        np.testing.assert_allclose(snap["pose"][3:], np.degrees(pose[3:]), atol=0.01)
    # the source is read by the job-side reader thread only, never by the loop of a server
    assert job.readers == {"motioncue-monitor-source"}
    assert mon.snapshots >= 3 and mon.errors == 0
    assert mon.stop_requests == 1
    if can_stop:
        assert reply == {"stop": "requested"} and job.stops == 1
    else:
        assert reply == {"stop": "refused: this job cannot park"} and job.stops == 0
