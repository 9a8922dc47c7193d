"""Platform kinematics: closed-form inverse, Newton forward, Jacobian, stroke checks, drives.

Pose vector ``[x, y, z, roll, pitch, yaw]`` (m, rad) of the platform frame relative to its
neutral pose, ``R = Rz(yaw) Ry(pitch) Rx(roll)``, ISO 8855 axes (x forward, y left, z up).
Actuator positions ``q`` are measured from the neutral pose: metres (linear), radians (rotary).

>>> from motioncue.kinematics import load_platform
>>> p = load_platform("stewart6-linear")
>>> q = p.inverse([0.0, 0.0, 0.01, 0.0, 0.0, 0.0])
"""

from ._drive import Drive
from ._forces import STANDARD_GRAVITY, ForceResult, Payload, actuator_forces, pose_wrench
from ._load import load_platform, platform_from_dict
from ._platform import (
    DOF_NAMES,
    CheckResult,
    Corner4,
    FKResult,
    Platform,
    Seat2Yaw,
    Seat3,
    Stewart6Linear,
    Stewart6Rotary,
)
from ._workspace import WorkspaceRanges, dof_ranges, plot_workspace

__all__ = [
    "DOF_NAMES",
    "STANDARD_GRAVITY",
    "CheckResult",
    "Corner4",
    "Drive",
    "FKResult",
    "ForceResult",
    "Payload",
    "Platform",
    "Seat2Yaw",
    "Seat3",
    "Stewart6Linear",
    "Stewart6Rotary",
    "WorkspaceRanges",
    "actuator_forces",
    "dof_ranges",
    "load_platform",
    "platform_from_dict",
    "plot_workspace",
    "pose_wrench",
]
