"""``motioncue ik`` and ``motioncue workspace``: look at a platform before driving it."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from ._common import PLATFORM, PLOT, json_option, load_platform_arg, set_option
from ._verb import Option, Verb, registrar

__all__ = ["register"]


def _pose_si(values: list[float], mm_deg: bool) -> np.ndarray:
    from .._errors import ConfigError

    pose = np.array(values, dtype=float)
    if not np.isfinite(pose).all():
        raise ConfigError(f"--pose {values} is invalid; allowed: six finite numbers")
    if mm_deg:
        pose[:3] *= 1e-3
        pose[3:] = np.radians(pose[3:])
    return pose


def _run_ik(args: argparse.Namespace) -> int:
    from ..kinematics import DOF_NAMES

    p = load_platform_arg(args.platform, args.overrides)
    pose = _pose_si(args.pose, args.mm_deg)
    res = p.check(pose)
    pulses = p.drives.to_pulses(res.q)
    absolute = p.absolute(res.q)
    unsupported = [DOF_NAMES[k] for k in np.flatnonzero(res.unsupported)]
    rows = []
    for i, name in enumerate(p.actuator_names):
        linear = p.actuator_kinds[i] == "linear"
        scale = 1e3 if linear else 180.0 / math.pi
        rows.append(
            {
                "name": name,
                "kind": p.actuator_kinds[i],
                "unit": "mm" if linear else "deg",
                "position": float(res.q[i] * scale),
                "absolute": float(absolute[i] * scale),
                "min": float(p.q_min[i] * scale),
                "max": float(p.q_max[i] * scale),
                "overshoot": float(res.overshoot[i] * scale),
                "in_stroke": bool(res.in_stroke[i]),
                "reachable": bool(res.reachable[i]),
                "pulses": int(pulses[i]),
            }
        )
    ok = bool(res.ok) and not unsupported
    if args.json:
        print(
            json.dumps(
                {
                    "platform": p.name,
                    "pose_si": pose.tolist(),
                    "actuators": rows,
                    "unsupported": unsupported,
                    "ok": ok,
                },
                indent=2,
            )
        )
        return 0 if ok else 1
    print(f"platform {p.name}: {p.description}")
    shown = ", ".join(
        f"{n}={v * (1e3 if k < 3 else 180 / math.pi):.3f}{'mm' if k < 3 else 'deg'}"
        for k, (n, v) in enumerate(zip(DOF_NAMES, pose, strict=True))
    )
    print(f"pose: {shown}")
    header = (
        f"{'actuator':<12s} {'unit':<4s} {'from neutral':>12s} {'absolute':>10s} "
        f"{'usable min':>10s} {'usable max':>10s} {'pulses':>10s}  status"
    )
    print(header)
    first_spare = p.n_actuators - p.spare_axes
    for i, r in enumerate(rows):
        status = "ok" if i < first_spare else "spare axis (held at pulse 0)"
        if not r["reachable"]:
            status = "UNREACHABLE (closest approach shown)"
        elif not r["in_stroke"]:
            status = f"OUT OF STROKE by {r['overshoot']:+.3f} {r['unit']}"
        print(
            f"{r['name']:<12s} {r['unit']:<4s} {r['position']:>12.3f} {r['absolute']:>10.3f} "
            f"{r['min']:>10.3f} {r['max']:>10.3f} {r['pulses']:>10d}  {status}"
        )
    if unsupported:
        print(
            f"note: {p.name} cannot produce {', '.join(unsupported)}; held at zero "
            "(request reported, not applied)"
        )
    print("pose is reachable" if ok else "pose is NOT reachable as asked")
    return 0 if ok else 1


def _run_workspace(args: argparse.Namespace) -> int:
    from ..kinematics import DOF_NAMES, dof_ranges, plot_workspace

    p = load_platform_arg(args.platform, args.overrides)
    ranges = dof_ranges(p)
    table = ranges.as_dict()
    plot_path = None
    if args.plot:
        plot_path = str(plot_workspace(p, args.plot, ranges))
    if args.json:
        print(json.dumps({"platform": p.name, "ranges": table, "plot": plot_path}, indent=2))
        return 0
    print(f"platform {p.name}: range of each degree of freedom alone (others at neutral)")
    for k, name in enumerate(DOF_NAMES):
        unit = "mm" if k < 3 else "deg"
        row = table[name]
        if not row["supported"]:
            print(f"  {name:<6s} not produced by this machine (held at 0)")
            continue
        capped = " (search bound reached)" if ranges.capped[k].any() else ""
        print(f"  {name:<6s} {row['min']:>9.2f} .. {row['max']:>8.2f} {unit}{capped}")
    if plot_path:
        print(f"plot saved to {plot_path}")
    return 0


_TABLE_AND_SET = (json_option("the table"), set_option(("platform",)))
"""The last options of both verbs: ``--json`` and ``--set platform...``."""

_VERBS = (
    Verb(
        "ik",
        _run_ik,
        help="actuator lengths, strokes and pulses for one pose",
        description=(
            "Inverse kinematics of one pose: actuator positions (from neutral and absolute), "
            "usable stroke, controller pulses, and whether the pose is reachable. Exit status "
            "1 when an actuator is out of stroke or unreachable or the pose asks for a "
            "component the machine cannot produce."
        ),
        options=(
            PLATFORM,
            Option.of(
                "--pose",
                nargs=6,
                type=float,
                required=True,
                metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
                help="pose from neutral: metres and radians (mm and degrees with --mm-deg)",
            ),
            Option.of("--mm-deg", action="store_true", help="pose given in mm and degrees"),
            _TABLE_AND_SET,
        ),
    ),
    Verb(
        "workspace",
        _run_workspace,
        help="reachable range of each degree of freedom alone",
        description="Range of each pose component alone (others at neutral), by bisection.",
        options=(
            PLATFORM,
            PLOT.but(help="also save a plot of the workspace"),
            _TABLE_AND_SET,
        ),
    ),
)

register = registrar(*_VERBS)
