"""The ``iface`` kind's registry entry: interface-string boards (SimTools / FlyPT Mover).

Frames go to a serial port or a UDP socket; the emulator listens on UDP and reads the
datagrams as one byte stream, through the board's firmware parser.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ..._errors import ConfigError
from .._registry import ControllerKind
from ._controller import IfaceController, controller_from_config
from ._emulator import IfaceEmulator

if TYPE_CHECKING:
    from .._controller_api import Controller
    from .._transport import TransportURL

__all__ = ["KIND"]


def _emulator(controller: Controller, url: TransportURL, homing_time_s: float) -> IfaceEmulator:
    if not isinstance(controller, IfaceController):
        raise ConfigError(f"the iface emulator needs an iface controller, not {controller.kind}")
    return IfaceEmulator(controller, url.host, url.port)


@runtime_checkable
class _SendsStop(Protocol):
    """A controller with a stop string (:class:`IfaceController`, or a wrapper that passes
    its attributes through)."""

    @property
    def stop_bytes(self) -> bytes: ...


def _end_of_run(controller: Controller) -> list[bytes]:
    """The stop string (``stop`` in the TOML), sent after the park; none when empty."""
    stop = controller.stop_bytes if isinstance(controller, _SendsStop) else b""
    return [stop] if stop else []


KIND = ControllerKind(
    "iface",
    controller_from_config,
    title="interface-string board (SimTools / FlyPT Mover string)",
    links=("serial", "udp", "file"),
    emulator=_emulator,
    emulator_schemes=("udp",),
    end_of_run=_end_of_run,
)
