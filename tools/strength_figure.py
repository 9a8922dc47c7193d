"""The figure of ``README.md``'s strength paragraph: the rider's perceived fx and fy on the
bundled lap (held out; never tuned on) for the live default and the ride-file default of
``stewart6-linear`` (with ``mbox6``), beside the driver's perceived motion scaled down.

Run: ``PYTHONPATH=src python tools/strength_figure.py [--out docs/figures/strength-lap.png]``.
Each preset goes through :func:`motioncue.analysis.run_chain` at 100 Hz (cueing, workspace,
actuator limits, the delivered poses through the vestibular models); the legend gives each
one's rendered share (rms of the rider's perceived motion over the driver's).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main(argv: list[str]) -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from motioncue.analysis import run_chain
    from motioncue.cueing import load_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.telemetry._recording import read_recording_csv, resample
    from motioncue.trajectory import ActuatorLimits

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=str(ROOT / "docs" / "figures" / "strength-lap.png"))
    ap.add_argument("--scale", type=float, default=0.15, help="the driver's motion drawn x this")
    args = ap.parse_args(argv)
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=100.0)
    rec = resample(read_recording_csv(ROOT / "configs" / "recordings" / "lap.csv"), 100.0)
    presets = [
        (platform.default_preset, "live default (bridge)"),
        (platform.ride_preset, "ride-file default (generate, cue)"),
    ]
    runs = []
    for name, role in presets:
        assert name is not None
        ev = run_chain(rec.f, rec.w, load_cueing(name), platform, limits, 100.0).evaluation
        runs.append((name, role, ev))
    t = np.arange(runs[0][2].perceived_vehicle.shape[0]) / 100.0
    fig, axes = plt.subplots(2, 1, figsize=(12, 6.5), sharex=True)
    for i, (ax, ch) in enumerate(zip(axes, ("fx", "fy"), strict=True)):
        pv = runs[0][2].perceived_vehicle[:, i]
        ax.plot(t, args.scale * pv, color="0.55", lw=0.9, label=f"driver x {args.scale:g}")
        for name, role, ev in runs:
            share = ev.metrics.rendered_share[i]
            ax.plot(t, ev.perceived_sim[:, i], lw=1.1, label=f"{name}, {role}: share {share:.3f}")
        thr = runs[0][2].thresholds[i]
        for s in (-thr, thr):
            ax.axhline(s, color="k", lw=0.5, ls=":")
        ax.set_ylabel(f"perceived {ch} (m/s$^2$)")
        ax.set_ylim(-3.5, 3.5)
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
    axes[1].set_xlabel("time (s); the bundled lap, held out; dotted: the perception threshold")
    axes[0].set_title("What the rider feels on stewart6-linear: the live and the ride-file default")
    fig.tight_layout()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=80)
    print(f"wrote {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
