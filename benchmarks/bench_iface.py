"""Benchmark of the interface-string encoders (issue 22): frames encoded per second, per
bundled string.

For each bundled ``iface`` config (SMC3, eh-msc-4dof, ODrive hexapod, decimal6) the
encoder of a run (``controller.run_encoder``: range check, pulses -> axis values, the
string) encodes ``N`` frames of positions sweeping the whole range; the figure is the median
over repeats of frames per second, target >= 100 k frames/s, with the reference-loop column
of ``_timing``. Each run's bytes are decoded by the board's firmware parser afterwards, which
must give back every frame (not timed).

Run: ``PYTHONPATH=src python benchmarks/bench_iface.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import median_time_s, report

TARGET = 100_000.0  # frames/s
N = 20_000
CONFIGS = ("smc3", "eh-msc-4dof", "odrive-hexapod", "decimal6")


def bench_encode() -> bool:
    from motioncue.output import load_controller
    from motioncue.output.iface import board_parser

    ok = True
    for name in CONFIGS:
        ctrl = load_controller(name)
        lo, hi, n = ctrl.pulses_lo, ctrl.pulses_hi, ctrl.n_axes
        span = hi - lo
        frames = [[lo + (k * 7919 + 613 * i) % (span + 1) for i in range(n)] for k in range(N)]
        out: list[bytes] = []

        def run(frames: list[list[int]] = frames, ctrl=ctrl, out=out) -> None:  # type: ignore[no-untyped-def]
            enc = ctrl.run_encoder(ctrl.frame_rate_hz)
            encode = enc.encode
            out.clear()
            for p in frames:
                out.extend(encode(0.0, p))

        per_frame = median_time_s(run, repeats=7) / N
        got = board_parser(ctrl.firmware).feed(b"".join(out))
        assert len(got) == N, (name, len(got))
        ok &= report(f"encode rate {name}", 1.0 / per_frame, "frames/s", TARGET, True)
    return ok


if __name__ == "__main__":
    raise SystemExit(0 if bench_encode() else 1)
