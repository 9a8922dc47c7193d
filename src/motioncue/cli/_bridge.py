"""``motioncue bridge``: live game telemetry to a motion controller, in real time."""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from typing import TYPE_CHECKING, Any

from .._errors import ConfigError
from ._common import (
    DURATION,
    LIMITS,
    PRESET,
    QUIET,
    RATE,
    RIG,
    TARGET,
    json_option,
    limits_for,
    load_platform_arg,
    print_json,
    say,
    set_option,
    status_line,
)
from ._monitor import MONITOR, start_monitor
from ._preset import add_intensity_option, apply_intensity, cueing_note
from ._verb import Allowed, Lazy, Option, Verb, registrar

if TYPE_CHECKING:
    from ..pipeline._bridge import Bridge, BridgeStats
    from ..pipeline._signals import SignalGuard
    from ..telemetry import ReplaySource, TelemetrySource
    from ..telemetry._shm import SharedMemorySource
    from ..telemetry._source import AutoSource

__all__ = ["register"]


def _source_help() -> str:
    from ..telemetry import GAMES

    return (
        f"{', '.join(GAMES)}, optionally with the port (and address) to listen on; or "
        "replay:FILE[?speed=X] to replay a recording (required unless --profile gives one)"
    )


def run(args: argparse.Namespace) -> int:
    from ..cueing import cueing_entry
    from ..output import load_controller, open_transport
    from ..output._controller_api import snap_rate_hz
    from ..pipeline._bridge import Bridge, BridgeConfig
    from ..pipeline._realtime import GateConfig
    from ..pipeline._signals import SignalGuard
    from ..telemetry import open_source
    from ..viewer._cueing import describe_cueing
    from ..viewer._monitor import BridgeSource
    from ._preset import choose_preset

    profile = None
    if args.profile is not None:
        from ..pipeline._profile import load_profile

        profile = load_profile(args.profile)
    source_spec = args.source or (profile.source if profile is not None else None)
    if source_spec is None:
        raise ConfigError("give --source GAME[:[HOST:]PORT] or --profile NAME")
    controller = load_controller(args.controller)
    # the bridge's own checks of the rate (and the rest of its config) come first
    config = BridgeConfig(
        rate_hz=snap_rate_hz(args.rate, controller),
        gate=GateConfig(timeout_s=args.timeout, fade_out_s=args.fade, fade_in_s=args.fade),
        rt_priority=args.rt_priority or None,
        upsample=args.upsample,
    )
    platform = load_platform_arg(args.platform, args.overrides)
    controller.check_rate(config.rate_hz)
    limits = limits_for(args, platform, controller, config.rate_hz)
    profile_preset = profile.preset_for(platform.name) if profile is not None else None
    preset = args.preset or profile_preset
    base, base_source = choose_preset(preset, platform, args.platform, args.overrides)
    intensity = args.intensity
    if intensity is None and profile is not None:
        intensity = profile.intensity
    cueing, preset_source = apply_intensity(base, intensity, base_source)
    shown = {"cueing": describe_cueing({"cueing": cueing_note(base, intensity, args.overrides)})}
    effects = None
    start_warnings: list[str] = []
    if profile is not None:
        from ..pipeline._effects import make_effects

        if args.preset is None and profile_preset is not None:
            preset_source = f"{cueing.name} (profile {profile.name})"
            own = platform.default_preset
            if platform.name not in profile.presets and own and own != profile_preset:
                start_warnings.append(
                    f"profile {profile.name} replaces platform {platform.name}'s tuned preset "
                    f"{own} by {cueing.name} (a [preset] table in the profile names a preset "
                    "per platform; --preset overrides it)"
                )
        else:
            preset_source += f", profile {profile.name}"
        cueing = profile.apply(cueing)
        effects = profile.effects
        make_effects(effects, config.rate_hz)  # refused below 100 Hz before anything opens
    frames = args.frames
    if frames == "auto":
        # frames on arrival: whole-ms stamped frames, no jerk limit, and a cueing algorithm
        # whose registry entry declares it cheap enough to step every millisecond (the
        # classical washout; the MPC runs at the frame rate)
        period_ms = 1000.0 / config.rate_hz
        whole = abs(period_ms - round(period_ms)) < 1e-9 and round(period_ms) >= 2
        stamped = controller.time_resolution_s == 1e-3
        cheap = cueing_entry(cueing.algorithm).frames_on_arrival
        frames = "arrival" if whole and stamped and limits.j_max is None and cheap else "fixed"
    config = dataclasses.replace(config, frame_clock=frames)
    # over UDP the IMAX and SC-MBOX report where their motors are: start from there
    q_start = "auto" if args.target.lower().startswith("udp:") else None
    # from here on SIGINT, SIGTERM, SIGHUP and SIGQUIT only set a flag: the bridge parks and
    # nothing cuts the park or the summary short
    with SignalGuard() as guard:
        source: TelemetrySource | ReplaySource | AutoSource | SharedMemorySource
        if args.telemetry_in_process or source_spec.startswith("replay:"):
            source = open_source(source_spec)
        else:
            from ..telemetry._shm import SharedMemorySource

            source = SharedMemorySource(source_spec)
        try:
            transport = open_transport(args.target)
            try:
                bridge = Bridge(
                    platform, controller, cueing, source, transport, limits, config,
                    q_start=q_start, effects=effects,
                )  # fmt: skip
                start_notes = list(bridge.stage.notes)
                for note in start_notes:
                    say(f"motioncue bridge: note: {note}")
                for warning in start_warnings:
                    say(f"motioncue bridge: warning: {warning}")
                say(
                    f"bridge: {_describe_source(source)} -> {args.target} ({args.controller}, "
                    f"{args.platform}, preset {preset_source}, {config.rate_hz:g} Hz, frames "
                    f"{frames}); Ctrl-C parks and exits"
                )
                if not args.quiet:
                    say(_legend(frames, config.rate_hz))
                monitor = start_monitor(
                    args.monitor, BridgeSource(bridge, shown), platform, limits,
                    f"bridge {args.source} -> {args.target} ({args.platform}, "
                    f"{args.controller})", say,
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
        say(_summary(final))
        if args.json:
            print_json(_stats_dict(final), best_effort=True)
        for note in final.notes:
            if note not in start_notes:
                say(f"motioncue bridge: note: {note}")
        clamp_warning = final.clamp_warning()
        if clamp_warning is not None:
            say(f"motioncue bridge: warning: {clamp_warning}")
        if not args.rt_priority and final.jitter_p99_ms > 1.0:
            say(
                f"motioncue bridge: note: output jitter p99 {final.jitter_p99_ms:.2f} ms; other "
                "programs delayed the frame loop: --rt-priority 10 (root or CAP_SYS_NICE) "
                "prevents that"
            )
        if final.error is not None:
            say(f"motioncue bridge: error: {final.error}")
            return 2
        if guard.first is not None:
            say(f"motioncue bridge: stopped by {guard.first}; parked at rest")
            return 130
        return 0


def _describe_source(
    source: TelemetrySource | ReplaySource | AutoSource | SharedMemorySource,
) -> str:
    """What the user set up: ``f1 telemetry on udp://127.0.0.1:20777`` or the replayed file."""
    from ..telemetry import ReplaySource

    if isinstance(source, ReplaySource):
        return f"replay of {source.path} (speed {source.speed:g})"
    return f"{source.game} telemetry on udp://{source.host}:{source.port}"


def _legend(frames: str, rate_hz: float) -> str:
    """One line, once, saying what the status line's figures are."""
    if frames == "arrival":
        out = (
            f"frames/s sent (frames on arrival: one on each telemetry sample and one "
            f"{1000.0 / rate_hz:g} ms after the last when none came, so more than "
            f"{rate_hz:g}/s when the game sends slower: 60 Hz gives 120/s)"
        )
    else:
        out = f"frames/s sent (one every {1000.0 / rate_hz:g} ms)"
    return (
        f"status: in = telemetry samples/s; out = {out}; limiter = frames the actuator "
        "limiter changed; workspace = poses scaled back into the workspace; bad = datagrams "
        "skipped; missed = frame deadlines missed"
    )


def _serve(
    bridge: Bridge, guard: SignalGuard, duration_s: float | None, *, quiet: bool
) -> BridgeStats:
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
    warned = False
    t_end = math.inf if duration_s is None else time.monotonic() + duration_s
    while (
        bridge.running
        and not bridge.source_finished
        and not guard.event.is_set()
        and time.monotonic() < t_end
    ):
        guard.event.wait(min(0.5, max(0.0, t_end - time.monotonic())))
        stats = bridge.stats
        if not quiet:
            status_line(stats.status_line(), tty)
        if not warned and stats.clamp_warning() is not None:
            warned = True  # once, live, even with --quiet; the summary says it again
            if not quiet and tty:
                say("")
            say(f"motioncue bridge: warning: {stats.clamp_warning()}")
    if not quiet:
        status_line("parking ...", tty)
    final = bridge.stop()
    while not bridge.wait(1.0):  # the park takes as long as it takes; only SIGKILL ends it
        final = bridge.stats
    if bridge.stats.error != final.error or bridge.stats.state != final.state:
        final = bridge.stats
    if not quiet and tty:
        say("")
    return final


def _summary(st: BridgeStats) -> str:
    def f(x: float) -> str:
        return "-" if math.isnan(x) else f"{x:.2f}"

    reasons = ", ".join(f"{k} {v}" for k, v in sorted(st.packet_reasons.items()))
    return (
        f"bridge {st.state}: {st.frames_sent} frames sent, {st.missed_deadlines} deadlines "
        f"missed; latency p50 {f(st.latency_p50_ms)} ms p99 {f(st.latency_p99_ms)} ms, "
        f"jitter p99 {f(st.jitter_p99_ms)} ms; limiter clamped {st.limiter_clamped_frames} "
        f"frames, workspace clamped {st.pose_clamped} poses ({st.pose_invalid} invalid), "
        f"cueing held {st.cueing_bad_samples} bad samples; {st.fade_outs} fade-outs, "
        f"{st.fade_ins} fade-ins; parked error {st.park_q_error:.3g}\n"
        f"telemetry: {reasons or 'nothing received'}"
    )


def _stats_dict(st: BridgeStats) -> dict[str, Any]:
    """The final bridge statistics for ``--json`` (NaN as None)."""

    def num(x: float) -> float | None:
        return None if math.isnan(x) else float(x)

    return {
        "state": str(st.state),
        "error": None if st.error is None else str(st.error),
        "frames_sent": int(st.frames_sent),
        "missed_deadlines": int(st.missed_deadlines),
        "latency_p50_ms": num(st.latency_p50_ms),
        "latency_p99_ms": num(st.latency_p99_ms),
        "jitter_p99_ms": num(st.jitter_p99_ms),
        "limiter_clamped_frames": int(st.limiter_clamped_frames),
        "pose_clamped": int(st.pose_clamped),
        "pose_invalid": int(st.pose_invalid),
        "cueing_bad_samples": int(st.cueing_bad_samples),
        "fade_outs": int(st.fade_outs),
        "fade_ins": int(st.fade_ins),
        "park_q_error": float(st.park_q_error),
        "telemetry": {str(k): int(v) for k, v in st.packet_reasons.items()},
        "notes": [str(n) for n in st.notes],
    }


_BRIDGE = Verb(
    "bridge",
    run,
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
    options=(
        Option.of("--source", metavar="GAME[:[HOST:]PORT]", help=Lazy(_source_help)),
        Option.of(
            "--profile",
            metavar="NAME",
            help="bundled profile name or .toml path binding a source, a preset, cue gains and "
            "effects for a game or car (configs/profiles); --source and --preset override it",
        ),
        RIG,
        TARGET.but(
            required=True,
            help="udp://HOST:PORT, serial:///dev/ttyUSB0?baud=19200, pcap:PATH or file:PATH",
        ),
        PRESET,
        add_intensity_option,
        RATE,
        LIMITS,
        Option.of(
            "--timeout",
            type=float,
            default=0.25,
            metavar="S",
            help="telemetry older than this counts as lost (default 0.25 s)",
        ),
        Option.of(
            "--fade", type=float, default=2.0, metavar="S", help="fade in/out time (default 2 s)"
        ),
        DURATION.but(help="stop (and park) after this long", allowed=Allowed(0.0, None)),
        Option.of(
            "--rt-priority",
            type=int,
            default=10,
            metavar="N",
            help="run the frame loop under SCHED_FIFO at priority N (1..99; Linux, root or "
            "CAP_SYS_NICE; refused quietly with a note elsewhere): keeps other programs from "
            "delaying frames on a busy PC (default 10; 0 = normal scheduling)",
        ),
        Option.choice(
            "--upsample",
            ("extrapolate", "interpolate", "hold"),
            help="telemetry slower than the frame rate, per frame: extrapolated and corrected "
            "on the next sample (default), interpolated one sample late, or held",
        ),
        Option.choice(
            "--frames",
            ("auto", "arrival", "fixed"),
            help="arrival: a frame as soon as a telemetry sample arrives (SC-MBOX, IMAX: "
            "whole-ms time stamps), else every period; fixed: every period; auto (default): "
            "arrival where the controller and the limits allow it",
        ),
        Option.of(
            "--telemetry-in-process",
            action="store_true",
            help="receive and decode live telemetry in the frame loop's process (default: in a "
            "child process, through shared memory, so decoding never delays a frame)",
        ),
        QUIET.but(help="no status line"),
        json_option("the final statistics (after the park)"),
        set_option(),
        MONITOR,
    ),
)

register = registrar(_BRIDGE)
