"""The exception tree shared by every part of motioncue."""

from __future__ import annotations

__all__ = [
    "MAX_MESSAGE_CHARS",
    "ConfigError",
    "ControllerSilent",
    "FramesRefused",
    "LimitError",
    "MotioncueError",
    "ProtocolError",
    "TransportError",
    "one_line",
]

MAX_MESSAGE_CHARS = 600
"""Longest error message :func:`one_line` lets through (characters)."""


def one_line(text: str, limit: int = MAX_MESSAGE_CHARS) -> str:
    """``text`` as one printable line of at most ``limit`` characters.

    Line breaks and tabs become spaces; any other character that is not printable (control
    bytes, raw binary decoded as Latin-1, lone surrogates) becomes its ``\\xNN`` /
    ``\\uNNNN`` escape; a longer text is cut, ending in ``... (N characters cut)``. For
    messages that quote untrusted input (a damaged file's bytes).
    """
    text = str(text)
    if len(text) > limit:  # escaping only lengthens: what is beyond the limit is cut anyway
        text, dropped = text[:limit], len(text) - limit
    else:
        dropped = 0
    out = []
    for ch in text:
        if ch in "\r\n\t":
            out.append(" ")
        elif ch.isprintable():
            out.append(ch)
        else:
            out.append(ch.encode("unicode_escape", "backslashreplace").decode("ascii"))
    line = "".join(out)
    if len(line) > limit or dropped:
        cut = len(line) - (limit - 40) + dropped
        line = f"{line[: limit - 40]}... ({cut} characters cut)"
    return line


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
