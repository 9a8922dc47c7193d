"""Issue 20: one classical preset (or a preset with overrides) on the tuning drives, as a table.

Runs each preset through the chain of ``motioncue compare`` (:func:`motioncue.analysis.run_chain`,
stewart6-linear with mbox6 at 100 Hz) on the tuning car drives chicane-gt, street-formula,
flowing-road and the unbundled chicane-formula (``--extra``; made by
``python tools/make_sample_lap.py --track chicane --car formula --laps 3 --seed 105 --out
chicane-formula.csv``) and prints per drive: share fx/fy, corr fx/fy, missed fx/fy %,
reversals % (fx, fy, fz parts), all false cues %, clamped %, frames changed by the actuator
limiter. ``--set NAME=VALUE`` overrides a :class:`~motioncue.cueing.CueingParams` field (a
Python literal; degrees are not converted). Never run it on the held-out drives for tuning.
Run from the repository root::

    python tools/classical_tuning_table.py racing-hexapod-firm --extra chicane-formula.csv \\
        --set tilt_fz_guard=1.0
"""

from __future__ import annotations

import argparse
import ast
from dataclasses import replace
from pathlib import Path

from motioncue.analysis import run_chain
from motioncue.cueing import load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
TUNING = [
    "configs/recordings/chicane-gt.csv",
    "configs/recordings/street-formula.csv",
    "configs/recordings/flowing-road.csv",
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("preset")
    ap.add_argument("--extra", nargs="*", default=[], help="more tuning drives")
    ap.add_argument("--set", nargs="*", default=[], help="NAME=VALUE overrides")
    args = ap.parse_args()
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    p = load_cueing(args.preset)
    for s in args.set:
        k, v = s.split("=", 1)
        p = replace(p, **{k: ast.literal_eval(v)})
    print(
        "drive                share fx/fy  corr fx/fy   missed fx/fy  rev % (fx fy fz)"
        "       false %  clamp %  limited"
    )
    for d in TUNING + list(args.extra):
        rec = resample(read_recording_csv(Path(d)), RATE)
        run = run_chain(rec.f, rec.w, p, platform, limits, RATE)
        ev = run.evaluation
        m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds,
                        clamped_share=run.poses_clamped / len(run.poses))  # fmt: skip
        s, c, mi, r = m.rendered_share, m.correlation, 100 * m.missed, 100 * m.reversals
        print(
            f"{Path(d).stem:20s} {s[0]:.3f}/{s[1]:.3f}  {c[0]:.3f}/{c[1]:.3f}  "
            f"{mi[0]:4.0f}/{mi[1]:4.0f}    {100 * m.reversals_any:5.2f} ({r[0]:.2f} {r[1]:.2f} "
            f"{r[2]:.2f})  {100 * m.false_any:6.2f}  {100 * m.clamped:6.2f}  {run.actuator_limited}"
        )


if __name__ == "__main__":
    main()
