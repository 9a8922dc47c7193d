"""Plot a rig's coupled reach (tools/bound_polygon_plot.py OUT.png [PLATFORM CONTROLLER]).

Per channel: reachable poses (x, -sin pitch) / (y, cos pitch sin roll) as dots, rig_reach's box
(dashed), the widened box and the pose polygon of reach_coupling (solid): what the bound's
relaxation allows at one sample.
"""

from __future__ import annotations

import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
from scipy.spatial import HalfspaceIntersection

from motioncue.analysis import reach_coupling, rig_reach
from motioncue.kinematics import dof_ranges, load_platform
from motioncue.output import load_controller
from motioncue.trajectory import ActuatorLimits, pulse_rounding_limits, reachable


def main() -> None:
    out = sys.argv[1]
    plat = sys.argv[2] if len(sys.argv) > 2 else "stewart6-linear"
    ctrl = sys.argv[3] if len(sys.argv) > 3 else "mbox6"
    pl = load_platform(plat)
    lim = ActuatorLimits.from_platform(pl, load_controller(ctrl), rate_hz=100.0)
    lims = pulse_rounding_limits(lim, pl, 0.01)
    old = rig_reach(pl, lims)
    new = reach_coupling(pl, lims, old)
    assert new.coupling is not None
    box = dof_ranges(pl)
    span = np.maximum(np.abs(box.lower), np.abs(box.upper)) * 1.4
    rng = np.random.default_rng(5)
    cand = rng.uniform(-1, 1, (200000, 6)) * span * np.asarray(pl.dof_mask)
    poses = cand[reachable(pl, cand, limits=lims)]
    taus = (-np.sin(poses[:, 4]), np.cos(poses[:, 4]) * np.sin(poses[:, 3]))
    fig, axes = plt.subplots(1, 2, figsize=(11, 5))
    for ch, ax in enumerate(axes):
        ax.plot(poses[:, ch] * 1e3, taus[ch], ".", ms=1.5, color="0.6", label="reachable poses")
        for r, style, lab in ((old, "--", "rig_reach box"), (new, "-", "widened box")):
            s, t = r.stroke_m[ch] * 1e3, math.sin(r.tilt_rad[ch])
            ax.plot([-s, s, s, -s, -s], [-t, -t, t, t, -t], style, color="tab:blue", lw=1,
                    label=lab)  # fmt: skip
        poly = new.coupling[ch]
        s, t = new.stroke_m[ch], math.sin(new.tilt_rad[ch])
        a = np.vstack([poly.normals, [[1, 0], [-1, 0], [0, 1], [0, -1]]])
        b = np.concatenate([poly.offsets, [s, s, t, t]])
        hs = HalfspaceIntersection(np.hstack([a, -b[:, None]]), np.zeros(2))
        v = hs.intersections
        order = np.argsort(np.arctan2(v[:, 1], v[:, 0] / s * t))
        v = np.vstack([v[order], v[order][:1]])
        ax.plot(v[:, 0] * 1e3, v[:, 1], "-", color="tab:red", lw=2, label="coupled (polygon)")
        ax.set_xlabel(("x" if ch == 0 else "y") + " (mm)")
        ax.set_ylabel("-sin(pitch)" if ch == 0 else "cos(pitch) sin(roll)")
        ax.set_title(f"{plat} / {ctrl}: {'fx' if ch == 0 else 'fy'} channel")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main()
