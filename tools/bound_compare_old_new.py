"""Old (boxes of rig_reach alone) and new (boxes widened + coupled reach) bound of a drive.

Usage: PYTHONPATH=src python tools/bound_compare_old_new.py DRIVE [PLATFORM CONTROLLER]
Prints the share bound at the acceptance's correlation, the gain bound and the error bound per
channel for both relaxations, and the CPU time of each cue_bound call.
"""

from __future__ import annotations

import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from motioncue.analysis import rig_reach
from motioncue.analysis._reach_coupling import reach_coupling
from motioncue.cueing import cue_bound
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits, pulse_rounding_limits


def main() -> None:
    drive = sys.argv[1]
    plat = sys.argv[2] if len(sys.argv) > 2 else "stewart6-linear"
    ctrl = sys.argv[3] if len(sys.argv) > 3 else "mbox6"
    fs = 100.0
    pl = load_platform(plat)
    lim = ActuatorLimits.from_platform(pl, load_controller(ctrl), rate_hz=fs)
    lims = pulse_rounding_limits(lim, pl, 1.0 / fs)
    old = rig_reach(pl, lims)
    new = reach_coupling(pl, lims, old)
    path = Path(__file__).resolve().parents[1] / "configs" / "recordings" / f"{drive}.csv"
    f = np.asarray(resample(read_recording_csv(path), fs).f, dtype=float)
    for label, reach in (("old", old), ("boxes widened", replace(new, coupling=None)),
                         ("new", new)):  # fmt: skip
        t = time.process_time()
        b = cue_bound(f, fs, reach)
        cpu = time.process_time() - t
        print(f"{drive} {label:>13}: share<= {b.share_max_at_corr.round(3)} found "
              f"{b.share_at_corr_primal.round(3)} zero-mean<= "
              f"{b.share_max_at_corr_zero_mean.round(3)} gain<= {b.gain_max.round(3)} "
              f"err>= {b.error_rms.round(3)} cpu {cpu:.1f} s", flush=True)  # fmt: skip


if __name__ == "__main__":
    main()
