"""The cueing interface: what every cueing algorithm offers, and the registry by name.

A cueing algorithm turns vehicle specific force ``f`` (m/s^2) and angular velocity ``w``
(rad/s), body frame of conventions.md, into platform poses ``[x, y, z, roll, pitch, yaw]``
(m, rad). Every algorithm follows the pattern of :class:`~._classical.ClassicalWashout`
(SciPy-style explicit state):

* a **frozen design** built from the preset's parameters and the sample rate
  (``factory(params, fs_hz)``; with ``needs_rig``, ``factory(params, fs_hz, rig=rig)``:
  the :class:`Rig`, the platform and its actuator limits, given by the caller), holding
  only what does not change during a run;
* an **explicit state** (:class:`CueingState`) from :meth:`CueingAlgorithm.initial_state`,
  mutated in place by :meth:`CueingAlgorithm.step` and optionally by
  :meth:`CueingAlgorithm.run`, put back to the start by :meth:`CueingAlgorithm.reset`; it
  has an integer ``bad_samples`` (input samples replaced because they were NaN, inf or
  spikes, since the last reset);
* :meth:`CueingAlgorithm.step` (one sample on plain floats, for the live bridge) and
  :meth:`CueingAlgorithm.run` (a whole recording, for ``generate`` and ``cue``) give the same
  numbers (to rounding).

The pipeline (``generate``, ``bridge``, ``cue``) and the analysis tools (``compare``,
``tune``, ``omct``) never name an algorithm: they call :func:`make_cueing` with the loaded
preset (which looks up ``params.algorithm``, the preset's ``algorithm = "..."`` key) and ask
:func:`cueing_entry` what it can do. Adding an algorithm is one module and one call, from
inside the package or from a plug-in (``MOTIONCUE_PLUGINS``)::

    register_cueing("classical", ClassicalWashout, frames_on_arrival=True,
                    tune=CLASSICAL_TUNING)

An entry declares (:class:`CueingEntry`): whether it streams (the live bridge steps it) or
needs the whole recording (ride files only), whether it may run on the 1 ms grid of frames
on arrival, whether its factory wants the rig, its own preset table (name, reader, writer)
and its tunable parameters (:class:`TunePlan`, what ``motioncue tune`` searches).
"""

from __future__ import annotations

import math
from collections.abc import Callable, MutableSequence, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, TypeVar, cast, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._classical import ClassicalWashout
from ._mpc_params import MpcParams, read_mpc_table
from ._params import CueingParams
from ._tune import CLASSICAL_TUNING, PLAN_TUNING, TunePlan, mpc_table_lines

if TYPE_CHECKING:
    from .._config import ConfigReader
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits
    from ._mpc import MpcCueing
    from ._optimal import OptimalCueing

__all__ = [
    "CueingAlgorithm",
    "CueingEntry",
    "CueingFactory",
    "CueingResult",
    "CueingState",
    "ParameterTable",
    "Rig",
    "check_algorithm_name",
    "check_rig",
    "cueing_algorithms",
    "cueing_entry",
    "make_cueing",
    "parameter_tables",
    "register_cueing",
    "unregister_cueing",
]


@runtime_checkable
class CueingState(Protocol):
    """What every algorithm's explicit state offers (the rest is the algorithm's own)."""

    @property
    def bad_samples(self) -> int:
        """Input samples replaced (NaN, inf, spikes) since the last reset."""
        ...


@runtime_checkable
class CueingResult(Protocol):
    """What :meth:`CueingAlgorithm.run` returns (at least).

    Attributes
    ----------
    poses : (N, 6) array
        Platform pose ``[x, y, z, roll, pitch, yaw]`` (m, rad) per input sample.
    bad_samples : int
        Input samples that were replaced (NaN, inf, spikes).
    """

    @property
    def poses(self) -> NDArray[np.float64]:
        """(N, 6) poses (m, rad)."""
        ...

    @property
    def bad_samples(self) -> int:
        """Replaced input samples."""
        ...


S = TypeVar("S", bound=CueingState)


@runtime_checkable
class CueingAlgorithm(Protocol[S]):
    """A cueing algorithm's frozen design (see the module docstring); ``S`` its state type.

    Attributes
    ----------
    params : CueingParams
        The preset it was built from.
    fs_hz : float
        Sample rate of :meth:`step` and :meth:`run` (Hz).
    """

    @property
    def params(self) -> CueingParams:
        """The preset it was built from."""
        ...

    @property
    def fs_hz(self) -> float:
        """Sample rate (Hz)."""
        ...

    def initial_state(self) -> S:
        """A fresh state (platform at neutral, vehicle at rest)."""
        ...

    def reset(self, state: S) -> None:
        """Put ``state`` back to :meth:`initial_state`, in place."""
        ...

    def step(
        self,
        state: S,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        """Advance one sample.

        Parameters
        ----------
        state : S
            This design's state (from :meth:`initial_state`), updated in place.
        f : 3 floats
            Specific force (m/s^2, body frame).
        w : 3 floats
            Angular velocity (rad/s, body frame).
        out : mutable sequence of 6 floats, optional
            Written in place and returned; a new list otherwise.

        Returns
        -------
        MutableSequence[float]
            The pose ``[x, y, z, roll, pitch, yaw]`` (m, rad); always finite.
        """
        ...

    def run(self, f: ArrayLike, w: ArrayLike, state: S | None = None) -> CueingResult:
        """A whole recording, ``f``, ``w`` of shape (N, 3) at ``fs_hz``; continues from and
        advances ``state`` when given. The same numbers as :meth:`step` sample by sample."""
        ...


Cueing = CueingAlgorithm[CueingState]
"""A design as its callers see it: its state is opaque to them (only passed back, and its
``bad_samples`` read)."""


def check_rig(platform: Platform, limits: ActuatorLimits) -> None:
    """Refuse actuator limits of another actuator count than the platform's.

    Raises
    ------
    ConfigError
        Naming both counts and the platform.
    """
    if limits.n_actuators != platform.n_actuators:
        raise ConfigError(
            f"limits have {limits.n_actuators} actuators; platform {platform.name!r} has "
            f"{platform.n_actuators}"
        )


@dataclass(frozen=True, eq=False)
class Rig:
    """The machine a cueing algorithm plans for, given by the caller (``--platform``,
    ``--controller`` and the limit overrides), never loaded by the algorithm.

    Attributes
    ----------
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits
        The actuator limits in SI (the platform's with the controller's, as
        ``ActuatorLimits.from_platform`` gives them; not tightened for pulse rounding).
    controller : str
        The controller's name (for messages).
    """

    platform: Platform
    limits: ActuatorLimits
    controller: str = ""

    def __post_init__(self) -> None:
        check_rig(self.platform, self.limits)


@dataclass(frozen=True, eq=False)
class ParameterTable:
    """An algorithm's own table in a preset file (``[NAME]``).

    Attributes
    ----------
    name : str
        The table's name (``"mpc"``).
    read : callable ``(ConfigReader) -> value``
        Reads and validates the table (unknown keys refused, the ConfigReader way); the value
        lands in :attr:`CueingParams.mpc` for ``"mpc"``, else in ``CueingParams.tables[name]``.
    write : callable ``(value) -> list of str``, optional
        The table's TOML lines (header first), for ``motioncue tune``'s preset file.
    """

    name: str
    read: Callable[[ConfigReader], object]
    write: Callable[[Any], list[str]] | None = None  # Any: the value is the reader's own type


CueingFactory = Callable[..., CueingAlgorithm[Any]]
"""``factory(params, fs_hz)``, or ``factory(params, fs_hz, rig=rig)`` with ``needs_rig``;
builds a design or raises ConfigError. (``...`` and ``Any``: each algorithm has its own state
type, erased in the registry.)"""


@dataclass(frozen=True, eq=False)
class CueingEntry:
    """One registered algorithm and what it declares.

    Attributes
    ----------
    name : str
    factory : CueingFactory
    streaming : bool
        The live bridge can step it sample by sample (False: it needs the whole recording;
        ride files only).
    frames_on_arrival : bool
        It may run on the 1 ms grid of frames on arrival (cheap enough for 1000 steps/s and
        rate-independent in design).
    needs_rig : bool
        Its factory takes ``rig=`` (the platform and limits it plans for).
    table : ParameterTable or None
        Its own preset table.
    tune : TunePlan or None
        Its tunable parameters (None: ``motioncue tune`` refuses it).
    max_rate_hz : float or None
        The highest rate a ride file is cued at (Hz): ``generate`` at a higher frame rate
        cues at the frame rate over the smallest whole divisor that brings it to this rate
        or below, and takes the frames' poses from a cubic spline through the cue's (a plan
        whose cost grows faster than its samples; its presets are tuned at this rate).
        None: cued at the frame rate.
    """

    name: str
    factory: CueingFactory
    streaming: bool = True
    frames_on_arrival: bool = False
    needs_rig: bool = False
    table: ParameterTable | None = None
    tune: TunePlan | None = None
    max_rate_hz: float | None = None

    def cue_rate_hz(self, frame_rate_hz: float) -> float:
        """The rate a ride at ``frame_rate_hz`` is cued at (see ``max_rate_hz``)."""
        cap = self.max_rate_hz
        if cap is None or frame_rate_hz <= cap:
            return frame_rate_hz
        k = max(1, math.ceil(frame_rate_hz / cap - 1e-9))  # 300 / 100: 3, not 4
        while frame_rate_hz / k > cap:
            k += 1
        return frame_rate_hz / k


_REGISTRY: dict[str, CueingEntry] = {}


def register_cueing(
    name: str,
    factory: CueingFactory,
    *,
    streaming: bool = True,
    frames_on_arrival: bool = False,
    needs_rig: bool = False,
    table: ParameterTable | None = None,
    tune: TunePlan | None = None,
    max_rate_hz: float | None = None,
) -> CueingEntry:
    """Make ``algorithm = "NAME"`` in a preset select ``factory`` (see :class:`CueingEntry`
    for the declarations).

    Parameters
    ----------
    name : str
        Non-empty, without spaces; not registered yet.
    factory : callable ``(params, fs_hz) -> CueingAlgorithm``
        With ``needs_rig``: ``(params, fs_hz, rig=Rig or None) -> CueingAlgorithm``.

    Returns
    -------
    CueingEntry

    Raises
    ------
    ConfigError
        Empty or already registered name, or a table name another algorithm reads
        differently.
    """
    if not isinstance(name, str) or not name or any(c.isspace() for c in name):
        raise ConfigError(f"cueing algorithm name {name!r} is invalid; a non-empty word")
    if name in _REGISTRY:
        raise ConfigError(f"cueing algorithm {name!r} is already registered")
    if not callable(factory):
        raise ConfigError(f"cueing algorithm {name!r}: factory {factory!r} is not callable")
    if table is not None:
        for other in _REGISTRY.values():
            if other.table is not None and other.table.name == table.name:
                if other.table.read is not table.read:
                    raise ConfigError(
                        f"cueing algorithm {name!r}: table [{table.name}] is already read by "
                        f"{other.name!r} with another reader"
                    )
    if max_rate_hz is not None and not (math.isfinite(max_rate_hz) and max_rate_hz > 0.0):
        raise ConfigError(
            f"cueing algorithm {name!r}: max_rate_hz {max_rate_hz!r} is invalid; allowed: a "
            "finite rate > 0 Hz or None"
        )
    entry = CueingEntry(
        name,
        factory,
        bool(streaming),
        bool(frames_on_arrival),
        bool(needs_rig),
        table,
        tune,
        None if max_rate_hz is None else float(max_rate_hz),
    )
    _REGISTRY[name] = entry
    return entry


def unregister_cueing(name: str) -> None:
    """Remove ``name`` from the registry (no error when absent); for tests and plug-ins."""
    _REGISTRY.pop(name, None)


def cueing_algorithms() -> tuple[str, ...]:
    """The registered algorithm names, sorted."""
    return tuple(sorted(_REGISTRY))


def check_algorithm_name(name: str) -> None:
    """Raise :class:`ConfigError` unless ``name`` is registered (the message lists them)."""
    if name not in _REGISTRY:
        raise ConfigError(
            f"algorithm = {name!r} is unknown; known cueing algorithms: "
            f"{', '.join(cueing_algorithms())}"
        )


def cueing_entry(name: str) -> CueingEntry:
    """The registry entry of ``name`` (what it declares).

    Raises
    ------
    ConfigError
        Unknown name (the known ones are listed).
    """
    check_algorithm_name(name)
    return _REGISTRY[name]


def parameter_tables() -> tuple[ParameterTable, ...]:
    """Every registered algorithm's own preset table, once per table name."""
    seen: dict[str, ParameterTable] = {}
    for entry in _REGISTRY.values():
        if entry.table is not None:
            seen.setdefault(entry.table.name, entry.table)
    return tuple(seen.values())


def make_cueing(params: CueingParams, fs_hz: float, rig: Rig | None = None) -> Cueing:
    """The design of ``params.algorithm`` for ``params`` at ``fs_hz`` (Hz).

    Parameters
    ----------
    params : CueingParams
    fs_hz : float
    rig : Rig, optional
        The platform and limits the ride is for; given to an algorithm that plans in
        actuator space (``needs_rig``). Without it such an algorithm plans for the rig its
        preset names (``[mpc] platform, controller``): for library use; ``generate``,
        ``bridge``, ``compare`` and ``tune`` always give it.

    Raises
    ------
    ConfigError
        Unknown algorithm (the known ones are listed), or the algorithm refuses the
        parameters, the rate or the rig.
    """
    entry = cueing_entry(params.algorithm)
    if entry.needs_rig:
        design = entry.factory(params, fs_hz, rig=rig)
    else:
        design = entry.factory(params, fs_hz)
    return cast(Cueing, design)


# ------------------------------------------------------------------------- the bundled ones
def _plan_rig(params: CueingParams, fs_hz: float, rig: Rig | None) -> Rig:
    """The rig an ``[mpc]`` plan is made for: the caller's, which must be the platform the
    preset was written for or one that moves as it does (``Platform.same_kinematics``: the
    seat3 plan on seat3-pot); without one, the platform and controller the preset names."""
    mp = params.mpc if params.mpc is not None else MpcParams()
    if rig is None:
        return named_rig(mp.platform, mp.controller, fs_hz)
    named = Path(mp.platform).stem if mp.platform.endswith(".toml") else mp.platform
    if rig.platform.name != named and not _moves_as(rig.platform, mp.platform):
        raise ConfigError(
            f"preset {params.name!r} plans for platform {mp.platform!r} ([mpc] platform); "
            f"the ride is for {rig.platform.name!r}: give a preset written for it"
        )
    return rig


def _moves_as(platform: Platform, named: str) -> bool:
    """Whether ``platform`` moves as the platform ``named`` (a bundled name or TOML path)."""
    from ..kinematics import load_platform

    return platform.same_kinematics(load_platform(named))


def named_rig(platform: str, controller: str, fs_hz: float) -> Rig:
    """The rig named by a preset (bundled names or TOML paths), for callers giving none."""
    from ..kinematics import load_platform
    from ..output import load_controller
    from ..trajectory import ActuatorLimits

    plat = load_platform(platform)
    ctl = load_controller(controller)
    return Rig(plat, ActuatorLimits.from_platform(plat, ctl, rate_hz=fs_hz), controller)


def _mpc(params: CueingParams, fs_hz: float, rig: Rig | None = None) -> MpcCueing:
    from ._mpc import MpcCueing  # numpy/scipy/casadi only when an MPC preset is used

    if params.mpc is not None and any(params.mpc.w_jerk):
        raise ConfigError(
            f'preset {params.name!r}: [mpc] w_jerk is for algorithm = "optimal" (its '
            "windows' input steps); the live mpc re-plans every sample: leave it out"
        )
    return MpcCueing(params, fs_hz, _plan_rig(params, fs_hz, rig))


def _optimal(params: CueingParams, fs_hz: float, rig: Rig | None = None) -> OptimalCueing:
    from ._optimal import OptimalCueing

    return OptimalCueing(params, fs_hz, _plan_rig(params, fs_hz, rig))


_MPC_TABLE = ParameterTable("mpc", read_mpc_table, mpc_table_lines)

# The registry: one call per algorithm.
register_cueing("classical", ClassicalWashout, frames_on_arrival=True, tune=CLASSICAL_TUNING)
register_cueing("mpc", _mpc, needs_rig=True, table=_MPC_TABLE, tune=PLAN_TUNING)
register_cueing(
    "optimal",
    _optimal,
    streaming=False,
    needs_rig=True,
    table=_MPC_TABLE,
    tune=PLAN_TUNING,
    max_rate_hz=100.0,  # its windows' QPs grow with their samples; tuned at 100 Hz
)
