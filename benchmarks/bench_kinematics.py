"""Kinematics speed: batch IK throughput, one-pose IK and FK latency (6-DOF linear hexapod),
and the same IK figures for the corner rigs ``corner4`` and ``corner4-tl`` (issue 15), timed
in the same process next to the hexapod's (ratios in the printout).

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
    ok &= _corner_rigs(poses, one, len(poses) / t_batch, t_ik)
    return 0 if ok else 1


def _corner_rigs(poses: np.ndarray, one: np.ndarray, hex_rate: float, hex_one_s: float) -> bool:
    """IK per pose and in batch on the corner rigs, and Gauss-Newton FK (4 legs, 3 DOF)."""
    ok = True
    for name in ("corner4", "corner4-tl"):
        p = load_platform(name)
        sub = poses * p.dof_mask
        t_batch = median_time_s(lambda p=p, sub=sub: p.inverse(sub), repeats=5)
        rate = len(sub) / t_batch
        ok &= report(f"{name} IK, 1e6 poses", rate, "poses/s", 3e6, True)
        print(f"  ({rate / hex_rate:.2f} x the hexapod's batch rate, same process)")
        it = iter(range(1 << 62))
        small = one * p.dof_mask

        def ik_one(p=p, small=small, it=it) -> None:
            p.inverse(small[next(it) % 2000])

        t_one = median_time_s(ik_one, repeats=7, number=5000)
        ok &= report(f"{name} IK, one pose per call", t_one * 1e6, "us", 15.0, False)
        print(f"  ({t_one / hex_one_s:.2f} x the hexapod's one-pose time)")
        qs = p.inverse(small[p.check(small).ok][:300])
        t0 = time.perf_counter()
        for q in qs:
            p.forward(q)
        t_fk = (time.perf_counter() - t0) / len(qs)
        ok &= report(f"{name} FK (Gauss-Newton from neutral), one", t_fk * 1e6, "us", 200.0, False)
    return ok


if __name__ == "__main__":
    raise SystemExit(main())
