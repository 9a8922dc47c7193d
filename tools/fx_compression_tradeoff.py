"""Issue 20, missed fx cues: can a compressed copy of the perceived fx meet both figures?

The rider's perceived fx is idealised as a static, lag-free compression of the driver's
perceived fx, ``r = k v / (1 + |k v / L|^p)^(1/p)`` (the classical washout's curve), with no
dynamics, no workspace but the limit ``L`` and no other channel. Over a grid of gains ``k``,
limits ``L`` (m/s^2; 2.6 is the pitch reach's 15 deg of tilt) and exponents ``p``, it prints
the fewest missed fx cues any such copy has at corr fx >= 0.95, and the best correlation of
one with missed fx <= 35 % (issue 20's two figures), with the metrics of
:mod:`motioncue.cueing._metrics` on the vestibular models of ``motioncue compare``.

Not a bound on every motion of the rig (a time-varying gain, translation or foresight are
left out); it says whether the two figures conflict for the shape of a drive's fx::

    python tools/fx_compression_tradeoff.py configs/recordings/flowing-formula.csv
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from motioncue.analysis import run_chain
from motioncue.cueing import load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drives", nargs="+", help="recordings (CSV)")
    ap.add_argument("--limits", type=float, nargs="+", default=[2.2, 2.6, 3.1, 4.0],
                    help="limits L to try (m/s^2)")  # fmt: skip
    args = ap.parse_args()
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    any_preset = load_cueing("racing-hexapod-auto")  # the vehicle's perception ignores it
    for drive in args.drives:
        rec = resample(read_recording_csv(Path(drive)), RATE)
        ev = run_chain(rec.f, rec.w, any_preset, platform, limits, RATE).evaluation
        vehicle = np.asarray(ev.perceived_vehicle)
        thr = np.asarray(ev.thresholds)
        rows = []
        for k in np.geomspace(0.03, 1.0, 25):
            for lim in args.limits:
                for p in (0.5, 1.0, 2.0, 4.0, 8.0):
                    sim = np.zeros_like(vehicle)
                    kv = k * vehicle[:, 0]
                    sim[:, 0] = kv / (1.0 + np.abs(kv / lim) ** p) ** (1.0 / p)
                    m = cue_metrics(vehicle, sim, thr)
                    rows.append((m.missed[0], m.correlation[0], k, lim, p, m.rendered_share[0]))
        print(Path(drive).name)
        ok = [r for r in rows if r[1] >= 0.95]
        if ok:
            r = min(ok)
            print(f"  fewest missed at corr fx >= 0.95: {100 * r[0]:.1f} % (corr {r[1]:.3f}, "
                  f"k {r[2]:.3f}, L {r[3]:.1f}, p {r[4]:g}, share {r[5]:.3f})")  # fmt: skip
        ok = [r for r in rows if r[0] <= 0.35]
        if ok:
            r = max(ok, key=lambda q: q[1])
            print(f"  best corr fx at missed <= 35 %: {r[1]:.3f} (missed {100 * r[0]:.1f} %, "
                  f"k {r[2]:.3f}, L {r[3]:.1f}, p {r[4]:g}, share {r[5]:.3f})")  # fmt: skip
        else:
            print("  no copy on the grid misses <= 35 %")


if __name__ == "__main__":
    main()
