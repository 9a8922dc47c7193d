"""The platform-kind registry: ``kind = "..."`` of a platform file -> how to build it.

A platform kind is one module: a :class:`~motioncue.kinematics.Platform` subclass (the
geometry) and a reader turning the file's tables into one, registered with
:func:`register_platform_kind` at import time. The registry may be filled from outside the
package (a plugin module named in ``MOTIONCUE_PLUGINS`` for the command line)::

    from motioncue.kinematics import (
        LinearLegPlatform, PlatformKind, linear_legs_reader, register_platform_kind,
    )

    class HeavePitch2(LinearLegPlatform):
        N_LEGS = 2
        DOF_MASK = (False, False, True, False, True, False)   # heave, pitch
        DEFAULT_NAME = "heave-pitch2"

    register_platform_kind(
        PlatformKind("heave-pitch2", HeavePitch2, linear_legs_reader(HeavePitch2), n_legs=2)
    )

What the loader does for every kind (:func:`~motioncue.kinematics.platform_from_dict`):
the common keys (``description``, ``actuators``, ``spare_axes``, ``default_preset``,
``ride_preset``), the
``[geometry]`` anchors and neutral height, then the kind's reader, then the optional
``[traction_loss]`` slider, spare axes and ``[limits]``. Drawing needs no registration: the
viewer draws every platform from its leg set (:attr:`Platform.legs`, whose
:meth:`~motioncue.kinematics._legs.LegSet.joints` gives the joints between the ends).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .._config import ConfigReader
from .._errors import ConfigError
from .._registry import register_entry, registered_entry
from ._platform import LinearLegPlatform, Platform

__all__ = [
    "PLATFORM_KINDS",
    "PlatformFile",
    "PlatformKind",
    "platform_kind",
    "register_platform_kind",
]

_NAME = re.compile(r"[a-z][a-z0-9]*(-[a-z0-9]+)*")


@dataclass(frozen=True, eq=False)
class PlatformFile:
    """What a kind's reader is given: a platform file with its common part already read.

    Attributes
    ----------
    config : ConfigReader
        The whole file; the reader reads its own tables from it (``config.table("stroke")``)
        and calls ``finish()`` on each, so unknown keys are refused.
    geometry : ConfigReader
        The ``[geometry]`` table, its anchors and ``neutral_height_mm`` already read; the
        reader reads any key of its own, then calls ``geometry.finish()``.
    base_anchors_m, platform_anchors_m : ndarray (n_legs, 3)
        Lower and upper joint centres (m), base and platform frames (a symmetric ring
        layout of a hexapod already expanded).
    neutral_height_m : float
        Height of the platform frame above the base frame at the neutral pose (m), > 0.
    actuator_names : tuple of str
        The kind's actuators in controller order: the legs, then its own yaw axis if it has
        one (a traction-loss slider and spare axes are not included).
    name, description : str
        The platform's name (the file's stem) and the file's description.
    """

    config: ConfigReader
    geometry: ConfigReader
    base_anchors_m: np.ndarray
    platform_anchors_m: np.ndarray
    neutral_height_m: float
    actuator_names: tuple[str, ...]
    name: str
    description: str


PlatformReader = Callable[[PlatformFile], Platform]
"""A kind's reader: a :class:`PlatformFile` -> the frozen platform (raises ConfigError)."""


@dataclass(frozen=True)
class PlatformKind:
    """What the registry knows about one platform kind.

    Attributes
    ----------
    name : str
        The ``kind`` value of platform files: lower case, words joined by ``-``.
    platform_class : type
        The :class:`~motioncue.kinematics.Platform` subclass the reader builds.
    reader : callable
        ``reader(PlatformFile) -> Platform`` (see :class:`PlatformFile`).
    n_legs : int
        Legs between base and platform, 1..12 (the length of the anchor lists).
    yaw_axis : bool
        True when the kind has its own yaw axis after its legs (a turntable): one more
        actuator name, no ``[traction_loss]`` slider, and ``[limits]`` takes the yaw axis's
        own ``yaw_max_speed_deg_s`` etc.
    title : str
        One line for listings (``"6-DOF hexapod, linear legs"``).
    """

    name: str
    platform_class: type[Platform]
    reader: PlatformReader
    n_legs: int
    yaw_axis: bool = False
    title: str = ""

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not _NAME.fullmatch(self.name):
            raise ConfigError(
                f"platform kind name {self.name!r} is invalid; allowed: lower-case letters "
                "and digits, words joined by '-' (\"stewart6-linear\")"
            )
        if not (
            isinstance(self.platform_class, type) and issubclass(self.platform_class, Platform)
        ):
            raise ConfigError(
                f"platform kind {self.name!r}: platform_class = {self.platform_class!r} is "
                "invalid; allowed: a subclass of motioncue.kinematics.Platform"
            )
        if not callable(self.reader):
            raise ConfigError(f"platform kind {self.name!r}: reader is not callable")
        if not (isinstance(self.n_legs, int) and 1 <= self.n_legs <= 12):
            raise ConfigError(
                f"platform kind {self.name!r}: n_legs = {self.n_legs!r} is invalid; allowed: 1..12"
            )
        cls = self.platform_class
        if issubclass(cls, LinearLegPlatform) and cls.N_LEGS != self.n_legs:
            raise ConfigError(
                f"platform kind {self.name!r}: n_legs = {self.n_legs} but "
                f"{cls.__name__}.N_LEGS = {cls.N_LEGS}"
            )

    @property
    def n_actuators(self) -> int:
        """Actuators of the kind itself: its legs, plus its own yaw axis."""
        return self.n_legs + (1 if self.yaw_axis else 0)


PLATFORM_KINDS: dict[str, PlatformKind] = {}
"""Registered platform kinds by name (``"stewart6-linear"``, ``"seat3"`` ...)."""


def register_platform_kind(kind: PlatformKind) -> PlatformKind:
    """Add a platform kind to :data:`PLATFORM_KINDS`; re-registering a name replaces it.

    Returns ``kind``, so a module may keep it: ``KIND = register_platform_kind(...)``.
    """
    return register_entry(PLATFORM_KINDS, kind, PlatformKind, "register_platform_kind")


def platform_kind(name: str) -> PlatformKind:
    """The registered kind ``name``.

    Raises
    ------
    ConfigError
        ``name`` is not registered (the message lists the registered kinds).
    """
    return registered_entry(PLATFORM_KINDS, name, "platform kind", "kinds")
