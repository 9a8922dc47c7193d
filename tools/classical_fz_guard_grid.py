"""Issue 20: the grid that chose ``[tilt] fz_guard`` for racing-hexapod-firm on tuning drives.

Each ``(loss_m_s2, above_m_s2, wn_rad_s)`` of the grid is added to racing-hexapod-firm and run
through the chain of ``motioncue compare`` (:func:`motioncue.analysis.run_chain`,
stewart6-linear with mbox6 at 100 Hz) on the tuning drives given (none held out); printed:
the drives' mean and largest reversals, the smallest ratio of share fy to firm's, the smallest
corr fy, the mean of all false cues, the frames the actuator limiter changed beyond firm's and
the largest clamped share. The rule (session 27): the least mean reversals with share fy at
least 0.985 x firm's on every drive and no frame limited beyond firm's. Run from the
repository root with the drives of ``tools/classical_tuning_table.py``'s docstring::

    python tools/classical_fz_guard_grid.py configs/recordings/chicane-gt.csv \\
        configs/recordings/street-formula.csv configs/recordings/flowing-road.csv \\
        chicane-formula.csv chicane-formula-106.csv street-formula-302.csv \\
        chicane-gt-301.csv flowing-gt-303.csv

Session 27 (the roll gives way): (0.1, 0.2, 5.0), mean reversals 1.483 -> 1.388 %, share fy
ratio >= 0.986, the effect all on flowing-gt-303 (1.33 -> 0.57 %, z 0.95 -> 0.19 %); the
other drives' low-passed ``f_z - g`` hardly reaches 0.2 m/s^2.
"""

from __future__ import annotations

import argparse
import itertools
from dataclasses import replace
from pathlib import Path

import numpy as np

from motioncue.analysis import run_chain
from motioncue.cueing import CueingParams, load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
LOSS_M_S2 = (0.05, 0.1, 0.15)
ABOVE_M_S2 = (0.2, 0.3, 0.5)
WN_RAD_S = (2.0, 3.0, 5.0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drives", nargs="+", help="tuning drives (CSV)")
    args = ap.parse_args()
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    recs = [resample(read_recording_csv(Path(d)), RATE) for d in args.drives]
    base = load_cueing("racing-hexapod-firm")

    def table(p: CueingParams) -> np.ndarray:
        rows = []
        for rec in recs:
            run = run_chain(rec.f, rec.w, p, platform, limits, RATE)
            ev = run.evaluation
            m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds,
                            clamped_share=run.poses_clamped / len(run.poses))  # fmt: skip
            rows.append((m.rendered_share[1], m.correlation[1], m.reversals_any, m.false_any,
                         m.clamped, run.actuator_limited))  # fmt: skip
        return np.array(rows)

    b = table(base)
    print(f"firm: mean reversals {100 * b[:, 2].mean():.3f} %, largest {100 * b[:, 2].max():.2f} %")
    for guard in itertools.product(LOSS_M_S2, ABOVE_M_S2, WN_RAD_S):
        g = table(replace(base, tilt_fz_guard=guard))
        print(
            f"{guard}: reversals mean {100 * g[:, 2].mean():.3f} % largest "
            f"{100 * g[:, 2].max():.2f} %, fy ratio >= {(g[:, 0] / b[:, 0]).min():.4f}, "
            f"corr fy >= {g[:, 1].min():.4f}, false mean {100 * g[:, 3].mean():.2f} %, "
            f"limited beyond firm {int((g[:, 5] - b[:, 5]).sum())}, "
            f"clamped <= {100 * g[:, 4].max():.2f} %",
            flush=True,
        )


if __name__ == "__main__":
    main()
