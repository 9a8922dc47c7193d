"""Benchmark of ``motioncue omct``: one whole OMCT (ten paths, twelve frequencies) through the
chain (washout, workspace limiting, actuator limiter, forward kinematics where limited).

Run: ``python benchmarks/bench_omct.py`` (with ``src`` on the path). Prints the median wall
time over a few repeats at the standard amplitudes (no limit reached on the bundled hexapod
with racing-hexapod) and at 10x (limits reached: forward kinematics on the limited frames),
with the frames run, and the target (a user waits at most 30 s for the whole test).
"""

from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import report
from motioncue.analysis._omct import run_omct
from motioncue.cueing import ClassicalWashout, load_cueing
from motioncue.kinematics import load_platform
from motioncue.output._controllers import load_controller
from motioncue.trajectory import ActuatorLimits

TARGET_S = 30.0


def main() -> int:
    rate = 100.0
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=rate)
    design = ClassicalWashout(load_cueing("racing-hexapod"), rate)
    ok = True
    for scale, repeats in ((1.0, 3), (10.0, 1)):
        times = []
        for _ in range(repeats):
            t0 = time.perf_counter()
            res = run_omct(design, platform, limits, amplitude_scale=scale)
            times.append(time.perf_counter() - t0)
        frames = sum(pt.frames for pt in res.points)
        limited = sum(pt.actuator_limited + pt.workspace_clamped for pt in res.points)
        med = statistics.median(times)
        print(
            f"omct racing-hexapod on stewart6-linear at {rate:g} Hz, amplitudes x{scale:g}: "
            f"{med:.2f} s median of {repeats} ({frames} frames, {limited} limited)"
        )
        ok &= report(f"omct, amplitudes x{scale:g}", med, "s", TARGET_S, False)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
