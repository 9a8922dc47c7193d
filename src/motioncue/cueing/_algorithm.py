"""The cueing interface: what every cueing algorithm offers, and the registry by name.

A cueing algorithm turns vehicle specific force ``f`` (m/s^2) and angular velocity ``w``
(rad/s), body frame of conventions.md, into platform poses ``[x, y, z, roll, pitch, yaw]``
(m, rad). Every algorithm follows the pattern of :class:`~._classical.ClassicalWashout`:

* a **frozen design** built from the preset's parameters and the sample rate
  (``factory(params, fs_hz)``), holding only what does not change during a run;
* an **explicit state** from :meth:`CueingAlgorithm.initial_state`, mutated in place by
  :meth:`CueingAlgorithm.step` and optionally by :meth:`CueingAlgorithm.run`, put back to the
  start by :meth:`CueingAlgorithm.reset`; it has an integer ``bad_samples`` (input samples
  replaced because they were NaN, inf or spikes, since the last reset);
* :meth:`CueingAlgorithm.step` (one sample on plain floats, for the live bridge) and
  :meth:`CueingAlgorithm.run` (a whole recording, for ``generate`` and ``cue``) give the same
  numbers (to rounding).

The pipeline (``generate``, ``bridge``, ``cue``) never names an algorithm: it calls
:func:`make_cueing` with the loaded preset, which looks up ``params.algorithm`` (the preset's
``algorithm = "..."`` key) in the registry. Adding an algorithm is one line::

    register_cueing("classical", ClassicalWashout)
"""

from __future__ import annotations

from collections.abc import Callable, MutableSequence, Sequence
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._classical import ClassicalWashout
from ._params import CueingParams

__all__ = [
    "CueingAlgorithm",
    "CueingFactory",
    "CueingResult",
    "check_algorithm_name",
    "cueing_algorithms",
    "make_cueing",
    "register_cueing",
    "unregister_cueing",
]


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


@runtime_checkable
class CueingAlgorithm(Protocol):
    """A cueing algorithm's frozen design (see the module docstring).

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

    def initial_state(self) -> Any:
        """A fresh state (platform at neutral, vehicle at rest); has ``bad_samples``."""
        ...

    def reset(self, state: Any) -> None:
        """Put ``state`` back to :meth:`initial_state`, in place."""
        ...

    def step(
        self,
        state: Any,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        """One sample: ``f`` (3, m/s^2), ``w`` (3, rad/s) -> pose (6, m and rad), finite;
        written into ``out`` when given (and ``out`` returned)."""
        ...

    def run(self, f: ArrayLike, w: ArrayLike, state: Any = None) -> CueingResult:
        """A whole recording, ``f``, ``w`` of shape (N, 3) at ``fs_hz``; continues from and
        advances ``state`` when given. The same numbers as :meth:`step` sample by sample."""
        ...


CueingFactory = Callable[[CueingParams, float], CueingAlgorithm]
"""Builds a design from a preset and a sample rate (Hz); raises ConfigError if it cannot."""

_REGISTRY: dict[str, CueingFactory] = {}


def register_cueing(name: str, factory: CueingFactory) -> None:
    """Make ``algorithm = "NAME"`` in a preset select ``factory``.

    Parameters
    ----------
    name : str
        Non-empty, without spaces; not registered yet.
    factory : callable ``(params, fs_hz) -> CueingAlgorithm``

    Raises
    ------
    ConfigError
        Empty or already registered name.
    """
    if not isinstance(name, str) or not name or any(c.isspace() for c in name):
        raise ConfigError(f"cueing algorithm name {name!r} is invalid; a non-empty word")
    if name in _REGISTRY:
        raise ConfigError(f"cueing algorithm {name!r} is already registered")
    _REGISTRY[name] = factory


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


def make_cueing(params: CueingParams, fs_hz: float) -> CueingAlgorithm:
    """The design of ``params.algorithm`` for ``params`` at ``fs_hz`` (Hz).

    Raises
    ------
    ConfigError
        Unknown algorithm (the known ones are listed), or the algorithm refuses the
        parameters or the rate.
    """
    check_algorithm_name(params.algorithm)
    return _REGISTRY[params.algorithm](params, fs_hz)


def _mpc(params: CueingParams, fs_hz: float) -> CueingAlgorithm:
    from ._mpc import MpcCueing  # numpy/scipy/casadi only when an MPC preset is used

    return MpcCueing(params, fs_hz)


def _optimal(params: CueingParams, fs_hz: float) -> CueingAlgorithm:
    from ._optimal import OptimalCueing

    return OptimalCueing(params, fs_hz)


# The registry: one line per algorithm.
register_cueing("classical", ClassicalWashout)
register_cueing("mpc", _mpc)
register_cueing("optimal", _optimal)
