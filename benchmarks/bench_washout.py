"""Benchmark of the classical washout: one streaming step and batch throughput.

Run: ``python benchmarks/bench_washout.py`` (with ``src`` on the path). Prints, for each
figure of issue 3, the median over several repeats, the target and the ratio.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import report
from motioncue.cueing import ClassicalWashout, load_cueing

G = 9.80665


def drive(n: int, fs: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A racing-like drive: braking/throttle, cornering, kerbs and noise, on all six axes."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    f = np.column_stack(
        [
            6 * np.sin(0.35 * t) + rng.normal(0, 0.4, n),
            12 * np.sin(0.21 * t) * np.abs(np.sin(0.05 * t)) + rng.normal(0, 0.4, n),
            G + 1.5 * np.sin(7.0 * t) * (np.sin(0.4 * t) > 0.8) + rng.normal(0, 0.3, n),
        ]
    )
    w = np.column_stack(
        [
            0.05 * np.sin(1.7 * t) + rng.normal(0, 0.01, n),
            0.04 * np.sin(0.9 * t) + rng.normal(0, 0.01, n),
            0.8 * np.sin(0.21 * t) + rng.normal(0, 0.02, n),
        ]
    )
    return f, w


def bench_step(design: ClassicalWashout, steps: int = 20000, repeats: int = 5) -> float:
    """Median of single-step times (us), over all steps of all repeats."""
    f, w = drive(steps, design.fs_hz, seed=1)
    fl, wl = f.tolist(), w.tolist()
    out = [0.0] * 6
    step = design.step
    clock = time.perf_counter_ns
    times: list[int] = []
    for _ in range(repeats):
        state = design.initial_state()
        for i in range(steps):
            t0 = clock()
            step(state, fl[i], wl[i], out)
            times.append(clock() - t0)
    return statistics.median(times) / 1000.0


def bench_batch(design: ClassicalWashout, n: int = 1_000_000, repeats: int = 5) -> float:
    """Median batch throughput (samples/s)."""
    f, w = drive(n, design.fs_hz, seed=2)
    design.run(f[:1000], w[:1000])  # warm-up (scipy import)
    rates = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        design.run(f, w)
        rates.append(n / (time.perf_counter() - t0))
    return statistics.median(rates)


def main() -> int:
    design = ClassicalWashout(load_cueing("racing"), fs_hz=100.0)
    step_us = bench_step(design)
    batch = bench_batch(design)
    ok = report("washout streaming step (6-DOF, racing, 100 Hz)", step_us, "us", 20.0, False)
    ok &= report("washout batch throughput (1e6 samples)", batch / 1e6, "M samples/s", 2.0, True)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
