"""The physical bound without false rotation cues, per drive, beside the presets' shares.

Usage: PYTHONPATH=src python tools/bound_rotation.py DRIVE [DRIVE ...] [--platform P]
       [--controller C] [--presets A B ...] [--corr-cuts K] [--rule spurious|false]

For each drive (configs/recordings/DRIVE.csv at 100 Hz) prints ``cue_bound(...,
forbid_false_rotation=True)`` on the platform's coupled reach (as ``compare --bound``): the
share bound at the acceptance's correlation, the share found, the zero-mean share bound and
the gain bound per channel, with its CPU time; then each preset's share per channel, its
percentage of that bound, and its time with a spurious or reversed rotation cue on the tilt
axes (pitch ``q`` for fx, roll ``p`` for fy), which the bound's motions never have, and its
time with a false one (the sign opposite to the vehicle's, whatever the vehicle's size).
``--rule false`` bounds the larger set with no *false* rotation cue only (``rotation_rule``),
which a preset with no false rotation cue is in. DRIVE: a name in configs/recordings or a
path to a recording.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from motioncue.analysis import compare_cueing, rig_reach
from motioncue.analysis._reach_coupling import reach_coupling
from motioncue.cueing import cue_bound, load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits, pulse_rounding_limits

PRESETS = ("racing-hexapod-firm", "mpc-hexapod", "optimal-hexapod")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("drives", nargs="+")
    ap.add_argument("--platform", default="stewart6-linear")
    ap.add_argument("--controller", default="mbox6")
    ap.add_argument("--presets", nargs="*", default=list(PRESETS))
    ap.add_argument("--corr-cuts", type=int, default=2, help="cue_bound's corr_cuts (compare's)")
    ap.add_argument("--rule", choices=("spurious", "false"), default="spurious",
                    help="cue_bound's rotation_rule")  # fmt: skip
    args = ap.parse_args()
    fs = 100.0
    pl = load_platform(args.platform)
    lim = ActuatorLimits.from_platform(pl, load_controller(args.controller), rate_hz=fs)
    lims = pulse_rounding_limits(lim, pl, 1.0 / fs)
    reach = reach_coupling(pl, lims, rig_reach(pl, lims))  # as compare --bound
    root = Path(__file__).resolve().parents[1] / "configs" / "recordings"
    for drive in args.drives:
        path = Path(drive) if drive.endswith(".csv") else root / f"{drive}.csv"
        rec = read_recording_csv(path)
        uni = resample(rec, fs)
        t = time.process_time()
        b = cue_bound(np.asarray(uni.f, dtype=float), fs, reach,
                      w_vehicle=np.asarray(uni.w, dtype=float),
                      forbid_false_rotation=True, corr_cuts=args.corr_cuts,
                      rotation_rule=args.rule)  # fmt: skip
        cpu = time.process_time() - t
        print(f"{drive} no-false-rotation bound ({b.rotation_cues}): "
              f"share<= {b.share_max_at_corr.round(3)} "
              f"(support LPs replaced by the larger set's: {b.solver['rotation_fallbacks']}) "
              f"found {b.share_at_corr_primal.round(3)} zero-mean<= "
              f"{b.share_max_at_corr_zero_mean.round(3)} gain<= {b.gain_max.round(3)} "
              f"err>= {b.error_rms.round(3)} (fx, fy) cpu {cpu:.1f} s", flush=True)  # fmt: skip
        if not args.presets:
            continue
        res = compare_cueing([(drive, rec)], [(p, load_cueing(p)) for p in args.presets], pl,
                             lim, rate_hz=fs)  # fmt: skip
        for run in res.runs:
            row = run.row()
            parts = []
            for i, (a, w) in enumerate((("fx", "q"), ("fy", "p"))):
                sh = row[f"share_{a}"]
                pct = 100.0 * sh / b.share_max_at_corr[i]
                parts.append(f"{a} share {sh:.3f} = {pct:.1f} % corr {row[f'corr_{a}']:.3f} "
                             f"(rotation {w}: spurious {row[f'spurious_s_{w}']:.1f} s, "
                             f"reversed {row[f'reversal_s_{w}']:.1f} s, "
                             f"false {row[f'false_cue_s_{w}']:.1f} s)")  # fmt: skip
            print(f"  {run.preset}: " + "; ".join(parts), flush=True)


if __name__ == "__main__":
    main()
