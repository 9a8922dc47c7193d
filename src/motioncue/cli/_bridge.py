"""``motioncue bridge``: live game telemetry to a motion controller, in real time."""

from __future__ import annotations

import argparse
import math
import sys
import time
from typing import Any

from .._errors import ConfigError
from ._monitor import add_monitor_argument, start_monitor

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
            "resume. Ctrl-C, SIGTERM, SIGHUP or SIGQUIT park smoothly (a second Ctrl-C does "
            "not cut the park short), then exit with status 130; a failure parks too, then "
            "exits with 2; the end of a replayed recording parks, then exits with 0. Over "
            "udp:// the controller's reported position is the start. A status line is "
            "refreshed on stderr about twice a second."
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
    parser.add_argument(
        "--preset",
        default=None,
        help="cueing preset name or .toml path (default: the platform's default_preset)",
    )
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
    add_monitor_argument(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from ..kinematics import load_platform
    from ..output import load_controller, open_transport
    from ..pipeline._bridge import Bridge, BridgeConfig
    from ..pipeline._realtime import GateConfig
    from ..pipeline._signals import SignalGuard
    from ..telemetry import open_source
    from ..trajectory import ActuatorLimits
    from ..viewer._monitor import BridgeSource
    from ._preset import choose_preset

    if args.duration is not None and not (math.isfinite(args.duration) and args.duration > 0):
        raise ConfigError(f"--duration {args.duration!r} is invalid; allowed: a number > 0")
    from ..output._controller_api import snap_rate_hz

    controller = load_controller(args.controller)
    config = BridgeConfig(
        rate_hz=snap_rate_hz(args.rate, controller),
        gate=GateConfig(timeout_s=args.timeout, fade_out_s=args.fade, fade_in_s=args.fade),
        rt_priority=args.rt_priority or None,
    )
    platform = load_platform(args.platform)
    controller.check_rate(config.rate_hz)
    limits = ActuatorLimits.from_platform(
        platform,
        controller,
        stroke_margin=args.stroke_margin,
        v_max=args.max_speed,
        a_max=args.max_accel,
        rate_hz=config.rate_hz,
    )
    cueing, preset_source = choose_preset(args.preset, platform, args.platform)
    # over UDP the IMAX and SC-MBOX report where their motors are: start from there
    q_start = "auto" if args.target.lower().startswith("udp:") else None
    # from here on SIGINT, SIGTERM, SIGHUP and SIGQUIT only set a flag: the bridge parks and
    # nothing cuts the park or the summary short
    with SignalGuard() as guard:
        source = open_source(args.source)
        try:
            transport = open_transport(args.target)
            try:
                bridge = Bridge(
                    platform, controller, cueing, source, transport, limits, config, q_start=q_start
                )
                start_notes = list(bridge.stage.notes)
                for note in start_notes:
                    _say(f"motioncue bridge: note: {note}")
                _say(
                    f"bridge: {source!r} -> {args.target} ({args.controller}, {args.platform}, "
                    f"preset {preset_source}, {config.rate_hz:g} Hz); Ctrl-C parks and exits"
                )
                monitor = start_monitor(
                    args.monitor, BridgeSource(bridge), platform, limits,
                    f"bridge {args.source} -> {args.target} ({args.platform}, "
                    f"{args.controller})", _say,
                )  # fmt: skip
                try:
                    final = _serve(bridge, guard, args.duration, quiet=args.quiet)
                finally:
                    if monitor is not None:
                        monitor.stop()
            finally:
                transport.close()
        finally:
            source.close()
        _say(_summary(final))
        for note in final.notes:
            if note not in start_notes:
                _say(f"motioncue bridge: note: {note}")
        if not args.rt_priority and final.jitter_p99_ms > 1.0:
            _say(
                f"motioncue bridge: note: output jitter p99 {final.jitter_p99_ms:.2f} ms; other "
                "programs delayed the frame loop: --rt-priority 10 (root or CAP_SYS_NICE) "
                "prevents that"
            )
        if final.error is not None:
            _say(f"motioncue bridge: error: {final.error}")
            return 2
        if guard.first is not None:
            _say(f"motioncue bridge: stopped by {guard.first}; parked at rest")
            return 130
        return 0


def _say(line: str) -> None:
    """One line on stderr; a terminal that is gone (SIGHUP) does not stop the program."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError):
        pass


def _serve(bridge: Any, guard: Any, duration_s: float | None, *, quiet: bool) -> Any:
    """Run the bridge until the duration, a stop signal or a failure; park; final stats.

    ``guard`` (an active :class:`~motioncue.pipeline._signals.SignalGuard`) turns SIGINT,
    SIGTERM, SIGHUP and SIGQUIT into a flag, so neither they nor a second Ctrl-C can cut
    the park short.
    """
    try:
        tty = sys.stderr.isatty()
    except (OSError, ValueError):
        tty = False
    bridge.start()
    t_end = math.inf if duration_s is None else time.monotonic() + duration_s
    while (
        bridge.running
        and not bridge.source_finished
        and not guard.event.is_set()
        and time.monotonic() < t_end
    ):
        guard.event.wait(min(0.5, max(0.0, t_end - time.monotonic())))
        if not quiet:
            _status(bridge.stats.status_line(), tty)
    if not quiet:
        _status("parking ...", tty)
    final = bridge.stop()
    while not bridge.wait(1.0):  # the park takes as long as it takes; only SIGKILL ends it
        final = bridge.stats
    if bridge.stats.error != final.error or bridge.stats.state != final.state:
        final = bridge.stats
    if not quiet and tty:
        _say("")
    return final


def _status(line: str, tty: bool) -> None:
    try:
        if tty:
            sys.stderr.write("\r" + line + "\x1b[K")
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()
    except (OSError, ValueError):
        pass


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
