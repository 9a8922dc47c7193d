"""``motioncue tune``: tune a cueing preset on recordings, within a platform's limits."""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from .._errors import ConfigError
from ._common import (
    LIMITS,
    OUT,
    PRESET,
    RATE,
    RECORDING,
    RIG,
    json_option,
    load_rig,
    print_json,
    set_option,
)
from ._preset import add_vestibular_option
from ._verb import Allowed, Option, Verb, registrar

if TYPE_CHECKING:
    from ..analysis import ChainMetrics, StrengthTargets

__all__ = ["register"]

_AXES = ("fx", "fy", "fz", "wx", "wy", "wz")


def _metrics_table(before: ChainMetrics, after: ChainMetrics) -> str:
    rows = [
        ("objective: cue score (mean)", before.objective, after.objective, ".4f"),
        ("perceived-motion error J (mean)", before.perceived_error, after.perceived_error, ".3f"),
    ]
    for i, a in enumerate(_AXES):
        rows.append((f"correlation {a} (mean)", before.correlation[i], after.correlation[i], ".3f"))
    rows.append(("false cues, any axis (%)", before.false_cue_fraction * 100,
                 after.false_cue_fraction * 100, ".2f"))  # fmt: skip
    for i, a in enumerate(_AXES):
        rows.append((f"false-cue time {a} (s)", before.false_cue_time_s[i],
                     after.false_cue_time_s[i], ".2f"))  # fmt: skip
    rows.append(("missed cues (mean %)", before.missed_cue_fraction * 100,
                 after.missed_cue_fraction * 100, ".2f"))  # fmt: skip
    rows.append(
        ("clamped poses (%)", before.clamped_fraction * 100, after.clamped_fraction * 100, ".2f")
    )
    rows.append(("frames breaking a limit", before.violating_frames, after.violating_frames, "d"))
    rows.append(("strength: sqrt(share fx fy)", before.strength, after.strength, ".4f"))
    if before.cue is not None and after.cue is not None:
        # cue strength and cue errors, pooled over the recordings (motioncue.cueing.cue_metrics)
        for i, a in enumerate(_AXES[:2]):
            rows.append((f"rendered share {a}", before.cue.rendered_share[i],
                         after.cue.rendered_share[i], ".3f"))  # fmt: skip
            rows.append((f"gain {a}", before.cue.gain[i], after.cue.gain[i], ".3f"))
            rows.append((f"missed cues {a} (%)", before.cue.missed[i] * 100,
                         after.cue.missed[i] * 100, ".2f"))  # fmt: skip
        for name, label in (("reversals_any", "reversals"), ("spurious_any", "spurious cues"),
                            ("false_any", "all false cues")):  # fmt: skip
            rows.append((f"{label}, any axis (%)", getattr(before.cue, name) * 100,
                         getattr(after.cue, name) * 100, ".2f"))  # fmt: skip
    lines = [f"{'metric':<32} {'before':>10} {'after':>10}"]
    for what, b_v, a_v, fmt in rows:
        lines.append(f"{what:<32} {format(b_v, fmt):>10} {format(a_v, fmt):>10}")
    return "\n".join(lines)


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from ..analysis import (
        PENALTY_BASE,
        StrengthTargets,
        TuneObjective,
        tilt_reach,
        tune_cueing,
        write_preset,
    )
    from ..cueing import Rig, cueing_algorithms, cueing_entry, get_model_set, load_cueing
    from ..cueing._tune import at_intensity, gentle_values, preset_toml, tuned_parameters
    from ..pipeline._inputs import load_generate_input
    from ..telemetry._motion import is_datagram_recording
    from ..telemetry._recording import read_recording_csv, resample
    from ..trajectory._derive import pulse_rounding_limits
    from ._preset import choose_preset

    if not 0 <= args.seed < 2**32:
        raise ConfigError(f"--seed {args.seed} is invalid; allowed: 0 to 2^32 - 1")
    if args.workers is not None and args.scheduler is not None:
        raise ConfigError("--workers and --scheduler exclude each other; give one")
    workers = args.workers if args.workers is not None else (os.cpu_count() or 1)
    if not 1 <= workers <= 1024:
        raise ConfigError(f"--workers {workers} is invalid; allowed: 1 to 1024")
    if args.scheduler is not None and not args.scheduler.startswith(("tcp://", "tls://")):
        raise ConfigError(
            f"--scheduler {args.scheduler!r} is invalid; allowed: tcp://HOST:PORT or tls://..."
        )
    if not 0 <= args.generations <= 100_000:
        raise ConfigError(f"--generations {args.generations} is invalid; allowed: 0 to 100000")
    if not 2 <= args.popsize <= 100:
        raise ConfigError(f"--popsize {args.popsize} is invalid; allowed: 2 to 100")
    if not (math.isfinite(args.rate) and 0.0 < args.rate <= 1000.0):
        raise ConfigError(f"--rate {args.rate!r} is invalid; allowed: (0, 1000] Hz")
    get_model_set(args.vestibular)
    out = Path(args.out)
    if out.suffix != ".toml":
        raise ConfigError(f"--out {out} is invalid; allowed: a .toml file name")
    if not out.parent.is_dir():
        raise ConfigError(f"--out {out}: folder {out.parent} does not exist")

    platform, controller, limits = load_rig(args, args.rate)
    base, base_source = choose_preset(args.preset, platform, args.platform, args.overrides)
    if cueing_entry(base.algorithm).tune is None:
        raise ConfigError(
            f"preset {base.name!r} uses the cueing algorithm {base.algorithm!r}, which "
            "declares no tunable parameters; tune optimises "
            + ", ".join(a for a in cueing_algorithms() if cueing_entry(a).tune is not None)
        )
    tight = pulse_rounding_limits(limits, platform, 1.0 / args.rate)
    excerpt = None
    if args.excerpt is not None:
        try:
            a_s, b_s = (float(v) for v in args.excerpt.split(":"))
        except ValueError:
            raise ConfigError(
                f"--excerpt {args.excerpt!r} is invalid; allowed: START:END in seconds"
            ) from None
        if not (math.isfinite(a_s) and math.isfinite(b_s) and 0.0 <= a_s and b_s - a_s >= 1.0):
            raise ConfigError(
                f"--excerpt {args.excerpt!r} is invalid; allowed: 0 <= START, END >= START + 1"
            )
        excerpt = (a_s, b_s)
    drives = []
    for path in args.input:
        if is_datagram_recording(Path(path)):  # a 'motioncue record' file
            rec = load_generate_input(path)[1]
        else:
            rec = read_recording_csv(path)
        if len(rec) < 2:
            raise ConfigError(f"{path}: too short to tune on ({len(rec)} samples)")
        uni = resample(rec, args.rate)
        f, w = uni.f, uni.w
        if excerpt is not None:
            a, b = round(excerpt[0] * args.rate), round(excerpt[1] * args.rate)
            if b > len(f):
                raise ConfigError(
                    f"{path}: --excerpt {args.excerpt} ends after the recording "
                    f"({len(f) / args.rate:.1f} s)"
                )
            f, w = f[a:b], w[a:b]
        drives.append((Path(path).name, f, w))
    for flag, value in (
        ("--max-reversals", args.max_reversals),
        ("--max-false", args.max_false),
        ("--max-clamped", args.max_clamped),
    ):
        if not (math.isfinite(value) and 0.0 < value <= 100.0):
            raise ConfigError(f"{flag} {value!r} is invalid; allowed: (0, 100] %")
    for v in args.min_corr:
        if not (math.isfinite(v) and -1.0 <= v < 1.0):
            raise ConfigError(f"--min-corr {v!r} is invalid; allowed: [-1, 1)")
    targets = StrengthTargets(
        max_reversals=args.max_reversals / 100.0,
        max_false=args.max_false / 100.0,
        max_clamped=args.max_clamped / 100.0,
        min_corr_fx=args.min_corr[0],
        min_corr_fy=args.min_corr[1],
    )
    if args.gentle_end and (base.tilt_shape is None or args.objective != "strength"):
        raise ConfigError(
            f"--gentle-end needs a base preset with the compressive tilt ([tilt] shape; "
            f"{base.name!r} has none) and --objective strength"
        )
    if not (math.isfinite(args.gentle_share) and 0.0 < args.gentle_share < 1.0):
        raise ConfigError(f"--gentle-share {args.gentle_share!r} is invalid; allowed: (0, 1)")
    hold: list[int] = []
    if args.gentle_keep:
        names = [p.name for p in tuned_parameters(base)]
        if not args.gentle_end:
            raise ConfigError("--gentle-keep needs --gentle-end")
        for k in args.gentle_keep:
            if k not in names:
                raise ConfigError(f"--gentle-keep {k!r} is invalid; allowed: {', '.join(names)}")
            hold.append(names.index(k))
    strong_end = base
    if base.tilt_shape is not None and not args.gentle_end and base.tilt_offset_m is None:
        base = replace(base, tilt_reach_rad=tilt_reach(platform, tight))  # the platform's own
        # (a preset with a reach offset keeps its reach: the reach with that offset)
    objective = TuneObjective(
        base, drives, platform, tight, args.rate, model=args.vestibular,
        objective=args.objective, targets=targets, rig=Rig(platform, limits, controller.name),
    )  # fmt: skip
    if args.gentle_end:  # gentler than the strong end in each channel, not only overall
        strong = objective.metrics(strong_end, full=True).cue
        shares = (math.nan, math.nan) if strong is None else strong.rendered_share[:2]
        if not all(math.isfinite(v) and v > 0.0 for v in shares):
            raise ConfigError(
                f"--gentle-end: the base preset {base.name!r} renders no fx or fy share on "
                "these recordings (nothing to be gentler than)"
            )
        targets = replace(
            targets,
            max_share=(args.gentle_share * float(shares[0]), args.gentle_share * float(shares[1])),
        )
        objective.targets = targets
    strength = args.objective == "strength"

    def progress(gen: int, best: float, rate: float, n_eval: int) -> None:
        if best >= PENALTY_BASE:
            shown = "none within the limits yet"
        elif strength and best >= 0.0:
            shown = f"none meets the targets yet (violation {best - 1.0:.3f})"
        elif strength:
            shown = f"strength {-best:8.4f}"
        else:
            shown = f"score {best:8.4f}"
        print(
            f"motioncue tune: generation {gen:4d}  best {shown}  "
            f"{rate:7.1f} evaluations/s  ({n_eval} evaluations)",
            file=sys.stderr,
            flush=True,
        )

    name = out.stem
    print(
        f"motioncue tune: base preset {base_source}; {len(drives)} recording(s); platform "
        f"{args.platform} with {args.controller} at {args.rate:g} Hz; seed {args.seed}",
        file=sys.stderr,
    )
    result = tune_cueing(
        objective,
        seed=args.seed,
        budget_s=args.budget_s,
        generations=args.generations,
        popsize=args.popsize,
        workers=workers,
        scheduler=args.scheduler,
        name=name,
        progress=progress,
        init_spread=args.init_spread,
        hold=hold,
    )
    pa = result.after.cue
    inputs = ", ".join(Path(p).name for p in args.input)
    if excerpt is not None:
        inputs += f" (each from {excerpt[0]:g} s to {excerpt[1]:g} s)"
    comments = [
        f"Written by motioncue tune from base preset {base.name!r}.",
        f"Tuned on: {inputs}",
        f"Platform {args.platform}, controller {args.controller}, {args.rate:g} Hz.",
        f"Optimiser: scipy differential_evolution, seed {args.seed}, "
        + (
            ""
            if args.init_spread is None
            else f"start about the base (spread {args.init_spread:g}), "
        )
        + (f"kept at the base: {', '.join(args.gentle_keep)}, " if args.gentle_keep else "")
        + f"popsize "
        f"{args.popsize}, {result.generations} generation(s), {result.evaluations} "
        f"evaluations ({result.stop_reason}).",
        _objective_comment(args, targets),
        f"Cue score on the tuning recordings: before {result.before.objective:.4f}, "
        f"after {result.after.objective:.4f}; J before {result.before.perceived_error:.3f}, "
        f"after {result.after.perceived_error:.3f}.",
        f"Strength (geometric mean of the shares of fx and fy) before "
        f"{result.before.strength:.4f}, after {result.after.strength:.4f}.",
    ]
    if pa is not None:
        comments.append(
            f"Pooled on the tuning recordings after: share fx/fy {pa.rendered_share[0]:.4f}/"
            f"{pa.rendered_share[1]:.4f}, missed fx/fy {pa.missed[0]:.1%}/{pa.missed[1]:.1%}, "
            f"reversals {pa.reversals_any:.2%}, false cues {pa.false_any:.2%}, corr fx/fy "
            f"{pa.correlation[0]:.3f}/{pa.correlation[1]:.3f}."
        )
    if strength and objective.targets.violation(result.after) > 0.0:
        raise ConfigError(
            f"no candidate met the targets in {result.generations} generation(s) (the best, "
            "pooled: "
            + (
                ""
                if pa is None
                else f"reversals {pa.reversals_any:.2%}, false cues {pa.false_any:.2%}, "
                f"corr fx/fy {pa.correlation[0]:.3f}/{pa.correlation[1]:.3f}, share fx/fy "
                f"{pa.rendered_share[0]:.4f}/{pa.rendered_share[1]:.4f}, "
            )
            + f"clamped {result.after.clamped_fraction:.2%}); nothing written"
        )
    written = result.params
    if args.gentle_end:
        written = replace(strong_end, name=name, intensity_gentle=gentle_values(result.params))
        comments.insert(
            0,
            "The tables are the base preset's (the strong end, 100 %); the [intensity] "
            "table at the end is the tuned gentle end (0 %).",
        )
    text = preset_toml(written, comments)
    # check what the file says (its decimal rounding) before it takes the name
    check = out.with_name(f".{out.stem}.partial-check.toml")
    try:
        write_preset(check, text)
        reread = load_cueing(check)
        after = objective.metrics(
            at_intensity(reread, 0.0) if args.gentle_end else reread, full=True
        )
        if not after.feasible or (strength and objective.targets.violation(after) > 0.0):
            raise ConfigError(f"{out}: the tuned preset breaks the limits after rounding")
        os.replace(check, out)
    except OSError as exc:
        raise ConfigError(f"{out}: cannot write: {exc}") from exc
    finally:
        check.unlink(missing_ok=True)
    print(
        f"motioncue tune: {result.generations} generation(s), {result.evaluations} "
        f"evaluations in {result.wall_s:.1f} s on {result.where} ({result.stop_reason})",
        file=sys.stderr,
    )
    if args.json:
        print_json(
            {
                "base": base.name, "out": str(out), "inputs": list(args.input),
                "generations": result.generations, "evaluations": result.evaluations,
                "wall_s": result.wall_s, "stop_reason": str(result.stop_reason),
                "before": _metrics_dict(result.before), "after": _metrics_dict(after),
            }
        )  # fmt: skip
        return 0
    print(f"base {base.name} -> tuned {out} on {inputs}")
    print(_metrics_table(result.before, after))
    print(f"wrote {out}")
    return 0


def _objective_comment(args: argparse.Namespace, targets: StrengthTargets) -> str:
    """The header line saying what was optimised."""
    chain = (
        f"of the poses after workspace limiting (vestibular models {args.vestibular}); "
        "constraints: zero frames breaking an actuator limit, at most 1 % of poses clamped"
    )
    if args.objective == "score":
        return (
            "Objective: mean cue score (motioncue.cueing.cue_score: perceived-motion error J "
            "relative to standing still, lost correlation, false and missed cues) " + chain + "."
        )
    cap = ""
    if targets.max_share is not None:
        cap = (
            f", share fx <= {targets.max_share[0]:.4f} and fy <= {targets.max_share[1]:.4f} "
            f"({args.gentle_share:g} x the base's)"
        )
    return (
        "Objective: strength, the geometric mean of the rendered shares of fx and fy (the "
        "recordings pooled) "
        + chain
        + f"; targets on every recording: reversals <= {targets.max_reversals:.2%}, false "
        f"cues <= {targets.max_false:.2%}, clamped <= {targets.max_clamped:.2%}, corr fx >= "
        f"{targets.min_corr_fx:g}, fy >= {targets.min_corr_fy:g}{cap}."
    )


def _metrics_dict(m: ChainMetrics) -> dict[str, object]:
    """A :class:`~motioncue.analysis.ChainMetrics` for ``--json`` (NaN as None)."""

    def num(v: float) -> float | None:
        return float(v) if math.isfinite(v) else None

    return {
        "objective": num(m.objective),
        "per_drive_objective": [num(v) for v in m.per_drive_objective],
        "correlation": [num(v) for v in m.correlation],
        "false_cue_time_s": [num(v) for v in m.false_cue_time_s],
        "duration_s": num(m.duration_s),
        "clamped_fraction": num(m.clamped_fraction),
        "violating_frames": int(m.violating_frames),
        "strength": num(m.strength),
        "feasible": bool(m.feasible),
        # definitions: motioncue.cueing.cue_metrics (pooled over the recordings)
        "cue_metrics": None if m.cue is None else m.cue.to_dict(),
    }


_TUNE = Verb(
    "tune",
    run,
    help="tune a cueing preset's main parameters on recordings (local or Dask)",
    description=(
        "Optimise the base preset's main parameters (translational scales and high-pass, "
        "tilt scales, filter, rate and acceleration limits, rotational scale and "
        "high-pass, yaw scale and high-pass; with the compressive tilt also the curves' "
        "limits and exponents and the share of the platform's tilt reach; bounded, log "
        "space) with the cheap chain of generate (cueing, workspace limiting, evaluation "
        "of the delivered poses through vestibular models). Objective strength (the "
        "default): the largest rendered share of fx and fy among candidates meeting the "
        "cue-quality targets (reversals, false cues, correlation, clamping); score: the "
        "cue score. A candidate that breaks an actuator limit on any frame or clamps more "
        "than 1 % of its poses is penalised above every one that does not; the result "
        "must meet the limits (and with strength the targets) or nothing is written. "
        "Optimiser: SciPy differential evolution, seeded. Evaluations run in local "
        "processes (--workers) or on a Dask cluster (--scheduler)."
    ),
    options=(
        RECORDING.but(nargs="+", help="recording CSVs to tune on"),
        RIG,
        PRESET.but(
            metavar="BASE",
            help="base preset (name or .toml; default: the platform's default_preset)",
        ),
        OUT.but(metavar="TUNED.toml", help="preset to write"),
        Option.of(
            "--budget-s",
            type=float,
            default=300.0,
            metavar="S",
            help="wall-time budget in seconds (default 300)",
            allowed=Allowed(0.0),
        ),
        Option.of("--seed", type=int, default=0, metavar="N", help="optimiser seed (0)"),
        Option.of(
            "--generations",
            type=int,
            default=100,
            metavar="N",
            help="most generations (default 100); the same seed and N give the same result",
        ),
        Option.of(
            "--popsize",
            type=int,
            default=6,
            metavar="K",
            help="population per tuned parameter (default 6: 96 candidates per generation)",
        ),
        Option.of(
            "--workers",
            type=int,
            default=None,
            metavar="N",
            help="local processes (default: the number of cores)",
        ),
        Option.of(
            "--scheduler",
            default=None,
            metavar="tcp://HOST:PORT",
            help="evaluate on this Dask distributed scheduler instead of local processes (its "
            "workers need motioncue installed; pip install 'motioncue[dask]')",
        ),
        RATE.but(help="frame rate (default 100)"),
        Option.choice(
            "--objective",
            ("strength", "score"),
            help="strength (default): the largest rendered share of fx and fy (their geometric "
            "mean, the recordings pooled) among candidates meeting the cue-quality "
            "targets below (pooled); score: the cue score (lower is better; the "
            "objective before issue 20, which barely moving can win)",
        ),
        Option.of(
            "--max-reversals",
            type=float,
            default=2.0,
            metavar="PCT",
            help="strength target: reversals (both above threshold, opposite signs) at most "
            "PCT %% of each recording (default 2)",
        ),
        Option.of(
            "--max-false",
            type=float,
            default=15.0,
            metavar="PCT",
            help="strength target: false cues (rider against the vehicle, any size) at most "
            "PCT %% of each recording (default 15)",
        ),
        Option.of(
            "--max-clamped",
            type=float,
            default=1.0,
            metavar="PCT",
            help="strength target: clamped poses at most PCT %% (default 1)",
        ),
        Option.of(
            "--min-corr",
            type=float,
            nargs=2,
            default=(0.95, 0.90),
            metavar=("FX", "FY"),
            help="strength target: perceived fx and fy correlation at least FX and FY on each "
            "recording (default 0.95 0.90)",
        ),
        Option.of(
            "--excerpt",
            default=None,
            metavar="START:END",
            help="tune on this window of each recording only (seconds from its start; a "
            "cheaper tune on short excerpts)",
        ),
        Option.of(
            "--init-spread",
            type=float,
            default=None,
            metavar="S",
            help="start from a population about the base preset (log-space normal steps of "
            "standard deviation S, e.g. 0.3) instead of over the whole search box: a local "
            "search from a good base",
        ),
        Option.of(
            "--gentle-end",
            action="store_true",
            help="tune the gentle (0 %%) end of the base preset's intensity range instead: "
            "the base must have the compressive tilt ([tilt] shape); the search starts from "
            "the base and the written preset is the base unchanged plus an [intensity] table "
            "holding the result (give tighter targets than the base's, e.g. --max-false 5)",
        ),
        Option.of(
            "--gentle-keep",
            nargs="+",
            default=(),
            metavar="NAME",
            help="with --gentle-end: tuned parameters kept at the base's value (names of the "
            "[intensity.gentle] table, e.g. the filters: trans_wn_xy_rad_s tilt_wn_rad_s ...)",
        ),
        Option.of(
            "--gentle-share",
            type=float,
            default=0.6,
            metavar="FRAC",
            help="with --gentle-end: the gentle end's rendered share of fx and of fy, each at "
            "most FRAC times the base's (the strong end's) on the same recordings (default "
            "0.6), so that every channel grows from 0 to 100 %%",
        ),
        add_vestibular_option,
        LIMITS,
        set_option(),
        json_option("the before/after metrics"),
    ),
)

register = registrar(_TUNE)
