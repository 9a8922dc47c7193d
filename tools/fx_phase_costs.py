"""Issue 20, fx: which phases of a drive cost a preset its fx correlation and reversals.

Runs a preset through the chain of ``motioncue compare`` (:func:`motioncue.analysis.run_chain`,
stewart6-linear with mbox6 at 100 Hz) and splits the residual of the perceived platform fx
``p`` after its least-squares fit on the perceived vehicle fx ``v`` (``e = p - k v``, ``k =
sum(p v) / sum(v v)``; ``1 - corr^2 = sum(e^2) / sum((p - mean p)^2)`` for zero-mean signals)
and the fx reversals over the phases of the drive: the first 0.5 s of each stop (``v`` below
minus the threshold), the rest of the stop, the 0.8 s after it, the throttle (``v`` above the
threshold) and the rest. Run from the repository root::

    python tools/fx_phase_costs.py racing-hexapod-firm configs/recordings/street-formula.csv
    python tools/fx_phase_costs.py fwd.toml chicane-formula-106.csv --tilt-scale-x 0.13
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np

from motioncue.analysis import run_chain
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0


def phases(v: np.ndarray, thr: float) -> dict[str, np.ndarray]:
    """Masks, (n,) bool, of the phases of the vehicle's perceived fx ``v`` (m/s^2, 100 Hz)
    against its threshold ``thr``: a stop's first 0.5 s, the rest of it, the 0.8 s after,
    throttle, other."""
    n = len(v)
    brake = v < -thr
    onset = np.zeros(n, dtype=bool)
    after = np.zeros(n, dtype=bool)
    edges = np.diff(brake.astype(int))
    for i in np.flatnonzero(edges == 1) + 1:
        onset[i : i + 50] = True
    for i in np.flatnonzero(edges == -1) + 1:
        after[i : i + 80] = True
    onset &= brake
    after &= ~brake
    steady = brake & ~onset
    throttle = (v > thr) & ~after
    rest = ~(onset | steady | after | throttle)
    return {
        "stop 0-0.5 s": onset,
        "stop rest": steady,
        "0.8 s after": after,
        "throttle": throttle,
        "other": rest,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("preset")
    ap.add_argument("drives", nargs="+")
    ap.add_argument("--tilt-scale-x", type=float, help="override the tilt's x gain")
    ap.add_argument("--forward-ratio", type=float, help="override [tilt] forward_ratio")
    args = ap.parse_args()
    p = load_cueing(args.preset)
    if args.tilt_scale_x is not None and p.tilt_scale is not None:
        p = replace(p, tilt_scale=(args.tilt_scale_x, p.tilt_scale[1]), intensity_gentle=None)
    if args.forward_ratio is not None:
        p = replace(p, tilt_forward_ratio=args.forward_ratio)
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    for d in args.drives:
        rec = resample(read_recording_csv(Path(d)), RATE)
        ev = run_chain(rec.f, rec.w, p, platform, limits, RATE).evaluation
        v = ev.perceived_vehicle[:, 0]
        s = ev.perceived_sim[:, 0]
        thr = ev.thresholds[0]
        e = s - float(np.dot(s, v) / np.dot(v, v)) * v
        n = len(v)
        rev = (np.abs(v) > thr) & (np.abs(s) > thr) & (v * s < 0.0)
        total = float(np.sum(e**2))
        corr = float(np.corrcoef(s, v)[0, 1])
        print(f"{Path(d).stem}: corr fx {corr:.3f}, fx reversals {100 * rev.mean():.2f} %")
        for name, m in phases(v, thr).items():
            print(
                f"  {name:20s} {100 * m.mean():5.1f} % of the time, "
                f"{100 * np.sum(e[m] ** 2) / total:5.1f} % of the residual, "
                f"fx reversals {100 * rev[m].sum() / n:.2f} % of the time"
            )


if __name__ == "__main__":
    main()
