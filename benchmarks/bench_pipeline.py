"""Benchmark of ``generate``: a 10-minute recording to a 100 Hz MBOX 6-axis ride.

Run: ``python benchmarks/bench_pipeline.py``. The recording is the bundled lap repeated to
10 minutes (about 60 000 output frames); the figure is the whole offline chain without
plotting (resample, cueing, workspace limiting, ramps, IK, casadi ride optimisation, pulses
and the independent frame check), median of 3 runs.
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
from motioncue._config import config_dir
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline import generate_ride
from motioncue.telemetry._recording import Recording, read_recording_csv
from motioncue.trajectory import ActuatorLimits


def ten_minutes() -> Recording:
    lap = read_recording_csv(config_dir("recordings") / "lap.csv")
    period = lap.t_s[-1] + 0.01
    n = int(np.ceil(600.0 / period))
    t = np.concatenate([lap.t_s + k * period for k in range(n)])
    keep = t < 600.0
    return Recording(t[keep], np.tile(lap.f, (n, 1))[keep], np.tile(lap.w, (n, 1))[keep])


def main() -> int:
    rec = ten_minutes()
    platform = load_platform("stewart6-linear")
    controller = load_controller("mbox6")
    limits = ActuatorLimits.from_platform(platform, controller)
    ok = True
    medians: dict[str, float] = {}
    ride_default = platform.ride_preset or "racing-hexapod"  # what generate uses unasked
    for preset in ("racing-hexapod", "racing", ride_default):
        cueing = load_cueing(preset)
        times = []
        for _ in range(3):
            t0 = time.perf_counter()
            ride, rep = generate_ride(rec, platform, controller, cueing, limits=limits)
            times.append(time.perf_counter() - t0)
        stages = ", ".join(f"{k} {v:.2f}" for k, v in rep.stage_s.items())
        print(
            f"  [{preset}] {ride.n_frames} frames; optimisation {rep.optimisation.status}, "
            f"{rep.optimisation.n_windows} windows, {rep.optimisation.n_repaired} frames "
            f"repaired, {rep.optimisation.n_solver_failures} solver failures; stages (s): {stages}"
        )
        medians[preset] = statistics.median(times)
        # the classical presets within 5 s; the whole-ride plan (stewart6-linear's ride-file
        # default since session 31) at 10x real time at least
        target = 60.0 if preset == platform.ride_preset else 5.0
        ok &= report(f"generate 10 min @100 Hz, {preset}", medians[preset], "s", target, False)
    print(
        f"  the ride-file default {ride_default} takes "
        f"{medians[ride_default] / medians['racing-hexapod']:.1f}x racing-hexapod's time "
        "(medians of 3, this process)"
    )
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
