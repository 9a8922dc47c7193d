"""See the motion: a self-contained HTML view of a ride, and a live monitor in the browser.

:func:`load_view_input` + :func:`write_view` make the page of ``motioncue view`` (plotly.js
embedded, works offline); :class:`Monitor` serves the live page of ``--monitor`` on
``bridge``, ``play`` and ``emulate`` (tornado, WebSocket), reading snapshots from a
:class:`MonitorSource` without ever blocking the frame loop. Heavy libraries (plotly,
tornado) are imported when a page is made or served.
"""

from ._monitor import (
    BridgeSource,
    EmulatorSource,
    Monitor,
    MonitorSource,
    PlaySource,
    SourceSnapshot,
    parse_monitor,
)
from ._scene import Scene, scene_from_poses, scene_from_q, stroke_use
from ._view import (
    CURVE_RATE_HZ,
    VIEW_RATE_HZ,
    ViewInput,
    load_view_input,
    rendered_shares,
    view_html,
    view_metrics,
    write_view,
)

__all__ = [
    "CURVE_RATE_HZ",
    "VIEW_RATE_HZ",
    "BridgeSource",
    "EmulatorSource",
    "Monitor",
    "MonitorSource",
    "PlaySource",
    "Scene",
    "SourceSnapshot",
    "ViewInput",
    "load_view_input",
    "parse_monitor",
    "rendered_shares",
    "scene_from_poses",
    "scene_from_q",
    "stroke_use",
    "view_html",
    "view_metrics",
    "write_view",
]
