"""The (1+2) random local search that made ``configs/cueing/racing-hexapod-firm.toml``.

Run from the repository root (slow: about 6 s per candidate on the four drives; budget in
seconds)::

    python tools/make_sample_lap.py --track chicane --car formula --laps 3 --seed 105 \\
        --out chicane-formula.csv
    python tools/classical_strength_search.py --stage 1 --budget-s 770 --seed 1 \\
        --base racing-hexapod-strong --out s1.toml
    python tools/classical_strength_search.py --stage 2 --budget-s 1200 --seed 2 \\
        --base s1.toml --out s2.toml
    python tools/classical_strength_search.py --stage 3 --budget-s 900 --seed 3 \\
        --base s2.toml --out s3.toml

(the first stage was stopped at 770 s.) Stage 4 (issue 20, the reach offset), from the
firm preset with ``[tilt] offset_mm``, ``reach_deg`` and ``reach_exponent`` of
``tools/tilt_reach_offset.py``::

    python tools/classical_strength_search.py --stage 4 --budget-s 1200 --seed 4 \
        --base firm-offset.toml --out s4.toml
 Each candidate runs through the chain of ``motioncue
compare`` (:func:`motioncue.analysis.run_chain`) on the tuning car drives chicane-gt,
street-formula, flowing-road and the unbundled chicane-formula; a candidate is better when it
violates the constraints less (Deb's rule), or meets them all with a larger strength.

* stage 1: the tuner's 21 parameters (``STRENGTH_TUNED_PARAMETERS``), ``[tilt] rate_mix`` of
  stewart6-linear's legs, the rate limit at most 32 deg/s; strength = mean over the drives of
  ``sqrt(share fx * share fy)``; on every drive corr fx >= 0.96, fy >= 0.93, all false cues
  <= 10 %, clamped <= 0.3 %, no frame changed by the actuator limiter; the drives' mean
  reversals <= 1.5 %.
* stage 2: also ``[tilt] lag_fill``; strength = mean of ``share fx^(2/3) share fy^(1/3)``;
  corr fx >= 0.97 on every drive.
* stage 3: the rate limit at most 30 deg/s; corr fx on every drive at least the old default's
  (racing-hexapod) there + 0.005.
* stage 4: as stage 3, and on every drive share fx and fy at least racing-hexapod-firm's
  there (:data:`FIRM_SHARES`); the base carries the reach offset, kept as it is. Run once
  (seed 4, 1200 s, 105 iterations): no candidate met the constraints (the best violated
  them by 0.067: the drives' mean reversals above 1.5 %, the heave offset's own heave
  reversals among them, and fy below firm's on the formula drives), so no preset came of it.
* stage 5 (session 27): from racing-hexapod-firm with ``f_scale`` z 0.2 (its heave cue
  made the z reversals of the formula drives' held roll rarer there); strength = mean of
  ``share fx^0.8 share fy^0.2``; as stage 3, and on every drive share fy at least firm's
  there - 0.002 and reversals <= 1.5 %, the drives' mean <= 1 %. Run once (seed 5,
  ``--budget-s 1500``, stopped by hand after about 430 s; the last kept step at 417 s,
  iteration 228): the base broke the constraints (chicane-formula's reversals 1.72 %); the
  first point meeting them had strength 0.04925, the last 0.04965 (+0.8 %) with 17
  parameters moved, so no preset came of it: the fx correlation floors hold fx where firm
  has it.

The seeds give the same sequence of candidates; the wall-clock budget decides where it stops.
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from _local_search import one_plus_two

from motioncue.analysis import run_chain
from motioncue.cueing import CueingParams, load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.cueing._tune import (
    STRENGTH_TUNED_PARAMETERS,
    params_from_vector,
    preset_toml,
    vector_from_params,
)
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
D2R = math.pi / 180.0
DRIVES = [
    "configs/recordings/chicane-gt.csv",
    "configs/recordings/street-formula.csv",
    "configs/recordings/flowing-road.csv",
    "chicane-formula.csv",
]
OLD_DEFAULT_CORR_FX = (0.984, 0.981, 0.970, 0.973)  # racing-hexapod on DRIVES
FIRM_SHARES = ((0.039, 0.132), (0.038, 0.119), (0.043, 0.137), (0.036, 0.112))  # fx, fy


def leg_rate_rows(platform_name: str = "stewart6-linear") -> tuple[tuple[float, float], ...]:
    """``[tilt] rate_mix``: each leg's speed per unit roll and pitch rate at neutral (finite
    differences of the inverse kinematics), one row per distinct pair, scaled to the largest."""
    platform = load_platform(platform_name)
    q0 = np.asarray(platform.inverse(np.zeros(6)))
    cols = []
    for k in (3, 4):
        e = np.zeros(6)
        e[k] = 1e-6
        cols.append(np.abs((np.asarray(platform.inverse(e)) - q0) / 1e-6))
    rows = sorted({(round(float(a), 4), round(float(b), 4)) for a, b in np.array(cols).T})
    top = max(max(r) for r in rows)
    return tuple((round(a / top, 3), round(b / top, 3)) for a, b in rows)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--stage", type=int, choices=(1, 2, 3, 4, 5), required=True)
    ap.add_argument("--budget-s", type=float, required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--base", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    recs = [resample(read_recording_csv(Path(d)), RATE) for d in DRIVES]

    rate_max = {1: 32.0, 2: 32.0, 3: 30.0, 4: 30.0, 5: 30.0}[args.stage]
    floors = [0.96] * 4 if args.stage == 1 else [0.97] * 4
    if args.stage >= 3:
        floors = [max(0.97, c + 0.005) for c in OLD_DEFAULT_CORR_FX]
    base: CueingParams = replace(load_cueing(args.base), tilt_rate_mix=leg_rate_rows())
    if args.stage == 1:
        base = replace(base, tilt_rate_limit_rad_s=30.0 * D2R)
    base = replace(base, tilt_rate_limit_rad_s=min(base.tilt_rate_limit_rad_s, rate_max * D2R))
    table = STRENGTH_TUNED_PARAMETERS
    lo = np.log([p.lo for p in table])
    hi = np.log([p.hi for p in table])
    hi[12] = math.log(rate_max)  # the tilt rate limit: the legs' speed
    x0 = vector_from_params(base)
    fill = args.stage >= 2
    if fill:
        x0 = np.append(x0, math.log(max(base.tilt_lag_fill, 0.5)))
        lo = np.append(lo, math.log(0.05))
        hi = np.append(hi, 0.0)

    def params(x: np.ndarray) -> CueingParams:
        if not fill:
            return params_from_vector(base, x, name="search")
        return replace(
            params_from_vector(base, x[:-1], name="search"), tilt_lag_fill=math.exp(x[-1])
        )

    def evaluate(x: np.ndarray) -> float:
        p = params(x)
        viol, strength, revs = 0.0, 0.0, []
        for rec, floor, firm in zip(recs, floors, FIRM_SHARES, strict=True):
            run = run_chain(rec.f, rec.w, p, platform, limits, RATE)
            ev = run.evaluation
            m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds,
                            clamped_share=run.poses_clamped / len(run.poses))  # fmt: skip
            viol += 10 * max(0.0, floor - m.correlation[0]) + 10 * max(0.0, 0.93 - m.correlation[1])
            viol += max(0.0, m.false_any - 0.10) + 10 * run.actuator_limited / 1000
            viol += 10 * max(0.0, m.clamped - 0.003)
            revs.append(m.reversals_any)
            sx, sy = m.rendered_share[0], m.rendered_share[1]
            if args.stage == 4:  # not weaker than firm in either channel
                viol += 10 * max(0.0, firm[0] - sx) + 10 * max(0.0, firm[1] - sy)
            if args.stage == 5:  # fy not weaker than firm's, reversals within 1.5 % per drive
                viol += 10 * max(0.0, firm[1] - 0.002 - sy)
                viol += 10 * max(0.0, m.reversals_any - 0.015)
            if args.stage in (1, 4):
                strength += (sx * sy) ** 0.5
            elif args.stage == 5:
                strength += sx**0.8 * sy**0.2
            else:
                strength += sx ** (2 / 3) * sy ** (1 / 3)
        viol += 10 * max(0.0, float(np.mean(revs)) - (0.01 if args.stage == 5 else 0.015))
        return -strength / len(recs) if viol == 0.0 else 1.0 + viol

    def better(it: int, elapsed_s: float, fit: float, x: np.ndarray, _: None) -> None:
        Path(args.out).write_text(preset_toml(params(x), [f"search it {it} fit {fit:.5f}"]))
        print(f"it {it} t {elapsed_s:.0f} s fit {fit:.5f}", flush=True)

    one_plus_two(
        lambda x: (evaluate(x), None),
        x0,
        lo,
        hi,
        seed=args.seed,
        budget_s=args.budget_s,
        k_max=5,
        sigma=0.12,
        on_better=better,
    )


if __name__ == "__main__":
    main()
