"""Issue 20, fx: what a perfect tilt alone could render (a ceiling for tilt-based washouts).

For each drive: the vehicle's longitudinal specific force ``f_x`` compressed into the
platform's pitch reach, ``y = compress(f_x, k_f, L, L, p)`` forward and ``compress(f_x, k, L,
L, p)`` rearward with ``L = g sin(reach)``, rendered *without any lag* (no low-pass, no rate
limit, no leg speeds: not a motion this rig can make, an upper estimate of what sustained
tilt can give), both through the x otolith model of the compare chain (Telban & Cardullo,
unit DC gain). Prints, per gain ``k``, the rendered share ``rms(p)/rms(v)`` and the
correlation of the two perceived signals; the largest share with correlation >= 0.95 is the
tilt's ceiling at issue 20's fx correlation. Run from the repository root::

    python tools/fx_tilt_ceiling.py configs/recordings/chicane-gt.csv ...
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drives", nargs="+")
    ap.add_argument("--reach-deg", type=float, default=13.2, help="pitch reach (deg)")
    ap.add_argument("--shape", type=float, default=8.0, help="compression exponent p")
    ap.add_argument("--forward-ratio", type=float, default=0.6, help="k_f / k")
    ap.add_argument("--min-corr", type=float, default=0.95)
    args = ap.parse_args()
    lim = G * math.sin(math.radians(args.reach_deg))
    gains = np.geomspace(0.03, 1.0, 60)
    for d in args.drives:
        f = resample(read_recording_csv(Path(d)), RATE).f[:, 0]
        v = TC_OTOLITH.apply(f, RATE)
        best = (0.0, 0.0, float("nan"))
        for k in gains:
            fwd = compress_array(f, k * args.forward_ratio, lim, lim, args.shape)
            y = np.where(f > 0.0, fwd, compress_array(f, k, lim, lim, args.shape))
            p = TC_OTOLITH.apply(y, RATE)
            share = float(np.sqrt(np.mean(p**2) / np.mean(v**2)))
            corr = float(np.corrcoef(p, v)[0, 1])
            if corr >= args.min_corr and share > best[0]:
                best = (share, float(k), corr)
        print(
            f"{Path(d).stem:22s} largest share {best[0]:.3f} at corr >= {args.min_corr} "
            f"(k {best[1]:.3f}, corr {best[2]:.3f})"
        )


if __name__ == "__main__":
    main()
