"""``motioncue generate | play | demo``: ride files made offline and played on time."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

from .._errors import ConfigError

__all__ = ["register"]


def register(sub: Any) -> None:
    g = sub.add_parser(
        "generate",
        help="make a ride file from a recording or pose keyframes",
        description="Recording (CSV t,fx,fy,fz,wx,wy,wz; or a 'motioncue record' file) -> "
        "cueing -> workspace limiting -> IK -> drives -> casadi ride optimisation -> frames. "
        "A pose-keyframe CSV (t,x,y,z,roll,pitch,yaw[,dout,dac1,dac2]) skips cueing and "
        "uses time-optimal transitions.",
    )
    g.add_argument("--input", required=True, metavar="REC")
    g.add_argument("--platform", required=True, metavar="P")
    g.add_argument("--controller", required=True, metavar="C")
    g.add_argument("--preset", default="racing-hexapod", metavar="NAME", help="cueing preset")
    g.add_argument("--rate", type=float, default=100.0, metavar="HZ", help="frame rate")
    g.add_argument("--out", required=True, metavar="RIDE")
    g.add_argument("--pcap", metavar="FILE", help="also write the exact datagrams as a pcap")
    g.add_argument("--report", metavar="DIR", help="write plots and cue metrics here")
    g.add_argument("--quiet", action="store_true", help="no progress bar")
    g.set_defaults(run=_generate)

    p = sub.add_parser(
        "play",
        help="stream a ride file to a controller on time (ramps in from park, parks at the end)",
    )
    p.add_argument("ride", metavar="RIDE")
    p.add_argument("--target", default=None, metavar="URL", help="default: the controller's")
    p.add_argument("--controller", default=None, help="default: the ride's controller")
    p.add_argument("--platform", default=None, help="default: the ride's platform")
    p.add_argument("--speed", type=float, default=1.0, help="pacing factor (default 1 = real time)")
    p.set_defaults(run=_play)

    d = sub.add_parser(
        "demo",
        help="generate an MBOX ride from the bundled lap, play it to the emulator, compare",
    )
    d.add_argument("--out", default="out/demo", metavar="DIR")
    d.add_argument("--speed", type=float, default=10.0, help="pacing factor for the emulator")
    d.set_defaults(run=_demo)


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
    from ..kinematics import load_platform
    from ..output import load_controller
    from ..pipeline import (
        generate_keyframe_ride,
        generate_ride,
        load_generate_input,
        play_ride,
        save_ride,
        write_report,
    )
    from ..trajectory import ActuatorLimits
    from ..washout import load_cueing

    if not (0 < args.rate <= 2000):
        raise ConfigError(f"--rate {args.rate!r} is invalid; allowed: (0, 2000] Hz")
    platform = load_platform(args.platform)
    controller = load_controller(args.controller)
    limits = ActuatorLimits.from_platform(platform, controller)
    kind, data, counters = load_generate_input(args.input)
    if counters:
        skipped = {k: v for k, v in counters.items() if k.startswith("skipped") and v}
        print(
            f"telemetry: {counters.get('sample', 0)} samples used; skipped {skipped}",
            file=sys.stderr,
        )
        for k, v in sorted(counters.items()):
            if k.startswith("note: ") and v:
                print(f"telemetry: {k} ({v} samples)", file=sys.stderr)
    bar = _Bar(not args.quiet)
    names = {"platform_name": args.platform, "controller_name": args.controller}
    if kind == "keyframes":
        ride, info = generate_keyframe_ride(
            data, platform, controller, rate_hz=args.rate, limits=limits,
            source=Path(args.input).name, **names,
        )  # fmt: skip
        report = None
        if info["late_keyframes"]:
            print(
                f"warning: {info['late_keyframes']} keyframe(s) could not be reached on time "
                f"within the limits (latest by {info['max_late_s']:.2f} s); later ones shifted",
                file=sys.stderr,
            )
    else:
        cueing = load_cueing(args.preset)
        ride, report = generate_ride(
            data, platform, controller, cueing, rate_hz=args.rate, limits=limits,
            source=Path(args.input).name, progress=bar, **names,
        )  # fmt: skip
    save_ride(args.out, ride)
    print(
        f"ride: {args.out}: {ride.n_frames} frames, {ride.duration_s:.1f} s at {ride.rate_hz:g} "
        f"Hz; {ride.notes.get('frame_check', '')}",
    )
    if args.pcap:
        if controller.kind == "easysmc":
            raise ConfigError(
                "--pcap is for the UDP controllers; for the EasySmc use "
                "'motioncue play RIDE --target file:PATH' (raw serial bytes)"
            )
        from ..output import open_transport

        with open_transport(f"pcap:{args.pcap}") as link:
            play_ride(ride, platform, controller, limits, link, paced=False)
        print(f"pcap: {args.pcap}")
    if args.report:
        if report is None:
            from ..pipeline import plot_actuators

            Path(args.report).mkdir(parents=True, exist_ok=True)
            plot_actuators(ride, Path(args.report) / "actuators.png")
        else:
            write_report(args.report, ride, report, platform, load_cueing(args.preset))
        print(f"report: {args.report}/")
    return 0


def _play(args: argparse.Namespace) -> int:
    from ..kinematics import load_platform
    from ..output import load_controller, open_transport
    from ..pipeline import load_ride, play_ride
    from ..trajectory import ActuatorLimits

    if not (0 < args.speed <= 1000):
        raise ConfigError(f"--speed {args.speed!r} is invalid; allowed: (0, 1000]")
    ride = load_ride(args.ride)
    platform = load_platform(args.platform or ride.platform)
    controller = load_controller(args.controller or ride.controller)
    if controller.n_axes != platform.n_actuators:
        raise ConfigError(
            f"controller {controller.name} drives {controller.n_axes} axes; platform "
            f"{platform.name} has {platform.n_actuators} actuators"
        )
    limits = ActuatorLimits.from_platform(platform, controller)
    table = limits.to_pulses_table(platform)
    if ride.limits.get("actuators") != table:
        print(
            "note: the ride was made with other limits; the current ones are enforced",
            file=sys.stderr,
        )
    target = args.target or controller.default_target
    paced = not target.startswith(("file:", "pcap:"))
    print(
        f"play: {args.ride} -> {target} ({ride.n_frames} frames, {ride.duration_s:.1f} s)",
        file=sys.stderr,
    )
    import signal
    import threading

    stop = threading.Event()

    def on_term(signum: int, frame: Any) -> None:
        stop.set()  # SIGTERM: stop the ride and park, as Ctrl-C does

    previous = signal.signal(signal.SIGTERM, on_term)
    try:
        with open_transport(target) as link:
            rep = play_ride(
                ride, platform, controller, limits, link, speed=args.speed, paced=paced,
                stop=stop.is_set,
            )  # fmt: skip
    finally:
        signal.signal(signal.SIGTERM, previous)
    print(
        f"sent {rep.frames_sent} frames ({rep.ride_frames_sent} of the ride, {rep.park_frames} "
        f"parking); limiter changed {rep.clamped_frames}; late {rep.late_frames}; "
        f"{'interrupted and parked' if rep.interrupted else 'finished'} in {rep.wall_s:.1f} s"
    )
    return 130 if rep.interrupted else 0


def _demo(args: argparse.Namespace) -> int:
    from ..pipeline import run_demo

    res = run_demo(args.out, speed=args.speed)
    return 0 if res.comparison.ok else 1
