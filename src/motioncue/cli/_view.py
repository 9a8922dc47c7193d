"""``motioncue view``: one self-contained HTML page of a ride or poses CSV (works offline)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import OUT, PLATFORM, json_option, print_json
from ._verb import Option, Verb, registrar

__all__ = ["register"]


def _view(args: argparse.Namespace) -> int:
    from ..viewer import load_view_input, write_view

    view = load_view_input(args.input, args.platform, args.recording)
    path = write_view(view, args.out)
    size_mb = path.stat().st_size / 1e6
    if args.json:
        print_json(
            {
                "out": str(path),
                "bytes": path.stat().st_size,
                "samples": int(view.scene.t_s.size),
                "duration_s": float(view.scene.t_s[-1]),
                "notes": list(view.notes),
                "metrics": None if view.metrics is None else view.metrics.to_dict(),
            }
        )
        return 0
    for line in view.notes:
        print(f"view: {line}")
    print(
        f"view: {path} ({size_mb:.1f} MB, {view.scene.t_s.size} samples, "
        f"{view.scene.t_s[-1]:.1f} s); open it in a browser (no network needed)"
    )
    return 0


_VIEW = Verb(
    "view",
    _view,
    help="an HTML page of a ride or poses CSV: the platform in 3D, actuators, perception",
    description="Write one self-contained HTML file (plotly.js embedded; opens offline): "
    "the platform in 3D (base, legs coloured by stroke use, top) animated in time with "
    "play/pause and a slider, synchronised with the actuator positions against their "
    "stroke and with the motion the rider perceives.",
    options=(
        Option.of(
            "input",
            metavar="RIDE|POSES.csv",
            help="a ride file, or a poses CSV "
            "t,x,y,z,roll,pitch,yaw (m, rad; _mm/_deg columns accepted)",
        ),
        PLATFORM.but(
            required=False,
            metavar="P",
            help="bundled platform name or TOML path (default: the ride's; required for a CSV)",
        ),
        Option.of(
            "--recording",
            default=None,
            metavar="CSV|REC",
            help="the recording the ride was made from: the vehicle's perceived motion is "
            "drawn beside the rider's, with the share the rider gets (default: the ride's "
            "source when it lies next to the ride file; when none is found the page says why)",
        ),
        OUT.but(type=Path, metavar="HTML", help="page to write"),
        json_option("what was written (path, size, samples, duration)"),
    ),
)

register = registrar(_VIEW)
