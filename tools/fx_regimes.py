"""Issue 20, fx: how each preset renders braking and throttle, and what the bound's motion does.

For one drive, the perceived fx of the driver ``v`` and of the rider ``s`` (the chain of
``motioncue compare``: :func:`motioncue.analysis.run_chain`, stewart6-linear with mbox6 at
100 Hz) split by the driver's regime: hard braking (``v < -5`` m/s^2), light braking
(``-5 <= v < -1``), coasting (``|v| < 1``) and throttle (``v > 1``). Per regime: its share of
the time, the rider's and the driver's mean, their ratio, and its share of the residual of
the least-squares line of ``s`` on ``v`` (what costs the correlation). A preset that renders
throttle at a larger ratio than braking (a compressed copy) loses correlation on a formula
car, whose perceived fx is dominated by short 4 g stops.

``--bound`` adds the motion behind the share bound at corr 0.95 (``cue_bound``'s
``share_at_corr_primal``: non-causal, in the first-order relaxation, within the rig's
reach), taken from inside ``cue_bound`` and evaluated as a pose (x and pitch only, no
inverse kinematics), to show how it reaches its share::

    PYTHONPATH=src python tools/fx_regimes.py build/drives/flowing-formula-107.csv \\
        racing-hexapod-auto mpc-hexapod optimal-hexapod-auto --bound
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from motioncue.analysis import rig_reach, run_chain
from motioncue.analysis._reach_coupling import reach_coupling
from motioncue.cueing import cue_bound, load_cueing
from motioncue.cueing._evaluate import evaluate_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits, pulse_rounding_limits

RATE = 100.0


def regimes(v: NDArray[np.float64], s: NDArray[np.float64]) -> list[str]:
    """The table's lines for driver ``v`` and rider ``s`` (perceived fx, m/s^2)."""
    vc, sc = v - v.mean(), s - s.mean()
    slope = float(vc @ sc) / float(vc @ vc)
    r = sc - slope * vc
    rr = float(r @ r)
    share = float(np.sqrt((s @ s) / (v @ v)))
    lines = [f"  corr {np.corrcoef(v, s)[0, 1]:.3f}, share {share:.3f}, slope {slope:.4f}"]
    for name, m in (
        ("hard braking", v < -5.0),
        ("light braking", (v >= -5.0) & (v < -1.0)),
        ("coasting", np.abs(v) < 1.0),
        ("throttle", v > 1.0),
    ):
        if not m.any():
            continue
        ratio = s[m].mean() / v[m].mean()
        lines.append(
            f"  {name:13s} {100 * m.mean():5.1f} % of the time: rider {s[m].mean():+7.3f}, "
            f"driver {v[m].mean():+8.3f} m/s^2, ratio {ratio:+7.3f}, "
            f"{100 * float(r[m] @ r[m]) / rr:5.1f} % of the residual"
        )
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("drive", type=Path)
    ap.add_argument("presets", nargs="*")
    ap.add_argument("--bound", action="store_true", help="the share bound's motion too")
    args = ap.parse_args()
    rec = resample(read_recording_csv(args.drive), RATE)
    f, w = np.asarray(rec.f, dtype=float), np.asarray(rec.w, dtype=float)
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    for preset in args.presets:
        run = run_chain(f, w, load_cueing(preset), platform, limits, RATE)
        ev = run.evaluation
        print(preset)
        print("\n".join(regimes(ev.perceived_vehicle[:, 0], ev.perceived_sim[:, 0])))
    if args.bound:
        import motioncue.cueing._bound as bound_impl

        caught: list[tuple[NDArray[np.float64], NDArray[np.float64]]] = []
        upsample = bound_impl._upsample_motion

        def keep(ch, p_d, tau_d, k, n):  # type: ignore[no-untyped-def]
            out = upsample(ch, p_d, tau_d, k, n)
            caught.append(out)
            return out

        bound_impl._upsample_motion = keep  # the primals at the full rate, as cue_bound checks
        tight = pulse_rounding_limits(limits, platform, 1.0 / RATE)
        reach = reach_coupling(platform, tight, rig_reach(platform, tight))
        b = cue_bound(f, RATE, reach, corr_cuts=0)
        print(f"bound: share <= {b.share_max_at_corr[0]:.3f} at corr >= 0.95 (of a motion "
              f"whose perceived fx has zero mean <= {b.share_max_at_corr_zero_mean[0]:.3f}), "
              f"found {b.share_at_corr_primal[0]:.3f} (corr {b.corr_at_primal[0]:.3f})"
              )  # fmt: skip
        best: tuple[float, NDArray[np.float64], NDArray[np.float64]] | None = None
        for p, tau in caught:  # fx's and fy's primals: keep fx's best (tau = -sin(pitch))
            poses = np.zeros((len(p), 6))
            poses[:, 0], poses[:, 4] = p, -np.arcsin(np.clip(tau, -1.0, 1.0))
            ev = evaluate_cueing(f, w, poses, RATE)
            v, s = ev.perceived_vehicle[:, 0], ev.perceived_sim[:, 0]
            c = float(np.corrcoef(v, s)[0, 1])
            if best is None or c > best[0]:  # fx's: the one closest to the bound's corr
                best = (c, v, s)
        if best is not None:
            print("the bound's motion (x and pitch as a pose)")
            print("\n".join(regimes(best[1], best[2])))


if __name__ == "__main__":
    main()
