"""EasySmc 2300 benchmark: the figures issue 5 names, median of several repeats.

Run: ``PYTHONPATH=src python benchmarks/bench_easysmc.py``

Figures
- frame encoding (XYZ, XYZU, dual) in microseconds per motion frame: must be negligible next
  to a frame period (target 200 us, i.e. < 1 % of a 20 Hz period);
- serial decoding of commands, frames per second (target 20 000/s, far above the ~40/s a
  19200-baud link carries);
- emulator throughput, frames per second through ``feed`` (target 5 000/s);
- link budget: highest frame rate per bundled config at 19200 baud (target: 20 Hz for XYZ;
  a property of the link, not of the code; printed for the record);
- a 10 s, 20 Hz XYZ stream through pyserial on the emulator's pty (19200-baud line held in
  real time): times the controller's buffer ran dry while streaming, target 0 (held by
  ``tests/test_easysmc_emulator.py`` until issue 21: a busy machine makes the sender late).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import median_time_s, report
from motioncue.output._controllers import load_controller
from motioncue.output.easysmc import (
    Command,
    EasySmcEmulator,
    EasySmcLink,
    EasySmcStreamer,
    Start,
    decode_command,
    encode_command,
    send_commands,
)

REPEATS = 5


def bench_encode(name: str, rate: float, n: int = 400) -> float:
    ctrl = load_controller(name)

    def run() -> None:
        enc = ctrl.frame_encoder(rate)
        for k in range(n):
            t = k / rate
            enc.encode(t, [(200 + 40 * i) * math.sin(0.9 * t) for i in range(ctrl.n_axes)])

    return median_time_s(run, repeats=REPEATS) / n * 1e6


def pty_stream_underflows(rate: float = 20.0, seconds: float = 10.0) -> tuple[int, int]:
    """(underflows, largest buffer depth) of a streamed XYZ trajectory over the emulator's pty."""
    from motioncue.output._transport_serial import open_serial

    ctrl = load_controller("easysmc")
    emu = EasySmcEmulator((0,), line_baud=ctrl.baud).start()
    try:
        port = open_serial(f"serial://{emu.path}?baud={ctrl.baud}")
        link = EasySmcLink(port, timeout_s=1.0)
        streamer = EasySmcStreamer.for_controller(ctrl, link, rate)
        streamer.send_all(ctrl.setup_commands())
        streamer.send_all(send_commands(ctrl, ["home"]))
        frames = [
            (k / rate, [400 * math.sin(2 * math.pi * 0.4 * k / rate), 0.0, 0.0])
            for k in range(int(seconds * rate))
        ]
        streamer.stream(ctrl.frame_encoder(rate), frames)
        streamer.drain(timeout_s=5.0)
        stats = emu.models[0].stats
        port.close()
        return int(stats["underflows"]), int(stats["max_depth"])
    finally:
        emu.stop()


def main() -> None:
    print(f"EasySmc benchmark, median of {REPEATS} repeats (machine shared with other sessions)")
    ok = report(
        "encode XYZ frame (easysmc, 20 Hz)", bench_encode("easysmc", 20), "us/frame", 200, False
    )
    ok &= report(
        "encode XYZU frame (easysmc-xyzu, 15 Hz)",
        bench_encode("easysmc-xyzu", 15),
        "us/frame",
        200,
        False,
    )
    ok &= report(
        "encode 6-axis frame (easysmc-dual, 10 Hz)",
        bench_encode("easysmc-dual", 10),
        "us/frame",
        200,
        False,
    )

    frames = [
        encode_command(Command.move(0x57, [k, -k, 2 * k], Start.SEQUENCE)) for k in range(2000)
    ]

    def decode_all() -> None:
        for f in frames:
            decode_command(f)

    rate = len(frames) / median_time_s(decode_all, repeats=REPEATS)
    ok &= report("decode serial command", rate, "frames/s", 20000, True)

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

    rate = 2 * len(small) / median_time_s(emulate, repeats=REPEATS)
    ok &= report("emulator feed (speed + move commands)", rate, "frames/s", 5000, True)
    for name in ("easysmc", "easysmc-xyzu", "easysmc-dual"):
        ctrl = load_controller(name)
        shown = min(20.0, math.floor(ctrl.max_frame_rate_hz))
        print(f"link budget {name:<14} {ctrl.link_budget().describe(shown)}")
    runs = [pty_stream_underflows() for _ in range(3)]
    under = sorted(r[0] for r in runs)[1]
    print(f"pty stream, 10 s at 20 Hz: underflows {[r[0] for r in runs]}, buffer depth "
          f"{[r[1] for r in runs]} (3 runs)")  # fmt: skip
    print(f"{'pty stream: buffer ran dry (median of 3)':<48s} {under:>12d} {'times':<10s} target "
          f"== 0{'':<8s} {'OK' if under == 0 else 'MISS'}", flush=True)  # fmt: skip
    ok &= under == 0
    if not ok:
        raise SystemExit(1)


if __name__ == "__main__":
    main()
