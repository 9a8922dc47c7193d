"""Decode rate of the games of issue 22, on their real captures where the repository has them.

Run: ``python benchmarks/bench_games.py`` (or ``python benchmarks/run.py games``).

Datagrams per second through ``Decoder.feed`` (median of 5 runs of a stream of
:data:`N` datagrams). Target 100 000/s per game: 10 us per datagram, against games that send
60-400 datagrams a second.
"""

from __future__ import annotations

import gzip
import sys
from collections.abc import Callable
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "src"))
sys.path.insert(0, str(HERE))

from _timing import median_time_s, report  # noqa: E402
from motioncue.telemetry import decoder_for  # noqa: E402

FIXTURES = HERE.parent / "tests" / "fixtures" / "games"
N = 20_000
TARGET = 100_000.0


def _split(data: bytes, size: int) -> list[bytes]:
    return [data[i : i + size] for i in range(0, len(data), size)]


def _ac() -> list[bytes]:  # a real lap of Monza
    return _split(gzip.open(FIXTURES / "ac" / "monza-a8lms.raw.gz").read(), 328)


def _gt7() -> list[bytes]:  # real encrypted packets (each one decrypted on feed)
    return _split((FIXTURES / "gt7" / "interlagos.gt7lap").read_bytes(), 296)


def _lfs() -> list[bytes]:  # synthetic OutSim2 (OutSim Opts 1ff): no public capture
    from motioncue.telemetry._lfs import OutSimMain

    return [
        OutSimMain(
            (0.01 * k, 0.02, 0.3), 0.001 * k, 0.02, -0.01, (1.0, 2.0, 0.1), (0.0, 30.0, 0.0)
        ).outsim2(time_ms=k * 10)
        for k in range(100)
    ]


def _wrc() -> list[bytes]:  # synthetic, motioncue's structure: no public capture
    import math

    from motioncue.telemetry._wrc import WRCDecoder

    layout = WRCDecoder().layout
    out = []
    for k in range(100):
        psi = 0.01 * k
        out.append(layout.pack({
            "game_total_time": k / 120, "stage_current_time": k / 120,
            "vehicle_acceleration_x": 1.0, "vehicle_acceleration_z": 2.0,
            "vehicle_forward_direction_x": math.sin(psi),
            "vehicle_forward_direction_z": math.cos(psi),
            "vehicle_left_direction_x": math.cos(psi),
            "vehicle_left_direction_z": -math.sin(psi),
            "vehicle_up_direction_y": 1.0, "vehicle_engine_rpm_current": 5000.0,
        }))  # fmt: skip
    return out


def _dcs() -> list[bytes]:  # synthetic, as MotioncueExport.lua formats it
    from motioncue.telemetry._dcs import DCSFrame

    return [DCSFrame(k / 100, (0.1, 1.2, -0.05 * k), (0.01 * k, 0.2, 0.3)).pack()
            for k in range(100)]  # fmt: skip


def _rbr() -> list[bytes]:  # synthetic NGP TelemetryData: no public capture
    from motioncue.telemetry._rbr import RBRCar

    return [RBRCar(k, k / 400, 4, 90.0, (1.0, 2.0, 30.0), (25.0, 0.1, 0.0, 1.0, 2.0, 3.0),
                   (1.0, 2.0, 0.3, 0.0, 0.0, 0.0), 6000.0).pack() for k in range(100)]  # fmt: skip


STREAMS: dict[str, Callable[[], list[bytes]]] = {
    "ac": _ac,
    "gt7": _gt7,
    "lfs": _lfs,
    "wrc": _wrc,
    "dcs": _dcs,
    "rbr": _rbr,
}


def bench_decode() -> bool:
    missed = []
    for game, make in STREAMS.items():
        packets = make()
        stream = (packets * (N // len(packets) + 1))[:N]
        dec = decoder_for(game)
        if game == "gt7":
            dec.max_gap_frames = 600  # type: ignore[attr-defined]  # the capture keeps 1 in 12-100
            from motioncue.telemetry._gt7_cipher import BACKEND, FALLBACK_REASONS

            # a fallback to a slower backend is what would make gt7 miss: say which is used
            why = "".join(f"; {k} not used: {v}" for k, v in FALLBACK_REASONS.items())
            print(f"gt7 Salsa20 backend: {BACKEND}{why}")
        feed = dec.feed

        def run(stream: list[bytes] = stream, feed=feed) -> None:  # type: ignore[no-untyped-def]
            for d in stream:
                feed(d, 0.0)

        per_call = median_time_s(run, repeats=5) / N
        assert dec.stats.get("sample", 0) > 0, dec.stats
        if not report(f"decode rate {game}", 1.0 / per_call, "dgram/s", TARGET, True):
            missed.append(game)
    if missed:
        print(f"bench_games: FAILED: decode rate below {TARGET:.0f} datagrams/s for "
              f"{', '.join(missed)} (median of 5; see the ratio and /ref columns: a busy "
              "machine lowers every rate and the reference alike)", file=sys.stderr)  # fmt: skip
    return not missed


if __name__ == "__main__":
    raise SystemExit(0 if bench_decode() else 1)
