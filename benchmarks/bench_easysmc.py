"""EasySmc 2300 benchmark: the figures issue 5 names, median of several repeats.

Run: ``PYTHONPATH=src python benchmarks/bench_easysmc.py``

Figures
- frame encoding (XYZ, XYZU, dual) in microseconds per motion frame: must be negligible next
  to a frame period (target 200 us, i.e. < 1 % of a 20 Hz period);
- serial decoding of commands, frames per second (target 20 000/s, far above the ~40/s a
  19200-baud link carries);
- emulator throughput, frames per second through ``feed`` (target 5 000/s);
- link budget: highest frame rate per bundled config at 19200 baud (target: 20 Hz for XYZ;
  a property of the link, not of the code; printed for the record).
"""

from __future__ import annotations

import math
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from motioncue.output._controllers import load_controller
from motioncue.output.easysmc import (
    Command,
    EasySmcEmulator,
    Start,
    decode_command,
    encode_command,
)

REPEATS = 5


def median_time(fn, repeats: int = REPEATS) -> float:  # type: ignore[no-untyped-def]
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def report(name: str, value: float, target: float, unit: str, lower_is_better: bool) -> None:
    ratio = value / target if lower_is_better else target / value
    verdict = "ok" if ratio <= 1 else "MISSED"
    print(
        f"{name:<44} {value:>12.1f} {unit:<9} target {target:>9.0f}  ratio {ratio:5.2f}  {verdict}"
    )


def bench_encode(name: str, rate: float, n: int = 400) -> float:
    ctrl = load_controller(name)

    def run() -> None:
        enc = ctrl.frame_encoder(rate)
        for k in range(n):
            t = k / rate
            enc.encode(t, [(200 + 40 * i) * math.sin(0.9 * t) for i in range(ctrl.n_axes)])

    return median_time(run) / n * 1e6


def main() -> None:
    print(f"EasySmc benchmark, median of {REPEATS} repeats (machine shared with other sessions)")
    report("encode XYZ frame (easysmc, 20 Hz)", bench_encode("easysmc", 20), 200, "us/frame", True)
    report(
        "encode XYZU frame (easysmc-xyzu, 15 Hz)",
        bench_encode("easysmc-xyzu", 15),
        200,
        "us/frame",
        True,
    )
    report(
        "encode 6-axis frame (easysmc-dual, 10 Hz)",
        bench_encode("easysmc-dual", 10),
        200,
        "us/frame",
        True,
    )

    frames = [
        encode_command(Command.move(0x57, [k, -k, 2 * k], Start.SEQUENCE)) for k in range(2000)
    ]

    def decode_all() -> None:
        for f in frames:
            decode_command(f)

    report("decode serial command", len(frames) / median_time(decode_all), 20000, "frames/s", False)

    speed = encode_command(Command(0xA3, (20000, 2000, 20000), Start.SEQUENCE))
    home = b"".join(encode_command(Command(c, (2,), Start.SEQUENCE)) for c in (0x41, 0x42, 0x43))

    small = [
        encode_command(Command.move(0x57, [k % 40, -(k % 30), 5], Start.SEQUENCE))
        for k in range(1000)
    ]

    def emulate() -> None:
        emu = EasySmcEmulator((0,), clock=lambda: 0.0)
        emu.feed(home, 0.0)
        for k, f in enumerate(small):
            t = k * 0.05  # each move (<= 40 pulses at 2 kHz) ends before the next frame
            emu.feed(speed, t)
            emu.feed(f, t)
        assert emu.models[0].stats["buffer_full"] == 0 and not emu.violations

    report(
        "emulator feed (speed + move pairs)", 2000 / median_time(emulate), 5000, "frames/s", False
    )
    for name in ("easysmc", "easysmc-xyzu", "easysmc-dual"):
        ctrl = load_controller(name)
        print(
            f"link budget {name:<14} max {ctrl.max_frame_rate_hz:5.1f} Hz at {ctrl.baud} baud: "
            f"{ctrl.link_budget().describe(min(20.0, math.floor(ctrl.max_frame_rate_hz)))}"
        )


if __name__ == "__main__":
    main()
