"""``motioncue limits``: print the effective actuator limits, in SI and in drive pulses."""

from __future__ import annotations

import argparse
import math
from typing import TYPE_CHECKING

from ._common import (
    CONTROLLER,
    LIMITS,
    PLATFORM,
    RATE,
    json_option,
    limits_for,
    load_platform_arg,
    set_option,
)
from ._verb import Verb, registrar

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits

__all__ = ["register"]


def run(args: argparse.Namespace) -> int:
    platform = load_platform_arg(args.platform, args.overrides)
    controller = None
    if args.controller:
        from ..output._controllers import load_controller

        controller = load_controller(args.controller)
        if args.rate is not None:
            controller.check_rate(args.rate)
    lim = limits_for(args, platform, controller, args.rate)
    if args.json:
        print(lim.to_json(platform))
        return 0
    print(_table(lim, platform, args))
    return 0


def _table(lim: ActuatorLimits, platform: Platform, args: argparse.Namespace) -> str:
    pulses = lim.to_pulses_table(platform)
    head = f"limits: platform {args.platform}" + (
        f", controller {args.controller}" if args.controller else ""
    )
    lines = [head]
    hdr = (
        f"{'axis':<12} {'kind':<7} {'stroke':>20} {'max speed':>13} {'max accel':>14}"
        f" {'stroke pulses':>20} {'pulses/s':>11} {'pulses/s^2':>12}"
    )
    lines.append(hdr)
    for i in range(lim.n_actuators):
        rot = lim.kinds[i] == "rotary"
        f, u = (180.0 / math.pi, "deg") if rot else (1e3, "mm")
        p = pulses[i]
        lines.append(
            f"{lim.names[i]:<12} {lim.kinds[i]:<7} "
            f"{f'[{lim.q_min[i] * f:.2f}, {lim.q_max[i] * f:.2f}] {u}':>20} "
            f"{f'{lim.v_max[i] * f:.1f} {u}/s':>13} {f'{lim.a_max[i] * f:.0f} {u}/s^2':>14} "
            f"{p['stroke_pulses']!s:>20} {p['max_speed_pulses_s']:>11.0f} "
            f"{p['max_accel_pulses_s2']:>12.4g}"
        )
    if lim.j_max is not None:
        lines.append("max jerk: " + ", ".join(f"{j:g}" for j in lim.j_max) + " (SI)")
    for key, text in lim.sources.items():
        lines.append(f"{key}: {text}")
    return "\n".join(lines)


_LIMITS = Verb(
    "limits",
    run,
    help="print the effective actuator limits (stroke, speed, acceleration)",
    description=(
        "Effective per-actuator limits of a platform driven by a controller: the "
        "platform's usable stroke, IMAX PA07/PA8x/PAax*PAbx speed and PAbx ramp, MBOX "
        "Fn0C0/Fn0C1 stroke, and the overrides given here (the smallest value wins). "
        "Printed in SI and in drive pulses, in controller axis order."
    ),
    options=(
        PLATFORM,
        CONTROLLER.but(required=False),
        LIMITS,
        RATE.but(
            default=None,
            help="frame rate, for controllers whose limits depend on it (EasySmc; checked "
            "against the controller's clock)",
        ),
        json_option("the table"),
        set_option(("platform",)),
    ),
)

register = registrar(_LIMITS)
