"""The demo: bundled lap -> MBOX 6-axis ride for the bundled hexapod -> emulator -> compare.

Another bundled platform and any controller whose kind has an emulator on UDP can be named
(``corner4-tl`` on ``mbox6``, ``imax6``; ``smc3`` alone picks ``seat3-pot``, the first bundled
platform it can drive); the cueing preset is the platform's ride-file preset
(``ride_preset``, the plan that sees the whole lap), else its ``default_preset``.

No hardware and no network: the emulator listens on loopback in this process.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from .._config import config_dir
from .._errors import ConfigError
from ._ridefile import Ride, save_ride
from ._verify import FrameCheck, check_frames

if TYPE_CHECKING:
    from motioncue.output import Controller, Emulator

__all__ = ["DEMO_SILENCE_S", "DemoResult", "compare_trace", "run_demo"]

#: Longest silence of the emulator the demo's player accepts (s): the emulator shares the
#: demo's process, so a busy machine that holds this process up silences it for a while
#: (762 ms seen with one core kept busy), which is no dead controller.
DEMO_SILENCE_S = 5.0


@dataclass(frozen=True)
class TraceComparison:
    """How the emulator's trace matches the ride it was sent."""

    frames_compared: int
    frames_expected: int
    max_pulse_error: int
    max_time_error_s: float
    limits: FrameCheck
    violations: list[str]

    @property
    def ok(self) -> bool:
        return (
            self.frames_compared == self.frames_expected
            and self.max_pulse_error <= 1
            and self.max_time_error_s <= 1e-3
            and self.limits.ok
            and not self.violations
        )


@dataclass(frozen=True)
class DemoResult:
    ride_path: Path
    report_dir: Path
    comparison: TraceComparison
    generate_s: float
    play_s: float


def compare_trace(ride: Ride, emulator: Emulator) -> TraceComparison:
    """Compare the emulator's per-axis trace with the ride's frames (first ``N`` rows)."""
    trace = emulator.trace
    n = min(ride.n_frames, len(trace.t_s))
    pos = np.asarray(trace.positions, dtype=np.int64)
    err = int(np.max(np.abs(pos[:n] - ride.pulses[:n]), initial=0))
    terr = float(np.max(np.abs(np.asarray(trace.t_s[:n]) - ride.t_s[:n]), initial=0.0))
    limits = check_frames(np.asarray(trace.t_s), pos, ride.limits, start_at_rest=True)
    violations = [f"{v.kind}: {v.detail}" for v in emulator.violations]
    return TraceComparison(n, ride.n_frames, err, terr, limits, violations)


def _platform_for(controller: Controller, rate_hz: float) -> str:
    """The bundled platform the demo uses for ``controller`` when none is named."""
    from motioncue.kinematics import load_platform
    from motioncue.trajectory import ActuatorLimits

    names = sorted(p.stem for p in config_dir("platforms").glob("*.toml"))
    for name in ["stewart6-linear", *(n for n in names if n != "stewart6-linear")]:
        platform = load_platform(name)
        if platform.n_actuators != controller.n_axes:
            continue
        try:
            ActuatorLimits.from_platform(platform, controller, rate_hz=rate_hz)
        except ConfigError:
            continue  # its drive disagrees with what the controller's values imply
        return name
    raise ConfigError(
        f"no bundled platform fits controller {controller.name!r} ({controller.n_axes} axes); "
        "name one with --platform"
    )


def run_demo(
    out_dir: str | Path = "out/demo",
    *,
    rate_hz: float = 100.0,
    speed: float = 10.0,
    log: Callable[[str], None] = print,
    platform_name: str | None = None,
    controller_name: str = "mbox6",
) -> DemoResult:
    """Generate, play to the emulator, compare, and write the report (see module docstring).

    ``platform_name``: a bundled platform or path (None: ``stewart6-linear`` if the
    controller can drive it, else the first bundled platform, by name, that it can: as many
    actuators as the controller has axes, and a drive its values agree with);
    ``controller_name``: a controller (name or path) whose kind declares an emulator on
    ``udp://``, played to that emulator. The
    cueing preset is the platform's ``ride_preset``, else its ``default_preset``.
    """
    from motioncue.cueing import FALLBACK_PRESET, load_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import controller_kind, load_controller, open_transport, parse_target
    from motioncue.telemetry._recording import read_recording_csv
    from motioncue.trajectory import ActuatorLimits

    from ._generate import generate_ride
    from ._report import write_report
    from ._stream import play_ride, receiver_throttle

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    lap = config_dir("recordings") / "lap.csv"
    controller = load_controller(controller_name)
    if platform_name is None:
        platform_name = _platform_for(controller, rate_hz)
    platform = load_platform(platform_name)
    kind = controller_kind(controller.kind)
    if kind.emulator is None or "udp" not in kind.emulator_schemes:
        raise ConfigError(
            f"controller {controller_name!r} is of kind {kind.name}, which has no emulator on "
            "udp://; the demo plays to a controller emulator on loopback"
        )
    preset = platform.cueing_preset(ride=True) or FALLBACK_PRESET
    cueing = load_cueing(preset)
    limits = ActuatorLimits.from_platform(platform, controller, rate_hz=rate_hz)
    log(
        f"demo: {lap.name} (a {rate_hz:g} Hz vehicle-model lap) -> {platform_name} on "
        f"{controller_name} (cueing preset {preset})"
    )
    t0 = time.perf_counter()
    ride, report = generate_ride(
        read_recording_csv(lap), platform, controller, cueing, rate_hz=rate_hz,
        limits=limits, source=lap.name, platform_name=platform_name,
        controller_name=controller_name,
    )  # fmt: skip
    gen_s = time.perf_counter() - t0
    ride_path = save_ride(out / "lap.ride", ride)
    log(
        f"generated {ride.n_frames} frames ({ride.duration_s:.1f} s) in {gen_s:.2f} s -> "
        f"{ride_path}; {report.frame_check.summary()}"
    )
    report_dir = out / "report"
    write_report(report_dir, ride, report, platform, cueing)
    log(f"report: {report_dir}/ (cueing.png, actuators.png, metrics.json, summary.txt)")
    # The emulator's buffer holds the whole ride, so the ride can be sent faster than real
    # time: the emulator's timeline follows the absolute frame times, not arrival.
    # (bundled UDP controllers are frozen dataclasses with a ``buffer_frames`` field)
    emu_ctrl = dataclasses.replace(
        controller,  # type: ignore[type-var]
        buffer_frames=ride.n_frames + 1024,
    )
    t1 = time.perf_counter()
    emu = kind.open_emulator(emu_ctrl, parse_target("udp://127.0.0.1:0")).start()
    try:
        # the emulator runs in this process: a silence of it is this process held up (its
        # thread waits for the interpreter and the CPU), not a dead controller; the link's
        # own option says so (a real controller keeps its 0.5 s)
        sep = "&" if "?" in emu.where else "?"
        with open_transport(f"{emu.where}{sep}silence_ms={round(DEMO_SILENCE_S * 1000)}") as link:
            log(f"playing to the {kind.name} emulator on {emu.where} at {speed:g}x")

            played = play_ride(
                ride, platform, controller, limits, link, speed=speed, spin_s=0.0,
                throttle=receiver_throttle(lambda: emu.frames_received),
            )  # fmt: skip
            deadline = time.monotonic() + 5.0
            while emu.frames_received < played.frames_sent and time.monotonic() < deadline:
                time.sleep(0.01)
            comparison = compare_trace(ride, emu)
    finally:
        emu.stop()
    play_s = time.perf_counter() - t1
    log(
        f"emulator: {comparison.frames_compared} of {ride.n_frames} ride frames traced; "
        f"max error {comparison.max_pulse_error} pulse(s), "
        f"{comparison.max_time_error_s * 1e3:.3f} ms; limits: "
        f"{comparison.limits.summary()}; violations: {len(comparison.violations)}"
    )
    log("demo " + ("passed" if comparison.ok else "FAILED"))
    return DemoResult(ride_path, report_dir, comparison, gen_s, play_s)
