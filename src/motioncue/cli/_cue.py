"""``motioncue cue``: a recording of vehicle motion to platform poses through the washout."""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from .._errors import ConfigError
from ._preset import add_vestibular_option

__all__ = ["register"]


def register(sub: argparse._SubParsersAction) -> None:
    parser = sub.add_parser(
        "cue",
        help="washout cueing of a recording to platform poses",
        description=(
            "Run the preset's cueing algorithm over a recording CSV (header with "
            "t,fx,fy,fz,wx,wy,wz in s, m/s^2, rad/s, body frame; extra columns ignored), "
            "resampled to --fs, and "
            "write the poses CSV t,x,y,z,roll,pitch,yaw (m, rad)."
        ),
    )
    parser.add_argument("--input", required=True, metavar="REC.csv", help="recording CSV")
    parser.add_argument(
        "--preset",
        default=None,
        metavar="NAME",
        help="cueing preset name or .toml path (default: the --platform's default_preset)",
    )
    parser.add_argument(
        "--platform",
        default=None,
        metavar="P",
        help="platform whose default_preset is used when --preset is not given",
    )
    parser.add_argument("--fs", required=True, type=float, metavar="HZ", help="sample rate")
    parser.add_argument("--out", required=True, metavar="POSES.csv", help="poses CSV to write")
    parser.add_argument("--plot", metavar="FILE.png", help="also write a cue-quality plot")
    add_vestibular_option(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..cueing import evaluate_cueing, get_model_set, make_cueing
    from ..telemetry._recording import read_recording_csv, resample
    from ._preset import choose_preset

    if not math.isfinite(args.fs) or args.fs <= 0:
        raise ConfigError(f"--fs {args.fs!r} is invalid; allowed: a finite number > 0")
    get_model_set(args.vestibular)  # an unknown set is refused before any file is written
    platform = None
    if args.platform is not None:
        from ..kinematics import load_platform

        platform = load_platform(args.platform)
    params, preset_source = choose_preset(args.preset, platform, args.platform)
    rec = read_recording_csv(args.input)
    if len(rec) == 0:
        raise ConfigError(f"{args.input}: no samples")
    uniform = resample(rec, args.fs)
    design = make_cueing(params, args.fs)
    res = design.run(uniform.f, uniform.w)
    out = Path(args.out)
    table = np.column_stack([uniform.t_s, res.poses])
    try:
        with open(out, "w", encoding="utf-8") as fh:
            fh.write("t,x,y,z,roll,pitch,yaw\n")
            for row in table.tolist():
                fh.write(",".join(repr(v) for v in row) + "\n")
    except OSError as exc:
        raise ConfigError(f"{out}: cannot write: {exc}") from exc
    # the input as the algorithm used it (bad samples held) when it reports it
    f_used = getattr(res, "f_used", uniform.f)
    w_used = getattr(res, "w_used", uniform.w)
    ev = evaluate_cueing(
        f_used,
        w_used,
        res.poses,
        args.fs,
        workspace=params.workspace,
        model=args.vestibular,
        head_offset_m=getattr(params, "head_offset_m", None),
    )
    print(
        f"motioncue cue: {len(rec)} samples -> {len(uniform)} at {args.fs:g} Hz, "
        f"preset {preset_source}; bad samples held: {res.bad_samples}; wrote {out}"
    )
    print(ev.summary())
    if res.bad_samples:
        print(
            f"motioncue cue: warning: {res.bad_samples} bad input samples (NaN/inf/spike) "
            "were replaced by the last good sample",
            file=sys.stderr,
        )
    if args.plot:
        from ..cueing import plot_cueing

        path = plot_cueing(
            ev,
            res.poses,
            args.plot,
            t_s=uniform.t_s,
            title=f"{Path(args.input).name} at {args.fs:g} Hz",
            preset=params.name,
            platform=(
                f"{args.platform} (named for its preset; poses not limited to it)"
                if args.platform
                else None
            ),
        )
        print(f"motioncue cue: plot written to {path}")
    return 0
