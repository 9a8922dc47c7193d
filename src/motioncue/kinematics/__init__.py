"""Platform kinematics: closed-form inverse, Newton forward, Jacobian, stroke checks, drives.

Pose vector ``[x, y, z, roll, pitch, yaw]`` (m, rad) of the platform frame relative to its
neutral pose, ``R = Rz(yaw) Ry(pitch) Rx(roll)``, ISO 8855 axes (x forward, y left, z up).
Actuator positions ``q`` are measured from the neutral pose: metres (linear), radians (rotary).

>>> from motioncue.kinematics import load_platform
>>> p = load_platform("stewart6-linear")
>>> q = p.inverse([0.0, 0.0, 0.01, 0.0, 0.0, 0.0])

Platform kinds (the ``kind`` of a platform file) are registered in :data:`PLATFORM_KINDS`
with :func:`register_platform_kind`: a new kind is one module, in or outside this package
(a plugin named in ``MOTIONCUE_PLUGINS`` for the command line), holding a :class:`Platform`
subclass and its reader (:class:`PlatformKind`, :class:`PlatformFile`; a kind of linear
legs only subclasses :class:`LinearLegPlatform` and reads with :func:`linear_legs_reader`).
"""

from ._drive import Drive
from ._forces import STANDARD_GRAVITY, ForceResult, Payload, actuator_forces, pose_wrench
from ._kinds import (
    PLATFORM_KINDS,
    PlatformFile,
    PlatformKind,
    PlatformReader,
    platform_kind,
    register_platform_kind,
)
from ._load import linear_legs_reader, load_platform, platform_from_dict
from ._platform import (
    DOF_NAMES,
    CheckResult,
    Corner4,
    FKResult,
    LinearLegPlatform,
    Platform,
    Seat2Yaw,
    Seat3,
    Stewart6Linear,
    Stewart6Rotary,
)
from ._workspace import WorkspaceRanges, dof_ranges, plot_workspace

__all__ = [
    "DOF_NAMES",
    "PLATFORM_KINDS",
    "STANDARD_GRAVITY",
    "CheckResult",
    "Corner4",
    "Drive",
    "FKResult",
    "ForceResult",
    "LinearLegPlatform",
    "Payload",
    "Platform",
    "PlatformFile",
    "PlatformKind",
    "PlatformReader",
    "Seat2Yaw",
    "Seat3",
    "Stewart6Linear",
    "Stewart6Rotary",
    "WorkspaceRanges",
    "actuator_forces",
    "dof_ranges",
    "linear_legs_reader",
    "load_platform",
    "platform_from_dict",
    "platform_kind",
    "plot_workspace",
    "pose_wrench",
    "register_platform_kind",
]
