"""Telemetry figures: decode rate per game, and live-receiver latency on loopback.

Run: ``python benchmarks/bench_telemetry.py`` (or ``python benchmarks/run.py telemetry``).

* decode rate: datagrams per second through ``Decoder.feed`` (every one yielding a sample
  or, for F1, alternating Motion Ex / Motion). Target 50 000/s: 20 us per datagram, a
  small slice of a 1 ms control budget at the games' 60-360 Hz.
* loopback latency: ``sendto`` -> sample visible to a consumer calling ``latest()`` (which
  polls every 0.1 ms, as a paced loop would), and ``sendto`` -> arrival stamp in the receiver
  thread. Target 1 ms.
"""

from __future__ import annotations

import socket
import statistics
import struct
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "src"))
sys.path.insert(0, str(HERE))

from _timing import median_time_s, report  # noqa: E402
from motioncue.telemetry import decoder_for, open_source  # noqa: E402
from motioncue.telemetry._beamng import BeamNGMotion  # noqa: E402
from motioncue.telemetry._forza import ForzaMotion  # noqa: E402
from motioncue.telemetry._pcars2 import PCars2Telemetry  # noqa: E402
from motioncue.telemetry._xplane import pack_data  # noqa: E402

F1_DIR = Path("/work/shared/data/f1/2024")
DIRT = HERE.parent / "tests" / "data" / "dirt" / "dr2-r5turbo-noorinbee-300.bin"
N = 20_000


def _f1_packets() -> list[bytes]:
    if F1_DIR.is_dir():
        return [(F1_DIR / "packet-13.bin").read_bytes(), (F1_DIR / "packet-0.bin").read_bytes()]
    # synthetic stand-ins with the F1 24 sizes (same code path)
    hdr = struct.pack("<HBBBBBQfIIBB", 2024, 24, 1, 0, 1, 13, 7, 1.0, 1, 1, 0, 255)
    ex = hdr + bytes(237 - len(hdr))
    motion = hdr[:6] + b"\x00" + hdr[7:] + bytes(1349 - len(hdr))
    return [ex, motion]


def _datagrams() -> dict[str, list[bytes]]:
    forza = ForzaMotion(1, 1, 8000.0, 800.0, 3000.0, (1.0, 2.0, 3.0), (0.0, 0.0, 30.0),
                        (0.1, 0.2, 0.3), 0.0, 0.05, -0.02).pack() + bytes(331 - 68)  # fmt: skip
    z = (0.0, 0.0, 0.0)
    beamng = BeamNGMotion(z, (0.0, -20.0, 0.0), (1.0, 2.0, 3.0), (0.0, 0.0, 1.0),
                          0.01, 0.02, 0.0, 0.1, 0.2, 0.3, 0.0, 0.0, 0.0).pack()  # fmt: skip
    xplane = pack_data({4: (0.1, -999.0, 0.0, -999.0, 1.1, 0.2, -0.1, -999.0),
                        16: (1.0, 2.0, 3.0)})  # fmt: skip
    dirt_raw = DIRT.read_bytes()  # 300 consecutive real DiRT Rally 2.0 datagrams
    dirt = [dirt_raw[i : i + 264] for i in range(0, len(dirt_raw), 264)]
    pcars2 = PCars2Telemetry(
        1, 30.0, 5000, 8000, 0x63, (0.01, 0.5, 0.02), (0.0, 0.0, -30.0), (0.1, 0.2, 0.3),
        (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 0.0),
    ).pack()  # fmt: skip
    return {"f1": _f1_packets(), "forza": [forza], "beamng": [beamng], "xplane": [xplane],
            "dirt": dirt, "pcars2": [pcars2]}  # fmt: skip


def bench_decode() -> bool:
    ok = True
    for game, packets in _datagrams().items():
        dec = decoder_for(game)
        stream = (packets * (N // len(packets) + 1))[:N]
        feed = dec.feed

        def run(stream: list[bytes] = stream, feed=feed) -> None:  # type: ignore[no-untyped-def]
            for d in stream:
                feed(d, 0.0)

        per_call = median_time_s(run, repeats=5) / N
        assert "sample" in dec.stats, dec.stats
        ok &= report(f"decode rate {game}", 1.0 / per_call, "dgram/s", 50_000.0, True)
    return ok


def bench_latency(count: int = 300) -> bool:
    ex, motion = _f1_packets()
    src = open_source("f1:127.0.0.1:0")
    visible, stamped = [], []
    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            dest = ("127.0.0.1", src.port)
            tx.sendto(ex, dest)
            time.sleep(0.05)
            for i in range(count):
                before = src.latest()
                if i % 20 == 0:
                    tx.sendto(ex, dest)
                    time.sleep(0.002)
                t_send = time.perf_counter()
                tx.sendto(motion, dest)
                while True:
                    s = src.latest()
                    if s is not None and s is not before:
                        break
                    if time.perf_counter() - t_send > 0.5:
                        s = None
                        break
                    time.sleep(0.0001)
                t_seen = time.perf_counter()
                if s is not None:
                    visible.append(t_seen - t_send)
                    stamped.append(s.t_s - t_send)
                time.sleep(0.003)
    finally:
        src.close()
    ok = report(
        "loopback sendto -> latest() visible", statistics.median(visible) * 1e3, "ms", 1.0, False
    )
    ok &= report(
        "loopback sendto -> arrival stamp", statistics.median(stamped) * 1e3, "ms", 1.0, False
    )
    print(
        f"  ({len(visible)}/{count} delivered; 95th percentile visible "
        f"{statistics.quantiles(visible, n=20)[-1] * 1e3:.3f} ms)"
    )
    return ok


if __name__ == "__main__":
    good = bench_decode()
    good &= bench_latency()
    raise SystemExit(0 if good else 1)
