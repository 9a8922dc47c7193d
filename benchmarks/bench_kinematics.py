"""Kinematics speed: batch IK throughput, one-pose IK and FK latency (6-DOF linear hexapod).

Usage: ``python benchmarks/bench_kinematics.py`` (or ``python benchmarks/run.py kinematics``).
Each figure is the median over several repeats; see ``_timing.report`` for the columns.
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "src"))

import numpy as np  # noqa: E402

from _timing import median_time_s, report  # noqa: E402
from motioncue.kinematics import load_platform  # noqa: E402


def main() -> int:
    p = load_platform("stewart6-linear")
    rng = np.random.default_rng(0)
    scale = np.array([0.05, 0.05, 0.04, 0.1, 0.1, 0.12])
    poses = rng.uniform(-1, 1, (1_000_000, 6)) * scale
    ok = True

    t_batch = median_time_s(lambda: p.inverse(poses), repeats=5)
    ok &= report("6-DOF linear IK, 1e6 poses", len(poses) / t_batch, "poses/s", 3e6, True)

    one = poses[:2000].copy()
    it = iter(range(1 << 62))

    def ik_one() -> None:
        p.inverse(one[next(it) % 2000])

    t_ik = median_time_s(ik_one, repeats=7, number=5000)
    ok &= report("6-DOF linear IK, one pose per call", t_ik * 1e6, "us", 15.0, False)

    reachable = one[p.check(one).ok][:500]
    qs = p.inverse(reachable)
    times = []
    iters = []
    for _ in range(5):
        t0 = time.perf_counter()
        for q in qs:
            iters.append(p.forward(q).iterations)
        times.append((time.perf_counter() - t0) / len(qs))
    t_fk = statistics.median(times)
    ok &= report("6-DOF linear FK (Newton from neutral), one pose", t_fk * 1e6, "us", 200.0, False)
    print(f"  (FK Newton iterations: median {statistics.median(iters):.0f}, max {max(iters)})")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
