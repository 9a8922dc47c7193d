"""``motioncue generate | play | demo``: ride files made offline and played on time."""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._errors import ConfigError
from ._common import (
    CONTROLLER,
    LIMITS,
    OUT,
    PLATFORM,
    PRESET,
    QUIET,
    RATE,
    RECORDING,
    REPORT,
    SPEED,
    TARGET,
    check_set_targets,
    cue_rate_line,
    json_option,
    limits_for,
    load_platform_arg,
    load_snapped_rig,
    print_json,
    say,
    set_option,
    status_line,
)
from ._monitor import MONITOR, start_monitor
from ._preset import add_intensity_option, apply_intensity, cueing_note
from ._verb import Allowed, Option, Verb, registrar

if TYPE_CHECKING:
    from ..output import Controller
    from ..pipeline import Ride

__all__ = ["register"]


class _Bar:
    def __init__(self, enabled: bool) -> None:
        self.enabled = enabled
        self.t0 = time.perf_counter()

    def __call__(self, stage: str, frac: float) -> None:
        if not self.enabled:
            return
        n = int(frac * 30)
        sys.stderr.write(
            f"\r[{'#' * n}{'.' * (30 - n)}] {frac:4.0%} {time.perf_counter() - self.t0:6.2f} s "
            f"{stage:<28s}"
        )
        if frac >= 1.0:
            sys.stderr.write("\n")
        sys.stderr.flush()


def _generate(args: argparse.Namespace) -> int:
    """Make the ride in memory, check it as ``play`` would, then publish the ride, the pcap
    and the report together: a refusal at any step leaves none of them."""
    from .._atomic import Interrupted, Staging
    from ..pipeline import (
        check_ride_for,
        generate_keyframe_ride,
        generate_ride,
        load_generate_input,
        play_ride,
        save_ride,
        write_report,
    )
    from ..pipeline._inputs import check_generate_size, held_warning
    from ._preset import choose_preset

    platform, controller, args.rate, limits = load_snapped_rig(args)
    if args.pcap and controller.link_kind != "udp":
        raise ConfigError(
            f"--pcap is for controllers on UDP; {args.controller} talks {controller.link_kind}: "
            "use 'motioncue play RIDE --target file:PATH' (the raw bytes)"
        )
    kind, data, counters = load_generate_input(args.input)
    check_generate_size(kind, data, args.rate, args.input)
    if counters:
        skipped = ", ".join(
            f"{k.removeprefix('skipped').strip(': ')} {v}"
            for k, v in sorted(counters.items())
            if k.startswith("skipped") and v
        )
        print(
            f"telemetry: {counters.get('sample', 0)} samples used; packets skipped: "
            f"{skipped or 'none'}",
            file=sys.stderr,
        )
        for k, v in sorted(counters.items()):
            if k.startswith("note: ") and v:
                print(f"telemetry: {k} ({v} samples)", file=sys.stderr)
    bar = _Bar(not args.quiet and not args.json)
    summary: dict[str, Any] = {}
    names = {"platform_name": args.platform, "controller_name": args.controller}
    if kind == "keyframes":
        ride, info = generate_keyframe_ride(
            data, platform, controller, rate_hz=args.rate, limits=limits,
            source=Path(args.input).name, **names,
        )  # fmt: skip
        report = None
        summary["content_start_s"] = info["content_start_s"]
        summary["late_keyframes"] = info["late_keyframes"]
        print(
            f"keyframes: the content's t=0 is at ride time {info['content_start_s']:.2f} s "
            "(after the ramp out of park); a keyframe at t is reached at that + t",
            file=sys.stderr,
        )
        fallbacks = list(info["transition_fallbacks"])
        join_notes: list[str] = []
        if info["late_keyframes"]:
            print(
                f"warning: {info['late_keyframes']} keyframe(s) could not be reached on time "
                f"within the limits (latest by {info['max_late_s']:.2f} s); later ones shifted",
                file=sys.stderr,
            )
    else:
        base, base_source = choose_preset(
            args.preset, platform, args.platform, args.overrides, ride=True
        )
        cueing, preset_source = apply_intensity(base, args.intensity, base_source)
        print(f"cueing: preset {preset_source}", file=sys.stderr)
        ride, report = generate_ride(
            data, platform, controller, cueing, rate_hz=args.rate, limits=limits,
            source=Path(args.input).name, progress=bar, **names,
        )  # fmt: skip
        if report.cue_rate_hz != args.rate:
            line = cue_rate_line(cueing.algorithm, report.cue_rate_hz, args.rate, "frames")
            print(f"cueing: {line}", file=sys.stderr)
        # the ride says which preset and intensity made it (view, the monitor and play
        # --intensity read it; in the header, so the digest covers it)
        note = cueing_note(base, args.intensity, args.overrides)
        ride = replace(ride, notes={**ride.notes, "cueing": note})
        fallbacks = list(report.transition_fallbacks)
        summary["joins"] = [dict(j) for j in report.joins]
        # a join the workspace made faster than the perception thresholds (or the fallback
        # stop-then-ramp) is something a rider may feel: say so, as the ramps' fallbacks are
        join_notes = [
            f"the cue's {j['end']} met the ramp {j['kind']} in {j['duration_s']:.2f} s: "
            f"{j['shortened']}"
            for j in report.joins
            if j.get("shortened")
        ]
        warning = held_warning(report.bad_samples, len(report.f_vehicle))
        if warning:
            print(warning, file=sys.stderr)
        n_poses = len(report.poses_cue)
        pct = 100.0 * report.poses_clamped / max(n_poses, 1)
        summary.update(
            preset=cueing.name, poses=n_poses, poses_clamped=report.poses_clamped,
            clamped_percent=pct,
        )  # fmt: skip
        if pct > CLAMP_WARN_PERCENT:
            print(
                f"warning: workspace limiting clamped {report.poses_clamped} of {n_poses} poses "
                f"({pct:.1f} %, above {CLAMP_WARN_PERCENT:g} %): the preset asks more than "
                f"{args.platform} can give; try a gentler preset, or scale it with --set "
                "preset.scaling.f_scale=[...]",
                file=sys.stderr,
            )
    summary["transition_fallbacks"] = len(fallbacks)
    for line in fallbacks + join_notes:
        print(f"note: {line}", file=sys.stderr)
    # the checks play will make: a ride that would be refused there is not published here
    check_ride_for(ride, platform, controller, limits, **names)
    with Staging() as staged:
        save_ride(staged.file(args.out), ride)
        if args.pcap:
            from ..output import open_transport

            with open_transport(f"pcap:{staged.file(args.pcap)}") as link:
                rep = play_ride(ride, platform, controller, limits, link, paced=False)
                if rep.interrupted:  # a stop signal: the player parked; the pcap is not the ride
                    raise Interrupted(rep.signal or "SIGINT")
        if args.report:
            folder = staged.directory(args.report)
            if report is None:
                from ..pipeline import plot_actuators

                plot_actuators(ride, folder / "actuators.png")
            else:
                write_report(folder, ride, report, platform, cueing)
    at_end_s = _time_at_stroke_end_s(ride)
    summary.update(
        ride=str(args.out), frames=ride.n_frames, duration_s=ride.duration_s,
        rate_hz=ride.rate_hz, platform=args.platform, controller=args.controller,
        frame_check=ride.notes.get("frame_check", ""), stroke_end_s=at_end_s,
        pcap=args.pcap, report=args.report,
    )  # fmt: skip
    if args.json:
        print_json(summary)
        return 0
    verdict = ride.notes.get("frame_check", "")
    if summary.get("clamped_percent", 0.0) > CLAMP_WARN_PERCENT:
        # the frames keep the limits, but the ride is not the motion the preset asked for
        verdict = verdict.replace(
            "(OK)",
            f"(frames within the limits; WARNING: {summary['clamped_percent']:.1f} % of the "
            "poses clamped)",
        )
    ends = f"; an actuator at a stroke end for {at_end_s:.2f} s" if at_end_s > 0 else ""
    print(
        f"ride: {args.out}: {ride.n_frames} frames, {ride.duration_s:.1f} s at {ride.rate_hz:g} "
        f"Hz; {verdict}{ends}",
    )
    if args.pcap:
        print(f"pcap: {args.pcap}")
    if args.report:
        print(f"report: {args.report}/")
    return 0


CLAMP_WARN_PERCENT = 1.0
"""Above this share of clamped poses ``generate`` warns (and never says OK)."""


def _time_at_stroke_end_s(ride: Ride) -> float:
    """Longest total time (s) one actuator spends within 0.1 % of the half stroke from an end
    of its pulse range (the limits table saved in the ride) while it moves.

    Each actuator's frames before its first change, and after its last one when it ends where
    it started, are the rig at rest (home, and the first or last frames of a slow ramp that
    round to the home pulse); they do not count. A rig homed at its stroke end (seat3-pot:
    pulse 0 is the pot's value 31, the usable stroke's lower end) was said to sit "at a stroke
    end" in every ride before.
    """
    import numpy as np

    rows = ride.limits.get("actuators", []) if isinstance(ride.limits, dict) else []
    pulses = np.asarray(ride.pulses, dtype=float)
    if not rows or pulses.ndim != 2 or pulses.shape[0] < 2:
        return 0.0
    lo = np.array([r["stroke_pulses"][0] for r in rows], dtype=float)
    hi = np.array([r["stroke_pulses"][1] for r in rows], dtype=float)
    half = np.maximum((hi - lo) / 2.0, 1e-9)
    at_end = np.abs(pulses - (hi + lo) / 2.0) / half >= 0.999
    longest = 0
    for j in range(pulses.shape[1]):
        q = pulses[:, j]
        changed = np.flatnonzero(q[1:] != q[:-1])
        if changed.size == 0:
            continue
        # its last run is the rest it started from only when it is that same pulse
        stop = changed[-1] + 1 if q[-1] == q[0] else q.size
        longest = max(longest, int(np.count_nonzero(at_end[changed[0] + 1 : stop, j])))
    return float(longest) / float(ride.rate_hz)


def _play(args: argparse.Namespace) -> int:
    from ..output import load_controller, open_transport
    from ..pipeline import check_ride_for, check_ride_integrity, load_ride, play_ride
    from ..pipeline._signals import SignalGuard
    from ..pipeline._stream import PlayAborted
    from ..viewer._cueing import describe_cueing
    from ..viewer._monitor import PlaySource
    from ._preset import check_play_intensity

    check_set_targets(args.overrides, ("platform",))
    ride = load_ride(args.ride)
    platform_name = args.platform or ride.platform
    controller_name = args.controller or ride.controller
    platform = load_platform_arg(platform_name, args.overrides)
    controller = load_controller(controller_name)
    if controller.n_axes != platform.n_actuators:
        raise ConfigError(
            f"controller {controller.name} drives {controller.n_axes} axes; platform "
            f"{platform.name} has {platform.axes_text}"
        )
    resync_after_s = None if args.resync_after_ms == 0.0 else args.resync_after_ms / 1000.0
    controller.check_rate(ride.rate_hz)
    limits = limits_for(args, platform, controller, ride.rate_hz)
    # nothing is sent unless the ride is the one generate made (or its edit was accepted and
    # is still a rigid platform's), belongs to this rig and keeps its limits now
    integrity_notes = check_ride_integrity(
        ride, platform, accept_edited=args.accept_edited, name=str(args.ride)
    )
    check_ride_for(
        ride, platform, controller, limits,
        platform_name=platform_name, controller_name=controller_name,
    )  # fmt: skip
    if args.intensity is not None:
        integrity_notes = [
            *integrity_notes,
            check_play_intensity(ride, args.intensity, str(args.ride)),
        ]
    target = args.target or controller.default_target
    scheme = target.split(":", 1)[0].lower()
    paced = scheme not in ("file", "pcap")
    if args.speed != 1.0 and paced:
        raise ConfigError(
            f"--speed {args.speed:g} is only for pcap: and file: targets: a controller plays "
            f"frames at their own time stamps, and its buffer ({controller_buffer(controller)}) "
            "would overflow"
        )
    # over UDP the IMAX and SC-MBOX report where their motors are: start from there
    q_start = "auto" if scheme == "udp" else None
    # from here on SIGINT, SIGTERM, SIGHUP and SIGQUIT only set a flag: the ride stops at the
    # next frame, and nothing cuts the park or the summary short
    with SignalGuard() as guard:
        for accepted in integrity_notes:
            say(f"motioncue play: note: {accepted}")
        say(f"play: {args.ride} -> {target} ({ride.n_frames} frames, {ride.duration_s:.1f} s)")
        error = None
        watch = None
        if args.monitor is not None:
            watch = PlaySource(ride.duration_s, {"cueing": describe_cueing(ride.notes)})
        stop = guard.event.is_set
        if watch is not None:
            stop = lambda: guard.event.is_set() or watch.stopped()  # noqa: E731
        progress = _PlayProgress(ride.n_frames, ride.rate_hz, stop)
        progress.enabled = paced and not args.quiet and not args.json
        monitor = start_monitor(
            args.monitor, watch, platform, limits, f"play {args.ride} -> {target}", say
        )
        if paced:  # frames on time beside a busy core (pipeline._realtime, Short slice)
            from motioncue.pipeline._realtime import request_short_slice

            note = request_short_slice(1e-4)
            if note is not None:
                say(f"play: {note}")
        try:
            with open_transport(target) as link:
                try:
                    rep = play_ride(
                        ride, platform, controller, limits, link, speed=args.speed,
                        paced=paced, q_start=q_start, stop=progress, handle_signals=False,
                        resync_after_s=resync_after_s,
                        on_start=None if watch is None else watch.attach,
                    )  # fmt: skip
                except PlayAborted as exc:
                    if exc.report is None:
                        raise
                    rep, error = exc.report, str(exc)
                finally:
                    progress.done()
        finally:
            if watch is not None:
                watch.finished = True
            if monitor is not None:
                monitor.stop()
        for note in rep.notes:
            say(f"motioncue play: note: {note}")
        if error is None and rep.refused_frames:
            error = (
                f"the controller refused {rep.refused_frames} of {rep.frame_replies} frames "
                "(buffer full or not ready): the ride was not played as made; parked"
            )
        if error is not None:
            outcome = "stopped on an error"
        elif rep.interrupted:
            outcome = f"interrupted and parked{f' ({guard.first})' if guard.first else ''}"
        else:
            outcome = "finished"
        retried = f"; {rep.send_errors} send errors retried" if rep.send_errors else ""
        if rep.skipped_frames:  # held up (a stopped process, a stalled machine): kept in sync
            retried += (
                f"; held up {rep.resyncs} time(s): skipped {rep.skipped_frames} late frames to "
                "stay on the ride's clock"
            )
        if args.json:
            print_json(
                {
                    "ride": str(args.ride), "target": target, "outcome": outcome,
                    "error": error, "frames_sent": rep.frames_sent,
                    "ride_frames_sent": rep.ride_frames_sent,
                    "park_frames": rep.park_frames, "clamped_frames": rep.clamped_frames,
                    "late_frames": rep.late_frames, "send_errors": rep.send_errors,
                    "skipped_frames": rep.skipped_frames, "resyncs": rep.resyncs,
                    "holdups": [asdict(h) for h in rep.holdups],
                    "wall_s": rep.wall_s, "notes": list(rep.notes),
                },
                best_effort=True,
            )  # fmt: skip
            return 2 if error is not None else (130 if rep.interrupted else 0)
        say(
            f"sent {rep.frames_sent} frames ({rep.ride_frames_sent} of the ride, {rep.park_frames} "
            f"parking); limiter changed {rep.clamped_frames}; late {rep.late_frames}{retried}; "
            f"{outcome} in {rep.wall_s:.1f} s",
            sys.stdout,
        )
        if error is not None:
            say(f"motioncue play: error: {error}")
            return 2
        return 130 if rep.interrupted else 0


class _PlayProgress:
    """The ``stop`` hook of ``play_ride`` (called before every frame) that also shows how far
    the ride is: ``play: 12.0 of 59.3 s (20 %)`` on stderr, refreshed each second on a
    terminal, every ten seconds otherwise. Cheap per frame: a counter and a clock read."""

    def __init__(self, n_frames: int, rate_hz: float, stop: Callable[[], object]) -> None:
        self.n_frames = n_frames
        self.rate_hz = rate_hz
        self.stop = stop
        self.enabled = True
        self.frame = 0
        try:
            self.tty = sys.stderr.isatty()
        except (OSError, ValueError):
            self.tty = False
        self.every_s = 1.0 if self.tty else 10.0
        self.next_t = time.monotonic() + self.every_s
        self.shown = False

    def __call__(self) -> bool:
        self.frame += 1
        if self.enabled and time.monotonic() >= self.next_t:
            self.next_t += self.every_s
            self.show()
        return bool(self.stop())

    def line(self) -> str:
        done = min(self.frame - 1, self.n_frames)  # frames sent before this one
        frac = done / max(self.n_frames, 1)
        return (
            f"play: {done / self.rate_hz:.1f} of {self.n_frames / self.rate_hz:.1f} s ({frac:.0%})"
        )

    def show(self) -> None:
        self.shown = True
        status_line(self.line(), self.tty)

    def done(self) -> None:
        if self.shown and self.tty:
            say("")


def controller_buffer(controller: Controller) -> str:
    return f"{controller.buffer_frames} frames"


def _demo(args: argparse.Namespace) -> int:
    from ..pipeline import run_demo

    res = run_demo(
        args.out, speed=args.speed, platform_name=args.platform, controller_name=args.controller
    )
    return 0 if res.comparison.ok else 1


_VERBS = (
    Verb(
        "generate",
        _generate,
        help="make a ride file from a recording or pose keyframes",
        description="Recording (CSV t,fx,fy,fz,wx,wy,wz; or a 'motioncue record' file) -> "
        "cueing -> workspace limiting -> IK -> drives -> casadi ride optimisation -> frames. "
        "A pose-keyframe CSV (t,x,y,z,roll,pitch,yaw[,dout,dac1,dac2]) skips cueing and "
        "uses time-optimal transitions.",
        options=(
            RECORDING.but(
                help="recording CSV, 'motioncue record' .mctr file, or pose-keyframe CSV"
            ),
            PLATFORM.but(metavar="P"),
            CONTROLLER.but(metavar="C"),
            PRESET,
            add_intensity_option,
            RATE.but(allowed=Allowed(0.0, 2000.0, unit="Hz")),
            OUT.but(metavar="RIDE", help="ride file to write"),
            Option.of("--pcap", metavar="FILE", help="also write the exact datagrams as a pcap"),
            REPORT.but(help="write plots and cue metrics here"),
            QUIET.but(help="no progress bar"),
            LIMITS,
            set_option(),
            json_option("the ride's summary"),
        ),
    ),
    Verb(
        "play",
        _play,
        help="stream a ride file to a controller on time (ramps in from park, parks at the end)",
        options=(
            Option.of("ride", metavar="RIDE", help="ride file made by 'motioncue generate'"),
            TARGET,
            CONTROLLER.but(required=False, metavar="C", help="default: the ride's controller"),
            PLATFORM.but(required=False, metavar="P", help="default: the ride's platform"),
            SPEED.but(
                default=1.0,
                help="pacing factor (default 1 = real time; other values for pcap: and file: only)",
                allowed=Allowed(0.0, 1000.0),
            ),
            QUIET.but(help="no progress line while playing"),
            Option.of(
                "--resync-after-ms",
                type=float,
                default=100.0,
                metavar="MS",
                help="when the player finds itself more than MS late (the process was stopped, "
                "the machine stalled), skip the ride frames whose time has passed and go on "
                "with the one due now, through the limiter (default 100); 0: never skip, send "
                "every frame (only for a controller that buffers frames and plays them on its "
                "own clock)",
                allowed=Allowed(0.0, None, lo_closed=True, show="g"),
            ),
            Option.of(
                "--intensity",
                type=float,
                default=None,
                metavar="PCT",
                help="the intensity (0-100) the ride must have been made at: a ride's frames "
                "are fixed when 'generate --intensity' makes them, so play checks the intensity "
                "the ride records and refuses another (with the generate command that makes "
                "it)",
            ),
            Option.of(
                "--accept-edited",
                action="store_true",
                help="play a ride changed after generate made it (its digest does not match) "
                "or one without a digest; its frames must still be a rigid platform's",
            ),
            LIMITS,
            set_option(("platform",)),
            json_option("the play summary"),
            MONITOR,
        ),
    ),
    Verb(
        "demo",
        _demo,
        help="generate a ride from the bundled lap, play it to the MBOX/IMAX emulator, compare",
        description="The whole chain without hardware or network: the bundled lap "
        "(configs/recordings/lap.csv) becomes a ride for --platform and --controller "
        "(generate), the ride is played on loopback to the built-in emulator of that "
        "controller (play, emulate), the emulator's trace is compared with the ride, and a "
        "report (cueing and actuator plots, metrics, summary) is written under --out.",
        options=(
            OUT.but(
                required=False,
                default="out/demo",
                metavar="DIR",
                help="folder for the demo's files (out/demo)",
            ),
            SPEED.but(default=10.0, help="pacing factor for the emulator"),
            PLATFORM.but(
                required=False,
                help="bundled platform or TOML path (default: stewart6-linear, or the first "
                "bundled platform the controller can drive)",
            ),
            CONTROLLER.but(required=False, default="mbox6", help="an MBOX or IMAX controller"),
        ),
    ),
)

register = registrar(*_VERBS)
