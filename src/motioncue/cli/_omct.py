"""``motioncue omct``: the Objective Motion Cueing Test of a preset on a platform."""

from __future__ import annotations

import argparse
import json
import sys
import time

from .._errors import ConfigError
from ._common import (
    CHECKED_RATE,
    LIMITS,
    PLOT,
    PRESET,
    RIG,
    json_option,
    load_preset_arg,
    load_rig,
    set_option,
)
from ._verb import Allowed, Option, Verb, registrar

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    from ..analysis import plot_omct, run_omct
    from ..cueing import ClassicalWashout

    rate = args.rate
    scale = args.amplitude_scale
    params = load_preset_arg(args.preset, args.overrides)
    algorithm = params.algorithm
    if algorithm != "classical":
        raise ConfigError(
            f"preset {params.name!r} uses the cueing algorithm {algorithm!r}; the OMCT's "
            "analytic comparison is defined for the classical washout only"
        )
    platform, _controller, limits = load_rig(args, rate)
    design = ClassicalWashout(params, rate)
    labels = {
        "preset": params.name,
        "platform": str(args.platform),
        "controller": str(args.controller),
    }
    tty = sys.stderr.isatty()
    t0 = time.perf_counter()
    last_path = [""]

    def progress(what: str, frac: float) -> None:
        if tty:
            print(
                f"\rmotioncue omct: {frac * 100.0:5.1f} % {what:<28}",
                end="",
                file=sys.stderr,
                flush=True,
            )
            return
        # not a terminal (a log, a pipe): one line per path, and one at the end
        path = what.split(" ", 1)[0]
        if path != last_path[0]:
            last_path[0] = path
            elapsed = time.perf_counter() - t0
            line = "done" if path == "done" else f"path {path} ({frac * 100.0:.0f} % done)"
            print(f"motioncue omct: {line}, {elapsed:.1f} s", file=sys.stderr, flush=True)

    result = run_omct(
        design,
        platform,
        limits,
        paths=args.paths,
        amplitude_scale=scale,
        labels=labels,
        progress=progress,
    )
    if tty:
        print("", file=sys.stderr)
    if args.json:
        print(json.dumps(result.to_dict(), indent=1, allow_nan=False))
    else:
        print(result.table())
    if args.plot:
        out = plot_omct(
            result,
            design,
            args.plot,
            title=(f"OMCT: preset {params.name} on {args.platform} with {args.controller}"),
        )
        print(
            f"motioncue omct: plot written to {out}", file=sys.stderr if args.json else sys.stdout
        )
    return 0


_OMCT = Verb(
    "omct",
    run,
    help="objective motion cueing test: frequency response of cueing plus platform",
    description=(
        "Objective Motion Cueing Test (OMCT, ICAO 9625; Hosman & Advani): sinusoidal "
        "runs at the twelve test frequencies 0.1 to 15.849 rad/s on ten signal paths "
        "(p->p, q->q, r->r, ax->ax, ay->ay, az->az, ax->q, ay->p, q->ax, p->ay) through "
        "the whole chain (cueing, workspace limiting, actuator limits of the platform "
        "driven by the controller); prints the gain and phase of the platform's motion "
        "against the input, next to the analytic response of the linear washout. The "
        "input amplitudes are motioncue's (rates up to 5 deg / 100 deg/s^2, 1 m/s^2), not "
        "ICAO 9625's table."
    ),
    options=(
        PRESET.but(required=True, help="cueing preset name or .toml path"),
        RIG,
        CHECKED_RATE,
        Option.of(
            "--amplitude-scale",
            type=float,
            default=1.0,
            metavar="X",
            help="multiply every input amplitude by X, in (0, 100] (default 1)",
            allowed=Allowed(0.0, 100.0),
        ),
        Option.of(
            "--paths",
            nargs="+",
            metavar="PATH",
            help="only these paths, as in-out (ax-q) or quoted in->out ('ax->q'); default: all ten",
        ),
        json_option("the table"),
        PLOT.but(help="write the plot in the OMCT format"),
        LIMITS,
        set_option(),
    ),
)

register = registrar(_OMCT)
