"""``motioncue record``: save a game's raw UDP telemetry to a replayable file."""

from __future__ import annotations

import argparse
import sys

from ._common import DURATION, OUT, add_deprecated_alias, json_option, print_json
from ._verb import Lazy, Option, Verb, registrar

__all__ = ["register"]


def _description() -> str:
    from ..telemetry._registry import games_text

    return (
        "Record the raw datagrams a game sends (undecoded, with receive times) to a "
        "motioncue recording; replay it anywhere a source is taken with "
        f"replay:FILE[?speed=X]. Games: {games_text()}."
    )


def run(args: argparse.Namespace) -> int:
    from ..telemetry import record

    def ready(port: int) -> None:
        until = f"for {args.duration:g} s" if args.duration else "until Ctrl-C"
        print(f"recording {args.source} on port {port} to {args.out} {until}", file=sys.stderr)

    summary = record(args.source, args.out, args.duration, on_ready=ready)
    if args.json:
        print_json(
            {
                "path": str(summary.path),
                "game": summary.game,
                "datagrams": summary.datagrams,
                "bytes": summary.nbytes,
                "duration_s": summary.duration_s,
                "stats": dict(summary.stats),
            }
        )
        return 0
    print(
        f"recorded {summary.datagrams} datagrams ({summary.nbytes} bytes) from "
        f"{summary.game} in {summary.duration_s:.1f} s to {summary.path}"
    )
    for reason, count in sorted(summary.stats.items()):
        print(f"  {reason}: {count}")
    return 0


_RECORD = Verb(
    "record",
    run,
    help="record a game's raw UDP telemetry to a file every command can replay",
    description=Lazy(_description),
    options=(
        Option.of(
            "--source",
            required=True,
            metavar="GAME[:[HOST:]PORT]",
            help="game and optional port, e.g. f1, forza:5301, beamng:0.0.0.0:4444 (default "
            "bind address 127.0.0.1; the games are listed above)",
        ),
        OUT.but(metavar="FILE", help="recording file to write"),
        DURATION,
        json_option("the summary"),
        lambda parser: add_deprecated_alias(parser, "--seconds", "--duration", type=float),
    ),
)

register = registrar(_RECORD)
