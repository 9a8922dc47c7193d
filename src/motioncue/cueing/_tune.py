"""What ``motioncue tune`` searches, declared by each algorithm: its tunable parameters.

A :class:`TunePlan` is part of an algorithm's registry entry
(:func:`motioncue.cueing.register_cueing`, ``tune=``): the parameters it exposes with their
bounds (:class:`TunableParameter`, searched in log space: all are positive scales,
frequencies or limits spanning a decade or more), the base preset's values, and how a point
of the search space becomes a preset. The search itself (objective, optimiser, back ends)
is :mod:`motioncue.analysis` (``tune_cueing``).

The bundled plans
-----------------
The classical washout (:data:`CLASSICAL_TUNING`): sixteen main parameters
(:data:`TUNED_PARAMETERS`): the translational force scales (x, y, z), the translational
high-pass natural frequency and third-order break (x and y share them) and the heave
high-pass frequency, the tilt-coordination scales (x, y), the tilt low-pass frequency, tilt
rate and acceleration limits and the tilt limit (the largest tilt: with the tilt scales it
decides how much sustained force is cued), the rotational scale and high-pass frequency
(roll and pitch share them) and the yaw scale and high-pass frequency. Everything else
(limits, dampings, input rejection, workspace, head offset) is kept from the base preset.
A classical preset with the compressive tilt (``[tilt] shape``) is tuned on
:data:`STRENGTH_TUNED_PARAMETERS` instead: the gains, limit and exponent of the compressive
curves, the share of the platform's tilt reach (``motioncue.analysis.tilt_reach``), the
tilt's lead, and the filters as above.

The ``mpc`` and ``optimal`` algorithms (:data:`PLAN_TUNING`) are tuned on their plan
(:data:`MPC_TUNED_PARAMETERS`: the scale and soft limit of the tracked copy of fx, fy, the
plan's tilt-rate limit, the canal weight, the x/y pose weight and the tilt acceleration
weight; with the compressive reference, ``ref_shape``, :data:`MPC_STRENGTH_TUNED_PARAMETERS`:
the copy's gain per axis, the share of the tilt reach, the curve's exponent and the roll and
pitch sign guard as well); their classical tables (the fallback washout) and every other
``[mpc]`` setting are kept.

Also here: :func:`at_intensity` (a preset at a point of its tuned range) and
:func:`preset_toml` (a preset's file text, with the algorithm's own table).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, replace
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError
from ._mpc_params import MpcParams
from ._params import INTENSITY_KEYS, CueingParams, intensity_keys

__all__ = [
    "CLASSICAL_TUNING",
    "MPC_STRENGTH_TUNED_PARAMETERS",
    "MPC_TUNED_PARAMETERS",
    "PLAN_TUNING",
    "STRENGTH_TUNED_PARAMETERS",
    "TUNED_PARAMETERS",
    "TunableParameter",
    "TunablePlanError",
    "TunePlan",
    "at_intensity",
    "gentle_values",
    "mpc_table_lines",
    "params_from_vector",
    "preset_toml",
    "tuned_parameters",
    "vector_from_params",
]

_D2R = math.pi / 180.0


@dataclass(frozen=True)
class TunableParameter:
    """One tuned parameter: its name, bounds (searched in log space, so both > 0) and unit."""

    name: str
    lo: float
    hi: float
    unit: str

    def __post_init__(self) -> None:
        if not (0.0 < self.lo < self.hi and math.isfinite(self.hi)):
            raise ConfigError(
                f"tunable parameter {self.name!r}: bounds ({self.lo!r}, {self.hi!r}) are "
                "invalid; allowed: 0 < lo < hi < inf"
            )


class TunePlan(Protocol):
    """The tunable parameters an algorithm declares (its registry entry's ``tune``)."""

    def parameters(self, params: CueingParams) -> tuple[TunableParameter, ...]:
        """The table tuned for this base preset."""
        ...

    def values(self, params: CueingParams) -> Sequence[float]:
        """The base preset's value of each parameter (their units; clipped to the bounds by
        the caller)."""
        ...

    def apply(self, base: CueingParams, v: Sequence[float], name: str) -> CueingParams:
        """``base`` with the parameters set to ``v`` (their units, within the bounds),
        named ``name`` (``""``: the base's name)."""
        ...

    @property
    def intensity_keys(self) -> tuple[str, ...]:
        """The keys of this algorithm's ``[intensity] gentle`` table (empty: no range)."""
        ...

    def check_intensity(self, params: CueingParams, gentle: Sequence[float]) -> None:
        """Raise :class:`ConfigError` (naming the key and the allowed range) unless
        ``gentle``, one value per ``intensity_keys`` (each a finite number >= 0), is a gentle
        end this preset can have."""
        ...

    def intensity(self, params: CueingParams, t: float, name: str) -> CueingParams:
        """``params`` (with ``intensity_gentle``) at the fraction ``t`` of its range, strictly
        between 0 (the gentle end) and 1 (the preset), named ``name``."""
        ...


class TunablePlanError(ConfigError):
    """The preset's algorithm declares no tunable parameters."""


TUNED_PARAMETERS: tuple[TunableParameter, ...] = (
    TunableParameter("f_scale_x", 0.02, 1.0, "-"),
    TunableParameter("f_scale_y", 0.02, 1.0, "-"),
    TunableParameter("f_scale_z", 0.02, 1.0, "-"),
    TunableParameter("trans_wn_xy_rad_s", 1.0, 20.0, "rad/s"),
    TunableParameter("trans_wb_xy_rad_s", 0.05, 5.0, "rad/s"),
    TunableParameter("tilt_scale_x", 0.01, 1.0, "-"),
    TunableParameter("tilt_scale_y", 0.01, 1.0, "-"),
    TunableParameter("tilt_wn_rad_s", 1.0, 20.0, "rad/s"),
    TunableParameter("tilt_rate_limit_deg_s", 2.0, 40.0, "deg/s"),
    TunableParameter("tilt_accel_limit_deg_s2", 5.0, 500.0, "deg/s^2"),
    TunableParameter("tilt_limit_deg", 2.0, 25.0, "deg"),
    TunableParameter("w_scale_rp", 0.05, 1.0, "-"),
    TunableParameter("rot_wn_rp_rad_s", 0.2, 5.0, "rad/s"),
    TunableParameter("w_scale_yaw", 0.02, 1.0, "-"),
    TunableParameter("rot_wn_yaw_rad_s", 0.2, 5.0, "rad/s"),
    TunableParameter("trans_wn_z_rad_s", 1.0, 20.0, "rad/s"),
)
"""The tuned parameters, their bounds (searched in log space) and units."""


MPC_TUNED_PARAMETERS: tuple[TunableParameter, ...] = (
    TunableParameter("ref_scale_xy", 0.05, 1.0, "-"),
    TunableParameter("ref_limit_xy_m_s2", 0.3, 10.0, "m/s^2"),
    TunableParameter("plan_tilt_rate_limit_deg_s", 1.0, 40.0, "deg/s"),
    TunableParameter("w_error_rp", 0.1, 30.0, "-"),
    TunableParameter("w_pose_xy", 1.0, 300.0, "-"),
    TunableParameter("w_acc_tilt", 0.1, 100.0, "-"),
)
"""The tuned parameters of an ``mpc`` or ``optimal`` preset (its ``[mpc]`` table): x and y
share each value; searched in log space like :data:`TUNED_PARAMETERS`."""

MPC_STRENGTH_TUNED_PARAMETERS: tuple[TunableParameter, ...] = (
    TunableParameter("ref_scale_x", 0.02, 1.0, "-"),
    TunableParameter("ref_scale_y", 0.02, 1.0, "-"),
    TunableParameter("ref_reach_use", 0.2, 1.0, "-"),
    TunableParameter("ref_shape", 1.0, 8.0, "-"),
    TunableParameter("plan_tilt_rate_limit_deg_s", 1.0, 40.0, "deg/s"),
    TunableParameter("w_error_rp", 0.01, 30.0, "-"),
    TunableParameter("w_pose_xy", 1.0, 300.0, "-"),
    TunableParameter("w_acc_tilt", 0.01, 100.0, "-"),
    TunableParameter("sign_guard_rp", 0.1, 5.0, "-"),
)
"""The tuned parameters of an ``mpc`` or ``optimal`` preset with the compressive reference
(``[mpc] ref_shape``): the gain of the tracked copy per axis, the share of the plan's tilt
reach its fx/fy limits use, the curve's exponent, the plan's tilt rate, the canal, x/y pose
and tilt-acceleration weights, and the sign guard of roll and pitch rate (only where the
base guards them; x and y share the others). Searched in log space."""

STRENGTH_TUNED_PARAMETERS: tuple[TunableParameter, ...] = (
    TunableParameter("f_scale_x", 0.01, 1.5, "-"),
    TunableParameter("f_scale_y", 0.01, 1.5, "-"),
    TunableParameter("f_limit_xy_m_s2", 0.2, 6.0, "m/s^2"),
    TunableParameter("f_shape_xy", 1.0, 8.0, "-"),
    TunableParameter("f_scale_z", 0.02, 1.0, "-"),
    TunableParameter("trans_wn_xy_rad_s", 1.0, 20.0, "rad/s"),
    TunableParameter("trans_wb_xy_rad_s", 0.05, 5.0, "rad/s"),
    TunableParameter("tilt_scale_x", 0.01, 2.0, "-"),
    TunableParameter("tilt_scale_y", 0.01, 2.0, "-"),
    TunableParameter("tilt_shape", 1.0, 8.0, "-"),
    TunableParameter("tilt_reach_use", 0.3, 1.0, "-"),
    TunableParameter("tilt_wn_rad_s", 1.0, 30.0, "rad/s"),
    TunableParameter("tilt_rate_limit_deg_s", 2.0, 60.0, "deg/s"),
    TunableParameter("tilt_accel_limit_deg_s2", 5.0, 1000.0, "deg/s^2"),
    TunableParameter("w_scale_rp", 0.05, 1.0, "-"),
    TunableParameter("rot_wn_rp_rad_s", 0.2, 5.0, "rad/s"),
    TunableParameter("w_scale_yaw", 0.02, 1.0, "-"),
    TunableParameter("rot_wn_yaw_rad_s", 0.2, 5.0, "rad/s"),
    TunableParameter("trans_wn_z_rad_s", 1.0, 20.0, "rad/s"),
    TunableParameter("lead_x_s", 0.02, 0.6, "s"),
    TunableParameter("lead_y_s", 0.02, 0.6, "s"),
)
"""The tuned parameters of a classical preset with the compressive tilt (``[tilt] shape``):
the compressive curves' gains, limit and exponents in place of the plain scales, and the
share of the platform's tilt reach in place of the tilt limit. Searched in log space."""

assert tuple(p.name for p in STRENGTH_TUNED_PARAMETERS) == INTENSITY_KEYS


def _clip_log(table: Sequence[TunableParameter], values: Sequence[float]) -> NDArray[np.float64]:
    out = np.empty(len(table))
    for i, (p, v) in enumerate(zip(table, values, strict=True)):
        out[i] = math.log(min(max(float(v), p.lo), p.hi))
    return out


def _geo(a: float, b: float, floor: float = 0.0) -> float:
    """Geometric mean of two values (each at least ``floor``): x and y share one value."""
    return math.sqrt(max(a, floor) * max(b, floor))


_Unset = float | tuple[float, ...] | Callable[["CueingParams"], float | Sequence[float]]
_Holder = CueingParams | MpcParams
_Fields = dict[str, Any]  # field values of several types, given to replace() by name
"""The fields a plan changes in a preset (or its plan), by name, for ``replace``."""


@dataclass(frozen=True)
class _Knob:
    """Where one tuned parameter lives in a preset: how it is read and how it is written.

    The parameter is the field ``field`` (of :class:`CueingParams`; of :class:`MpcParams` for
    the ``[mpc]`` plan's). In a vector field, the components ``comps`` share it: read as
    their geometric mean (each at least ``floor``), one component as it is; a scalar field
    has no ``comps``. The field holds ``per_unit`` times the parameter (deg -> rad:
    ``_D2R``). An unset field (None) reads ``unset`` (a value, or a function of the preset;
    ``None``: the parameter's upper bound) and, written, takes the value in every component.
    ``read`` and ``write`` (given the preset) replace these rules for a parameter that does
    not follow them.
    """

    field: str
    comps: tuple[int, ...] = ()
    per_unit: float = 1.0
    floor: float = 0.0
    unset: _Unset | None = None
    read: Callable[[CueingParams], float] | None = None
    write: Callable[[_Fields, CueingParams, float], None] | None = None

    def value(self, params: CueingParams, holder: _Holder, hi: float) -> float:
        """The parameter in ``holder`` (``params`` or its plan), in its unit; ``hi``: its
        upper bound."""
        if self.read is not None:
            return self.read(params)
        raw = getattr(holder, self.field)
        if raw is None:
            if self.unset is None:
                return hi
            raw = self.unset(params) if callable(self.unset) else self.unset
        if len(self.comps) == 1:
            raw = raw[self.comps[0]]
        elif self.comps:
            raw = _geo(raw[self.comps[0]], raw[self.comps[1]], self.floor)
        return float(raw) / self.per_unit if self.per_unit != 1.0 else raw

    def put(self, fields: _Fields, params: CueingParams, holder: _Holder, v: float) -> None:
        """Write ``v`` (its unit) into ``fields``, the changed fields of ``holder``."""
        if self.write is not None:
            self.write(fields, params, v)
            return
        value = v * self.per_unit if self.per_unit != 1.0 else v
        if not self.comps:
            fields[self.field] = value
            return
        vec = fields.get(self.field)
        if not isinstance(vec, list):
            old = getattr(holder, self.field)
            if old is None:
                unset = self.unset(params) if callable(self.unset) else self.unset
                old = [value] * (len(unset) if isinstance(unset, Sequence) else 1)
            vec = list(old)
        for i in self.comps:
            vec[i] = value
        fields[self.field] = vec


def _knob_values(
    knobs: dict[str, _Knob],
    table: Sequence[TunableParameter],
    params: CueingParams,
    holder: _Holder,
) -> tuple[float, ...]:
    """The value of each parameter of ``table`` in ``holder`` (the preset or its plan)."""
    return tuple(knobs[p.name].value(params, holder, p.hi) for p in table)


def _knob_fields(
    knobs: dict[str, _Knob],
    names: Sequence[str],
    params: CueingParams,
    holder: _Holder,
    v: Sequence[float],
) -> _Fields:
    """The fields of ``holder`` that the parameters ``names`` set to ``v`` (for
    ``replace``)."""
    fields: _Fields = {}
    for name, value in zip(names, v, strict=True):
        knobs[name].put(fields, params, holder, value)
    return {k: tuple(x) if isinstance(x, list) else x for k, x in fields.items()}


def _names(table: Sequence[TunableParameter]) -> list[str]:
    return [p.name for p in table]


def _tilt_scale_unset(params: CueingParams) -> Sequence[float]:
    """A preset without ``tilt_scale`` starts with its translational ``f_scale`` (x, y)."""
    return params.f_scale[:2]


_CLASSICAL_KNOBS: dict[str, _Knob] = {
    "f_scale_x": _Knob("f_scale", (0,)),
    "f_scale_y": _Knob("f_scale", (1,)),
    "f_scale_z": _Knob("f_scale", (2,)),
    "f_limit_xy_m_s2": _Knob("f_limit_m_s2", (0, 1)),
    "f_shape_xy": _Knob("f_shape", (0, 1), unset=(2.0, 2.0, 2.0)),
    "trans_wn_xy_rad_s": _Knob("trans_wn_rad_s", (0, 1)),
    "trans_wb_xy_rad_s": _Knob("trans_wb_rad_s", (0, 1), floor=1e-9),
    "trans_wn_z_rad_s": _Knob("trans_wn_rad_s", (2,)),
    "tilt_scale_x": _Knob("tilt_scale", (0,), unset=_tilt_scale_unset),
    "tilt_scale_y": _Knob("tilt_scale", (1,), unset=_tilt_scale_unset),
    "tilt_shape": _Knob("tilt_shape"),
    "tilt_reach_use": _Knob("tilt_reach_use"),
    "tilt_wn_rad_s": _Knob("tilt_wn_rad_s"),
    "tilt_rate_limit_deg_s": _Knob("tilt_rate_limit_rad_s", per_unit=_D2R),
    "tilt_accel_limit_deg_s2": _Knob("tilt_accel_limit_rad_s2", per_unit=_D2R),
    "tilt_limit_deg": _Knob("tilt_limit_rad", per_unit=_D2R),
    "w_scale_rp": _Knob("w_scale", (0, 1)),
    "w_scale_yaw": _Knob("w_scale", (2,)),
    "rot_wn_rp_rad_s": _Knob("rot_wn_rad_s", (0, 1)),
    "rot_wn_yaw_rad_s": _Knob("rot_wn_rad_s", (2,)),
    "lead_x_s": _Knob("lead_s", (0,), unset=(0.02, 0.02)),
    "lead_y_s": _Knob("lead_s", (1,), unset=(0.02, 0.02)),
}
"""Where each parameter of :data:`TUNED_PARAMETERS` and :data:`STRENGTH_TUNED_PARAMETERS`
lives in a :class:`CueingParams` (x and y share the ``_xy`` ones, roll and pitch the
``_rp`` ones). A preset without ``tilt_accel_limit_rad_s2`` starts at the upper bound; one
without ``f_shape`` at 2, and written, the heave curve takes the x/y exponent as well."""

_INTENSITY_FIELDS: tuple[str, ...] = tuple(
    dict.fromkeys(_CLASSICAL_KNOBS[p.name].field for p in STRENGTH_TUNED_PARAMETERS)
)
"""The :class:`CueingParams` fields an intensity range moves (:func:`at_intensity`): those
the knobs of :data:`STRENGTH_TUNED_PARAMETERS` write, in table order."""


def _gentle_table(params: CueingParams) -> tuple[float, ...]:
    """The preset's ``[intensity.gentle]`` values (:func:`at_intensity` checks first)."""
    if params.intensity_gentle is None:
        raise ConfigError(f"preset {params.name!r} has no tuned intensity range")
    return params.intensity_gentle


class _ClassicalTuning:
    """The classical washout's plan: :data:`TUNED_PARAMETERS`, or
    :data:`STRENGTH_TUNED_PARAMETERS` with the compressive tilt (``tilt_shape``)."""

    def parameters(self, params: CueingParams) -> tuple[TunableParameter, ...]:
        return TUNED_PARAMETERS if params.tilt_shape is None else STRENGTH_TUNED_PARAMETERS

    def values(self, params: CueingParams) -> tuple[float, ...]:
        return _knob_values(_CLASSICAL_KNOBS, self.parameters(params), params, params)

    def apply(self, base: CueingParams, v: Sequence[float], name: str) -> CueingParams:
        fields = _knob_fields(_CLASSICAL_KNOBS, _names(self.parameters(base)), base, base, v)
        return replace(base, name=name or base.name, algorithm="classical", **fields)

    @property
    def intensity_keys(self) -> tuple[str, ...]:
        return INTENSITY_KEYS

    def check_intensity(self, params: CueingParams, gentle: Sequence[float]) -> None:
        for key, v in zip(INTENSITY_KEYS, gentle, strict=True):
            _check_gentle(key, v, zero_ok=False)
        if params.tilt_shape is None:
            raise ConfigError(
                "CueingParams.intensity_gentle needs the compressive tilt (tilt_shape)"
            )

    def intensity(self, params: CueingParams, t: float, name: str) -> CueingParams:
        gentle = _gentle_table(params)
        gentle_end = params_from_vector(
            params, _clip_log(STRENGTH_TUNED_PARAMETERS, gentle).tolist(), name
        )
        if t == 0.0:
            return gentle_end
        # the strong end: the preset's own fields; one it leaves unset, as the tuner reads it
        unset = [f for f in _INTENSITY_FIELDS if getattr(params, f) is None]
        strong_end = params
        if unset:
            read = params_from_vector(params, vector_from_params(params).tolist())
            strong_end = replace(params, **{f: getattr(read, f) for f in unset})
        fields = _between_fields(gentle_end, strong_end, t)
        return replace(params, name=name, **fields)


def _plan_of(params: CueingParams) -> MpcParams:
    return params.mpc if params.mpc is not None else MpcParams()


def _read_sign_guard(params: CueingParams) -> float:
    """The roll and pitch sign guard: the geometric mean of those the plan sets (> 0)."""
    guard = [g for g in _plan_of(params).sign_guard[3:5] if g > 0.0]
    return math.sqrt(guard[0] * guard[-1]) if guard else 0.7


def _write_sign_guard(fields: _Fields, params: CueingParams, v: float) -> None:
    """Only the roll and pitch guards the plan sets (> 0) take the tuned value."""
    guard = _plan_of(params).sign_guard
    fields["sign_guard"] = [v if i in (3, 4) and g > 0.0 else g for i, g in enumerate(guard)]


def _read_reach_use(params: CueingParams) -> float:
    """An unset reach share (0) reads 1."""
    use = _plan_of(params).ref_reach_use
    return use if use > 0.0 else 1.0


def _plan_tilt_rate_unset(params: CueingParams) -> float:
    """A plan without its own tilt-rate limit starts with the ``[tilt]`` table's."""
    return params.tilt_rate_limit_rad_s


def _read_adapt_x(params: CueingParams) -> float:
    """The plan's adaptive fx cap; 0 where it sets none."""
    peak = _plan_of(params).ref_adapt_peak_m_s2
    return 0.0 if peak is None else float(peak[0])


def _write_adapt_x(fields: _Fields, params: CueingParams, v: float) -> None:
    """Only a cap the plan sets takes the value (0 stays none)."""
    peak = _plan_of(params).ref_adapt_peak_m_s2
    if peak is not None:
        fields["ref_adapt_peak_m_s2"] = (v, peak[1])


_PLAN_KNOBS: dict[str, _Knob] = {
    "ref_scale_xy": _Knob("ref_scale", (0, 1), floor=1e-9),
    "ref_scale_x": _Knob("ref_scale", (0,)),
    "ref_scale_y": _Knob("ref_scale", (1,)),
    "ref_limit_xy_m_s2": _Knob("ref_limit", (0, 1)),
    "ref_reach_use": _Knob("ref_reach_use", read=_read_reach_use),
    "ref_shape": _Knob("ref_shape"),
    "plan_tilt_rate_limit_deg_s": _Knob(
        "tilt_rate_limit_rad_s", per_unit=_D2R, unset=_plan_tilt_rate_unset
    ),
    "w_error_rp": _Knob("w_error", (3, 4), floor=1e-9),
    "w_pose_xy": _Knob("w_pose", (0, 1), floor=1e-9),
    "w_acc_tilt": _Knob("w_acc", (3, 4), floor=1e-9),
    "sign_guard_rp": _Knob("sign_guard", read=_read_sign_guard, write=_write_sign_guard),
    "w_vehicle_x": _Knob("w_vehicle", (0,)),
    "w_vehicle_y": _Knob("w_vehicle", (1,)),
    "ref_adapt_peak_x_m_s2": _Knob("ref_adapt_peak_m_s2", read=_read_adapt_x, write=_write_adapt_x),
    "ref_small_gain_x": _Knob("ref_small_gain", (0,)),
}
"""Where each parameter of :data:`MPC_TUNED_PARAMETERS`, :data:`MPC_STRENGTH_TUNED_PARAMETERS`
and :data:`PLAN_INTENSITY_KEYS` lives in a preset's :class:`MpcParams` (its ``[mpc]``
table; x and y share the ``_xy`` ones, roll and pitch the ``_rp`` and ``tilt`` ones). An
unset reach share reads 1."""


PLAN_INTENSITY_KEYS: tuple[str, ...] = (
    "ref_scale_x",
    "ref_scale_y",
    "ref_adapt_peak_x_m_s2",
    "w_vehicle_x",
    "w_vehicle_y",
    "ref_small_gain_x",
)
"""Keys of an ``mpc`` or ``optimal`` preset's ``[intensity] gentle`` table (knobs of
:data:`_PLAN_KNOBS`): the terms of the plan's cost that ask for strength, at the gentle
(0 %) end. ``ref_scale_x``, ``ref_scale_y``: the gain of the tracked copy of the vehicle's fx,
fy (``[mpc] ref_scale``, > 0); ``ref_adapt_peak_x_m_s2``: the adaptive cap of the fx gain
(``[mpc] ref_adapt_peak_m_s2``'s fx, m/s^2; > 0 exactly where the preset sets one, 0 where it
has none); ``w_vehicle_x``, ``w_vehicle_y``: the price of the rider's error to the vehicle's
whole fx, fy (``[mpc] w_vehicle``, >= 0); ``ref_small_gain_x``: the extra gain of small
fx cues (``[mpc] ref_small_gain``'s fx, >= 0). Every point of the range is the plan's optimum for
its own cost, so a point of the front of that cost between strength and the error terms, not
a gain on a ride."""

_PLAN_INTENSITY_ZERO_OK = frozenset(
    {"ref_adapt_peak_x_m_s2", "w_vehicle_x", "w_vehicle_y", "ref_small_gain_x"}
)
"""Keys of a plan's gentle table that may be 0 (a term the preset does not use)."""


class _PlanTuning:
    """The ``[mpc]`` plan's parameters (``mpc``, ``optimal``): :data:`MPC_TUNED_PARAMETERS`,
    or :data:`MPC_STRENGTH_TUNED_PARAMETERS` with the compressive reference (``ref_shape``)."""

    def parameters(self, params: CueingParams) -> tuple[TunableParameter, ...]:
        if _plan_of(params).ref_shape > 0.0:
            return MPC_STRENGTH_TUNED_PARAMETERS
        return MPC_TUNED_PARAMETERS

    def values(self, params: CueingParams) -> tuple[float, ...]:
        return _knob_values(_PLAN_KNOBS, self.parameters(params), params, _plan_of(params))

    def apply(self, base: CueingParams, v: Sequence[float], name: str) -> CueingParams:
        mp = _plan_of(base)
        fields = _knob_fields(_PLAN_KNOBS, _names(self.parameters(base)), base, mp, v)
        return replace(base, name=name or base.name, mpc=replace(mp, **fields))

    @property
    def intensity_keys(self) -> tuple[str, ...]:
        return PLAN_INTENSITY_KEYS

    def check_intensity(self, params: CueingParams, gentle: Sequence[float]) -> None:
        for key, v in zip(PLAN_INTENSITY_KEYS, gentle, strict=True):
            _check_gentle(key, v, zero_ok=key in _PLAN_INTENSITY_ZERO_OK)
        own = plan_intensity_values(params)[PLAN_INTENSITY_KEYS.index("ref_adapt_peak_x_m_s2")]
        g = gentle[PLAN_INTENSITY_KEYS.index("ref_adapt_peak_x_m_s2")]
        if (own > 0.0) != (g > 0.0):
            raise ConfigError(
                f"intensity gentle ref_adapt_peak_x_m_s2 = {g!r} is invalid; allowed: > 0 "
                "where the preset's [mpc] ref_adapt_peak_m_s2 sets an fx cap, 0 where it "
                f"sets none (it sets {own!r})"
            )

    def intensity(self, params: CueingParams, t: float, name: str) -> CueingParams:
        own = plan_intensity_values(params)
        v = [_between(g, o, t) for g, o in zip(_gentle_table(params), own, strict=True)]
        mp = _plan_of(params)
        fields = _knob_fields(_PLAN_KNOBS, PLAN_INTENSITY_KEYS, params, mp, v)
        return replace(params, name=name, mpc=replace(mp, **fields))


def plan_intensity_values(params: CueingParams) -> tuple[float, ...]:
    """An ``mpc`` or ``optimal`` preset's own values of :data:`PLAN_INTENSITY_KEYS` (in
    that order): its strong (100 %) end, the values a gentle table is chosen below."""
    mp = _plan_of(params)
    return tuple(_PLAN_KNOBS[k].value(params, mp, math.inf) for k in PLAN_INTENSITY_KEYS)


def _check_gentle(key: str, v: float, zero_ok: bool) -> None:
    if not (math.isfinite(v) and (v >= 0.0 if zero_ok else v > 0.0) and v <= 1e6):
        raise ConfigError(
            f"intensity gentle {key} = {v!r} is invalid; allowed: "
            f"{'0' if zero_ok else 'above 0'} to 1e6"
        )


CLASSICAL_TUNING: TunePlan = _ClassicalTuning()
"""The classical washout's tunable parameters."""

PLAN_TUNING: TunePlan = _PlanTuning()
"""The ``[mpc]`` plan's tunable parameters (``mpc`` and ``optimal``)."""


def _tuning(params: CueingParams) -> TunePlan:
    """The plan the preset's algorithm declares (registry entry ``tune``)."""
    from ._algorithm import cueing_entry

    plan = cueing_entry(params.algorithm).tune
    if plan is None:
        raise TunablePlanError(
            f"preset {params.name!r} uses the cueing algorithm {params.algorithm!r}, which "
            "declares no tunable parameters"
        )
    return plan


def tuned_parameters(params: CueingParams) -> tuple[TunableParameter, ...]:
    """The table tuned for ``params``, as its algorithm declares it (:class:`TunePlan`)."""
    return _tuning(params).parameters(params)


def vector_from_params(params: CueingParams) -> NDArray[np.float64]:
    """The base preset as a point of the search space (log values, clipped to the bounds)."""
    plan = _tuning(params)
    return _clip_log(plan.parameters(params), plan.values(params))


def gentle_values(params: CueingParams) -> tuple[float, ...]:
    """The tuned parameters of a compressive-tilt preset, in their units (the values of an
    ``[intensity] gentle`` table, :data:`INTENSITY_KEYS` order)."""
    return tuple(float(math.exp(v)) for v in vector_from_params(params))


def params_from_vector(base: CueingParams, x: Sequence[float], name: str = "") -> CueingParams:
    """The base preset with the tuned parameters set from a point ``x`` (log values)."""
    plan = _tuning(base)
    table = plan.parameters(base)
    if len(x) != len(table):
        raise ConfigError(f"tuning vector has {len(x)} values; expected {len(table)}")
    v = [min(max(math.exp(float(xi)), p.lo), p.hi) for xi, p in zip(x, table, strict=True)]
    return plan.apply(base, v, name)


def _between(a: float, b: float, t: float) -> float:
    """``a`` at ``t = 0``, ``b`` at ``t = 1``: geometric in between where both have the same
    sign (the tuner's log space), linear where one is zero or they differ in sign (no log);
    monotonic in ``t`` either way, and exact at the ends and where ``a == b``."""
    if t == 0.0 or a == b:
        return a
    if t == 1.0:
        return b
    if a * b > 0.0:
        la, lb = math.log(abs(a)), math.log(abs(b))
        return math.copysign(math.exp(la + t * (lb - la)), a)
    return a + t * (b - a)


def _between_fields(gentle: CueingParams, strong: CueingParams, t: float) -> _Fields:
    """Each of :data:`_INTENSITY_FIELDS` between the two ends, element by element
    (:func:`_between`); for ``replace`` on ``strong``."""
    fields: _Fields = {}
    for name in _INTENSITY_FIELDS:
        a, b = getattr(gentle, name), getattr(strong, name)
        if isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b):
            fields[name] = tuple(_between(float(u), float(v), t) for u, v in zip(a, b, strict=True))
        elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
            fields[name] = _between(float(a), float(b), t)
        else:  # the knobs write what they read: both ends have the same shape
            raise AssertionError(f"intensity field {name}: {a!r} and {b!r} differ in shape")
    return fields


def at_intensity(params: CueingParams, percent: float) -> CueingParams:
    """The preset at an intensity: a point of its tuned range, not a plain gain.

    ``100`` is the preset itself (its tables: the strongest tuned point within its cue
    budget), ``0`` its ``[intensity] gentle`` end (tuned for a tighter false-cue budget): the
    preset with the tuned parameters (:data:`STRENGTH_TUNED_PARAMETERS`) set to that table,
    ``params_from_vector(params, log(gentle))``. In between, every field those parameters
    write (:data:`_INTENSITY_FIELDS`: gains, limits, exponents, filter frequencies, tilt rate
    and acceleration limits, reach share, leads) is interpolated element by element between
    the gentle end's value ``v0`` and the preset's own ``v100``, geometrically (the tuner's
    log space), ``v = v0^(1 - t) v100^t`` with ``t = percent / 100`` (linearly for an element
    that is zero at one end), so that every point is a complete washout design between two
    tuned ones and the range is continuous up to 100 %: the preset's own values, not their
    image in the tuner's space (which holds one f_limit for x and y, their geometric mean,
    ``tilt_shape`` at most 8, and every value clipped to its bounds), are the strong end. A
    field the preset leaves unset (``None``, e.g. no lead) is read there as the tuner reads
    it (:func:`vector_from_params`). Everything else, the ``adapt_*`` keys among them, is the
    preset's at every intensity.

    An ``mpc`` or ``optimal`` preset's range moves the terms of its plan's cost that ask for
    strength (the keys of its ``[intensity.gentle]`` table: the tracked copy's fx and
    fy gains, the adaptive cap of the fx gain, the price of the error to the vehicle's whole
    fx and fy), each between its gentle value and the preset's own in the same way (linearly
    where one end is 0). Every point is then the plan's optimum for its own cost: a point of
    that cost's front between strength and the error terms (false cues, guards, limits), not a
    gain on a ride.

    Whatever the intensity, the chain after the cueing (workspace limiting, the actuator
    limiter) keeps every frame within the limits.

    Parameters
    ----------
    params : CueingParams
        A preset with an intensity range (``intensity_gentle``) whose algorithm declares one
        (its :class:`TunePlan`'s ``intensity_keys``: classical, mpc, optimal).
    percent : float
        0 to 100.

    Returns
    -------
    CueingParams
        Named ``"NAME@PCT%"`` (the preset itself at 100).

    Raises
    ------
    ConfigError
        ``percent`` outside 0..100, a preset without an intensity range, or one whose
        algorithm declares no tunable parameters.
    """
    if isinstance(percent, bool) or not (math.isfinite(percent) and 0.0 <= percent <= 100.0):
        raise ConfigError(f"intensity {percent!r} % is invalid; allowed: 0 to 100")
    if params.intensity_gentle is None:
        raise ConfigError(
            f"preset {params.name!r} has no tuned intensity range (no [intensity] table); "
            "give a preset that has one (e.g. racing-hexapod-strong) or leave out the intensity"
        )
    plan = _tuning(params)
    if percent == 100.0:
        return params
    return plan.intensity(params, percent / 100.0, f"{params.name}@{percent:g}%")


def _fmt(v: float) -> str:
    return repr(float(v))


def _vec(values: Iterable[float], k: float = 1.0) -> str:
    return "[" + ", ".join(_fmt(v * k) for v in values) + "]"


def _optional(key: str, value: float | Sequence[float] | None, k: float = 1.0) -> list[str]:
    """``key = value`` (times ``k``) for an optional key; nothing when it is unset."""
    if value is None:
        return []
    if isinstance(value, int | float):
        return [f"{key} = {_fmt(value * k)}"]
    return [f"{key} = {_vec(value, k)}"]


def preset_toml(params: CueingParams, comments: Sequence[str] = ()) -> str:
    """The TOML text of a preset (the layout :func:`load_cueing` reads): the classical
    tables, and for an ``mpc`` or ``optimal`` preset its ``[mpc]`` table.

    Angles are written in degrees, lengths in millimetres (the file's units); ``comments``
    become ``#`` lines at the top.
    """
    from ._params import DOF_NAMES

    r2d = 1.0 / _D2R
    lines = [f"# {c}".rstrip() for c in comments]
    lines += [
        f"description = {_quote(f'{params.name}: tuned by motioncue tune')}",
        f"algorithm = {_quote(params.algorithm)}",
        "dofs = ["
        + ", ".join(f'"{n}"' for n, on in zip(DOF_NAMES, params.dofs, strict=True) if on)
        + "]",
        "",
        "[scaling]",
        f"f_scale = {_vec(params.f_scale)}",
        f"f_limit_m_s2 = {_vec(params.f_limit_m_s2)}",
        f"w_scale = {_vec(params.w_scale)}",
        f"w_limit_deg_s = {_vec(params.w_limit_rad_s, r2d)}",
        f"soft_knee = {_fmt(params.soft_knee)}",
    ]
    lines += _optional("f_shape", params.f_shape)
    lines += _optional("w_shape", params.w_shape)
    lines += _optional("lead_s", params.lead_s)
    lines += [
        "",
        "[translational]",
        f"wn_rad_s = {_vec(params.trans_wn_rad_s)}",
        f"zeta = {_vec(params.trans_zeta)}",
        f"wb_rad_s = {_vec(params.trans_wb_rad_s)}",
        "",
        "[tilt]",
        f"wn_rad_s = {_fmt(params.tilt_wn_rad_s)}",
        f"zeta = {_fmt(params.tilt_zeta)}",
        f"rate_limit_deg_s = {_fmt(params.tilt_rate_limit_rad_s * r2d)}",
        f"limit_deg = {_fmt(params.tilt_limit_rad * r2d)}",
    ]
    lines += _optional("scale", params.tilt_scale)
    lines += _optional("accel_limit_deg_s2", params.tilt_accel_limit_rad_s2, r2d)
    lines += _optional("shape", params.tilt_shape)
    if params.tilt_reach_rad is not None:
        lines.append(f"reach_deg = {_vec(params.tilt_reach_rad, r2d)}")
        lines.append(f"reach_use = {_fmt(params.tilt_reach_use)}")
    if params.tilt_additive:
        lines.append("additive = true")
    if params.tilt_lag_fill > 0.0:
        lines.append(f"lag_fill = {_fmt(params.tilt_lag_fill)}")
    if params.tilt_forward_ratio != 1.0:
        lines.append(f"forward_ratio = {_fmt(params.tilt_forward_ratio)}")
    if params.tilt_rate_mix is not None:
        rows = ", ".join(_vec(r) for r in params.tilt_rate_mix)
        lines.append(f"rate_mix = [{rows}]")
    if params.tilt_reach_exponent != 2.0:
        lines.append(f"reach_exponent = {_fmt(params.tilt_reach_exponent)}")
    if params.tilt_fz_guard is not None:
        lines.append(f"fz_guard = {_vec(params.tilt_fz_guard)}")
    if params.tilt_adapt_peak_m_s2 is not None:
        lines.append(f"adapt_peak_m_s2 = {_vec(params.tilt_adapt_peak_m_s2)}")
        lines.append(f"adapt_tau_s = {_fmt(params.tilt_adapt_tau_s)}")
        lines.append(f"adapt_start_m_s2 = {_fmt(params.tilt_adapt_start_m_s2)}")
    if params.tilt_offset_m is not None:
        rows = ", ".join(_vec(r, 1e3) for r in params.tilt_offset_m)
        lines.append(f"offset_mm = [{rows}]")
    lines += [
        "",
        "[rotational]",
        f"wn_rad_s = {_vec(params.rot_wn_rad_s)}",
        f"zeta = {_vec(params.rot_zeta)}",
        "",
        "[input]",
        f"reject_f_m_s2 = {_fmt(params.reject_f_m_s2)}",
        f"reject_w_deg_s = {_fmt(params.reject_w_rad_s * r2d)}",
        "",
        "[workspace]",
        f"half_range_mm = {_vec(params.workspace[:3], 1e3)}",
        f"half_range_deg = {_vec(params.workspace[3:], r2d)}",
        "",
        "[head]",
        f"offset_mm = {_vec(params.head_offset_m, 1e3)}",
        "",
    ]
    lines += _table_lines(params)
    if params.intensity_gentle is not None:
        lines += ["[intensity.gentle]"]
        lines += [
            f"{k} = {_fmt(v)}"
            for k, v in zip(intensity_keys(params.algorithm), params.intensity_gentle, strict=True)
        ]
        lines.append("")
    return "\n".join(lines)


def mpc_table_lines(mp: MpcParams) -> list[str]:
    """The ``[mpc]`` table of :func:`preset_toml` (the writer of its registered table)."""
    r2d = 1.0 / _D2R
    lines = [
        "[mpc]",
        f"platform = {_quote(mp.platform)}",
        f"controller = {_quote(mp.controller)}",
        f"horizon_s = {_fmt(mp.horizon_s)}",
        f"blocks = {mp.blocks}",
    ]
    for key in (
        "w_error",
        "w_pose",
        "w_vel",
        "w_acc",
        "w_vehicle",
        "ref_scale",
        "ref_scale_hf",
        "sign_guard",
    ):
        lines.append(f"{key} = {_vec(getattr(mp, key))}")
    if any(mp.w_prior):  # mpc's pose prior (written only where set)
        lines.append(f"w_prior = {_vec(mp.w_prior)}")
    if any(mp.w_jerk):  # optimal's price of the input's steps (written only where set)
        lines.append(f"w_jerk = {_vec(mp.w_jerk)}")
    lines += [
        f"ref_limit_m_s2 = {_vec(mp.ref_limit[:3])}",
        f"ref_limit_deg_s = {_vec([min(1e9, v * r2d) for v in mp.ref_limit[3:]])}",
    ]
    for key in (
        "prediction_tau_s",
        "ref_split_hz",
        "ref_shape",
        "ref_reach_use",
        "tilt_fz_use",
        "tilt_fz_use_against",
        "sign_guard_weight",
        "stroke_use",
        "rate_use",
        "deadline_ms",
        "window_s",
        "stride_s",
    ):
        lines.append(f"{key} = {_fmt(getattr(mp, key))}")
    lines.append(f"block_samples = {mp.block_samples}")
    if mp.sign_guard_every:
        lines.append(f"sign_guard_every = {mp.sign_guard_every}")
    if mp.ref_adapt_peak_m_s2 is not None:  # the adaptive gain (written only where set)
        lines.append(f"ref_adapt_peak_m_s2 = {_vec(mp.ref_adapt_peak_m_s2)}")
        lines.append(f"ref_adapt_tau_s = {_fmt(mp.ref_adapt_tau_s)}")
        lines.append(f"ref_adapt_start_m_s2 = {_fmt(mp.ref_adapt_start_m_s2)}")
    if any(mp.ref_small_gain):  # small cues' extra gain (written only where set)
        lines.append(f"ref_small_gain = {_vec(mp.ref_small_gain)}")
        lines.append(f"ref_small_knee_m_s2 = {_fmt(mp.ref_small_knee_m_s2)}")
    if mp.tilt_rate_limit_rad_s is not None:
        lines.append(f"tilt_rate_limit_deg_s = {_fmt(mp.tilt_rate_limit_rad_s * r2d)}")
    lines += [f"solver = {_quote(mp.solver)}", ""]
    return lines


def _table_lines(params: CueingParams) -> list[str]:
    """The algorithm's own table (its registered writer), where the preset has one."""
    from ._algorithm import cueing_entry

    table = cueing_entry(params.algorithm).table
    if table is None or table.write is None:
        return []
    value = params.mpc if table.name == "mpc" else params.tables.get(table.name)
    return [] if value is None else table.write(value)


def _quote(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'
