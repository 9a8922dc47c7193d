"""The exception tree shared by every part of motioncue."""

from __future__ import annotations

__all__ = [
    "ConfigError",
    "ControllerSilent",
    "FramesRefused",
    "LimitError",
    "MotioncueError",
    "ProtocolError",
    "TransportError",
]


class MotioncueError(Exception):
    """Base class of every error motioncue raises on purpose."""


class ConfigError(MotioncueError, ValueError):
    """A configuration file, argument or constructor value is invalid.

    The message names the key (or argument), the value given and what is allowed.
    """


class ProtocolError(MotioncueError, ValueError):
    """Bytes that do not decode as the wire format says (confirm code, length, checksum...)."""


class LimitError(MotioncueError):
    """A request cannot be met within the machine's stroke, speed or acceleration limits."""


class TransportError(MotioncueError, OSError):
    """A link to a controller failed (socket, serial port, file). Raised ``from`` the cause."""


class ControllerSilent(TransportError):
    """The controller stopped answering (power loss, reset, cable, nothing listening): no
    reply to frames or status requests for longer than the link's silence limit."""


class FramesRefused(MotioncueError):
    """The controller refuses the frames for a reason waiting does not cure (a frame of
    the other axis mode, an e-stop, a command error)."""
