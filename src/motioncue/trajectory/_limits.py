"""Per-actuator limits (stroke, speed, acceleration, optional jerk) and their discrete check.

Discrete-time definitions (used everywhere in :mod:`motioncue.trajectory`, in the tests and
in every check a user may run on frames that were sent): on a frame grid of period ``dt``,

* speed        ``v[k] = (q[k] - q[k-1]) / dt``
* acceleration ``a[k] = (q[k] - 2 q[k-1] + q[k-2]) / dt**2``
* jerk         ``j[k] = (q[k] - 3 q[k-1] + 3 q[k-2] - q[k-3]) / dt**3``

A trajectory respects the limits when every frame is within ``[q_min, q_max]`` and every
finite difference that can be formed is within ``+-v_max``, ``+-a_max`` (``+-j_max``).
"""

from __future__ import annotations

import json
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from .._errors import ConfigError

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..kinematics import Platform
    from ..output import Controller

__all__ = [
    "ActuatorLimits",
    "LimitCheck",
    "PulsesRow",
    "check_trajectory",
    "finite_differences",
]


class PulsesRow(TypedDict):
    """One actuator's limits in drive pulses (a row of :meth:`ActuatorLimits.to_pulses_table`,
    as a ride file and ``motioncue limits --json`` carry it)."""

    name: str
    kind: str
    pulses_per_unit: float
    stroke_pulses: list[int]
    """``[min, max]``: the pulse counts of the stroke ends, ordered."""
    max_speed_pulses_s: float
    max_accel_pulses_s2: float
    max_jerk_pulses_s3: float | None


def _vec(name: str, value: ArrayLike, n: int | None) -> np.ndarray:
    arr = np.array(value, dtype=float).reshape(-1)
    if n is not None and arr.shape != (n,):
        raise ConfigError(f"{name} has {arr.size} values; expected {n} (one per actuator)")
    if not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} = {arr.tolist()} is invalid; allowed: finite numbers")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class ActuatorLimits:
    """Limits of each actuator, in SI (m, m/s, m/s^2, m/s^3; rad... for rotary actuators).

    Parameters
    ----------
    q_min, q_max : array_like, shape (n,)
        Usable stroke (safety margin already applied), ``q_min < q_max``.
    v_max, a_max : array_like, shape (n,)
        Largest speed and acceleration magnitudes, ``> 0``.
    j_max : array_like, shape (n,), optional
        Largest jerk magnitude, ``> 0``; ``None`` = no jerk limit.
    names : sequence of str, optional
        Actuator names in controller order (default ``a1..an``).
    kinds : sequence of str, optional
        ``"linear"`` or ``"rotary"`` per actuator (default all linear).
    sources : mapping of str to str, optional
        Where each quantity came from (``{"v_max": "IMAX PA80..PA85 x PA41"}``), for reports.
    """

    q_min: np.ndarray
    q_max: np.ndarray
    v_max: np.ndarray
    a_max: np.ndarray
    j_max: np.ndarray | None = None
    names: tuple[str, ...] = ()
    kinds: tuple[str, ...] = ()
    sources: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        q_min = _vec("q_min", self.q_min, None)
        n = q_min.size
        if n < 1:
            raise ConfigError("q_min is empty; allowed: at least one actuator")
        q_max = _vec("q_max", self.q_max, n)
        v_max = _vec("v_max", self.v_max, n)
        a_max = _vec("a_max", self.a_max, n)
        for i in range(n):
            if not q_min[i] < q_max[i]:
                raise ConfigError(
                    f"actuator {i}: stroke [{q_min[i]}, {q_max[i]}] is invalid; "
                    "allowed: q_min < q_max"
                )
        for name, arr in (("v_max", v_max), ("a_max", a_max)):
            if np.any(arr <= 0):
                raise ConfigError(f"{name} = {arr.tolist()} is invalid; allowed: > 0")
        j_max = None
        if self.j_max is not None:
            j_max = _vec("j_max", self.j_max, n)
            if np.any(j_max <= 0):
                raise ConfigError(f"j_max = {j_max.tolist()} is invalid; allowed: > 0 or None")
        names = tuple(self.names) if self.names else tuple(f"a{i + 1}" for i in range(n))
        kinds = tuple(self.kinds) if self.kinds else ("linear",) * n
        if len(names) != n or len(kinds) != n:
            raise ConfigError(f"names/kinds need {n} entries; got {len(names)}/{len(kinds)}")
        bad = [k for k in kinds if k not in ("linear", "rotary")]
        if bad:
            raise ConfigError(f"kinds {bad} are invalid; allowed: linear | rotary")
        object.__setattr__(self, "q_min", q_min)
        object.__setattr__(self, "q_max", q_max)
        object.__setattr__(self, "v_max", v_max)
        object.__setattr__(self, "a_max", a_max)
        object.__setattr__(self, "j_max", j_max)
        object.__setattr__(self, "names", names)
        object.__setattr__(self, "kinds", kinds)
        object.__setattr__(self, "sources", dict(self.sources))

    # ------------------------------------------------------------------ basics
    @property
    def n_actuators(self) -> int:
        return int(self.q_min.size)

    def braking_steps(self, dt_s: float) -> int:
        """Frames needed to stop from full speed at full deceleration (largest over actuators)."""
        return int(np.max(np.ceil(self.v_max / (self.a_max * dt_s)))) + 1

    def scaled(
        self, *, speed: float = 1.0, accel: float = 1.0, jerk: float = 1.0
    ) -> ActuatorLimits:
        """The same limits with speed/acceleration/jerk multiplied by factors in (0, 1]."""
        for name, f in (("speed", speed), ("accel", accel), ("jerk", jerk)):
            if not 0.0 < f <= 1.0:
                raise ConfigError(f"{name} = {f} is invalid; allowed: a factor in (0, 1]")
        return ActuatorLimits(
            self.q_min,
            self.q_max,
            self.v_max * speed,
            self.a_max * accel,
            None if self.j_max is None else self.j_max * jerk,
            self.names,
            self.kinds,
            self.sources,
        )

    def without_jerk(self) -> ActuatorLimits:
        """The same limits without the jerk limit."""
        return ActuatorLimits(
            self.q_min, self.q_max, self.v_max, self.a_max, None, self.names, self.kinds,
            self.sources,
        )  # fmt: skip

    def contains(self, q: ArrayLike) -> np.ndarray:
        """Whether positions ``q`` (..., n) are inside the stroke, per frame (...)."""
        q = np.asarray(q, dtype=float)
        with np.errstate(invalid="ignore"):
            inside: np.ndarray = np.all((q >= self.q_min) & (q <= self.q_max), axis=-1)
        return inside

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_platform(
        cls,
        platform: Platform,
        controller: Controller | None = None,
        *,
        stroke_margin: float | Sequence[float] | None = None,
        v_max: float | Sequence[float] | None = None,
        a_max: float | Sequence[float] | None = None,
        j_max: float | Sequence[float] | None = None,
        rate_hz: float | None = None,
    ) -> ActuatorLimits:
        """Effective limits of a platform driven by a controller (``motioncue limits`` prints
        them with the source of each value).

        Parameters
        ----------
        platform : Platform
            Its usable stroke, drives and optional own ``v_max``, ``a_max``, ``j_max``.
        controller : Controller, optional
            Its parameters' stroke, speed, acceleration and catch-up factor; None: the
            platform and the overrides only.
        stroke_margin, v_max, a_max, j_max : float or sequence of n floats, optional
            Overrides in SI (m or rad based; one number for all actuators or one each).
        rate_hz : float, optional
            The frame rate (Hz), for controllers whose limits depend on it (an EasySmc frame
            is a move that must ramp up and down within one period); None gives the limits
            that hold at any rate.

        Returns
        -------
        ActuatorLimits
            With :attr:`sources` saying where each value comes from.

        Raises
        ------
        ConfigError
            A drive that disagrees with the controller, an invalid override, or a quantity
            with no source.

        Notes
        -----
        The controller is used only through its interface
        (:class:`motioncue.output.Controller`): ``drive_expectations()``,
        ``pulse_limits(rate_hz)`` and ``catch_up_factor``; no controller kind is named. Rules,
        each recorded in :attr:`sources`:

        Agreement
            The controller's pulses per motor turn and screw lead (linear actuators) must
            equal the platform's drive, otherwise the positions sent would be other lengths
            than planned: a :class:`~motioncue.ConfigError` names both values.

        Stroke
            The platform's usable stroke ``[q_min, q_max]`` (its config already keeps
            ``margin_mm`` from each end stop), shrunk by ``stroke_margin`` (SI, optional
            extra margin), and intersected with the controller's stroke in pulses where its
            parameters set one.

        Speed, acceleration (``v_max``, ``a_max``)
            The smallest of: the override; the platform's own ``[limits]``; the controller's
            pulse limits converted through the drive (``pulses / |pulses_per_unit|``).

        Catch-up
            A controller that may play frames ``c = catch_up_factor`` times faster than their
            time stamps (MBOX Fn012 = 1200: ``c = 1.2``) moves the motors ``c`` times as fast
            as the frames say, and accelerates ``c**2`` as hard. The limits are planned on the
            host's clock, so every speed limit is divided by ``c`` and every acceleration
            (jerk) limit by ``c**2`` (``c**3``).

        Jerk (``j_max``)
            Only from the override or the platform (no controller parameter defines it).

        A quantity with no source raises :class:`~motioncue.ConfigError` naming what to give.
        """
        from ._derive import _check_drives, _per_axis, _within_stroke

        n = int(platform.n_actuators)
        kinds = tuple(platform.actuator_kinds)
        q_min = np.array(platform.q_min, dtype=float)
        q_max = np.array(platform.q_max, dtype=float)
        pname = platform.name
        sources: dict[str, str] = {"stroke": f"platform {pname} usable stroke"}
        margin = _per_axis("stroke_margin", stroke_margin, n)
        if margin is not None:
            if np.any(margin < 0):
                raise ConfigError(f"stroke_margin = {stroke_margin!r} is invalid; allowed: >= 0")
            q_min, q_max = q_min + margin, q_max - margin
            sources["stroke"] += f" minus extra margin {margin.tolist()}"

        drives = platform.drives
        ppu = np.abs(np.asarray(drives.pulses_per_unit, dtype=float))
        v_cands: list[tuple[np.ndarray, str]] = []
        a_cands: list[tuple[np.ndarray, str]] = []
        catch_up = 1.0

        if controller is not None:
            who = f"controller {controller.name!r}"
            n_axes = int(controller.n_axes)
            if n_axes != n:
                raise ConfigError(
                    f"{who} drives {n_axes} axes; platform {pname!r} has {n} actuators"
                )
            _check_drives(platform, controller.drive_expectations(), who)
            catch_up = float(controller.catch_up_factor)
            if not (np.isfinite(catch_up) and catch_up >= 1.0):
                raise ConfigError(f"{who}: catch_up_factor = {catch_up!r}; allowed: >= 1")
            pl = controller.pulse_limits(rate_hz)
            if pl.has_stroke:
                q_min, q_max = _within_stroke(drives, pl, q_min, q_max)
                sources["stroke"] += f" within {pl.sources.get('stroke', who + ' stroke')}"
            if pl.has_speed:
                v_cands.append((pl.max_speed_pulses_s / ppu, pl.sources.get("v_max", who)))
            if pl.has_accel:
                a_cands.append((pl.max_accel_pulses_s2 / ppu, pl.sources.get("a_max", who)))

        # a platform description may carry its own actuator limits (SI arrays v_max / a_max /
        # j_max), e.g. the servo's rated speed; they take part like any other source
        for attr, own, cands in (
            ("v_max", platform.v_max, v_cands),
            ("a_max", platform.a_max, a_cands),
        ):
            if own is not None:
                arr = _per_axis(f"platform {attr}", own, n)
                if arr is not None:
                    cands.append((arr, "platform config"))
        ov_v = _per_axis("v_max", v_max, n)
        ov_a = _per_axis("a_max", a_max, n)
        if ov_v is not None:
            v_cands.append((ov_v, "given"))
        if ov_a is not None:
            a_cands.append((ov_a, "given"))
        if not v_cands:
            raise ConfigError(
                "no maximum speed known: give v_max (--max-speed; m/s or rad/s) or a controller"
            )
        if not a_cands:
            raise ConfigError(
                "no maximum acceleration known: give a_max (--max-accel; m/s^2 or rad/s^2), a "
                "[limits] table in the platform config, or a controller that sets one"
            )
        v = np.min(np.stack([c for c, _ in v_cands]), axis=0)
        a = np.min(np.stack([c for c, _ in a_cands]), axis=0)
        sources["v_max"] = "min of: " + "; ".join(s for _, s in v_cands)
        sources["a_max"] = "min of: " + "; ".join(s for _, s in a_cands)
        j_cands: list[tuple[np.ndarray, str]] = []
        own_j = platform.j_max
        if own_j is not None:
            arr = _per_axis("platform j_max", own_j, n)
            if arr is not None:
                j_cands.append((arr, "platform config"))
        ov_j = _per_axis("j_max", j_max, n)
        if ov_j is not None:
            j_cands.append((ov_j, "given"))
        j = None
        if j_cands:
            j = np.min(np.stack([c for c, _ in j_cands]), axis=0)
            sources["j_max"] = "min of: " + "; ".join(s for _, s in j_cands)
        if catch_up != 1.0:
            v, a = v / catch_up, a / catch_up**2
            note = (
                f"; divided by the controller's catch-up factor {catch_up:g} (speed), "
                f"{catch_up:g}^2 (acceleration): it may play frames that much faster than stamped"
            )
            sources["v_max"] += note
            sources["a_max"] += note
            if j is not None:
                j = j / catch_up**3
                sources["j_max"] += f"; divided by {catch_up:g}^3 (catch-up)"
        sources["catch_up"] = f"{catch_up:g}"
        return cls(q_min, q_max, v, a, j, tuple(platform.actuator_names), kinds, sources)

    # ------------------------------------------------------------------ reporting
    def to_dict(self) -> dict[str, Any]:
        """SI table, JSON-ready."""
        out: dict[str, Any] = {"units": "SI (m, rad, s)", "actuators": []}
        for i in range(self.n_actuators):
            row: dict[str, Any] = {
                "name": self.names[i],
                "kind": self.kinds[i],
                "stroke": [float(self.q_min[i]), float(self.q_max[i])],
                "max_speed": float(self.v_max[i]),
                "max_accel": float(self.a_max[i]),
                "max_jerk": None if self.j_max is None else float(self.j_max[i]),
            }
            out["actuators"].append(row)
        out["sources"] = dict(self.sources)
        return out

    def to_pulses_table(self, platform: Platform) -> list[PulsesRow]:
        """Per actuator (controller order) the limits in drive pulses.

        Keys: ``name``, ``pulses_per_unit``, ``stroke_pulses`` ``[min, max]`` (the pulse
        counts of the stroke ends, ordered), ``max_speed_pulses_s``, ``max_accel_pulses_s2``,
        ``max_jerk_pulses_s3`` (or ``None``). Stroke ends are rounded inwards so that every
        pulse count in the range is inside the SI stroke.
        """
        ppu = np.asarray(platform.drives.pulses_per_unit, dtype=float).reshape(-1)
        if ppu.size != self.n_actuators:
            raise ConfigError(
                f"platform has {ppu.size} drives; these limits have {self.n_actuators} actuators"
            )
        rows: list[PulsesRow] = []
        for i in range(self.n_actuators):
            q_home = _pulse_origin(platform, i)  # q at pulse 0
            a = (float(self.q_min[i]) - q_home) * ppu[i]
            b = (float(self.q_max[i]) - q_home) * ppu[i]
            lo = int(np.ceil(min(a, b) - 1e-6))
            hi = int(np.floor(max(a, b) + 1e-6))
            lo, hi = _inside(platform, self, i, lo, hi)
            rows.append(
                {
                    "name": self.names[i],
                    "kind": self.kinds[i],
                    "pulses_per_unit": float(ppu[i]),
                    "stroke_pulses": [lo, hi],
                    "max_speed_pulses_s": float(self.v_max[i] * abs(ppu[i])),
                    "max_accel_pulses_s2": float(self.a_max[i] * abs(ppu[i])),
                    "max_jerk_pulses_s3": (
                        None if self.j_max is None else float(self.j_max[i] * abs(ppu[i]))
                    ),
                }
            )
        return rows

    def to_json(self, platform: Platform | None = None) -> str:
        """JSON of :meth:`to_dict`; with a platform each actuator entry also carries the
        pulse keys of :meth:`to_pulses_table` (``stroke_pulses``, ``max_speed_pulses_s``,
        ``max_accel_pulses_s2``, ...)."""
        data = self.to_dict()
        if platform is not None:
            for row, pulses in zip(data["actuators"], self.to_pulses_table(platform), strict=True):
                row.update(pulses)
        return json.dumps(data, indent=2)


def _pulse_origin(platform: Platform, i: int) -> float:
    """Actuator position at pulse 0 (the homed position) of actuator i."""
    n = len(np.asarray(platform.drives.pulses_per_unit).reshape(-1))
    zero = np.zeros(n, dtype=np.int64)
    return float(np.asarray(platform.drives.from_pulses(zero), dtype=float).reshape(-1)[i])


def _inside(platform: Platform, lim: ActuatorLimits, i: int, lo: int, hi: int) -> tuple[int, int]:
    """Step the pulse range inwards until both ends map back inside the SI stroke."""
    n = lim.n_actuators
    for _ in range(4):
        pulses = np.zeros((2, n), dtype=np.int64)
        pulses[:, i] = (lo, hi)
        q = np.asarray(platform.drives.from_pulses(pulses), dtype=float)[:, i]
        qa, qb = min(q), max(q)
        if qa >= lim.q_min[i] - 1e-12 and qb <= lim.q_max[i] + 1e-12:
            break
        lo, hi = lo + 1, hi - 1
    return lo, hi


def finite_differences(
    q: ArrayLike, dt_s: float, history: ArrayLike | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Speed, acceleration and jerk of frames ``q`` (N, n) by the module's definitions.

    ``history`` (h, n) are frames sent before ``q[0]`` (oldest first); differences that
    need them are formed when they are given. Returns arrays of shapes (N+h-1, n),
    (N+h-2, n), (N+h-3, n) over the concatenated frames.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[:, None]
    if history is not None:
        h = np.asarray(history, dtype=float).reshape(-1, q.shape[1])
        q = np.concatenate([h, q])
    v = np.diff(q, axis=0) / dt_s
    a = (q[2:] - 2.0 * q[1:-1] + q[:-2]) / dt_s**2
    j = (q[3:] - 3.0 * q[2:-1] + 3.0 * q[1:-2] - q[:-3]) / dt_s**3
    return v, a, j


@dataclass(frozen=True)
class LimitCheck:
    """Largest violation of each limit over a trajectory (0 = none; SI units).

    ``ok`` is True when every violation is within ``tol`` (absolute, SI).
    """

    stroke: float
    speed: float
    accel: float
    jerk: float
    finite: bool
    tol: float

    @property
    def ok(self) -> bool:
        return self.finite and max(self.stroke, self.speed, self.accel, self.jerk) <= self.tol


def check_trajectory(
    q: ArrayLike,
    dt_s: float,
    limits: ActuatorLimits,
    *,
    history: ArrayLike | None = None,
    tol: float = 1e-9,
    relative: bool = True,
) -> LimitCheck:
    """Check frames ``q`` (N, n) against ``limits`` with the module's finite differences.

    Violations are reported relative to each limit (``relative=True``: 1e-9 means one part
    in 1e9 of v_max) or in SI units; stroke violations are always in SI units.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        q = q[:, None]
    finite = bool(np.all(np.isfinite(q)))
    stroke = float(np.max(np.maximum(limits.q_min - q, q - limits.q_max), initial=0.0))
    v, a, j = finite_differences(q, dt_s, history)

    def excess(x: np.ndarray, lim: np.ndarray) -> float:
        if x.size == 0:
            return 0.0
        e = np.abs(x) - lim
        if relative:
            e = e / lim
        return float(max(np.max(e), 0.0))

    jerk = 0.0 if limits.j_max is None else excess(j, limits.j_max)
    return LimitCheck(
        stroke=max(stroke, 0.0),
        speed=excess(v, limits.v_max),
        accel=excess(a, limits.a_max),
        jerk=jerk,
        finite=finite,
        tol=tol,
    )
