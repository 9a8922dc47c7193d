"""Issue 20's table: cue strength and cue errors of every preset on the held-out drives.

Run: ``python benchmarks/bench_cue_table.py [--platform P] [--controller C] [--presets ...]
[--kind car] [--no-bound] [--fresh]`` (with ``src`` on the path; ``--fresh`` adds the
generated held-out drives of ``configs/recordings/generated.toml``). For each held-out drive
(``sample_drives("held-out")``, or only those of ``--kind``) and the bundled lap, every
preset runs through the chain of ``motioncue compare`` (cueing, workspace limiting, actuator
limits, delivered poses through the vestibular models) on the bundled ``stewart6-linear``
hexapod driven by an ``mbox6`` unless told otherwise. None of these drives is a tuning drive.

Printed per drive and preset (definitions: ``docs/cue-metrics.md``,
:func:`motioncue.cueing.cue_metrics`): correlation fx / fy, rendered share fx / fy, gain
fx / fy, missed cues fx / fy (% of the time), reversals fx / fy / any channel and all
false cues (any channel; % of the time), clamped poses (%), the jolt fx / fy (the rider's
perceived motion above 2 Hz in thresholds, :func:`motioncue.cueing.jolt`; in brackets the
vehicle's own: pulses far above it are knocks the vehicle did not have), and with the bound
(:func:`motioncue.cueing.cue_bound`, default on) each preset's share as % of the largest
gain the rig could give without a reversal and of the largest share it could give at the
acceptance's correlation (0.95 fx, 0.90 fy); then per drive the bound itself. Ends with the
wall time of the chains and of the bounds (one run; these are figures, not timings to
compare).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

ROOT = Path(__file__).resolve().parents[1]
# every preset made for the bundled hexapod, then the generic one; the platform's own
# default_preset and ride_preset are put first whatever the platform
HEXAPOD_PRESETS = ("racing-hexapod-firm", "racing-hexapod", "racing-hexapod-strong",
                   "racing-hexapod-adaptive", "mpc-hexapod", "mpc-hexapod-auto",
                   "optimal-hexapod",
                   "optimal-hexapod-auto",
                   "racing")  # fmt: skip


def _pct(v: float) -> str:
    return f"{v:5.1f}" if v == v else "    -"


def main(argv: list[str]) -> int:
    from motioncue.analysis._compare import compare_cueing
    from motioncue.cueing import load_cueing
    from motioncue.cueing._bound import CORR_MIN
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.pipeline._inputs import load_generate_input
    from motioncue.telemetry import sample_drives
    from motioncue.trajectory import ActuatorLimits

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--platform", default="stewart6-linear")
    ap.add_argument("--controller", default="mbox6")
    ap.add_argument("--presets", nargs="+", default=None,
                    help="default: the platform's default preset, then (stewart6-linear) every "
                    "hexapod preset and racing")  # fmt: skip
    ap.add_argument("--no-bound", action="store_true", help="skip the physical bound")
    ap.add_argument("--kind", default=None, help="only held-out drives of this kind (car, ...)")
    ap.add_argument("--fresh", action="store_true", help="also the generated held-out drives "
                    "(configs/recordings/generated.toml, written into build/drives)")  # fmt: skip
    args = ap.parse_args(argv)
    platform = load_platform(args.platform)
    limits = ActuatorLimits.from_platform(platform, load_controller(args.controller), rate_hz=100.0)
    held_out = sample_drives("held-out", kind=args.kind) if args.kind else sample_drives("held-out")
    drives = [*held_out, ROOT / "configs" / "recordings" / "lap.csv"]
    if args.fresh:
        sys.path.insert(0, str(ROOT / "tools"))
        from make_generated_drives import generated_drives

        drives += generated_drives(ROOT / "build" / "drives", set="held-out", kind=args.kind)
    recs = []
    for path in drives:
        kind, data, _ = load_generate_input(str(path))
        assert kind == "recording"
        recs.append((Path(path).stem, data))
    if args.presets is None:
        # the platform's live default and its ride-file default (generate, cue) first
        own = [p for p in (platform.default_preset, platform.ride_preset) if p]
        rest = HEXAPOD_PRESETS if args.platform == "stewart6-linear" else ("racing",)
        args.presets = list(dict.fromkeys([*own, *rest]))
        print(f"presets: {', '.join(args.presets)} (defaults of {args.platform}: {own or '-'})")
    presets = [(p, load_cueing(p)) for p in args.presets]
    t0 = time.perf_counter()
    res = compare_cueing(recs, presets, platform, limits, platform_name=args.platform,
                         controller_name=args.controller, bound=not args.no_bound)  # fmt: skip
    wall = time.perf_counter() - t0
    print(f"platform {args.platform}, controller {args.controller}, 100 Hz, vestibular models "
          f"{res.model_set}; drives: held-out + the bundled lap"
          + (" + the generated held-out drives" if args.fresh else ""))  # fmt: skip
    wr = max(len(k) for k, _ in recs)
    wp = max(len(p) for p in args.presets)
    print(
        f"{'drive':<{wr}} {'preset':<{wp}} {'corr fx/fy':>11} {'share fx/fy':>11} "
        f"{'gain fx/fy':>11} {'missed% fx/fy':>13} {'rev% fx/fy/any':>16} {'false%':>6} "
        f"{'clamp%':>6} {'jolt fx/fy (veh)':>22} "
        f"{'%bound fx/fy':>12} {'%@corr fx/fy':>12}"
    )
    for r in res.rows():
        dur = r["duration_s"]
        mx, my = (100 * r[f"missed_cue_s_{a}"] / dur for a in ("fx", "fy"))
        rx, ry = (100 * r[f"reversal_s_{a}"] / dur for a in ("fx", "fy"))
        print(
            f"{r['recording']:<{wr}} {r['preset']:<{wp}} "
            f"{r['corr_fx']:5.2f}/{r['corr_fy']:5.2f} {r['share_fx']:5.3f}/{r['share_fy']:5.3f} "
            f"{r['gain_fx']:5.3f}/{r['gain_fy']:5.3f} {mx:6.1f}/{my:6.1f} "
            f"{rx:4.2f}/{ry:4.2f}/{r['reversal_pct_any']:5.2f} {r['false_cue_pct_any']:6.2f} "
            f"{r['clamped_pct']:6.2f} "
            f"{r['jolt_fx']:4.2f}/{r['jolt_fy']:4.2f} "
            f"({r['jolt_vehicle_fx']:5.2f}/{r['jolt_vehicle_fy']:5.2f}) "
            f"{_pct(r['share_of_bound_pct_fx'])}/{_pct(r['share_of_bound_pct_fy'])} "
            f"{_pct(r['share_of_corr_bound_pct_fx'])}/{_pct(r['share_of_corr_bound_pct_fy'])}"
        )
    if res.bound_text():
        print()
        print(res.bound_text())
        beaten = [
            (r["recording"], r["preset"], a)
            for r in res.rows()
            for a in ("fx", "fy")
            if r[f"rms_{a}_m_s2"] < r[f"bound_error_{a}_m_s2"]
        ]
        print(f"presets below the error bound: {beaten or 'none'}")
        above = [
            (r["recording"], r["preset"], a)
            for r in res.rows()
            for i, a in enumerate(("fx", "fy"))
            if r[f"corr_{a}"] >= CORR_MIN[i] and r[f"share_{a}"] > r[f"bound_share_corr_{a}"]
        ]
        print(f"presets above the share bound at their correlation: {above or 'none'}")
    print(f"wall time (chains{' and bounds' if not args.no_bound else ''}): {wall:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
