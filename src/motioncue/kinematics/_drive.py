"""Drives: actuator position <-> motor revolutions <-> controller pulses.

A drive turns an actuator position ``q`` (metres for a linear actuator, radians for a rotary
one, measured from the neutral pose like every ``q`` in motioncue) into motor revolutions and
pulses. Pulse 0 is the homed position, which the controllers define as the mechanical zero
found by homing plus a lift (IMAX PA40/PA41, per axis PA43..; MBOX: the initial-positioning
origin), so ``q_home`` is where the actuator sits at pulse 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from .._errors import ConfigError
from .._frozen import readonly, set_fields

__all__ = ["Drive"]


@dataclass(frozen=True, eq=False)
class Drive:
    """The drives of all ``n`` actuators of a platform, vectorised.

    Parameters
    ----------
    kinds
        ``"linear"`` or ``"rotary"`` per actuator.
    pulses_per_rev
        ``(n,)`` integer pulses per motor revolution (after the servo's electronic gear).
    units_per_rev
        ``(n,)`` actuator travel per motor revolution: the screw lead in metres for a linear
        actuator, ``2*pi / gear_ratio`` radians for a rotary one.
    direction
        ``(n,)`` +1 when positive pulses extend the actuator (increase ``q``), -1 otherwise.
    q_home
        ``(n,)`` actuator position at pulse 0 (m or rad, from neutral).
    """

    kinds: tuple[str, ...]
    pulses_per_rev: NDArray[np.float64]
    units_per_rev: NDArray[np.float64]
    direction: NDArray[np.float64]
    q_home: NDArray[np.float64]

    def __post_init__(self) -> None:
        n = len(self.kinds)
        for kind in self.kinds:
            if kind not in ("linear", "rotary"):
                raise ConfigError(f"drive kind {kind!r} is invalid; allowed: linear | rotary")
        ppr = np.asarray(self.pulses_per_rev)
        if ppr.shape != (n,) or not np.all(ppr == np.round(ppr)) or np.any(ppr < 1):
            raise ConfigError(
                f"pulses_per_rev = {ppr.tolist()} is invalid; allowed: {n} integers >= 1"
            )
        upr = np.asarray(self.units_per_rev, dtype=float)
        if upr.shape != (n,) or not np.all(np.isfinite(upr)) or np.any(upr <= 0):
            raise ConfigError(
                f"units_per_rev (lead or 2*pi/gear ratio) = {upr.tolist()} is invalid; "
                f"allowed: {n} finite numbers > 0"
            )
        dirs = np.asarray(self.direction)
        if dirs.shape != (n,) or not np.all(np.isin(dirs, (-1, 1))):
            raise ConfigError(
                f"direction = {dirs.tolist()} is invalid; allowed: {n} values of +1 or -1"
            )
        home = np.asarray(self.q_home, dtype=float)
        if home.shape != (n,) or not np.all(np.isfinite(home)):
            raise ConfigError(f"q_home = {home.tolist()} is invalid; allowed: {n} finite numbers")
        set_fields(
            self,
            kinds=tuple(self.kinds),
            pulses_per_rev=readonly(ppr, np.int64),
            units_per_rev=readonly(upr),
            direction=readonly(dirs, np.int64),
            q_home=readonly(home),
        )
        ppu = self.direction * self.pulses_per_rev / self.units_per_rev
        set_fields(self, _ppu=readonly(ppu))

    # --- constructors -------------------------------------------------------------------
    @classmethod
    def _axes(
        cls,
        kind: str,
        units_per_rev: npt.ArrayLike,
        pulses_per_rev: npt.ArrayLike,
        q_home: npt.ArrayLike,
        direction: npt.ArrayLike,
    ) -> Drive:
        """``len(q_home)`` drives of one kind, each other argument one value or one per axis."""
        home = np.atleast_1d(np.asarray(q_home, dtype=float))
        n = len(home)
        return cls(
            kinds=(kind,) * n,
            pulses_per_rev=np.broadcast_to(np.asarray(pulses_per_rev), (n,)).copy(),
            units_per_rev=np.broadcast_to(np.asarray(units_per_rev, dtype=float), (n,)).copy(),
            direction=np.broadcast_to(np.asarray(direction), (n,)).copy(),
            q_home=home,
        )

    @classmethod
    def linear(
        cls,
        lead_m: npt.ArrayLike,
        pulses_per_rev: npt.ArrayLike,
        q_home: npt.ArrayLike,
        direction: npt.ArrayLike = 1,
    ) -> Drive:
        """Ball-screw drives: ``lead_m`` travel per motor revolution."""
        return cls._axes("linear", lead_m, pulses_per_rev, q_home, direction)

    @classmethod
    def rotary(
        cls,
        gear_ratio: npt.ArrayLike,
        pulses_per_rev: npt.ArrayLike,
        q_home: npt.ArrayLike,
        direction: npt.ArrayLike = 1,
    ) -> Drive:
        """Geared rotary axes: ``gear_ratio`` motor revolutions per output revolution."""
        n = len(np.atleast_1d(q_home))
        ratio = np.broadcast_to(np.asarray(gear_ratio, dtype=float), (n,))
        if not np.all(np.isfinite(ratio)) or np.any(ratio <= 0):
            raise ConfigError(f"gear_ratio = {ratio.tolist()} is invalid; allowed: finite > 0")
        return cls._axes("rotary", 2.0 * math.pi / ratio, pulses_per_rev, q_home, direction)

    @classmethod
    def concat(cls, *drives: Drive) -> Drive:
        """The drives of several actuator groups, in order."""
        return cls(
            kinds=sum((d.kinds for d in drives), ()),
            pulses_per_rev=np.concatenate([d.pulses_per_rev for d in drives]),
            units_per_rev=np.concatenate([d.units_per_rev for d in drives]),
            direction=np.concatenate([d.direction for d in drives]),
            q_home=np.concatenate([d.q_home for d in drives]),
        )

    # --- conversions --------------------------------------------------------------------
    @property
    def n(self) -> int:
        return len(self.kinds)

    @property
    def pulses_per_unit(self) -> NDArray[np.float64]:
        """``(n,)`` signed pulses per metre (linear) or per radian (rotary)."""
        ppu: NDArray[np.float64] = self._ppu  # type: ignore[attr-defined]
        return ppu

    @property
    def gear_ratio(self) -> NDArray[np.float64]:
        """``(n,)`` motor revolutions per output revolution (rotary; NaN for linear)."""
        kinds = np.array([k == "rotary" for k in self.kinds])
        return np.where(kinds, 2.0 * math.pi / self.units_per_rev, np.nan)

    def _check(self, name: str, x: npt.ArrayLike) -> NDArray[np.float64]:
        x = np.asarray(x, dtype=float)
        if x.ndim == 0 or x.shape[-1] != self.n:
            raise ConfigError(f"{name} has shape {x.shape}; expected (..., {self.n})")
        if not np.all(np.isfinite(x)):
            bad = np.argwhere(~np.isfinite(x))[0]
            raise ConfigError(
                f"{name}{list(bad.tolist())} = {x[tuple(bad)]!r} is invalid; allowed: finite"
            )
        return x

    def to_revolutions(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Motor revolutions from the homed position, ``(..., n)``, signed by direction."""
        q = self._check("q", q)
        return (q - self.q_home) * self.direction / self.units_per_rev

    def from_revolutions(self, revs: npt.ArrayLike) -> NDArray[np.float64]:
        """Actuator positions ``(..., n)`` from motor revolutions."""
        revs = self._check("revolutions", revs)
        return self.q_home + revs * self.units_per_rev * self.direction

    def to_pulses(self, q: npt.ArrayLike) -> NDArray[np.int64]:
        """Pulses ``(..., n)`` int64 for actuator positions ``q``; rounds to the nearest pulse."""
        q = self._check("q", q)
        pulses = np.rint((q - self.q_home) * self.pulses_per_unit)
        if np.any(np.abs(pulses) >= 2.0**62):
            raise ConfigError(f"q = {q!r} is beyond any pulse count (|pulses| >= 2**62)")
        return pulses.astype(np.int64)

    def from_pulses(self, pulses: npt.ArrayLike) -> NDArray[np.float64]:
        """Actuator positions ``(..., n)`` for pulses (exact inverse of :meth:`to_pulses`)."""
        p = np.asarray(pulses)
        if p.ndim == 0 or p.shape[-1] != self.n:
            raise ConfigError(f"pulses has shape {p.shape}; expected (..., {self.n})")
        if p.dtype.kind not in "iu":
            p = self._check("pulses", p)
        return self.q_home + p / self.pulses_per_unit
