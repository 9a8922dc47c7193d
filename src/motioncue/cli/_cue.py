"""``motioncue cue``: a recording of vehicle motion to platform poses through the washout."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from .._errors import ConfigError
from ._common import (
    OUT,
    PLATFORM,
    PLOT,
    PRESET,
    RATE,
    RECORDING,
    add_deprecated_alias,
    cue_rate_line,
    json_option,
    load_platform_arg,
    print_json,
    set_option,
)
from ._preset import add_vestibular_option
from ._verb import Allowed, Verb, registrar

if TYPE_CHECKING:
    from ..cueing import CueingEvaluation

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    import numpy as np

    from ..cueing import evaluate_cueing, get_model_set
    from ..pipeline._chain import cue_recording
    from ..pipeline._inputs import load_generate_input
    from ..telemetry._motion import is_datagram_recording
    from ..telemetry._recording import read_recording_csv
    from ._preset import choose_preset

    rate_hz = args.rate
    get_model_set(args.vestibular)  # an unknown set is refused before any file is written
    platform = None
    if args.platform is not None:
        platform = load_platform_arg(args.platform, args.overrides)
    params, preset_source = choose_preset(
        args.preset, platform, args.platform, args.overrides, ride=True
    )
    counters: dict[str, int] = {}
    if is_datagram_recording(Path(args.input)):
        # a 'motioncue record' file: decoded as generate and compare decode it
        rec, counters = load_generate_input(args.input)[1:]
    else:
        rec = read_recording_csv(args.input)  # rows in any order, bad samples held below
    if len(rec) == 0:
        raise ConfigError(f"{args.input}: no samples")
    # at the algorithm's rate (a plan's highest, its poses splined to --rate), with the input
    # as the algorithm used it
    cued, poses, uniform, cue_hz = cue_recording(params, rec, rate_hz)
    res = cued.result
    f_used, w_used = cued.f_used, cued.w_used
    if cue_hz != rate_hz:  # judged against the input at --rate, as the poses are
        f_used, w_used = uniform.f, uniform.w
        line = cue_rate_line(params.algorithm, cue_hz, rate_hz, "poses")
        print(f"motioncue cue: {line}", file=sys.stderr)
    out = Path(args.out)
    table = np.column_stack([uniform.t_s, poses])
    try:
        with open(out, "w", encoding="utf-8") as fh:
            fh.write("t,x,y,z,roll,pitch,yaw\n")
            for row in table.tolist():
                fh.write(",".join(repr(v) for v in row) + "\n")
    except OSError as exc:
        raise ConfigError(f"{out}: cannot write: {exc}") from exc
    ev = evaluate_cueing(
        f_used,
        w_used,
        poses,
        rate_hz,
        workspace=params.workspace,
        model=args.vestibular,
        head_offset_m=params.head_offset_m,
    )
    if args.json:
        print_json(
            {
                "input": str(args.input),
                "samples": len(rec),
                "resampled": len(uniform),
                "rate_hz": rate_hz,
                "preset": params.name,
                "preset_source": preset_source,
                "bad_samples": int(res.bad_samples),
                "telemetry": dict(counters),
                "out": str(out),
                "metrics": _metrics(ev),
            }
        )
    else:
        print(
            f"motioncue cue: {len(rec)} samples -> {len(uniform)} at {rate_hz:g} Hz, "
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
            poses,
            args.plot,
            t_s=uniform.t_s,
            title=f"{Path(args.input).name} at {rate_hz:g} Hz",
            preset=params.name,
            platform=(
                f"{args.platform} (named for its preset; poses not limited to it)"
                if args.platform
                else None
            ),
        )
        print(
            f"motioncue cue: plot written to {path}", file=sys.stderr if args.json else sys.stdout
        )
    return 0


def _metrics(ev: CueingEvaluation) -> dict[str, object]:
    """The evaluation's scalar metrics, for ``--json`` (numbers as floats, NaN as None)."""
    import numpy as np

    out: dict[str, object] = {}
    for name, value in vars(ev).items():
        arr = np.asarray(value)
        if arr.dtype.kind in "fiub" and arr.size <= 6:
            out[name] = [None if not np.isfinite(v) else float(v) for v in arr.ravel().tolist()]
    out["metrics"] = ev.metrics.to_dict()  # definitions: motioncue.cueing.cue_metrics
    return out


_CUE = Verb(
    "cue",
    run,
    help="washout cueing of a recording to platform poses",
    description=(
        "Run the preset's cueing algorithm over a recording (a CSV with the header "
        "t,fx,fy,fz,wx,wy,wz in s, m/s^2, rad/s, body frame, extra columns ignored; or a "
        "'motioncue record' .mctr file), resampled to --rate, and "
        "write the poses CSV t,x,y,z,roll,pitch,yaw (m, rad)."
    ),
    options=(
        RECORDING,
        PRESET.but(
            help="cueing preset name or .toml path (default: the --platform's default_preset)"
        ),
        PLATFORM.but(
            required=False,
            metavar="P",
            help="platform whose default_preset is used when --preset is not given",
        ),
        RATE.but(
            help="rate the recording is resampled to and the cueing runs at (default 100; a plan "
            "above its highest rate runs there and its poses are splined to this rate)",
            allowed=Allowed(0.0, 2000.0, unit="Hz"),
        ),
        OUT.but(metavar="POSES.csv", help="poses CSV to write"),
        PLOT.but(help="also write a cue-quality plot"),
        add_vestibular_option,
        set_option(),
        json_option("the summary and the cue metrics"),
        lambda parser: add_deprecated_alias(parser, "--fs", "--rate", type=float),
    ),
)

register = registrar(_CUE)
