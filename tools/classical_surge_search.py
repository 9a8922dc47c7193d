"""Issue 20, fx: the (1+2) random local search of a stronger tilt whose lag a slow surge fills.

What the live MPC does on a stop that the classical default does not
(``tools/fx_mpc_vs_classical.py``): it pitches about 1.8x as far (its tilt part of fx on the
stops of the tuning drives -0.9 to -1.2 m/s^2 against the default's -0.5 to -0.7) and holds
it, and its surge renders the stop's edges while the tilt travels (x'' about -0.7 m/s^2 at
the onset and +0.7 at the end, x to 30-46 mm; the default's -0.3 and 7-9 mm). Doubling the
default's tilt gain alone gives the MPC's fx share at its correlation but 2-5x its reversals,
at the stop's onset and in the 0.8 s after it (``tools/classical_reversals.py``). The
default's surge is nearly all lag fill (``f_scale`` x 0.021): its x translational filter
(``wn`` 5.3 rad/s, ``zeta`` 1) cuts a fill pulse after about 1 / wn = 0.19 s. A slower x
filter (``[translational] wn_rad_s``, ``wb_rad_s`` x apart from y) lets the fill last the
tilt's travel.

This search starts from racing-hexapod-firm with the tilt's x gain, the lag fill, the x
translational filter (wn, wb), the x phase lead and the translation's x gain free (log space;
y, z, the rotational channel, the tilt's y gain untouched) and, on each of the TUNING drives
(chicane-gt, street-formula, flowing-road and the unbundled chicane-formula of
racing-hexapod-firm.toml's header), keeps: corr fx at least the firm preset's there
(:data:`FIRM_CORR_FX`), reversals at most the firm preset's there + ``--rev-slack``
(:data:`FIRM_REVERSALS`), all false cues <= 10 %, clamped <= 0.3 %, share fy at least the firm
preset's - 0.002, no frame changed by the actuator limiter; it maximises the mean share fx over
the drives. Run from the repository root (about 2-4 s per candidate on the shared machine,
twice that with ``--augment-fx``)::

    python tools/make_sample_lap.py --track chicane --car formula --laps 3 --seed 105 \\
        --out chicane-formula.csv
    nice -n 10 python tools/classical_surge_search.py --budget-s 900 --seed 1 \\
        --drives configs/recordings/chicane-gt.csv configs/recordings/street-formula.csv \\
        configs/recordings/flowing-road.csv chicane-formula.csv --out surge.toml

Session 26 (issue 20), all from racing-hexapod-firm (figures per tuning drive in the order
above: share fx, corr fx, reversals %):

* probes (``tilt_scale`` x times k, the rest firm's): k = 2: 0.075 / 0.071 / 0.080 / 0.067,
  corr 0.965 / 0.955 / 0.987 / 0.930, reversals 1.77 / 2.09 / 0.73 / 4.98 (mpc-hexapod on the
  same whole drives: 0.075 / 0.068 / 0.083 / 0.064, 0.959 / 0.953 / 0.977 / 0.931, 0.45 / 0.73
  / 0.09 / 1.69): the MPC's fx is the classical's at twice the tilt gain, at the same
  correlation, with a fifth to a third of the reversals. k = 1.5 with the x filter at wn 3, wb
  0.8 (firm's 5.3, 1.25): corr 0.987 / 0.981 / 0.985 / 0.969 (k = 1.5 alone: 0.979 / 0.972 /
  0.985 / 0.954). A faster tilt (45 or 90 deg/s, no rate_mix) lowers corr fx (0.80-0.96) and
  the actuator limiter changes frames.
* ``--rev-slack 0.003 --augment-fx 1.3 --seed 3`` from that point (stopped at 370 s):
  0.046 / 0.044 / 0.050 / 0.043, corr 0.991 / 0.987 / 0.981 / 0.978. Held out (looked at once
  as a check): fx 0.049 / 0.040 / 0.046 (forest-rally, flowing-formula, lap; firm 0.042 /
  0.034 / 0.039), but on flowing-formula corr fx 0.946 (firm 0.951), reversals 4.03 % (4.00)
  and 0.54 % of the poses clamped (firm 0): braking in its 2.8 g corners (roll 10-12 deg,
  pitch 1.4-5.5 deg nose-down, x -11 to -16 mm), which no tuning drive has at that size.
* ``--augment-fx 1.3 --augment-fy 1.3`` (seed 4, 600 s) and ``--augment-fy 1.15`` (seed 5,
  480 s), the reach exponent free: the search returns to the firm's fx (tilt gain 0.039 /
  0.040): held out fx 0.042 / 0.036 / 0.040 and 0.042 / 0.035 / 0.039, fewer false cues
  (4.6 / 6.3 / 1.7-1.8 %; firm 5.6 / 6.4 / 2.7), reversals 1.18 / 3.77 / 0.26 % (firm 1.45 /
  4.00 / 0.19), corr fx on flowing-formula 0.949. None beats the default held out on fx with
  corr fx >= 0.95 on every drive and reversals no worse; no preset was made of them.
"""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

import numpy as np
from _local_search import one_plus_two

from motioncue.analysis import run_chain
from motioncue.cueing import CueingParams, load_cueing
from motioncue.cueing._metrics import cue_metrics
from motioncue.cueing._tune import preset_toml
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.telemetry._recording import read_recording_csv, resample
from motioncue.trajectory import ActuatorLimits

RATE = 100.0
FIRM_CORR_FX = (0.991, 0.987, 0.975, 0.978)  # racing-hexapod-firm on the drives, in order
FIRM_REVERSALS = (0.0049, 0.0154, 0.0061, 0.0289)
FIRM_SHARE_FY = (0.132, 0.119, 0.137, 0.112)
# name, lower, upper bound (the search is in their logs)
FREE = (
    ("tilt_scale_x", 0.03, 0.12),
    ("lag_fill", 0.2, 1.0),
    ("trans_wn_x", 1.5, 8.0),
    ("trans_wb_x", 0.2, 2.0),
    ("lead_x", 0.02, 0.3),
    ("f_scale_x", 0.005, 0.1),
    ("reach_exponent", 1.2, 2.0),
)


def with_x(base: CueingParams, v: dict[str, float]) -> CueingParams:
    """``base`` with the free x parameters ``v`` (the names of :data:`FREE`)."""
    assert base.tilt_scale is not None and base.lead_s is not None
    return replace(
        base,
        tilt_scale=(v["tilt_scale_x"], base.tilt_scale[1]),
        tilt_lag_fill=v["lag_fill"],
        trans_wn_rad_s=(v["trans_wn_x"], *base.trans_wn_rad_s[1:]),
        trans_wb_rad_s=(v["trans_wb_x"], *base.trans_wb_rad_s[1:]),
        lead_s=(v["lead_x"], base.lead_s[1]),
        f_scale=(v["f_scale_x"], *base.f_scale[1:]),
        tilt_reach_exponent=v["reach_exponent"],
        intensity_gentle=None,
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--budget-s", type=float, required=True)
    ap.add_argument("--seed", type=int, required=True)
    ap.add_argument("--drives", nargs=4, required=True, help="the four tuning drives, in order")
    ap.add_argument("--base", default="racing-hexapod-firm")
    ap.add_argument("--start", nargs="*", default=[], metavar="NAME=VALUE")
    ap.add_argument("--out", required=True)
    ap.add_argument(
        "--rev-slack",
        type=float,
        default=0.0005,
        help="reversals allowed above the firm preset's on each drive (share, not %%)",
    )
    ap.add_argument(
        "--augment-fy",
        type=float,
        default=1.0,
        help="with --augment-fx: the augmented drives' fy times this too",
    )
    ap.add_argument(
        "--augment-fx",
        type=float,
        default=0.0,
        help="also each drive with its fx times this (harder stops): corr fx there at "
        "least the firm preset's there, no more poses clamped than it, none limited",
    )
    args = ap.parse_args()
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=RATE)
    recs = [resample(read_recording_csv(Path(d)), RATE) for d in args.drives]
    base = load_cueing(args.base)
    hard: list[tuple[np.ndarray, np.ndarray]] = []
    hard_corr: list[float] = []
    hard_clamped: list[int] = []
    if args.augment_fx > 0.0:
        for rec in recs:
            f = np.array(rec.f, dtype=float)
            f[:, 0] *= args.augment_fx
            f[:, 1] *= args.augment_fy
            hard.append((f, np.asarray(rec.w, dtype=float)))
        firm = replace(load_cueing("racing-hexapod-firm"), intensity_gentle=None)
        for f, w in hard:
            frun = run_chain(f, w, firm, platform, limits, RATE)
            ev = frun.evaluation
            hard_clamped.append(frun.poses_clamped)
            hard_corr.append(
                float(np.corrcoef(ev.perceived_sim[:, 0], ev.perceived_vehicle[:, 0])[0, 1])
            )
        corr_txt = " ".join(f"{c:.3f}" for c in hard_corr)
        clamp_txt = " ".join(str(c) for c in hard_clamped)
        print(f"firm on the augmented drives: corr fx {corr_txt}, clamped poses {clamp_txt}")
    assert base.tilt_scale is not None and base.lead_s is not None
    start = {
        "tilt_scale_x": base.tilt_scale[0],
        "lag_fill": base.tilt_lag_fill,
        "trans_wn_x": base.trans_wn_rad_s[0],
        "trans_wb_x": base.trans_wb_rad_s[0],
        "lead_x": base.lead_s[0],
        "f_scale_x": base.f_scale[0],
        "reach_exponent": base.tilt_reach_exponent,
    }
    for item in args.start:
        k, _, val = item.partition("=")
        start[k] = float(val)
    names = [n for n, _, _ in FREE]
    lo = np.log([a for _, a, _ in FREE])
    hi = np.log([b for _, _, b in FREE])
    x0 = np.clip(np.log([start[n] for n in names]), lo, hi)

    def params(x: np.ndarray) -> CueingParams:
        return with_x(base, dict(zip(names, np.exp(x).tolist(), strict=True)))

    def evaluate(x: np.ndarray) -> tuple[float, str]:
        p = params(x)
        viol, strength, cells = 0.0, 0.0, []
        for rec, c0, r0, fy0 in zip(recs, FIRM_CORR_FX, FIRM_REVERSALS, FIRM_SHARE_FY, strict=True):
            run = run_chain(rec.f, rec.w, p, platform, limits, RATE)
            ev = run.evaluation
            m = cue_metrics(ev.perceived_vehicle, ev.perceived_sim, ev.thresholds,
                            clamped_share=run.poses_clamped / len(run.poses))  # fmt: skip
            viol += 10 * max(0.0, c0 - m.correlation[0])
            viol += 10 * max(0.0, m.reversals_any - (r0 + args.rev_slack))
            viol += max(0.0, m.false_any - 0.10) + 10 * max(0.0, m.clamped - 0.003)
            viol += 10 * run.actuator_limited / 1000 + 10 * max(
                0.0, fy0 - 0.002 - m.rendered_share[1]
            )
            strength += m.rendered_share[0]
            cells.append(
                f"{m.rendered_share[0]:.3f}/{m.rendered_share[1]:.3f} c{m.correlation[0]:.3f} "
                f"r{100 * m.reversals_any:.2f} f{100 * m.false_any:.1f} L{run.actuator_limited}"
            )
        for (f, w), c0, k0 in zip(hard, hard_corr, hard_clamped, strict=True):
            run = run_chain(f, w, p, platform, limits, RATE)
            ev = run.evaluation
            c = float(np.corrcoef(ev.perceived_sim[:, 0], ev.perceived_vehicle[:, 0])[0, 1])
            viol += 10 * max(0.0, c0 - c) + 10 * max(0, run.poses_clamped - k0) / len(run.poses)
            viol += 10 * run.actuator_limited / 1000
            cells.append(f"aug c{c:.3f} cl{run.poses_clamped} L{run.actuator_limited}")
        fit = -strength / len(recs) if viol == 0.0 else 1.0 + viol
        return fit, " | ".join(cells)

    def better(it: int, elapsed_s: float, fit: float, x: np.ndarray, cells: str) -> None:
        v = dict(zip(names, np.exp(x).tolist(), strict=True))
        note = [f"classical_surge_search it {it} fit {fit:.5f}", cells]
        Path(args.out).write_text(preset_toml(params(x), note))
        print(
            f"it {it} t {elapsed_s:.0f} s fit {fit:.5f} "
            + " ".join(f"{k}={val:.4g}" for k, val in v.items()),
            flush=True,
        )
        print(f"    {cells}", flush=True)

    one_plus_two(evaluate, x0, lo, hi, seed=args.seed, budget_s=args.budget_s, k_max=4, sigma=0.1,
                 on_better=better)  # fmt: skip


if __name__ == "__main__":
    main()
