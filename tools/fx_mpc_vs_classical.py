"""Issue 20, fx: what the live MPC's poses do on a stop that the classical washout's do not.

Runs presets through the chain of ``motioncue compare`` (:func:`motioncue.analysis.run_chain`,
stewart6-linear with mbox6 at 100 Hz) on an excerpt of a TUNING drive (never a held-out drive
or the lap), then for the strongest stops of the excerpt plots, per preset, the surge x (mm),
the pitch (deg, nose-up up), the platform's specific force along x split into its tilt part
``-g sin(pitch)`` and its translation part ``cos(pitch) x''`` (m/s^2), and the perceived fx of
the vehicle and of each preset (the vehicle's scaled to the same axis by ``--vehicle-scale``).
Prints, per preset and per stop, the perceived fx share of the stop's first 0.5 s and of its
whole, the tilt and translation parts' means, the peak pitch rate. Run from the repository
root::

    python tools/fx_mpc_vs_classical.py configs/recordings/chicane-gt.csv --excerpt 20:80 \\
        --presets racing-hexapod-firm mpc-hexapod --out /tmp/cls/chicane-gt.png
"""

from __future__ import annotations

import argparse
from pathlib import Path

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

RATE = 100.0
G = 9.80665


def stops(v: np.ndarray, thr: float, k: int) -> list[int]:
    """Indices of the onsets of the ``k`` strongest stops (perceived fx below -thr)."""
    brake = v < -thr
    on = np.flatnonzero(np.diff(brake.astype(int)) == 1) + 1
    peaks = [float(-v[i : i + 100].min()) for i in on]
    order = np.argsort(peaks)[::-1][:k]
    return sorted(int(on[j]) for j in order)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("drive")
    ap.add_argument("--excerpt", default="20:80", help="A:B seconds")
    ap.add_argument("--presets", nargs="+", default=["racing-hexapod-firm", "mpc-hexapod"])
    ap.add_argument("--stops", type=int, default=4)
    ap.add_argument("--vehicle-scale", type=float, default=0.05)
    ap.add_argument("--out", required=True, help="PNG path; an .npz of the series beside it")
    args = ap.parse_args()
    a_s, b_s = (float(x) for x in args.excerpt.split(":"))
    rec = resample(read_recording_csv(Path(args.drive)), RATE)
    a, b = round(a_s * RATE), round(b_s * RATE)
    f, w = np.asarray(rec.f, float)[a:b], np.asarray(rec.w, float)[a:b]
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    runs = {}
    for name in args.presets:
        r = run_chain(f, w, load_cueing(name), platform, limits, RATE)
        runs[name] = r
    ev0 = next(iter(runs.values())).evaluation
    v = ev0.perceived_vehicle[:, 0]
    thr = float(ev0.thresholds[0])
    t = a_s + np.arange(len(v)) / RATE
    series: dict[str, np.ndarray] = {"t": t, "vehicle_fx": v}
    parts = {}
    for name, r in runs.items():
        p = r.poses
        x = p[:, 0]
        pitch = p[:, 4]
        acc = np.gradient(np.gradient(x, 1 / RATE), 1 / RATE)
        tilt = -G * np.sin(pitch)
        trans = np.cos(pitch) * acc
        parts[name] = (x, pitch, tilt, trans, r.evaluation.perceived_sim[:, 0])
        series[f"{name}:x"] = x
        series[f"{name}:pitch"] = pitch
        series[f"{name}:fx"] = r.evaluation.perceived_sim[:, 0]
    np.savez(Path(args.out).with_suffix(".npz"), **series)
    idx = stops(v, thr, args.stops)
    print(f"{Path(args.drive).stem} {args.excerpt}: fx threshold {thr:.3f} m/s^2")
    for name, (x, pitch, tilt, trans, s) in parts.items():
        m = np.abs(v) > thr
        print(
            f"  {name}: whole excerpt share fx {np.sqrt(np.mean(s**2) / np.mean(v**2)):.3f}, "
            f"corr {np.corrcoef(s, v)[0, 1]:.3f}, "
            f"x range {1e3 * x.min():.0f}..{1e3 * x.max():.0f} mm, "
            f"pitch {np.degrees(pitch.min()):.1f}..{np.degrees(pitch.max()):.1f} deg, "
            f"reversals fx {100 * np.mean(m & (np.abs(s) > thr) & (s * v < 0)):.2f} %"
        )
        for i in idx:
            on = slice(i, i + 50)
            j = (
                i + int(np.argmax(v[i : i + 300] > -thr))
                if np.any(v[i : i + 300] > -thr)
                else i + 300
            )
            whole = slice(i, max(j, i + 50))
            rate_deg_s = np.degrees(np.abs(np.diff(pitch[max(i - 30, 0) : j + 30])).max() * RATE)
            print(
                f"    stop at {t[i]:6.2f} s ({(j - i) / RATE:.2f} s, vehicle min "
                f"{v[whole].min():6.2f}): share first 0.5 s "
                f"{np.sqrt(np.mean(s[on] ** 2) / np.mean(v[on] ** 2)):.3f}, whole "
                f"{np.sqrt(np.mean(s[whole] ** 2) / np.mean(v[whole] ** 2)):.3f}; "
                f"tilt/trans mean first 0.5 s {tilt[on].mean():+.2f}/{trans[on].mean():+.2f}, "
                f"whole {tilt[whole].mean():+.2f}/{trans[whole].mean():+.2f} m/s^2; "
                f"peak pitch rate {rate_deg_s:.0f} deg/s, "
                f"x {1e3 * x[whole].min():.0f}..{1e3 * x[whole].max():.0f} mm"
            )
    fig, axes = plt.subplots(5, len(idx), figsize=(4.2 * len(idx), 12), squeeze=False, sharey="row")
    colours = ["tab:blue", "tab:red", "tab:green", "tab:purple"]
    for c, i in enumerate(idx):
        win = slice(max(i - 150, 0), min(i + 350, len(v)))
        tt = t[win]
        ax = axes[:, c]
        for k, (name, (x, pitch, tilt, trans, s)) in enumerate(parts.items()):
            col = colours[k % len(colours)]
            ax[0].plot(tt, 1e3 * x[win], col, label=name)
            ax[1].plot(tt, -np.degrees(pitch[win]), col)
            ax[2].plot(tt, tilt[win], col)
            ax[3].plot(tt, trans[win], col)
            ax[4].plot(tt, s[win], col)
        ax[4].plot(tt, args.vehicle_scale * v[win], "k--", label=f"vehicle x {args.vehicle_scale}")
        for r in ax:
            r.axvline(t[i], color="grey", lw=0.5)
            r.axhline(0, color="grey", lw=0.5)
            r.grid(alpha=0.3)
        ax[0].set_title(f"stop at {t[i]:.1f} s")
        ax[4].set_xlabel("t (s)")
    axes[0, 0].set_ylabel("surge x (mm)")
    axes[1, 0].set_ylabel("pitch, nose-up + (deg)")
    axes[2, 0].set_ylabel("fx from tilt (m/s^2)")
    axes[3, 0].set_ylabel("fx from x'' (m/s^2)")
    axes[4, 0].set_ylabel("perceived fx (m/s^2)")
    axes[0, 0].legend(fontsize=8)
    axes[4, 0].legend(fontsize=8)
    fig.suptitle(f"{Path(args.drive).stem} {args.excerpt} s (tuning drive): stops")
    fig.tight_layout()
    fig.savefig(args.out, dpi=80)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
