"""Benchmark of the cue-quality evaluation on a 10-minute recording at 100 Hz.

Run: ``python benchmarks/bench_evaluate.py`` (with ``src`` on the path). Prints the median
time of one :func:`perceived_motion_error` (the tuning objective) and of one full
:func:`evaluate_cueing` (all per-axis metrics), for each vestibular model set.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _timing import median_time_s, report
from bench_washout import drive
from motioncue.cueing import (
    MODEL_SETS,
    ClassicalWashout,
    evaluate_cueing,
    load_cueing,
    perceived_motion_error,
    simulator_motion,
)


def main() -> int:
    fs, n = 100.0, 60_000  # ten minutes
    f, w = drive(n, fs, seed=3)
    params = load_cueing("racing-hexapod")
    res = ClassicalWashout(params, fs_hz=fs).run(f, w)
    sf, sw = simulator_motion(res.poses, fs)
    ok = True
    for name in MODEL_SETS:
        t_obj = median_time_s(
            lambda name=name: perceived_motion_error(res.f_used, res.w_used, sf, sw, fs, model=name)
        )
        ok &= report(f"objective, 10 min at 100 Hz ({name})", t_obj * 1e3, "ms", 50.0, False)
        t_all = median_time_s(
            lambda name=name: evaluate_cueing(
                res.f_used, res.w_used, res.poses, fs, workspace=params.workspace, model=name
            ),
            repeats=3,
        )
        ok &= report(f"full evaluation, 10 min at 100 Hz ({name})", t_all * 1e3, "ms", 500.0, False)
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
