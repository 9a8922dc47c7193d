"""Benchmark of the emulator's trace plot (``motioncue emulate --plot``) with many violations.

Run: ``python benchmarks/bench_trace_plot.py`` (with ``src`` on the path). A 60 s, 6-axis trace
(6000 frames) with 3000 per-axis violations: the plot as written today (one marker collection
per axis) against the former drawing (one red line per violation, measured in the same
process as the reference), medians of three runs each, and the target (a user waits at most
2 s for the picture).
"""

from __future__ import annotations

import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from _timing import report
from motioncue.output._trace_plot import plot_trace
from motioncue.output._udp_emulator import Trace, Violation

TARGET_S = 2.0


def _one_line_each(trace: Trace, violations: list[Violation], path: Path) -> None:
    """The former drawing, kept here as the reference: ``axvline`` per violation."""
    n = trace.positions.shape[1]
    fig, axes = plt.subplots(n, 1, sharex=True, figsize=(9, 1.6 * n + 0.8), squeeze=False)
    for i in range(n):
        ax = axes[i, 0]
        ax.step(trace.t_s, trace.positions[:, i], where="post", lw=1.0)
        for v in violations:
            if v.axis is None or v.axis == i:
                ax.axvline(v.t_s, color="red", alpha=0.4, lw=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> int:
    n = 6000
    trace = Trace(np.arange(n) * 0.01, np.tile((np.arange(n) % 100)[:, None], (1, 6)), np.arange(n))
    violations = [Violation(k * 0.01, "speed", k % 6, "x") for k in range(0, n, 2)]
    times: dict[str, list[float]] = {"collection": [], "line each": []}
    with tempfile.TemporaryDirectory() as tmp:
        for _ in range(3):
            t0 = time.perf_counter()
            plot_trace(trace, Path(tmp) / "new.png", violations=violations)
            times["collection"].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            _one_line_each(trace, violations, Path(tmp) / "old.png")
            times["line each"].append(time.perf_counter() - t0)
    new, old = (statistics.median(times[k]) for k in ("collection", "line each"))
    print(
        f"trace plot, 6 axes x 6000 frames, {len(violations)} violations: {new:.2f} s median "
        f"of 3 (one line per violation, the reference: {old:.2f} s, {old / new:.1f}x slower)"
    )
    ok = report(
        f"trace plot, {len(violations)} violations", new, "s", TARGET_S, False,
        f"{new / old:8.3g} x the line-per-violation drawing",
    )  # fmt: skip
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
