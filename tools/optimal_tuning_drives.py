r"""Cue metrics of ``optimal-hexapod`` candidates on whole tuning drives (the figures of session
26 in the header of configs/cueing/optimal-hexapod.toml).

The drives: the bundled car tuning drives (``sample_drives("tuning", kind="car")``) and formula
drives made for tuning only with ``tools/make_sample_lap.py`` into ``--made DIR`` (not bundled;
never the held-out drives or the demo lap):

    python tools/make_sample_lap.py --track chicane --car formula --laps 1 --seed 301 \
        --out DIR/chicane-formula-301.csv

and the same for ``--track street --laps 2 --seed 401`` (street-formula-401.csv), ``--track
flowing --laps 1 --seed 501``, ``--laps 2 --seed 502``, ``--laps 1 --seed 601``, 602, 603
(flowing-formula-SEED.csv). Each candidate (``--mpc KEY=JSON`` overrides of the preset's
``[mpc]`` table, ``MpcParams`` fields) and ``racing-hexapod-firm`` run through the chain of
``motioncue compare`` (:func:`run_chain`) on each whole drive, one process per drive
(``--jobs``); printed per drive: share fx/fy and its ratio to the firm preset's, corr fx/fy,
reversals (all, fz), all false cues, clamped %, frames changed by the actuator limiter.

    python tools/optimal_tuning_drives.py --made DIR --mpc 'sign_guard_weight=1e5'
"""

from __future__ import annotations

import argparse
import dataclasses
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from motioncue.analysis._compare import run_chain
from motioncue.cueing import get_model_set, load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline._inputs import load_generate_input
from motioncue.telemetry import sample_drives
from motioncue.telemetry._recording import resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
BASE = "optimal-hexapod"
CLASSICAL = "racing-hexapod-firm"


def _one(job: tuple[str, str, str, dict[str, object]]) -> tuple[str, str, list[float]]:
    path, preset, key, over = job
    _, data, _ = load_generate_input(path)
    r = resample(data, RATE)
    f, w = np.asarray(r.f, float), np.asarray(r.w, float)
    params = load_cueing(preset)
    if over:
        assert params.mpc is not None
        params = dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, **over))
    plat = load_platform("stewart6-linear")
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox6"), rate_hz=RATE)
    thr = get_model_set("telban-cardullo-2005").thresholds
    run = run_chain(f, w, params, plat, lim, RATE, recording=Path(path).stem, preset=preset)
    ev = run.evaluation
    m = cue_metrics(
        ev.perceived_vehicle, ev.perceived_sim, thr, clamped_share=run.poses_clamped / f.shape[0]
    )
    vals = [
        *m.rendered_share[:2],
        *m.correlation[:2],
        100 * m.reversals_any,
        100 * m.reversals[2],
        100 * m.false_any,
        100 * m.clamped,
        float(run.actuator_limited),
    ]
    return Path(path).stem, key, [float(v) for v in vals]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--made", type=Path, required=True, help="directory of the made drives")
    ap.add_argument("--mpc", action="append", default=[], metavar="KEY=JSON")
    ap.add_argument("--preset", default=BASE)
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args(argv)
    paths = [str(p) for p in sample_drives("tuning", kind="car")]
    paths += [str(p) for p in sorted(args.made.glob("*.csv"))]
    over: dict[str, object] = {}
    for item in args.mpc:
        key, _, val = item.partition("=")
        v = json.loads(val)
        over[key] = tuple(v) if isinstance(v, list) else v
    jobs = [(p, args.preset, "cand", over) for p in paths]
    jobs += [(p, CLASSICAL, "firm", {}) for p in paths]
    with ProcessPoolExecutor(args.jobs) as ex:
        res = list(ex.map(_one, jobs))
    got = {(name, key): v for name, key, v in res}
    print(f"== {args.preset} {' '.join(args.mpc)}")
    worst = {"rx": 9.0, "ry": 9.0, "rev": 0.0, "false": 0.0, "cx": 1.0, "cy": 1.0, "cl": 0.0}
    lrx, lry = [], []
    limited = 0.0
    for p in paths:
        name = Path(p).stem
        c, fm = got[(name, "cand")], got[(name, "firm")]
        rx, ry = c[0] / fm[0], c[1] / fm[1]
        lrx.append(np.log(rx))
        lry.append(np.log(ry))
        limited += c[8]
        worst.update(
            rx=min(worst["rx"], rx),
            ry=min(worst["ry"], ry),
            rev=max(worst["rev"], c[4]),
            false=max(worst["false"], c[6]),
            cx=min(worst["cx"], c[2]),
            cy=min(worst["cy"], c[3]),
            cl=max(worst["cl"], c[7]),
        )
        print(
            f"{name:22s} share {c[0]:.3f}/{c[1]:.3f} ({rx:.2f}/{ry:.2f}x) corr "
            f"{c[2]:.3f}/{c[3]:.3f} rev {c[4]:.2f} % (fz {c[5]:.2f}) false {c[6]:.1f} % "
            f"clamped {c[7]:.2f} % limited {int(c[8])}"
        )
    print(
        f"summary ratio fx {np.exp(np.mean(lrx)):.2f}/{worst['rx']:.2f} fy "
        f"{np.exp(np.mean(lry)):.2f}/{worst['ry']:.2f} (geo mean/least) max rev "
        f"{worst['rev']:.2f} % max false {worst['false']:.1f} % min corr "
        f"{worst['cx']:.3f}/{worst['cy']:.3f} max clamped {worst['cl']:.2f} % limited "
        f"{int(limited)}",
        flush=True,
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
