"""Issue 20, fx: what a perfect tilt alone could render (a ceiling for tilt-based washouts).

For each drive: the vehicle's longitudinal specific force ``f_x`` compressed into the
platform's pitch reach, ``y = compress(f_x, k_f, L, L, p)`` forward and ``compress(f_x, k, L,
L, p)`` rearward with ``L = g sin(reach)``, rendered *without any lag* (no low-pass, no rate
limit, no leg speeds: not a motion this rig can make, an upper estimate of what sustained
tilt can give), both through the x otolith model of the compare chain (Telban & Cardullo,
unit DC gain). Prints, per gain ``k``, the rendered share ``rms(p)/rms(v)`` and the
correlation of the two perceived signals; the largest share with correlation >= 0.95 is the
tilt's ceiling at issue 20's fx correlation.

``--rate-dps R``: the same tilt reached at most at ``R`` deg/s (the rendered force changes at
most ``g R`` per second, a rate limiter after the compression; still no low-pass and no
legs): a causal tilt that turns at the rig's speed and never lags more than it must. At 30
deg/s (the pure pitch the actuator limiter leaves unchanged on stewart6-linear) this caps the
share at corr >= 0.95 far below the lag-free figure on race drives (README, Cue quality).
Run from the repository root::

    python tools/fx_tilt_ceiling.py configs/recordings/chicane-gt.csv ... [--rate-dps 30]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from motioncue.cueing._filters import compress_array
from motioncue.cueing._vestibular import TC_OTOLITH
from motioncue.telemetry._recording import read_recording_csv, resample

RATE = 100.0
G = 9.80665


def _rate_limited(y: np.ndarray, step: float) -> np.ndarray:
    """``y`` followed from 0 with changes of at most ``step`` a sample."""
    out = np.empty_like(y)
    cur = 0.0
    for i, target in enumerate(y.tolist()):
        cur += min(max(target - cur, -step), step)
        out[i] = cur
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drives", nargs="+")
    ap.add_argument("--reach-deg", type=float, default=13.2, help="pitch reach (deg)")
    ap.add_argument("--shape", type=float, default=8.0, help="compression exponent p")
    ap.add_argument("--forward-ratio", type=float, default=0.6, help="k_f / k")
    ap.add_argument("--min-corr", type=float, default=0.95)
    ap.add_argument(
        "--rate-dps",
        type=float,
        default=None,
        help="the tilt's largest rate (deg/s); default: no limit (lag-free)",
    )
    args = ap.parse_args()
    step = None if args.rate_dps is None else G * math.radians(args.rate_dps) / RATE
    lim = G * math.sin(math.radians(args.reach_deg))
    gains = np.geomspace(0.03, 1.0, 60)
    for d in args.drives:
        f = resample(read_recording_csv(Path(d)), RATE).f[:, 0]
        v = TC_OTOLITH.apply(f, RATE)
        best = (0.0, 0.0, float("nan"))
        for k in gains:
            fwd = compress_array(f, k * args.forward_ratio, lim, lim, args.shape)
            y = np.where(f > 0.0, fwd, compress_array(f, k, lim, lim, args.shape))
            if step is not None:
                y = _rate_limited(y, step)
            p = TC_OTOLITH.apply(y, RATE)
            share = float(np.sqrt(np.mean(p**2) / np.mean(v**2)))
            corr = float(np.corrcoef(p, v)[0, 1])
            if corr >= args.min_corr and share > best[0]:
                best = (share, float(k), corr)
        rate = "lag-free" if step is None else f"at {args.rate_dps:g} deg/s"
        print(
            f"{Path(d).stem:22s} {rate}: largest share {best[0]:.3f} at corr >= {args.min_corr} "
            f"(k {best[1]:.3f}, corr {best[2]:.3f})"
        )


if __name__ == "__main__":
    main()
