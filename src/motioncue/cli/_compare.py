"""``motioncue compare``: several cueing presets side by side, as the rider feels them."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .._errors import ConfigError
from ._common import (
    CHECKED_RATE,
    LIMITS,
    RECORDING,
    REPORT,
    RIG,
    json_option,
    load_preset_arg,
    load_rig,
    set_option,
)
from ._preset import add_vestibular_option
from ._verb import Option, Verb, registrar

__all__ = ["register"]


def _labels(names: list[str], short: list[str], what: str) -> list[str]:
    """``short`` labels, falling back to the argument where two would be the same."""
    seen: dict[str, int] = {}
    for s in short:
        seen[s] = seen.get(s, 0) + 1
    labels = [s if seen[s] == 1 else n for s, n in zip(short, names, strict=True)]
    if len(set(labels)) != len(labels):
        dup = sorted({x for x in labels if labels.count(x) > 1})
        raise ConfigError(f"{what} {', '.join(dup)} given more than once")
    return labels


def _progress(line: str) -> None:
    """One progress line on stderr (stdout keeps the table or the JSON)."""
    print(f"motioncue compare: {line}", file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    from ..analysis import compare_cueing, plot_file_names, write_compare_report
    from ..cueing import get_model_set
    from ..pipeline._inputs import check_generate_size, load_generate_input

    rate = args.rate
    model = get_model_set(args.vestibular)
    platform, _controller, limits = load_rig(args, rate)
    presets = [load_preset_arg(p, args.overrides) for p in args.presets]
    preset_labels = _labels(list(args.presets), [p.name for p in presets], "preset")
    recs = []
    for path in args.input:
        kind, data, _counters = load_generate_input(path)
        if kind != "recording":
            raise ConfigError(
                f"{path}: pose keyframes, not a recording of vehicle motion; compare needs "
                "recordings (t,fx,fy,fz,wx,wy,wz CSV or a motioncue record file)"
            )
        check_generate_size(kind, data, rate, path)
        recs.append(data)
    rec_labels = _labels(list(args.input), [Path(p).name for p in args.input], "recording")
    result = compare_cueing(
        list(zip(rec_labels, recs, strict=True)),
        list(zip(preset_labels, presets, strict=True)),
        platform,
        limits,
        rate_hz=rate,
        model=model.name,
        platform_name=args.platform,
        controller_name=args.controller,
        progress=_progress,
        bound=args.bound,
    )
    paths = write_compare_report(result, args.report)
    if args.json:
        print(json.dumps(result.to_dict(plot_file_names(result.recordings)), allow_nan=False))
    else:
        print(
            f"motioncue compare: {len(presets)} preset(s) x {len(recs)} recording(s) on "
            f"platform {args.platform}, controller {args.controller}, {rate:g} Hz, "
            f"vestibular models {model.name}"
        )
        print(result.table())
        if result.bound_text():
            print(result.bound_text())
        print(
            f"motioncue compare: report in {args.report} ({len(paths)} files; columns "
            "explained in summary.txt)"
        )
    return 0


_COMPARE = Verb(
    "compare",
    run,
    help="compare cueing presets on recordings: overlay plots and a metrics table",
    description=(
        "Run each preset on each recording through the chain a rider gets (resample, "
        "cueing, workspace limiting with the platform's and the controller's limits, "
        "actuator speed/acceleration limits), evaluate the delivered motion through the "
        "vestibular models, and write to --report DIR: one overlay plot of perceived "
        "motion per recording (perceived-NAME.png), metrics.csv, metrics.json and "
        "summary.txt (the table with its columns explained). Prints the table (or, with "
        "--json, the JSON)."
    ),
    options=(
        RECORDING.but(
            nargs="+", help="recording CSVs (t,fx,fy,fz,wx,wy,wz) or motioncue record files"
        ),
        Option.of(
            "--presets",
            required=True,
            nargs="+",
            metavar="PRESET",
            help="cueing preset names or .toml paths",
        ),
        RIG,
        REPORT.but(required=True, help="folder for the report"),
        Option.of(
            "--bound",
            action="store_true",
            help="also compute each recording's physical bound on the platform (the least "
            "perceived error and the largest gain without a reversal any motion within its "
            "limits could give) and each preset's share of it; seconds to a minute per "
            "recording",
        ),
        json_option("the metrics"),
        CHECKED_RATE,
        add_vestibular_option,
        LIMITS,
        set_option(),
    ),
)

register = registrar(_COMPARE)
