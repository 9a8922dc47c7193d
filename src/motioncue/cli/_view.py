"""``motioncue view``: one self-contained HTML page of a ride or poses CSV (works offline)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from ._common import add_json_option, print_json

__all__ = ["register"]


def register(sub: Any) -> None:
    p = sub.add_parser(
        "view",
        help="an HTML page of a ride or poses CSV: the platform in 3D, actuators, perception",
        description="Write one self-contained HTML file (plotly.js embedded; opens offline): "
        "the platform in 3D (base, legs coloured by stroke use, top) animated in time with "
        "play/pause and a slider, synchronised with the actuator positions against their "
        "stroke and with the motion the rider perceives.",
    )
    p.add_argument("input", metavar="RIDE|POSES.csv", help="a ride file, or a poses CSV "
                   "t,x,y,z,roll,pitch,yaw (m, rad; _mm/_deg columns accepted)")  # fmt: skip
    p.add_argument(
        "--platform",
        default=None,
        metavar="P",
        help="bundled platform name or TOML path (default: the ride's; required for a CSV)",
    )
    p.add_argument(
        "--recording",
        default=None,
        metavar="CSV|REC",
        help="the recording the ride was made from: the vehicle's perceived motion is drawn "
        "beside the rider's, with the share the rider gets (default: the ride's source when it "
        "lies next to the ride file; when none is found the page says why)",
    )
    p.add_argument("--out", required=True, type=Path, metavar="HTML", help="page to write")
    add_json_option(p, "what was written (path, size, samples, duration)")
    p.set_defaults(run=_view)


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
