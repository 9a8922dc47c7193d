"""``motioncue send-telemetry``: play a recording to the bridge as a game's own packets."""

from __future__ import annotations

import argparse
import sys

from .._errors import ConfigError
from ._common import QUIET, RATE, RECORDING, TARGET, json_option, print_json
from ._verb import Allowed, Lazy, Option, Verb, registrar

__all__ = ["register"]


def _description() -> str:
    from ..telemetry import GAMES
    from ..telemetry._registry import encodable_games, games_text

    unable = [name for name in GAMES if name not in encodable_games()]
    return (
        "Encode a recording of vehicle motion (t,fx,fy,fz,wx,wy,wz CSV or a "
        "'motioncue record' file) into the packets the game sends, in the layouts the "
        "bridge's decoders read, and send them on the recording's clock to --target, the "
        "address 'motioncue bridge --source GAME' listens on. The vehicle is kept level; "
        "its specific force and angular velocity come back from the decoder as recorded. "
        f"Games: {games_text(ports=False, encodable=True)}"
        + (f" (not {', '.join(unable)}: no encoder)" if unable else "")
        + ". Ctrl-C stops."
    )


def _encodable_games() -> tuple[str, ...]:
    from ..telemetry._registry import encodable_games

    return encodable_games()


def _run(args: argparse.Namespace) -> int:
    from ..output import parse_target
    from ..pipeline._inputs import load_generate_input
    from ..telemetry import GAMES, resample
    from ..telemetry._encode import send_recording

    target = args.target or f"udp://127.0.0.1:{GAMES[args.game].default_port}"
    url = parse_target(target)
    if url.scheme != "udp":
        raise ConfigError(f"--target {target!r}: game telemetry goes over udp://HOST:PORT")
    kind, rec, _counters = load_generate_input(args.input)
    if kind != "recording":
        raise ConfigError(
            f"{args.input}: pose keyframes, not a recording of vehicle motion "
            "(t,fx,fy,fz,wx,wy,wz CSV or a motioncue record file)"
        )
    uniform = resample(rec, args.rate)
    total_s = float(uniform.t_s[-1] - uniform.t_s[0])

    def progress(done: int, total: int) -> None:
        if not args.quiet:
            print(
                f"motioncue send-telemetry: {done} of {total} samples "
                f"({done / args.rate:.1f} of {total_s:.1f} s)",
                file=sys.stderr,
                flush=True,
            )

    if not args.quiet:
        print(
            f"send-telemetry: {args.input} as {args.game} packets -> {target}, "
            f"{args.rate:g} Hz, {total_s:.1f} s; Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )
    summary = send_recording(
        args.game, uniform.t_s, uniform.f, uniform.w, url.host, url.port, progress=progress
    )
    if args.json:
        print_json({"game": args.game, "target": target, "rate_hz": args.rate,
                    "samples": summary.samples, "datagrams": summary.datagrams,
                    "duration_s": summary.duration_s, "late": summary.late})  # fmt: skip
    else:
        print(
            f"send-telemetry: sent {summary.samples} samples ({summary.datagrams} datagrams, "
            f"{summary.duration_s:.1f} s) to {target}; late {summary.late}"
        )
    return 0


_SEND_TELEMETRY = Verb(
    "send-telemetry",
    _run,
    help="send a recording as a game's UDP telemetry (try the bridge without the game)",
    description=Lazy(_description),
    options=(
        Option.of(
            "--game", required=True, choices=Lazy(_encodable_games), help="the game to imitate"
        ),
        RECORDING,
        TARGET.but(
            help="udp://HOST:PORT to send to (default: udp://127.0.0.1: and the game's port)"
        ),
        RATE.but(
            default=60.0,
            help="packets per second (the recording is resampled to it; default 60, as F1)",
            allowed=Allowed(1.0, 1000.0, lo_closed=True, unit="Hz"),
        ),
        QUIET,
        json_option("the summary"),
    ),
)

register = registrar(_SEND_TELEMETRY)
