"""Independent loopback instruments for the bridge's timing (issue 13 acceptance).

Nothing here imports the bridge, the output stage or the frame encoders: frames are read
with ``struct`` at the SC-MBOX layout of ``docs/controllers.md`` (12-byte header, then
Line u32, Time u32 ms, 6 x i32 positions, big-endian), and every frame's arrival is the
kernel's receive time stamp (``SO_TIMESTAMPNS``, CLOCK_REALTIME ns) on the recording socket.

* :func:`record_frames` (run in its own process): a UDP socket that records each datagram's
  kernel stamp, line, time field and positions until told to stop;
* :func:`busy_core` (its own process, normal priority): saturates one core;
* :func:`send_f1` (its own process): the moving F1 stream at 60 Hz from the real captures
  (``test_bridge.F1Stream``), optionally lateral-g steps, with the send time of each step.
"""

from __future__ import annotations

import math
import socket
import struct
import time
from typing import Any

import numpy as np

SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35)
_HEAD = 12
_BODY = struct.Struct(">II6i")


def record_frames(port_q: Any, stop: Any, out_q: Any) -> None:
    """Record MBOX 6-axis frames with kernel receive stamps; put a dict on ``out_q``."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setsockopt(socket.SOL_SOCKET, SO_TIMESTAMPNS, 1)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4 << 20)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(0.05)
    port_q.put(sock.getsockname()[1])
    stamps: list[int] = []
    rows: list[tuple[int, ...]] = []
    while not stop.is_set():
        try:
            data, anc, _flags, _addr = sock.recvmsg(2048, 256)
        except TimeoutError:
            continue
        ts = 0
        for level, kind, cdata in anc:
            if level == socket.SOL_SOCKET and kind == SO_TIMESTAMPNS:
                sec, nsec = struct.unpack("qq", cdata[:16])
                ts = sec * 1_000_000_000 + nsec
        if len(data) >= _HEAD + _BODY.size and data[:2] == b"\x55\xaa":
            stamps.append(ts)
            rows.append(_BODY.unpack_from(data, _HEAD))
    sock.close()
    out_q.put({"t_ns": stamps, "rows": rows})


def busy_core(stop: Any) -> None:
    """Saturate one core at normal priority until ``stop`` is set."""
    x = 0
    while not stop.is_set():
        for _ in range(100_000):
            x += 1


def send_f1(port: int, stop: Any, steps_q: Any, step_every_s: float = 0.0) -> None:
    """The 60 Hz F1 stream to ``port``; with ``step_every_s`` the lateral g alternates
    0 / 1 g every that many seconds (else the lap motion), and the realtime ns just before
    the Motion packet of each step is put on ``steps_q`` at the end (a list)."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from test_bridge import F1Stream, lap_motion

    stream = F1Stream(2024)
    steps: list[int] = []
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
        t0 = time.perf_counter()
        k = 0
        level = 0.0
        while not stop.is_set():
            k += 1
            left = t0 + k / 60.0 - time.perf_counter()
            if left > 0:
                time.sleep(left)
            t = k / 60.0
            if step_every_s > 0:
                new = 1.0 if int(t / step_every_s) % 2 else 0.0
                ex, motion = stream.frame(k, new, 0.0, 0.0, (0.0, 0.0, 0.0))
                tx.sendto(ex, ("127.0.0.1", port))
                if new != level:
                    steps.append(time.time_ns())
                level = new
                tx.sendto(motion, ("127.0.0.1", port))
            else:
                g_lat, g_lon, g_vert, w = lap_motion(t)
                ex, motion = stream.frame(k, g_lat, g_lon, g_vert, w)
                tx.sendto(ex, ("127.0.0.1", port))
                tx.sendto(motion, ("127.0.0.1", port))
    steps_q.put(steps)


def jitter_ms(t_ns: np.ndarray, period_s: float) -> np.ndarray:
    """``|interval between kernel arrival stamps - period|`` in ms."""
    return np.abs(np.diff(np.asarray(t_ns, dtype=np.int64)) * 1e-6 - period_s * 1e3)


def step_delays_ms(
    t_ns: np.ndarray, positions: np.ndarray, steps_ns: list[int], threshold: float = 6.0
) -> tuple[np.ndarray, int]:
    """Delay from each step's send to the first frame that moves with it (ms).

    A frame moves with the step when the third difference of its positions (pulses, any
    axis) exceeds ``threshold``: once the washout has settled on a constant input its frames
    repeat, and the pulse rounding contributes at most 4 to a third difference; a step of
    1 g in the specific force changes the actuators' acceleration at once. Steps whose 10
    frames before were not quiet, or with no such frame within 50 ms, are not counted (their
    number is returned).
    """
    t = np.asarray(t_ns, dtype=np.int64)
    p = np.asarray(positions, dtype=np.int64)
    d3 = np.zeros(len(p))
    if len(p) > 3:
        d3[3:] = np.max(np.abs(p[3:] - 3 * p[2:-1] + 3 * p[1:-2] - p[:-3]), axis=1)
    out, skipped = [], 0
    for s in steps_ns:
        k = int(np.searchsorted(t, s, side="right"))
        if k < 13 or np.any(d3[k - 10 : k] > threshold):
            skipped += 1
            continue
        moving = np.nonzero(d3[k:] > threshold)[0]
        if moving.size == 0 or t[k + moving[0]] - s > 50_000_000:
            skipped += 1
            continue
        out.append((t[k + moving[0]] - s) * 1e-6)
    return np.array(out, dtype=float), skipped


def percentile(v: np.ndarray, q: float) -> float:
    return float(np.percentile(v, q)) if len(v) else math.nan
