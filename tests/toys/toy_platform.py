"""A toy platform kind registered from outside the package: two vertical legs, heave and pitch.

Imported as a plugin (``MOTIONCUE_PLUGINS=toy_platform``, this folder on ``sys.path``): the
whole kind is this module, a :class:`~motioncue.kinematics.LinearLegPlatform` subclass and
one :func:`~motioncue.kinematics.register_platform_kind` call. Its file is
``toy-heave-pitch2.toml`` next to this module.
"""

from __future__ import annotations

from pathlib import Path

from motioncue.kinematics import (
    LinearLegPlatform,
    PlatformKind,
    linear_legs_reader,
    register_platform_kind,
)

KIND_NAME = "toy-heave-pitch2"
TOML = Path(__file__).with_name(f"{KIND_NAME}.toml")
"""The toy rig's platform file."""


class HeavePitch2(LinearLegPlatform):
    """Two vertical linear legs, one ahead of and one behind the seat's pivot: heave and
    pitch (x, y, roll and yaw held by a guide)."""

    N_LEGS = 2
    DOF_MASK = (False, False, True, False, True, False)
    DEFAULT_NAME = KIND_NAME


KIND = register_platform_kind(
    PlatformKind(
        KIND_NAME,
        HeavePitch2,
        linear_legs_reader(HeavePitch2),
        n_legs=2,
        title="toy: two vertical legs, heave and pitch",
    )
)
