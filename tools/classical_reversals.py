"""Issue 20: where a preset's reversals are, per channel and per phase of the drive.

Runs a preset through the chain of ``motioncue compare`` (:func:`motioncue.analysis.run_chain`,
stewart6-linear with mbox6 at 100 Hz) and prints, for each perceived channel (fx, fy, fz, p,
q, r), its reversals (vehicle and platform both above threshold, opposite signs; the
``reversals`` of :func:`motioncue.cueing._metrics.cue_metrics`) as a share of the drive and
in seconds, and the share of the drive with a reversal on any channel. Each channel's reversal
time is split by the phase of the perceived vehicle fx (``v``): the first 0.5 s of a stop
(``v`` below minus the fx threshold), the rest of the stop, the 0.8 s after it, the throttle
(``v`` above the threshold), the rest; and by the vehicle's perceived fy (``|fy| > 2`` m/s^2:
in a corner). With ``--episodes`` the longest runs of reversals are listed (start, length,
channel, the vehicle's and the platform's perceived value and the platform's roll and pitch).
With ``--png`` a plot of the drive's perceived fz (vehicle x ``--scale``, platform), the
platform's roll and pitch, and the reversal times per channel. Diagnosis only (a held-out
drive may be looked at; no preset is tuned here). Run from the repository root::

    python tools/classical_reversals.py racing-hexapod-firm \\
        configs/recordings/flowing-formula.csv --episodes 8 --png /tmp/rev.png
"""

from __future__ import annotations

import argparse
import ast
from dataclasses import replace
from pathlib import Path

import numpy as np
from fx_phase_costs import phases

from motioncue.analysis import run_chain
from motioncue.cueing import load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
CHANNELS = ("fx", "fy", "fz", "p", "q", "r")


def runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, length) of each run of True."""
    d = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return [
        (int(a), int(b - a))
        for a, b in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1), strict=True)
    ]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("preset")
    ap.add_argument("drive")
    ap.add_argument("--episodes", type=int, default=0)
    ap.add_argument("--png")
    ap.add_argument("--scale", type=float, default=0.1, help="vehicle fz scale in the plot")
    ap.add_argument("--set", nargs="*", default=[], help="NAME=VALUE parameter overrides")
    args = ap.parse_args()
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    rec = resample(read_recording_csv(Path(args.drive)), RATE)
    params = load_cueing(args.preset)
    for item in args.set:
        key, value = item.split("=", 1)
        params = replace(params, **{key: ast.literal_eval(value)})
    run = run_chain(rec.f, rec.w, params, platform, limits, RATE)
    ev = run.evaluation
    pv, ps, thr = ev.perceived_vehicle, ev.perceived_sim, ev.thresholds
    m = cue_metrics(pv, ps, thr, clamped_share=run.poses_clamped / len(run.poses))
    rev = (np.abs(pv) > thr) & (np.abs(ps) > thr) & (pv * ps < 0.0)
    n = len(pv)
    print(
        f"{Path(args.drive).stem} x {args.preset}: reversals any {100 * m.reversals_any:.2f} % "
        f"({rev.any(axis=1).sum() / RATE:.1f} s of {n / RATE:.0f} s)"
    )
    ph = phases(pv[:, 0], float(thr[0]))
    corner = np.abs(pv[:, 1]) > 2.0
    head = "  ".join(f"{k:>12s}" for k in ph)
    print(f"  chan   rev %     s   {head}   in corner   only this channel")
    for c, name in enumerate(CHANNELS):
        r = rev[:, c]
        only = r & ~np.delete(rev, c, axis=1).any(axis=1)
        cells = "  ".join(f"{r[mk].sum() / RATE:10.1f} s" for mk in ph.values())
        print(
            f"  {name:4s} {100 * r.mean():6.2f} {r.sum() / RATE:6.1f}   {cells}   "
            f"{(r & corner).sum() / RATE:7.1f} s   {only.sum() / RATE:7.1f} s"
        )
    if args.episodes:
        eps = []
        for c, name in enumerate(CHANNELS):
            for a, ln in runs(rev[:, c]):
                eps.append((ln, a, c, name))
        eps.sort(reverse=True)
        print("  longest reversals:")
        p = run.poses
        for ln, a, c, name in eps[: args.episodes]:
            sl = slice(a, a + ln)
            print(
                f"    {name} at {a / RATE:7.2f} s for {ln / RATE:.2f} s: vehicle "
                f"{pv[sl, c].mean():+.2f}, platform {ps[sl, c].mean():+.2f} (thr {thr[c]:.2f}); "
                f"vehicle fx {pv[sl, 0].mean():+.2f} fy {pv[sl, 1].mean():+.2f}; roll "
                f"{np.degrees(p[sl, 3]).mean():+.1f} pitch {np.degrees(p[sl, 4]).mean():+.1f} deg, "
                f"z {1e3 * p[sl, 2].mean():+.0f} mm"
            )
    if args.png:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        t = np.arange(n) / RATE
        fig, ax = plt.subplots(4, 1, figsize=(14, 10), sharex=True)
        ax[0].plot(
            t, args.scale * pv[:, 2], "k", lw=0.8, label=f"vehicle perceived fz x {args.scale}"
        )
        ax[0].plot(t, ps[:, 2], "tab:red", lw=0.8, label="platform perceived fz")
        ax[0].axhline(thr[2], color="grey", lw=0.5)
        ax[0].axhline(-thr[2], color="grey", lw=0.5)
        ax[0].set_ylabel("perceived fz - g (m/s^2)")
        ax[0].legend(fontsize=8)
        ax[1].plot(t, 0.05 * pv[:, 0], "k", lw=0.8, label="vehicle perceived fx x 0.05")
        ax[1].plot(t, ps[:, 0], "tab:blue", lw=0.8, label="platform perceived fx")
        ax[1].set_ylabel("perceived fx (m/s^2)")
        ax[1].legend(fontsize=8)
        ax[2].plot(t, np.degrees(run.poses[:, 3]), label="roll")
        ax[2].plot(t, np.degrees(run.poses[:, 4]), label="pitch")
        ax[2].set_ylabel("deg")
        ax[2].legend(fontsize=8)
        for c in range(len(CHANNELS)):
            ax[3].fill_between(t, c, c + 0.8 * rev[:, c], step="mid", alpha=0.8)
        ax[3].set_yticks(np.arange(6) + 0.4, CHANNELS)
        ax[3].set_ylabel("reversal")
        ax[3].set_xlabel("t (s)")
        for a in ax:
            a.grid(alpha=0.3)
        fig.suptitle(
            f"{Path(args.drive).stem} x {args.preset}: reversals {100 * m.reversals_any:.2f} %"
        )
        fig.tight_layout()
        fig.savefig(args.png, dpi=75)
        print(f"wrote {args.png}")


if __name__ == "__main__":
    main()
