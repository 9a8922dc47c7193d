"""A toy cueing algorithm registered from outside ``src/``: a scaled and clipped copy.

Pose ``x = clip(kx fx, +-L)``, ``y = clip(ky fy, +-L)``, ``z = clip(kz (fz - g), +-L)``,
everything else 0 (m, rad), with ``fx, fy, fz`` the vehicle's specific force (m/s^2),
``g`` = 9.80665 m/s^2, and ``kx, ky`` (m per m/s^2), ``L`` (m) and the optional ``kz``
(default 0: no heave) from the preset's own ``[toy]`` table. Non-finite input counts as a
bad sample and gives 0.

Importing this module registers it as ``"toy-copy"`` (``MOTIONCUE_PLUGINS=toys.toy_cueing``)
with every declaration an algorithm can make: streaming, not for frames on arrival, the rig
wanted by its factory (recorded in :data:`RIGS_SEEN`), its table (reader and writer),
two tunable parameters and an intensity range over them.
"""

from __future__ import annotations

from collections.abc import MutableSequence, Sequence
from dataclasses import dataclass, field, replace

import numpy as np
from numpy.typing import ArrayLike, NDArray

from motioncue._config import ConfigReader
from motioncue._errors import ConfigError
from motioncue.cueing import (
    CueingParams,
    ParameterTable,
    Rig,
    TunableParameter,
    cueing_algorithms,
    register_cueing,
)

NAME = "toy-copy"
G_M_S2 = 9.80665
RIGS_SEEN: list[tuple[str, int]] = []
"""(platform name, actuators) of every rig the factory was given."""


@dataclass(frozen=True)
class ToyTable:
    """The ``[toy]`` table: gains (m per m/s^2) and the clip (m)."""

    gain_x: float = 0.004
    gain_y: float = 0.004
    limit_m: float = 0.02
    gain_z: float = 0.0


def read_toy(table: ConfigReader) -> ToyTable:
    gain = table.vector("gain_m_per_m_s2", 2)
    limit_mm = table.number("limit_mm", lo=0.0, hi=100.0, lo_open=True)
    gain_z = table.number("gain_z_m_per_m_s2", 0.0, lo=0.0, hi=1.0)
    table.finish()
    return ToyTable(gain[0], gain[1], limit_mm * 1e-3, gain_z)


def write_toy(t: ToyTable) -> list[str]:
    return [
        "[toy]",
        f"gain_m_per_m_s2 = [{t.gain_x!r}, {t.gain_y!r}]",
        f"limit_mm = {t.limit_m * 1e3!r}",
        f"gain_z_m_per_m_s2 = {t.gain_z!r}",
        "",
    ]


def table_of(params: CueingParams) -> ToyTable:
    value = params.tables.get("toy")
    return value if isinstance(value, ToyTable) else ToyTable()


def closed_form(f: ArrayLike, table: ToyTable) -> NDArray[np.float64]:
    """The toy's poses (N, 6) for specific force ``f`` (N, 3): the oracle of the tests."""
    fa = np.asarray(f, dtype=float)
    good = np.all(np.isfinite(fa), axis=1)
    poses = np.zeros((len(fa), 6))
    lim = table.limit_m
    poses[:, 0] = np.where(good, np.clip(table.gain_x * np.nan_to_num(fa[:, 0]), -lim, lim), 0.0)
    poses[:, 1] = np.where(good, np.clip(table.gain_y * np.nan_to_num(fa[:, 1]), -lim, lim), 0.0)
    heave = table.gain_z * (np.nan_to_num(fa[:, 2]) - G_M_S2)
    poses[:, 2] = np.where(good, np.clip(heave, -lim, lim), 0.0)
    return poses


@dataclass(eq=False)
class ToyState:
    bad_samples: int = 0


@dataclass(frozen=True)
class ToyResult:
    poses: NDArray[np.float64]
    bad_samples: int


@dataclass(frozen=True, eq=False)
class ToyCopy:
    params: CueingParams
    fs_hz: float
    table: ToyTable = field(default_factory=ToyTable)

    def initial_state(self) -> ToyState:
        return ToyState()

    def reset(self, state: ToyState) -> None:
        state.bad_samples = 0

    def step(
        self,
        state: ToyState,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        pose = closed_form([list(f)], self.table)[0]
        if not np.all(np.isfinite(np.asarray(f, dtype=float))):
            state.bad_samples += 1
        res = [float(v) for v in pose]
        if out is None:
            return res
        out[:] = res
        return out

    def run(self, f: ArrayLike, w: ArrayLike, state: ToyState | None = None) -> ToyResult:
        fa = np.asarray(f, dtype=float)
        bad = int(np.count_nonzero(~np.all(np.isfinite(fa), axis=1)))
        if state is not None:
            state.bad_samples += bad
        return ToyResult(closed_form(fa, self.table), bad)


def make_toy(params: CueingParams, fs_hz: float, rig: Rig | None = None) -> ToyCopy:
    if rig is not None:
        RIGS_SEEN.append((rig.platform.name, rig.platform.n_actuators))
    return ToyCopy(params, float(fs_hz), table_of(params))


class ToyTuning:
    """Tunable: the two gains."""

    PARAMETERS = (
        TunableParameter("gain_x", 1e-4, 0.02, "m/(m/s^2)"),
        TunableParameter("gain_y", 1e-4, 0.02, "m/(m/s^2)"),
    )

    def parameters(self, params: CueingParams) -> tuple[TunableParameter, ...]:
        return self.PARAMETERS

    def values(self, params: CueingParams) -> tuple[float, float]:
        t = table_of(params)
        return (t.gain_x, t.gain_y)

    def apply(self, base: CueingParams, v: Sequence[float], name: str) -> CueingParams:
        t = replace(table_of(base), gain_x=float(v[0]), gain_y=float(v[1]))
        return replace(base, name=name or base.name, tables={**base.tables, "toy": t})

    @property
    def intensity_keys(self) -> tuple[str, ...]:
        """An ``[intensity.gentle]`` table of the two gains."""
        return ("gain_x", "gain_y")

    def check_intensity(self, params: CueingParams, gentle: Sequence[float]) -> None:
        """Each gentle gain within the tuned bounds."""
        for p, g in zip(self.PARAMETERS, gentle, strict=True):
            if not p.lo <= g <= p.hi:
                raise ConfigError(f"intensity gentle {p.name} = {g!r}; allowed {p.lo}-{p.hi}")

    def intensity(self, params: CueingParams, t: float, name: str) -> CueingParams:
        """Each gain linear from the gentle table's to the preset's."""
        gentle = params.intensity_gentle
        assert gentle is not None
        own = self.values(params)
        v = [g + t * (o - g) for g, o in zip(gentle, own, strict=True)]
        return self.apply(params, v, name)


if NAME not in cueing_algorithms():  # imported once per process; a re-import is a no-op
    register_cueing(
        NAME,
        make_toy,
        streaming=True,
        frames_on_arrival=False,
        needs_rig=True,
        table=ParameterTable("toy", read_toy, write_toy),
        tune=ToyTuning(),
    )
