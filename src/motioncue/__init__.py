"""motioncue: vehicle motion to electric-cylinder motion platforms.

The subpackages follow the data flow:

``telemetry`` -> ``cueing`` -> ``kinematics`` -> ``trajectory`` -> ``output``

``import motioncue`` stays light: the heavy libraries (Pinocchio, casadi, toppra,
matplotlib) are imported only by the functions that use them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ._errors import ConfigError, LimitError, MotioncueError, ProtocolError, TransportError

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "LimitError",
    "MotioncueError",
    "ProtocolError",
    "TransportError",
    "__version__",
    "load_platform",
]

if TYPE_CHECKING:
    from .kinematics import load_platform


def __getattr__(name: str) -> Any:
    if name == "load_platform":
        from .kinematics import load_platform

        return load_platform
    raise AttributeError(f"module 'motioncue' has no attribute {name!r}")
