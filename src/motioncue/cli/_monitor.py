"""``--monitor [[HOST:]PORT]`` for ``bridge``, ``play`` and ``emulate``: the live web page."""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import TYPE_CHECKING

from ._verb import Option

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits
    from ..viewer import Monitor, MonitorSource

__all__ = ["MONITOR", "start_monitor"]


def _monitor_value(text: str) -> str:
    """Checked when the command line is read, before anything is opened or sent."""
    from .._errors import ConfigError
    from ..viewer._monitor import parse_monitor

    try:
        parse_monitor(text)
    except ConfigError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    return text


MONITOR = Option.of(
    "--monitor",
    nargs="?",
    const="",
    default=None,
    type=_monitor_value,
    metavar="[HOST:]PORT",
    help="serve a live page (3D pose, actuator bars, cue, telemetry timing, state, a stop "
    "button that parks) at http://HOST:PORT/ (default 127.0.0.1:8765; port 0 = any free "
    "port; loopback unless a HOST is named)",
)
"""``--monitor [[HOST:]PORT]``: the live page (checked when the command line is read)."""


def start_monitor(
    value: str | None,
    source: MonitorSource | None,
    platform: Platform,
    limits: ActuatorLimits | None,
    title: str,
    say: Callable[[str], None],
) -> Monitor | None:
    """Start a :class:`~motioncue.viewer.Monitor` when ``--monitor`` was given, else None
    (``source`` may be None then)."""
    if value is None or source is None:
        return None
    from ..viewer._monitor import Monitor, parse_monitor

    host, port = parse_monitor(value)
    mon = Monitor(source, platform, limits, host=host, port=port, title=title).start()
    say(f"monitor: {mon.url}")
    if not mon.local_only:
        say(
            f"monitor: note: listening on {host}, not loopback: anyone who reaches it sees "
            "the ride and can stop (park) the platform"
        )
    return mon
