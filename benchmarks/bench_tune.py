"""Benchmark of ``motioncue tune``: candidate evaluations per second per core.

Run: ``python benchmarks/bench_tune.py`` (with ``src`` on the path). One evaluation is what
the tuner does for each candidate on a 10-minute recording at 100 Hz: the classical washout
run, workspace limiting of the bundled hexapod (``stewart6-linear`` driven by ``mbox6``) and
the cue score of the delivered poses. Measured in this process (one core): the
rate a pool of N processes or N single-threaded Dask workers multiplies by about N.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import median_time_s, report
from bench_washout import drive
from motioncue.analysis._tune import TuneObjective
from motioncue.cueing import load_cueing
from motioncue.cueing._tune import vector_from_params
from motioncue.kinematics import load_platform
from motioncue.output._controllers import load_controller
from motioncue.trajectory import ActuatorLimits
from motioncue.trajectory._derive import pulse_rounding_limits


def main() -> int:
    fs, n = 100.0, 60_000  # ten minutes
    f, w = drive(n, fs, seed=3)
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=fs)
    tight = pulse_rounding_limits(limits, platform, 1.0 / fs)
    base = load_cueing("racing-hexapod")
    objective = TuneObjective(base, [("drive", f, w)], platform, tight, fs)
    x0 = vector_from_params(base)
    t = median_time_s(lambda: objective(x0), repeats=7)
    ok = report("tune evaluations, 10 min at 100 Hz, per core", 1.0 / t, "eval/s", 5.0, True)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
