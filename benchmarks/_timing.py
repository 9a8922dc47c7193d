"""Shared timing helpers for the benchmark scripts: medians over repeats, and one line each."""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable


def median_time_s(fn: Callable[[], object], repeats: int = 7, number: int = 1) -> float:
    """Median wall time of ``number`` calls of ``fn``, over ``repeats`` runs, per call (s)."""
    fn()  # warm up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return statistics.median(times)


def report(name: str, value: float, unit: str, target: float, higher_is_better: bool) -> bool:
    """Print one figure with its target and the ratio (>= 1 means the target is met)."""
    ratio = value / target if higher_is_better else target / value
    ok = ratio >= 1.0
    sign = ">=" if higher_is_better else "<="
    print(
        f"{name:<48s} {value:>12.4g} {unit:<10s} target {sign} {target:<10.4g} "
        f"ratio {ratio:6.2f}  {'OK' if ok else 'MISS'}",
        flush=True,
    )
    return ok
