"""Benchmarks of motioncue.output (issue 5).

Figures (median over ``--repeats`` runs, target, ratio = median / target, or for the stream
the number of frames lost or reordered, target 0):

* encode: SC-MBOX 6-axis frames per second through ``ctrl.frame_encoder().encode``;
* decode: SC-MBOX 6-axis frames per second through ``motioncue.output.mbox.decode``;
* IMAX decode of random frame-shaped datagrams (a frame function code, a channel for 2..12
  axes, random bytes of random length, at each port-out width; decoded or refused with
  ``ProtocolError``) per second: the figure ``tests/test_imax_port_out.py`` held as a wall-clock
  bound (60 000 in 30 s) until issue 21;
* stream: a 1 kHz UDP stream of 6-axis frames to the in-process MBOX emulator on loopback
  for ``--stream-seconds`` (default 10 s): frames lost, frames reordered, worst send lateness.

Run: ``PYTHONPATH=src python benchmarks/bench_output.py``
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import report
from motioncue import ProtocolError
from motioncue.output import imax, load_controller, mbox, open_transport


def bench_encode(n: int) -> float:
    enc = load_controller("mbox6").frame_encoder()
    pulses = [[k, -k, 2 * k, 3 * k, 4, 5] for k in range(1000)]
    t = time.perf_counter()
    for k in range(n):
        enc.encode(k * 0.001, pulses[k % 1000], 0x5, (100, 200))
    return n / (time.perf_counter() - t)


def bench_decode(n: int) -> float:
    enc = load_controller("mbox6").frame_encoder()
    raws = [enc.encode(k * 0.001, [k, -k, 2 * k, 3 * k, 4, 5])[0] for k in range(1000)]
    decode = mbox.decode
    t = time.perf_counter()
    for k in range(n):
        decode(raws[k % 1000])
    return n / (time.perf_counter() - t)


_IMAX_FRAME_CODES = ("1301", "1302", "1303", "1401", "1402", "1405", "1801", "1802", "1901",
                     "1904")  # fmt: skip


def bench_imax_random_decode(n: int, seed: int = 10) -> float:
    rng = np.random.default_rng(seed)
    prefixes = [bytes.fromhex("55AA0000" + c) for c in _IMAX_FRAME_CODES]
    blob = os.urandom(n * 72)
    lengths = rng.integers(0, 72, size=n)
    channels = rng.integers(0, 13, size=n)
    datagrams = [
        prefixes[i % len(prefixes)] + int(channels[i]).to_bytes(2, "big")
        + blob[i * 72 : i * 72 + int(lengths[i])]
        for i in range(n)
    ]  # fmt: skip
    widths = (2, 4, None)
    t = time.perf_counter()
    for i, data in enumerate(datagrams):
        try:
            imax.decode(data, widths[i % 3])
        except ProtocolError:
            pass
    return n / (time.perf_counter() - t)


def bench_stream(seconds: float, rate_hz: float = 1000.0) -> dict[str, float]:
    ctrl = load_controller("mbox6")
    n = round(seconds * rate_hz)
    period = 1.0 / rate_hz
    q = np.rint(50_000 * (1 - np.cos(2 * np.pi * 0.5 * np.arange(n) * period))).astype(int)
    late = 0.0
    with mbox.MboxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder(who_reply=0)
        start = time.monotonic()
        for k in range(n):
            due = start + k * period
            delay = due - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            else:
                late = max(late, -delay)
            tr.send(enc.encode(k * period, [int(q[k])] * 6)[0])
        deadline = time.monotonic() + 5.0
        while emu.received < n and time.monotonic() < deadline:
            time.sleep(0.01)
        frames = emu.trace.frames
        refused = emu.refused_frames
    reordered = int(np.sum(np.diff(frames) < 0)) if len(frames) > 1 else 0
    return {
        "sent": n,
        "received": emu.received,
        "lost": n - len(frames),
        "reordered": reordered,
        "refused": refused,
        "late_ms": late * 1e3,
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--frames", type=int, default=200_000)
    parser.add_argument("--stream-seconds", type=float, default=10.0)
    parser.add_argument("--stream-repeats", type=int, default=3)
    args = parser.parse_args()

    enc = [bench_encode(args.frames) for _ in range(args.repeats)]
    dec = [bench_decode(args.frames) for _ in range(args.repeats)]
    rnd = [bench_imax_random_decode(60_000) for _ in range(args.repeats)]
    runs = [bench_stream(args.stream_seconds) for _ in range(args.stream_repeats)]
    ok = True
    for name, values, target in (
        ("MBOX 6-axis frames encoded per s", enc, 200_000.0),
        ("MBOX 6-axis frames decoded per s", dec, 200_000.0),
        ("IMAX random frame-shaped datagrams decoded per s", rnd, 2_000.0),
    ):
        ok &= report(name, statistics.median(values), "frames/s", target, True)
    for key in ("lost", "reordered", "refused"):
        med = statistics.median(r[key] for r in runs)
        print(
            f"{f'1 kHz x {args.stream_seconds:g} s UDP stream: frames {key}':48s} "
            f"{med:12.0f} {0:10d} {'ok' if med == 0 else 'FAIL':>7s}"
        )
        ok &= med == 0
    sent = runs[0]["sent"]
    print(
        f"(stream: {sent} frames per run, {args.stream_repeats} runs; received "
        f"{[int(r['received']) for r in runs]}; worst send lateness "
        f"{max(r['late_ms'] for r in runs):.2f} ms)"
    )
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
