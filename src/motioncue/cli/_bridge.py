"""``motioncue bridge``: live game telemetry to a motion controller, in real time."""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
import time
from typing import Any

from .._errors import ConfigError

__all__ = ["register"]


def register(sub: Any) -> None:
    parser = sub.add_parser(
        "bridge",
        help="drive a platform live from a game's telemetry",
        description=(
            "Receive a game's UDP telemetry and stream controller frames in real time: washout "
            "cueing, workspace limiting, inverse kinematics, actuator limits (the table "
            "'motioncue limits' prints), frames to --target. Starts parked and ramps in; when "
            "packets stop or the game pauses the platform fades to park and ramps back in on "
            "resume. Ctrl-C or SIGTERM parks smoothly, then exits; so does the end of a "
            "replayed recording. A status line is refreshed on stderr about twice a second."
        ),
    )
    parser.add_argument(
        "--source",
        required=True,
        metavar="GAME[:[HOST:]PORT]",
        help="f1, forza or beamng, optionally with the port (and address) to listen on; or "
        "replay:FILE[?speed=X] to replay a recording",
    )
    parser.add_argument("--platform", required=True, help="bundled platform name or TOML path")
    parser.add_argument("--controller", required=True, help="bundled controller name or TOML path")
    parser.add_argument(
        "--target",
        required=True,
        metavar="URL",
        help="udp://HOST:PORT, serial:///dev/ttyUSB0?baud=19200, pcap:PATH or file:PATH",
    )
    parser.add_argument("--preset", default="racing", help="cueing preset name or .toml path")
    parser.add_argument("--rate", type=float, default=100.0, metavar="HZ", help="frame rate")
    parser.add_argument("--max-speed", type=float, help="speed limit, m/s (rad/s for cranks)")
    parser.add_argument("--max-accel", type=float, help="acceleration limit, m/s^2 (rad/s^2)")
    parser.add_argument(
        "--stroke-margin", type=float, help="extra margin at each stroke end, m (rad)"
    )
    parser.add_argument(
        "--timeout",
        type=float,
        default=0.25,
        metavar="S",
        help="telemetry older than this counts as lost (default 0.25 s)",
    )
    parser.add_argument(
        "--fade", type=float, default=2.0, metavar="S", help="fade in/out time (default 2 s)"
    )
    parser.add_argument(
        "--duration", type=float, metavar="S", help="stop (and park) after this long"
    )
    parser.add_argument(
        "--rt-priority",
        type=int,
        default=10,
        metavar="N",
        help="run the frame loop under SCHED_FIFO at priority N (1..99; Linux, root or "
        "CAP_SYS_NICE; refused quietly with a note elsewhere): keeps other programs from "
        "delaying frames on a busy PC (default 10; 0 = normal scheduling)",
    )
    parser.add_argument("--quiet", action="store_true", help="no status line")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..kinematics import load_platform
    from ..output import load_controller, open_transport
    from ..pipeline._bridge import Bridge, BridgeConfig
    from ..pipeline._realtime import GateConfig
    from ..telemetry import open_source
    from ..trajectory import ActuatorLimits
    from ..washout import load_cueing

    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ConfigError(f"--duration {args.duration!r} is invalid; allowed: a number > 0")
    config = BridgeConfig(
        rate_hz=args.rate,
        gate=GateConfig(timeout_s=args.timeout, fade_out_s=args.fade, fade_in_s=args.fade),
        rt_priority=args.rt_priority or None,
    )
    platform = load_platform(args.platform)
    controller = load_controller(args.controller)
    limits = ActuatorLimits.from_platform(
        platform,
        controller,
        stroke_margin=args.stroke_margin,
        v_max=args.max_speed,
        a_max=args.max_accel,
    )
    cueing = load_cueing(args.preset)
    err = sys.stderr
    source = open_source(args.source)
    try:
        transport = open_transport(args.target)
        try:
            bridge = Bridge(platform, controller, cueing, source, transport, limits, config)
            print(
                f"bridge: {source!r} -> {args.target} ({args.controller}, {args.platform}, "
                f"preset {args.preset}, {config.rate_hz:g} Hz); Ctrl-C parks and exits",
                file=err,
            )
            final = _serve(bridge, args.duration, quiet=args.quiet)
        finally:
            transport.close()
    finally:
        source.close()
    print(_summary(final), file=err)
    for note in final.notes:
        print(f"motioncue bridge: note: {note}", file=err)
    if not args.rt_priority and final.jitter_p99_ms > 1.0:
        print(
            f"motioncue bridge: note: output jitter p99 {final.jitter_p99_ms:.2f} ms; other "
            "programs delayed the frame loop: --rt-priority 10 (root or CAP_SYS_NICE) "
            "prevents that",
            file=err,
        )
    if final.error is not None:
        print(f"motioncue bridge: error: {final.error}", file=err)
        return 2
    return 0


def _serve(bridge: Any, duration_s: float | None, *, quiet: bool) -> Any:
    """Run the bridge until the duration, Ctrl-C, SIGTERM or a failure; park; final stats."""
    err = sys.stderr
    tty = err.isatty()
    term = threading.Event()
    old_handler: Any = None
    in_main = threading.current_thread() is threading.main_thread()
    if in_main:
        old_handler = signal.signal(signal.SIGTERM, lambda signum, frame: term.set())
    try:
        bridge.start()
        t_end = math.inf if duration_s is None else time.monotonic() + duration_s
        try:
            while (
                bridge.running
                and not bridge.source_finished
                and not term.is_set()
                and time.monotonic() < t_end
            ):
                term.wait(min(0.5, max(0.0, t_end - time.monotonic())))
                if not quiet:
                    _status(bridge.stats.status_line(), tty)
        except KeyboardInterrupt:
            pass
        if not quiet:
            _status("parking ...", tty)
        while True:
            try:
                final = bridge.stop()
                break
            except KeyboardInterrupt:  # a second Ctrl-C: the park still finishes
                print("\nmotioncue bridge: parking, please wait", file=err)
        if not quiet and tty:
            print(file=err)
        return final
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, old_handler)


def _status(line: str, tty: bool) -> None:
    if tty:
        sys.stderr.write("\r" + line + "\x1b[K")
    else:
        sys.stderr.write(line + "\n")
    sys.stderr.flush()


def _summary(st: Any) -> str:
    def f(x: float) -> str:
        return "-" if math.isnan(x) else f"{x:.2f}"

    reasons = ", ".join(f"{k} {v}" for k, v in sorted(st.packet_reasons.items()))
    return (
        f"bridge {st.state}: {st.frames_sent} frames sent, {st.missed_deadlines} deadlines "
        f"missed; latency p50 {f(st.latency_p50_ms)} ms p99 {f(st.latency_p99_ms)} ms, "
        f"jitter p99 {f(st.jitter_p99_ms)} ms; limiter clamped {st.limiter_clamped_frames} "
        f"frames, workspace clamped {st.pose_clamped} poses ({st.pose_invalid} invalid), "
        f"washout held {st.washout_bad_samples} bad samples; {st.fade_outs} fade-outs, "
        f"{st.fade_ins} fade-ins; parked error {st.park_q_error:.3g}\n"
        f"telemetry: {reasons or 'nothing received'}"
    )
