"""Cue metrics of presets on excerpts of the bundled car drives (the figures in the headers of
configs/cueing/optimal-hexapod.toml and mpc-hexapod.toml).

Each preset runs through the chain of ``motioncue compare`` (:func:`run_chain`: cueing,
workspace limiting, the actuator limiter, forward kinematics, vestibular models) on the
``--excerpt`` window of each drive of ``--set`` (``tuning``: the car tuning drives; ``held-out``:
the held-out car drives and the demo lap, for reporting only: never tune on them); the
metrics are :func:`cue_metrics`' per drive and pooled. ``--mpc KEY=JSON`` overrides one
``[mpc]`` setting (``MpcParams`` field), e.g. ``--mpc 'w_vehicle=[0.07, 0.2, 0, 0, 0, 0]'``.

    python tools/excerpt_metrics.py --set tuning --excerpt 30:50 optimal-hexapod
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from motioncue.analysis._compare import run_chain
from motioncue.cueing import get_model_set, load_cueing
from motioncue.cueing._metrics import CueMetrics, cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline._inputs import load_generate_input
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
LAP = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"


def _row(label: str, m: CueMetrics, limited: int) -> str:
    def pair(v: np.ndarray, k: float = 1.0, f: str = ".3f") -> str:
        return f"{k * v[0]:{f}}/{k * v[1]:{f}}"

    return (
        f"{label:16s} share {pair(m.rendered_share)} corr {pair(m.correlation)} "
        f"missed {pair(m.missed, 100, '.0f')} % reversals {100 * m.reversals_any:.2f} % "
        f"false {100 * m.false_any:.1f} % clamped {100 * m.clamped:.1f} % limited {limited}"
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("presets", nargs="+")
    ap.add_argument("--set", choices=("tuning", "held-out"), default="tuning")
    ap.add_argument("--excerpt", default="30:50", help="A:B seconds from each drive's start")
    ap.add_argument("--mpc", action="append", default=[], metavar="KEY=JSON")
    args = ap.parse_args(argv)
    a_s, b_s = (float(v) for v in args.excerpt.split(":"))
    paths = list(sample_drives(args.set, kind="car"))
    if args.set == "held-out":
        paths.append(LAP)
    drives = []
    for p in paths:
        _, data, _ = load_generate_input(str(p))
        r = resample(data, RATE)
        a, b = round(a_s * RATE), round(b_s * RATE)
        drives.append((p.stem, np.asarray(r.f, float)[a:b], np.asarray(r.w, float)[a:b]))
    plat = load_platform("stewart6-linear")
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox6"), rate_hz=RATE)
    thr = get_model_set("telban-cardullo-2005").thresholds
    over = {}
    for item in args.mpc:
        key, _, val = item.partition("=")
        v = json.loads(val)
        over[key] = tuple(v) if isinstance(v, list) else v
    for name in args.presets:
        params = load_cueing(name)
        if over:
            if params.mpc is None:
                print(f"{name}: no [mpc] table for --mpc", file=sys.stderr)
                return 2
            params = dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, **over))
        print(f"== {name} {' '.join(args.mpc)}")
        pv, ps = [], []
        clamped = n = limited = 0
        for label, f, w in drives:
            run = run_chain(f, w, params, plat, lim, RATE, recording=label, preset=name)
            ev = run.evaluation
            pv.append(ev.perceived_vehicle)
            ps.append(ev.perceived_sim)
            share = run.poses_clamped / f.shape[0]
            m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, thr, clamped_share=share)
            print(_row(label, m, run.actuator_limited))
            clamped += run.poses_clamped
            limited += run.actuator_limited
            n += f.shape[0]
        m = cue_metrics(np.concatenate(pv), np.concatenate(ps), thr, clamped_share=clamped / n)
        print(_row("pooled", m, limited), flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
