"""``motioncue record``: save a game's raw UDP telemetry to a replayable file."""

from __future__ import annotations

import argparse
import sys

from ._common import add_deprecated_alias, add_json_option, print_json

__all__ = ["register"]


def register(sub: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    from ..telemetry._registry import games_text

    p = sub.add_parser(
        "record",
        help="record a game's raw UDP telemetry to a file every command can replay",
        description=(
            "Record the raw datagrams a game sends (undecoded, with receive times) to a "
            "motioncue recording; replay it anywhere a source is taken with "
            f"replay:FILE[?speed=X]. Games: {games_text()}."
        ),
    )
    p.add_argument(
        "--source",
        required=True,
        metavar="GAME[:[HOST:]PORT]",
        help="game and optional port, e.g. f1, forza:5301, beamng:0.0.0.0:4444 (default bind "
        "address 127.0.0.1; the games are listed above)",
    )
    p.add_argument("--out", required=True, metavar="FILE", help="recording file to write")
    p.add_argument(
        "--duration", type=float, default=None, metavar="S", help="stop after S seconds "
        "(default: until Ctrl-C)"
    )  # fmt: skip
    add_json_option(p, "the summary")
    add_deprecated_alias(p, "--seconds", "--duration", type=float)
    p.set_defaults(run=run)


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
