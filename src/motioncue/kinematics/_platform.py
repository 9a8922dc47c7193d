"""Platform models: closed-form inverse kinematics, Newton forward kinematics, Jacobian, checks.

Pose vector: ``[x, y, z, roll, pitch, yaw]`` (m, rad) of the platform frame relative to its
neutral pose, ``R = Rz(yaw) Ry(pitch) Rx(roll)``, ISO 8855 axes. Actuator positions ``q`` are
measured from the neutral pose: metres for linear actuators, radians for rotary ones.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from typing import TypedDict

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from .._errors import ConfigError
from .._frozen import readonly, set_fields
from ._drive import Drive
from ._legs import CrankLegs, LegSet, LinearLegs
from ._rotation import rot9, rot9_derivatives, rot_one

__all__ = [
    "DOF_NAMES",
    "CheckResult",
    "Corner4",
    "FKResult",
    "LinearLegPlatform",
    "Platform",
    "Seat2Yaw",
    "Seat3",
    "Stewart6Linear",
    "Stewart6Rotary",
]

DOF_NAMES = ("x", "y", "z", "roll", "pitch", "yaw")
_CHUNK = 2048  # poses per block in batch IK: temporaries stay in cache, BLAS stays single-threaded
_JAC_CHUNK = 8192  # poses per block in batch Jacobians (bounds temporary memory)
_NO_REACH = np.ones((0, 0), dtype=bool)
_TL_MAX_RAD = math.radians(89.0)  # a traction-loss slider's pin leaves its slot beyond this


@dataclass(frozen=True)
class FKResult:
    """Result of :meth:`Platform.forward`.

    Attributes
    ----------
    pose
        ``(6,)`` pose found (m, rad): the rigid pose nearest to ``q`` (least squares) when
        no pose gives ``q`` exactly.
    converged
        True when ``residual`` fell below the tolerance ``tol``.
    iterations
        Newton iterations taken (the least-squares fallback's evaluations not counted).
    residual
        Max abs difference between the positions the pose gives and the requested ``q``
        (m or rad). A crank leg may pass the point where crank and rod align onto its other
        assembly branch: its position is compared with the nearer branch's.
    status
        ``"exact"`` (``residual <= tol``); ``"rounded"`` (every actuator within its rounding
        tolerance, by default one pulse of its drive: positions a rigid pose gives, rounded
        to pulses); ``"inconsistent"`` (the nearest rigid pose leaves an actuator beyond its
        rounding tolerance: no rigid pose gives these positions).
    residuals
        ``(n,)`` signed per-actuator differences ``q - q(pose)`` (m or rad).
    tolerance
        ``(n,)`` rounding tolerance the status was judged with (m or rad).
    """

    pose: NDArray[np.float64]
    converged: bool
    iterations: int
    residual: float
    status: str = "exact"
    residuals: NDArray[np.float64] | None = None
    tolerance: NDArray[np.float64] | None = None

    @property
    def ok(self) -> bool:
        """True when a rigid pose gives ``q`` within the rounding (status exact or rounded)."""
        return self.status in ("exact", "rounded")

    @property
    def worst(self) -> int:
        """Index of the actuator with the largest residual relative to its tolerance."""
        if self.residuals is None or self.tolerance is None:
            return 0
        return int(np.argmax(np.abs(self.residuals) / self.tolerance))


@dataclass(frozen=True)
class CheckResult:
    """Result of :meth:`Platform.check` for poses ``(..., 6)`` on ``n`` actuators.

    Attributes
    ----------
    q
        ``(..., n)`` actuator positions (m or rad, from neutral).
    in_stroke
        ``(..., n)`` bool: ``q_min <= q <= q_max``.
    overshoot
        ``(..., n)`` signed amount beyond the stroke (``q - q_max`` above, ``q - q_min``
        below), 0 inside.
    reachable
        ``(..., n)`` bool: False where a crank cannot reach its rod (rotary legs); ``q`` is
        then the crank angle of closest approach.
    unsupported
        ``(..., 6)`` bool: a nonzero request of a pose component the machine cannot produce.
    ok
        ``(...)`` bool: every actuator in stroke and reachable.
    """

    q: NDArray[np.float64]
    in_stroke: NDArray[np.bool_]
    overshoot: NDArray[np.float64]
    reachable: NDArray[np.bool_]
    unsupported: NDArray[np.bool_]
    ok: NDArray[np.bool_]


def _bad_input(name: str, arr: NDArray[np.float64]) -> ConfigError:
    bad = np.argwhere(~np.isfinite(arr))[0]
    return ConfigError(
        f"{name}{list(bad.tolist())} = {arr[tuple(bad)]!r} is invalid; allowed: finite numbers"
    )


def _as_poses(poses: npt.ArrayLike) -> NDArray[np.float64]:
    arr = np.asarray(poses, dtype=float)
    if arr.ndim == 0 or arr.shape[-1] != 6:
        raise ConfigError(f"poses has shape {arr.shape}; expected (..., 6) [x,y,z,roll,pitch,yaw]")
    if not np.isfinite(arr).all():
        raise _bad_input("poses", arr)
    return arr


class _PlatformArgs(TypedDict):
    """The keyword arguments a :class:`Platform` was built with (to build a modified copy)."""

    name: str
    actuator_names: Sequence[str]
    legs: LegSet
    leg_pose_mask: Sequence[bool]
    dof_mask: Sequence[bool]
    q_min: npt.ArrayLike
    q_max: npt.ArrayLike
    drives: Drive | None
    yaw_axis: bool
    yaw_arm_m: float | None
    spare_axes: int
    description: str


class Platform:
    """A motion platform: legs (linear or crank) plus, optionally, a yaw axis (a turntable
    under the legs, or a traction-loss slider on top) and spare controller axes.

    Instances are frozen. Build one with :func:`~motioncue.kinematics.load_platform` or the
    geometry classes (:class:`Stewart6Linear`, :class:`Stewart6Rotary`, :class:`Seat3`,
    :class:`Seat2Yaw`, :class:`Corner4`), then :meth:`with_traction_loss` and
    :meth:`with_spare_axes`. Everything downstream (limits, limiters, rides, emulators)
    sees only ``n_actuators`` positions with their strokes, drives and limits: a slider is
    one more linear actuator, a spare axis one whose position is always 0 (pulse 0). There
    may be more moving actuators than degrees of freedom (a corner rig: four legs, three);
    the Jacobian at neutral must have full column rank, :meth:`forward` solves in least
    squares and :meth:`project` maps positions onto the nearest rigid pose.

    Attributes
    ----------
    name : str
    actuator_names : tuple of str
        In controller order.
    n_actuators : int
    actuator_kinds : tuple of str
        ``"linear"`` (m) or ``"rotary"`` (rad) per actuator.
    dof_mask : ndarray (6,) bool
        Pose components the machine can produce.
    q_neutral, q_min, q_max, q_park : ndarray (n,)
        Actuator positions at neutral (zeros), usable stroke, and parked (homed).
    pose_park : ndarray (6,)
        Pose at ``q_park``.
    neutral_absolute : ndarray (n,)
        At the neutral pose, pin-to-pin length (m) of linear actuators, crank angle from its
        zero direction (rad) of rotary ones: absolute position = ``q + neutral_absolute``.
    drives : Drive
    v_max, a_max, j_max : ndarray (n,) or None
        The actuators' own speed, acceleration and jerk limits (SI: m/s, m/s^2, m/s^3 or
        rad/s...), when the configuration gives them (see :meth:`with_actuator_limits`);
        :func:`motioncue.trajectory.ActuatorLimits.from_platform` combines them with the
        controller's.
    default_preset : str or None
        The cueing preset (name or path) made for this machine, used by ``generate``,
        ``bridge`` and ``cue`` when no ``--preset`` is given (the file's ``default_preset``).
    ride_preset : str or None
        The cueing preset used instead of ``default_preset`` where the whole recording is
        known before the first frame (``generate`` and ``cue``, and so ride files): a plan
        that sees the whole ride (the file's ``ride_preset``); ``None``: ``default_preset``
        there too. ``bridge`` always uses ``default_preset``.
    """

    v_max: NDArray[np.float64] | None = None
    a_max: NDArray[np.float64] | None = None
    j_max: NDArray[np.float64] | None = None
    default_preset: str | None = None
    ride_preset: str | None = None

    def with_default_preset(self, preset: str | None) -> Platform:
        """A copy naming ``preset`` (a cueing preset name or path) as its default."""
        return self._with_preset(default_preset=preset)

    def with_ride_preset(self, preset: str | None) -> Platform:
        """A copy naming ``preset`` (a cueing preset name or path) as its ride-file default."""
        return self._with_preset(ride_preset=preset)

    def _with_preset(self, **preset: str | None) -> Platform:
        import copy

        out = copy.copy(self)
        set_fields(out, **preset)
        return out

    def cueing_preset(self, ride: bool = False) -> str | None:
        """The preset a command runs unasked: ``ride_preset`` where the whole recording is
        known (``ride``: ``generate``, ``cue``, the demo) and the platform names one, else
        ``default_preset`` (None: the platform names neither)."""
        return (self.ride_preset if ride else None) or self.default_preset

    def with_actuator_limits(
        self,
        v_max: npt.ArrayLike | None = None,
        a_max: npt.ArrayLike | None = None,
        j_max: npt.ArrayLike | None = None,
    ) -> Platform:
        """A copy carrying the actuators' own limits (each a number or ``n`` numbers, > 0)."""
        import copy

        given: dict[str, NDArray[np.float64]] = {}
        for key, value in (("v_max", v_max), ("a_max", a_max), ("j_max", j_max)):
            if value is None:
                continue
            arr = np.broadcast_to(np.asarray(value, dtype=float), (self.n_actuators,)).copy()
            if not np.all(np.isfinite(arr) & (arr > 0)):
                raise ConfigError(
                    f"{key} = {np.asarray(value).tolist()} is invalid; allowed: finite numbers "
                    f"> 0, one or {self.n_actuators}"
                )
            given[key] = readonly(arr)
        out = copy.copy(self)
        set_fields(out, **given)
        return out

    def with_traction_loss(
        self,
        *,
        name: str,
        arm_m: float,
        q_min: float,
        q_max: float,
        drive: Drive | None = None,
    ) -> Platform:
        """This platform with a traction-loss slider on top: one more (linear) actuator.

        The slider turns the seat about a vertical pivot through the platform frame origin; a
        linear actuator pushes a pin ``arm_m`` behind the pivot sideways in a slot, so its
        travel is ``arm_m * tan(yaw)``. The slider takes the pose's yaw, and the legs below
        it see the pose without yaw (a hexapod's own yaw is held at zero). Modelling note:
        the slider's yaw is the pose's Z-Y-X yaw, as for a turntable under the tilt; a slider
        on top of a tilted frame turns about the frame's own vertical, a difference of second
        order (roll times yaw) that the cueing does not resolve.

        Parameters
        ----------
        name
            The new actuator's name (controller order: after the legs).
        arm_m
            Pivot-to-pin distance (m), > 0.
        q_min, q_max
            Usable slider travel from its centre (m), ``q_min < 0 < q_max``.
        drive
            The slider's drive (one linear actuator); default 5 mm lead, 10000 pulses per
            turn, homed at the centre.

        Returns
        -------
        Platform
            A new frozen platform with ``n_actuators + 1`` actuators and yaw in its
            ``dof_mask``. The actuators' own limits are not carried over (give them again with
            :meth:`with_actuator_limits`).

        Raises
        ------
        ConfigError
            The platform already has a yaw axis or spare axes, or a value is out of range.
        """
        if self._yaw_axis or self._n_spare:
            raise ConfigError(
                f"platform {self.name!r} already has a yaw axis or spare axes; a traction-loss "
                "slider goes on a platform of legs only (give spare axes after it)"
            )
        mask = list(self._init_args["leg_pose_mask"])
        mask[5] = False
        dof = list(self._init_args["dof_mask"])
        dof[5] = True
        if drive is None:
            drive = Drive.linear(0.005, 10000, [0.0])
        args: _PlatformArgs = {
            **self._init_args,
            "name": self.name,
            "actuator_names": (*self.actuator_names, name),
            "leg_pose_mask": mask,
            "dof_mask": dof,
            "q_min": [*self.q_min, float(q_min)],
            "q_max": [*self.q_max, float(q_max)],
            "drives": Drive.concat(self.drives, drive),
            "yaw_axis": True,
            "yaw_arm_m": _positive("arm_m", arm_m),
        }
        return _rebuilt(self, args)

    def with_spare_axes(self, names: Sequence[str], drive: Drive | None = None) -> Platform:
        """This platform with controller axes that drive nothing, after its actuators.

        A 6-axis controller (the SC-MBOX in 6-axis mode, an IMAX with PA02 = 6) always takes
        six positions per frame (MBOX manual 4.2.7/4.2.9: object channel 1 carries X Y Z U V
        W); on a rig with fewer actuators the spare axes are held at pulse 0, their homed
        (initial-positioning) origin, in every frame: their position is 0 whatever the pose,
        so the limiters never move them. Their usable stroke is 1.75 pulses either side of
        that origin, so the limits table (stroke rounded inwards to whole pulses) allows
        ``[-1, 1]`` pulses: room for the half-pulse rounding margins the generator and the
        player keep (two of them), and any frame moving a spare axis by more than one pulse
        (0.5 um on a 5 mm lead) is refused by the ride check and flagged by the independent
        frame checker that judges the emulators' traces.

        Parameters
        ----------
        names
            One name per spare axis (controller order, after the actuators).
        drive
            The spare axes' drive: they must agree with the controller's drive parameters
            like the others (MBOX Fn0C1/Fn0C2); default the first actuator's lead and pulses.
        """
        k = len(names)
        if k < 1:
            raise ConfigError("names is empty; allowed: one name per spare axis")
        if self._n_spare:
            raise ConfigError(f"platform {self.name!r} already has spare axes")
        if drive is None:
            lead = float(self.drives.units_per_rev[0])
            ppr = int(self.drives.pulses_per_rev[0])
            drive = Drive.linear([lead] * k, [ppr] * k, [0.0] * k)
        if drive.n != k or set(drive.kinds) != {"linear"} or np.any(drive.q_home != 0.0):
            raise ConfigError(
                f"spare axes drive must be {k} linear drive(s) homed at 0 (pulse 0 = hold)"
            )
        half = 1.75 / np.abs(np.asarray(drive.pulses_per_unit, dtype=float))
        args: _PlatformArgs = {
            **self._init_args,
            "name": self.name,
            "actuator_names": (*self.actuator_names, *names),
            "q_min": [*self.q_min, *(-half)],
            "q_max": [*self.q_max, *half],
            "drives": Drive.concat(self.drives, drive),
            "spare_axes": k,
        }
        return _rebuilt(self, args)

    @property
    def spare_axes(self) -> int:
        """Number of trailing controller axes held at pulse 0 (see :meth:`with_spare_axes`)."""
        return self._n_spare

    @property
    def axes_text(self) -> str:
        """The controller axes in words: ``"6 actuators"``, or for a rig with spare axes
        ``"4 actuators and 2 spare axes (6 controller axes)"``."""
        n = self.n_actuators - self._n_spare
        text = f"{n} actuator{'s' if n != 1 else ''}"
        if self._n_spare:
            k = self._n_spare
            text += (
                f" and {k} spare ax{'es' if k != 1 else 'is'} ({self.n_actuators} controller axes)"
            )
        return text

    @property
    def traction_loss_arm_m(self) -> float | None:
        """Pivot-to-pin distance (m) of a traction-loss slider, None without one."""
        return self._yaw_arm

    def __init__(
        self,
        *,
        name: str,
        actuator_names: Sequence[str],
        legs: LegSet,
        leg_pose_mask: Sequence[bool],
        dof_mask: Sequence[bool],
        q_min: npt.ArrayLike,
        q_max: npt.ArrayLike,
        drives: Drive | None,
        yaw_axis: bool = False,
        yaw_arm_m: float | None = None,
        spare_axes: int = 0,
        description: str = "",
    ) -> None:
        if yaw_arm_m is not None and not (yaw_axis and math.isfinite(yaw_arm_m) and yaw_arm_m > 0):
            raise ConfigError(
                f"yaw_arm_m = {yaw_arm_m!r} is invalid; allowed: a finite length > 0 (m), "
                "with a yaw axis"
            )
        if not (isinstance(spare_axes, int) and 0 <= spare_axes <= 12):
            raise ConfigError(f"spare_axes = {spare_axes!r} is invalid; allowed: 0..12")
        n_moving = legs.n + (1 if yaw_axis else 0)
        n = n_moving + spare_axes
        names = tuple(str(a) for a in actuator_names)
        if len(names) != n or len(set(names)) != n:
            raise ConfigError(
                f"actuator_names = {list(names)} is invalid; allowed: {n} distinct names"
            )
        q_lo = np.asarray(q_min, dtype=float)
        q_hi = np.asarray(q_max, dtype=float)
        if q_lo.shape != (n,) or q_hi.shape != (n,):
            raise ConfigError(f"q_min/q_max must have shape ({n},)")
        for i in range(n):
            if not (q_lo[i] < 0.0 < q_hi[i]):
                raise ConfigError(
                    f"actuator {names[i]!r}: usable stroke [{q_lo[i]:.6g}, {q_hi[i]:.6g}] "
                    "(from neutral) does not contain the neutral pose strictly inside; "
                    "check the neutral height and the stroke"
                )
        yaw_kind = "rotary" if yaw_arm_m is None else "linear"
        kinds = (legs.kind,) * legs.n + ((yaw_kind,) if yaw_axis else ()) + ("linear",) * spare_axes
        if drives is None:
            drives = _default_drives(kinds, q_lo)
        if drives.kinds != kinds:
            raise ConfigError(f"drives kinds {drives.kinds} do not match actuators {kinds}")
        home = drives.q_home
        for i in range(n):
            if not (q_lo[i] - 1e-12 <= home[i] <= q_hi[i] + 1e-12):
                raise ConfigError(
                    f"actuator {names[i]!r}: homed position {home[i]:.6g} (from neutral) is "
                    f"outside the usable stroke [{q_lo[i]:.6g}, {q_hi[i]:.6g}]"
                )
        set_fields(
            self,
            name=str(name),
            description=str(description),
            actuator_names=names,
            n_actuators=n,
            actuator_kinds=kinds,
            dof_mask=readonly(dof_mask, bool),
            _legs=legs,
            _leg_mask=np.asarray(leg_pose_mask, dtype=float),
            _leg_mask_list=[bool(v) for v in leg_pose_mask],
            _all_dof_legs=all(bool(v) for v in leg_pose_mask),
        )
        fast = (
            self._all_dof_legs and not yaw_axis and not spare_axes and isinstance(legs, LinearLegs)
        )
        init_args = {
            "name": name, "actuator_names": names, "legs": legs,
            "leg_pose_mask": [bool(v) for v in leg_pose_mask],
            "dof_mask": [bool(v) for v in dof_mask], "q_min": q_lo, "q_max": q_hi,
            "drives": drives, "yaw_axis": bool(yaw_axis), "yaw_arm_m": yaw_arm_m,
            "spare_axes": int(spare_axes), "description": description,
        }  # fmt: skip
        dof_idx = np.flatnonzero(np.asarray(dof_mask, dtype=bool))
        set_fields(
            self,
            _fast_linear=legs if fast else None,
            _yaw_axis=bool(yaw_axis),
            _yaw_arm=None if yaw_arm_m is None else float(yaw_arm_m),
            _n_spare=int(spare_axes),
            _tail=[0.0] * int(spare_axes),
            _init_args=init_args,
            _dof_idx=dof_idx,
            _dof_list=[int(k) for k in dof_idx],
            q_neutral=readonly(np.zeros(n)),
            q_min=readonly(q_lo),
            q_max=readonly(q_hi),
            q_park=readonly(home),
            drives=drives,
        )
        if isinstance(legs, LinearLegs):
            absolute = legs.length0
        elif isinstance(legs, CrankLegs):
            absolute = legs.theta0
        else:
            raise TypeError(f"unknown leg set {type(legs).__name__}")
        set_fields(
            self,
            neutral_absolute=readonly(np.concatenate([absolute, [0.0] * (yaw_axis + spare_axes)])),
        )
        if len(self._dof_idx) > n_moving:
            raise ConfigError(
                f"{n_moving} moving actuators cannot drive {len(self._dof_idx)} degrees of "
                f"freedom ({', '.join(DOF_NAMES[i] for i in self._dof_idx)})"
            )
        if isinstance(legs, CrankLegs) and not np.all(legs.reachable0):
            bad = [names[i] for i in np.flatnonzero(~legs.reachable0)]
            raise ConfigError(f"crank legs {bad} cannot reach their rod at the neutral pose")
        jac0 = self._jacobian_one([0.0] * 6)[:, self._dof_idx]
        # more actuators than degrees of freedom (a corner rig's fourth leg): the Jacobian
        # must still have full column rank, and forward kinematics solves in least squares
        if not np.linalg.cond(jac0) < 1e10:
            raise ConfigError(
                "the geometry is singular at the neutral pose (the actuators cannot hold "
                f"{', '.join(DOF_NAMES[i] for i in self._dof_idx)} there)"
            )
        set_fields(self, _square=jac0.shape[0] == jac0.shape[1], _jac0_inv=np.linalg.pinv(jac0))
        fk = self.forward(home)
        if not fk.converged:
            raise ConfigError(
                f"no pose puts the actuators at their homed positions {home.tolist()} "
                "(from neutral): is the stroke minimum possible for this geometry?"
            )
        set_fields(self, pose_park=readonly(fk.pose))

    name: str
    description: str
    actuator_names: tuple[str, ...]
    n_actuators: int
    actuator_kinds: tuple[str, ...]
    dof_mask: NDArray[np.bool_]
    q_neutral: NDArray[np.float64]
    q_min: NDArray[np.float64]
    q_max: NDArray[np.float64]
    q_park: NDArray[np.float64]
    pose_park: NDArray[np.float64]
    neutral_absolute: NDArray[np.float64]
    drives: Drive
    _legs: LegSet
    _leg_mask: NDArray[np.float64]  # 1.0 or 0.0 per pose component, a multiplier
    _leg_mask_list: list[bool]
    _all_dof_legs: bool
    _fast_linear: LinearLegs | None
    _jac0_inv: NDArray[np.float64]
    _yaw_axis: bool
    _yaw_arm: float | None
    _n_spare: int
    _tail: list[float]
    _init_args: _PlatformArgs
    _square: bool
    _dof_idx: NDArray[np.intp]
    _dof_list: list[int]

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"{type(self).__name__} is frozen; cannot set {key!r}")

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(name={self.name!r}, actuators={list(self.actuator_names)}, "
            f"dof={[d for d, m in zip(DOF_NAMES, self.dof_mask, strict=True) if m]})"
        )

    # --- inverse kinematics -------------------------------------------------------------
    def _features_t(self, poses: NDArray[np.float64]) -> NDArray[np.float64]:
        """Transposed features ``(13, N)``: R entries, translation, 1 (masked pose)."""
        a = poses.T
        if not self._all_dof_legs:
            a = a * self._leg_mask[:, None]
        f = np.empty((13, poses.shape[0]))
        cr, sr = np.cos(a[3]), np.sin(a[3])
        cp, sp = np.cos(a[4]), np.sin(a[4])
        cy, sy = np.cos(a[5]), np.sin(a[5])
        spsr = sp * sr
        spcr = sp * cr
        np.multiply(cy, cp, out=f[0])
        f[1] = cy * spsr - sy * cr
        f[2] = cy * spcr + sy * sr
        np.multiply(sy, cp, out=f[3])
        f[4] = sy * spsr + cy * cr
        f[5] = sy * spcr - cy * sr
        np.negative(sp, out=f[6])
        np.multiply(cp, sr, out=f[7])
        np.multiply(cp, cr, out=f[8])
        f[9:12] = a[0:3]
        f[12] = 1.0
        return f

    def _ik_block(
        self, poses: NDArray[np.float64], want_reach: bool
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """q and reachable for a block ``(N, 6)`` of validated poses."""
        legs = self._legs
        n_pose = poses.shape[0]
        feat_t = self._features_t(poses)
        if isinstance(legs, LinearLegs):
            q_legs = legs.q_from_features_t(feat_t).T
            reach = np.ones((n_pose, legs.n), dtype=bool) if want_reach else _NO_REACH
        else:
            q_legs, reach = legs.q(legs.vectors(feat_t.T))
        if self._yaw_axis or self._n_spare:
            parts = [q_legs]
            reach_parts = [reach]
            if self._yaw_axis:
                q_yaw, yaw_ok = self._yaw_q(poses[:, 5])
                parts.append(q_yaw[:, None])
                reach_parts.append(yaw_ok[:, None])
            parts.append(np.zeros((n_pose, self._n_spare)))
            q = np.concatenate(parts, axis=1)
            if want_reach:
                reach_parts.append(np.ones((n_pose, self._n_spare), dtype=bool))
                reach = np.concatenate(reach_parts, axis=1)
            return q, reach
        return q_legs, reach

    def _yaw_q(self, yaw: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Yaw-axis position ``(N,)`` and reachable ``(N,)`` for yaw angles ``(N,)`` (rad).

        A turntable (no arm): ``q = yaw`` (rad). A traction-loss slider with arm ``L``: a pin
        at ``L`` behind the pivot in a slot of the seat, pushed sideways by a linear actuator:
        ``q = L tan(yaw)`` (m); beyond +-89 deg the pin leaves any slot (unreachable, ``q``
        held at its +-89 deg value).
        """
        arm = self._yaw_arm
        if arm is None:
            return yaw.copy(), np.ones(yaw.shape, dtype=bool)
        ok = np.abs(yaw) < _TL_MAX_RAD
        return arm * np.tan(np.clip(yaw, -_TL_MAX_RAD, _TL_MAX_RAD)), ok

    def _yaw_q_one(self, yaw: float) -> tuple[float, bool]:
        arm = self._yaw_arm
        if arm is None:
            return yaw, True
        return arm * math.tan(min(max(yaw, -_TL_MAX_RAD), _TL_MAX_RAD)), abs(yaw) < _TL_MAX_RAD

    def _yaw_dq(self, yaw: float) -> float:
        """``d q / d yaw`` of the yaw axis (1 for a turntable, ``L / cos(yaw)^2`` for TL)."""
        arm = self._yaw_arm
        if arm is None:
            return 1.0
        c = math.cos(min(max(yaw, -_TL_MAX_RAD), _TL_MAX_RAD))
        return arm / (c * c)

    def _inverse_one(self, pose: list[float]) -> list[float]:
        fast = self._fast_linear
        if fast is not None:
            total = sum(pose)  # NaN or inf anywhere makes this NaN or inf
            if total - total == 0.0:
                x, y, z, roll, pitch, yaw = pose
                return fast.q_pose_one(rot_one(roll, pitch, yaw), x, y, z)
        return self._inverse_one_checked(pose)[0]

    def _inverse_one_checked(self, pose: list[float]) -> tuple[list[float], bool]:
        _, q, reachable = self._eval_one(pose)
        return q, reachable

    def _eval_one(
        self, pose: list[float]
    ) -> tuple[list[tuple[float, float, float]], list[float], bool]:
        """Leg vectors, actuator positions and reachability for one pose (plain floats)."""
        for v in pose:
            if not math.isfinite(v):
                raise _bad_input("poses", np.asarray(pose))
        m = self._leg_mask_list
        x, y, z, roll, pitch, yaw = [v if keep else 0.0 for v, keep in zip(pose, m, strict=True)]
        legs = self._legs
        d = legs.vectors_one(rot_one(roll, pitch, yaw), (x, y, z))
        q, reachable = legs.q_one_checked(d)
        if self._yaw_axis:
            q_yaw, yaw_ok = self._yaw_q_one(pose[5])
            q.append(q_yaw)
            reachable = reachable and yaw_ok
        if self._n_spare:
            q.extend(self._tail)
        return d, q, reachable

    def inverse(self, poses: npt.ArrayLike) -> NDArray[np.float64]:
        """Actuator positions for poses, in closed form.

        Parameters
        ----------
        poses
            ``(..., 6)`` [x, y, z, roll, pitch, yaw] (m, rad) from the neutral pose. Pose
            components the machine cannot produce are held at zero (see :meth:`check`).

        Returns
        -------
        ndarray ``(..., n)``
            m (linear) or rad (rotary), from neutral. Where a crank cannot reach (rotary), the
            angle of closest approach; :meth:`check` flags it.

        Raises
        ------
        ConfigError
            Wrong shape, NaN or inf in ``poses`` (the message names the element).
        """
        if isinstance(poses, np.ndarray):
            if poses.shape == (6,):
                return np.array(self._inverse_one(poses.tolist()))
        elif (
            isinstance(poses, list | tuple)
            and len(poses) == 6
            and not isinstance(poses[0], list | tuple | np.ndarray)
        ):
            return np.array(self._inverse_one([float(v) for v in poses]))
        return self._inverse_batch(_as_poses(poses))[0]

    def _inverse_batch(
        self, arr: NDArray[np.float64], want_reach: bool = False
    ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """q ``(..., n)`` and, when ``want_reach``, reachable ``(..., n)`` (else empty)."""
        lead = arr.shape[:-1]
        flat = arr.reshape(-1, 6)
        total = flat.shape[0]
        n = self.n_actuators
        if total <= _CHUNK:
            q, reach = self._ik_block(flat, want_reach)
        else:
            q = np.empty((total, n))
            reach = np.empty((total, n), dtype=bool) if want_reach else _NO_REACH
            for start in range(0, total, _CHUNK):
                stop = min(start + _CHUNK, total)
                q[start:stop], r = self._ik_block(flat[start:stop], want_reach)
                if want_reach:
                    reach[start:stop] = r
        if not want_reach:
            return q.reshape(*lead, n), _NO_REACH
        return q.reshape(*lead, n), reach.reshape(*lead, n)

    def same_kinematics(self, other: Platform, atol: float = 1e-9) -> bool:
        """Whether ``other`` moves as this machine does: the same actuator kinds in the same
        order, degrees of freedom, usable stroke and neutral positions, and the same
        :meth:`inverse` (within ``atol``, m or rad) at neutral and at small steps of each
        degree of freedom it produces. Drives, homing, limits and names may differ (seat3 and
        seat3-pot: one seat on two kinds of actuator). A plan tuned for one fits the other.
        """
        if (
            self.actuator_kinds != other.actuator_kinds
            or not np.array_equal(self.dof_mask, other.dof_mask)
            or not np.allclose(self.q_min, other.q_min, rtol=0.0, atol=atol)
            or not np.allclose(self.q_max, other.q_max, rtol=0.0, atol=atol)
            or not np.allclose(self.neutral_absolute, other.neutral_absolute, rtol=0.0, atol=atol)
        ):
            return False
        step = np.array([0.01, 0.01, 0.01, 0.03, 0.03, 0.03])  # m, rad: inside any stroke
        poses = np.vstack([np.zeros(6), np.diag(step), -np.diag(step), step / 2.0])
        return bool(np.allclose(self.inverse(poses), other.inverse(poses), rtol=0.0, atol=atol))

    # --- Jacobian -----------------------------------------------------------------------
    def jacobian(self, poses: npt.ArrayLike) -> NDArray[np.float64]:
        """``d q / d pose`` for poses ``(..., 6)``; returns ``(..., n, 6)``.

        Columns of pose components the machine does not produce are zero (``inverse`` holds
        them at zero). Angles are the Euler angles of the pose vector, not body rates.
        """
        arr = _as_poses(poses)
        lead = arr.shape[:-1]
        flat = arr.reshape(-1, 6)
        n = self.n_actuators
        if flat.shape[0] <= _JAC_CHUNK:
            return self._jacobian_block(flat).reshape(*lead, n, 6)
        out = np.empty((flat.shape[0], n, 6))
        for start in range(0, flat.shape[0], _JAC_CHUNK):
            out[start : start + _JAC_CHUNK] = self._jacobian_block(flat[start : start + _JAC_CHUNK])
        return out.reshape(*lead, n, 6)

    def _jacobian_block(self, flat: NDArray[np.float64]) -> NDArray[np.float64]:
        legs = self._legs
        m = self._leg_mask
        ang = flat[:, 3:6] * m[3:6]
        feat = np.empty((flat.shape[0], 13))
        feat[:, :9] = rot9(ang)
        feat[:, 9:12] = flat[:, 0:3] * m[0:3]
        feat[:, 12] = 1.0
        d = legs.vectors(feat)
        q, _ = legs.q(d)
        g = legs.gradient(d, q)  # (N, nl, 3)
        dp = legs.anchor_derivatives(rot9_derivatives(ang))  # (N, 3, nl, 3)
        jac = np.zeros((flat.shape[0], self.n_actuators, 6))
        jac[:, : legs.n, 0:3] = g
        jac[:, : legs.n, 3:6] = np.einsum("nij,nkij->nik", g, dp)
        jac[:, : legs.n, :] *= m
        if self._yaw_axis:
            if self._yaw_arm is None:
                jac[:, legs.n, 5] = 1.0
            else:
                c = np.cos(np.clip(flat[:, 5], -_TL_MAX_RAD, _TL_MAX_RAD))
                jac[:, legs.n, 5] = self._yaw_arm / (c * c)
        return jac

    def _jacobian_one(
        self,
        pose: list[float],
        d: list[tuple[float, float, float]] | None = None,
        q: list[float] | None = None,
    ) -> NDArray[np.float64]:
        """``(n, 6)`` Jacobian for one pose; ``d`` and ``q`` from :meth:`_eval_one` if known."""
        if d is None or q is None:
            d, q, _ = self._eval_one(pose)
        x, y, z, roll, pitch, yaw = [
            v if keep else 0.0 for v, keep in zip(pose, self._leg_mask_list, strict=True)
        ]
        legs = self._legs
        rows = legs.jacobian_one(d, q[: legs.n], (x, y, z), (roll, pitch, yaw))
        nl = len(rows)
        # the yaw axis' row and the spare axes' zero rows go in before the one conversion
        # (no vstack per row block); the leg mask multiplies the leg rows only, as before
        if self._yaw_axis:
            rows.append([0.0, 0.0, 0.0, 0.0, 0.0, self._yaw_dq(pose[5])])
        if self._n_spare:
            rows.extend([0.0] * 6 for _ in range(self._n_spare))
        jac: NDArray[np.float64] = np.array(rows, dtype=float)
        if not self._all_dof_legs:
            jac[:nl] *= self._leg_mask
        return jac

    # --- forward kinematics -------------------------------------------------------------
    @property
    def q_rounding(self) -> NDArray[np.float64]:
        """``(n,)`` one pulse of each actuator's drive (m or rad): the resolution of the
        positions a controller is sent, and the default tolerance of :meth:`forward`."""
        cached = self.__dict__.get("_q_rounding")
        if cached is None:
            cached = readonly(1.0 / np.abs(self.drives.pulses_per_unit))
            set_fields(self, _q_rounding=cached)
        out: NDArray[np.float64] = cached
        return out

    def forward(
        self,
        q: npt.ArrayLike,
        guess: npt.ArrayLike | None = None,
        *,
        tol: float = 1e-12,
        max_iter: int = 50,
        rounding: npt.ArrayLike | None = None,
    ) -> FKResult:
        """Pose for actuator positions, by Newton's method on the closed-form inverse, with a
        least-squares fallback that converges wherever a ride can go.

        With more moving actuators than degrees of freedom (a corner rig's fourth leg) the
        steps are Gauss-Newton (least squares): positions no rigid pose gives (they would twist
        the frame) end with ``converged=False`` and ``residual`` = how far the nearest rigid
        pose is from them (see :meth:`project`). Positions rounded to pulses twist the frame
        by up to about a pulse: within ``rounding`` of a rigid pose, the status is
        ``"rounded"`` (``FKResult.ok``); beyond it ``"inconsistent"``.

        A starting guess from which the iteration fails (one where a crank cannot reach its
        rod, or too far away) is abandoned for the neutral pose, which every platform reaches;
        the result is the better of the two runs, and ``iterations`` counts both. When neither
        ends within the rounding, a damped least-squares solve (``scipy.optimize.
        least_squares``, Levenberg-Marquardt) of the leg closure equations follows from the
        guess, from Newton's best pose, from neutral and along a continuation from neutral;
        it lets a crank leg pass the point where crank and rod align onto its other assembly
        branch (which a ride through that point does).

        Parameters
        ----------
        q
            ``(n,)`` actuator positions (m or rad, from neutral).
        guess
            ``(6,)`` starting pose (the previous frame's, in a ride); the neutral pose when
            None.
        tol
            Convergence threshold on the max abs actuator residual (m or rad).
        max_iter
            Iteration limit (per Newton start).
        rounding
            Per-actuator tolerance ``(n,)`` or one number (m or rad) within which positions
            count as a rigid pose's (status ``"rounded"``); default :attr:`q_rounding` (one
            pulse).

        Returns
        -------
        FKResult
        """
        qv = np.asarray(q, dtype=float)
        n = self.n_actuators
        if qv.shape != (n,):
            raise ConfigError(f"q has shape {qv.shape}; expected ({n},)")
        if not np.isfinite(qv).all():
            raise _bad_input("q", qv)
        if rounding is None:
            tol_q = self.q_rounding
        else:
            tol_q = np.broadcast_to(np.asarray(rounding, dtype=float), (n,)).copy()
            if not (np.all(np.isfinite(tol_q)) and np.all(tol_q >= 0.0)):
                raise ConfigError(
                    f"rounding = {rounding!r} is invalid; allowed: finite numbers >= 0 (m or rad)"
                )
        tol_q = np.maximum(tol_q, tol)
        idx = self._dof_list
        target = qv.tolist()
        if guess is None:
            best = self._newton([0.0] * 6, target, idx, True, tol, max_iter, 0)
            start = None
        else:
            g = np.asarray(guess, dtype=float)
            if g.shape != (6,) or not np.isfinite(g).all():
                raise ConfigError(f"guess = {g!r} is invalid; allowed: 6 finite numbers")
            pose = [0.0] * 6
            for k in idx:
                pose[k] = float(g[k])
            start = pose
            best = self._newton(pose, target, idx, False, tol, max_iter, 0)
            if not best.converged and not self._within(best, tol_q):
                again = self._newton([0.0] * 6, target, idx, True, tol, max_iter, best.iterations)
                if again.residual <= best.residual:
                    best = again
                else:
                    best = replace(best, iterations=again.iterations)
        if best.converged:  # the usual case: Newton found the pose
            return FKResult(
                best.pose, True, best.iterations, best.residual, "exact", best.residuals, tol_q
            )
        r = self._residuals(best.pose, qv)
        if not np.all(np.abs(r) <= tol_q):
            starts = [best.pose.tolist()] + ([start] if start is not None else []) + [[0.0] * 6]
            pose_ls = self._least_squares(qv, idx, starts, tol_q)
            r_ls = self._residuals(pose_ls, qv)
            if np.max(np.abs(r_ls) / tol_q) < np.max(np.abs(r) / tol_q):
                best, r = replace(best, pose=pose_ls), r_ls
        residual = float(np.max(np.abs(r))) if np.all(np.isfinite(r)) else math.inf
        if residual <= tol:
            status = "exact"
        elif np.all(np.abs(r) <= tol_q):
            status = "rounded"
        else:
            status = "inconsistent"
        return replace(
            best,
            converged=bool(residual <= tol),
            residual=residual,
            status=status,
            residuals=r,
            tolerance=tol_q,
        )

    @staticmethod
    def _within(fk: FKResult, tol_q: NDArray[np.float64]) -> bool:
        r = fk.residuals
        return r is not None and bool(np.all(np.abs(r) <= tol_q))

    def _residuals(self, pose: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        """``q - q(pose)`` ``(n,)``; a crank leg compared with the nearer assembly branch."""
        pl = [float(v) for v in pose]
        d, cur, reachable = self._eval_one(pl)
        r: NDArray[np.float64] = q - np.asarray(cur, dtype=float)
        legs = self._legs
        if isinstance(legs, CrankLegs):
            nl = legs.n
            a, b, c = legs._abc(np.asarray(d, dtype=float)[None])
            rho = np.hypot(a[0], b[0])
            ratio = np.divide(c[0], rho, out=np.full_like(rho, 2.0), where=rho > 0)
            other = np.arctan2(b[0], a[0]) - legs.branch * np.arccos(np.clip(ratio, -1.0, 1.0))
            q_other = (other - legs.theta0 + math.pi) % (2.0 * math.pi) - math.pi
            r_other = q[:nl] - q_other
            r_other = (r_other + math.pi) % (2.0 * math.pi) - math.pi
            r[:nl] = (r[:nl] + math.pi) % (2.0 * math.pi) - math.pi
            r[:nl] = np.where(np.abs(r_other) < np.abs(r[:nl]), r_other, r[:nl])
            # an unreachable crank (rod too short or too long for the pose) is no solution
            r[:nl] = np.where(np.abs(ratio) <= 1.0, r[:nl], np.inf)
        elif not reachable:
            r[:] = np.inf
        return r

    def _closure(self, q: NDArray[np.float64]) -> Callable[[list[float]], NDArray[np.float64]]:
        """The leg closure residuals ``f(pose)`` for positions ``q``: zero exactly where a
        pose gives ``q``, smooth everywhere, whatever the crank's assembly branch: leg length
        minus the actuator's length (m) for linear legs, distance from crank tip to anchor
        minus the rod length (m) for crank legs, the yaw axis' position error (m or rad)."""
        legs = self._legs
        nl = legs.n
        mask = self._leg_mask_list
        if isinstance(legs, LinearLegs):
            want = legs.length0 + q[:nl]
            tips = np.zeros((nl, 3))
        else:
            assert isinstance(legs, CrankLegs)
            tips, _ = legs.crank_vectors(q[None, :nl])
            tips = tips[0]
            want = legs.rod
        q_yaw = float(q[nl]) if self._yaw_axis else 0.0

        def f(pose: list[float]) -> NDArray[np.float64]:
            x, y, z, roll, pitch, yaw = (v if m else 0.0 for v, m in zip(pose, mask, strict=True))
            d = np.asarray(legs.vectors_one(rot_one(roll, pitch, yaw), (x, y, z)), dtype=float)
            out = np.asarray(np.linalg.norm(d - tips, axis=1) - want, dtype=float)
            if self._yaw_axis:
                out = np.append(out, self._yaw_q_one(pose[5])[0] - q_yaw)
            return out

        return f

    def _least_squares(
        self,
        q: NDArray[np.float64],
        idx: list[int],
        starts: list[list[float]],
        tol_q: NDArray[np.float64],
    ) -> NDArray[np.float64]:
        """The best pose of damped least-squares solves of the closure equations from each
        start, then along a continuation from neutral (``t q`` for t = 1/4 .. 1)."""
        from scipy.optimize import least_squares

        def solve(target: NDArray[np.float64], start: list[float]) -> NDArray[np.float64]:
            f = self._closure(target)
            x0 = np.array([start[k] for k in idx])

            def g(x: NDArray[np.float64]) -> NDArray[np.float64]:
                pose = [0.0] * 6
                for j, k in enumerate(idx):
                    pose[k] = float(x[j])
                return f(pose)

            try:
                sol = least_squares(
                    g, x0, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=400
                )
                x = sol.x
            except (ValueError, np.linalg.LinAlgError):
                x = x0
            pose = np.zeros(6)
            pose[idx] = x
            return pose

        best = np.zeros(6)
        best_score = math.inf
        for start in starts:
            pose = solve(q, start)
            score = float(np.max(np.abs(self._residuals(pose, q)) / tol_q))
            if score < best_score:
                best, best_score = pose, score
            if best_score <= 1.0:
                return best
        pose = np.zeros(6)
        for t in (0.25, 0.5, 0.75, 1.0):
            pose = solve(t * q, pose.tolist())
        score = float(np.max(np.abs(self._residuals(pose, q)) / tol_q))
        return pose if score < best_score else best

    def _newton(
        self,
        pose: list[float],
        target: list[float],
        idx: list[int],
        from_neutral: bool,
        tol: float,
        max_iter: int,
        done: int,
    ) -> FKResult:
        """Newton (Gauss-Newton) iterations from ``pose``; ``done`` iterations already spent."""
        square = self._square
        d, cur, reachable = self._eval_one(pose)
        r = [c - t for c, t in zip(cur, target, strict=True)]
        sq = sum(v * v for v in r) if reachable else math.inf
        iterations = 0
        # Newton with backtracking: a full step is taken whenever it lowers the residual (the
        # usual case, quadratic convergence); otherwise, or when it leaves the region where
        # every crank reaches its rod, the step is halved. An unreachable start cannot be
        # improved on (its residual is not a distance): the caller restarts from neutral.
        while reachable and max(map(abs, r)) > tol and iterations < max_iter:
            iterations += 1
            if iterations == 1 and from_neutral:
                step = (self._jac0_inv @ r).tolist()  # Jacobian at neutral, inverted once
            else:
                jac = self._jacobian_one(pose, d, cur)
                if len(idx) != 6:
                    jac = jac[:, idx]
                try:
                    if square:
                        step = np.linalg.solve(jac, r).tolist()
                    else:
                        step = np.linalg.lstsq(jac, np.asarray(r), rcond=None)[0].tolist()
                except np.linalg.LinAlgError:
                    break
            if not all(math.isfinite(v) for v in step):
                break
            alpha = 1.0
            for _ in range(30):
                trial = pose[:]
                for j, k in enumerate(idx):
                    trial[k] -= alpha * step[j]
                d_new, cur_new, ok = self._eval_one(trial)
                r_new = [c - t for c, t in zip(cur_new, target, strict=True)]
                sq_new = sum(v * v for v in r_new)
                if sq_new < sq and ok:
                    break
                alpha *= 0.5
            else:
                break
            stalled = not square and sq - sq_new <= 1e-9 * sq  # at the least-squares minimum
            pose, d, cur, r, sq = trial, d_new, cur_new, r_new, sq_new
            if stalled:
                break
        residual = max(map(abs, r)) if reachable else math.inf
        if not reachable and iterations == 0:
            iterations = 1  # the unreachable start was evaluated and given up
        return FKResult(
            pose=np.array(pose),
            converged=bool(residual <= tol),
            iterations=done + iterations,
            residual=residual,
            residuals=-np.array(r) if reachable else np.full(len(r), np.inf),
        )

    def project(
        self, q: npt.ArrayLike, *, tol: float = 1e-9
    ) -> tuple[NDArray[np.float64], str | None]:
        """The actuator positions of the rigid pose nearest to ``q`` (least squares).

        On a platform with as many moving actuators as degrees of freedom every reachable
        ``q`` is its own projection. With more (a corner rig: four legs, three degrees of
        freedom) positions that no rigid pose gives would twist the frame; they are replaced
        by the nearest positions a rigid frame can take.

        Parameters
        ----------
        q
            ``(n,)`` actuator positions (m or rad, from neutral).
        tol
            Largest change (m or rad) accepted as "consistent" without a note.

        Returns
        -------
        q_rigid : ndarray ``(n,)``
            Positions of the nearest rigid pose.
        note : str or None
            None when ``q`` is consistent within ``tol``; otherwise one line saying which
            actuator moved and by how much (the frame would have been twisted).
        """
        qv = np.asarray(q, dtype=float)
        fk = self.forward(qv)
        # the positions of the pose found, a crank on the assembly branch nearer to q
        r = fk.residuals
        q_rigid = self.inverse(fk.pose) if r is None or not np.all(np.isfinite(r)) else qv - r
        change = q_rigid - qv
        worst = int(np.argmax(np.abs(change)))
        if abs(change[worst]) <= tol:
            return q_rigid, None
        linear = self.actuator_kinds[worst] == "linear"
        unit, scale = ("mm", 1e3) if linear else ("deg", 180 / math.pi)
        moved = change[worst] * scale
        return q_rigid, (
            f"actuator positions {np.round(qv * scale, 6).tolist()} would twist the rigid "
            f"frame of {self.name}: no pose gives them; projected to the nearest rigid pose "
            f"(actuator {self.actuator_names[worst]!r} moved by {moved:+.6g} {unit})"
        )

    # --- checks -------------------------------------------------------------------------
    def check(self, poses: npt.ArrayLike) -> CheckResult:
        """Per actuator: in stroke or not and by how much, reachable or not; as data.

        Parameters
        ----------
        poses
            ``(..., 6)`` poses (m, rad).

        Returns
        -------
        CheckResult
        """
        arr = _as_poses(poses)
        q, reach = self._inverse_batch(arr, want_reach=True)
        above = q > self.q_max
        below = q < self.q_min
        overshoot = np.where(above, q - self.q_max, np.where(below, q - self.q_min, 0.0))
        in_stroke = ~(above | below)
        unsupported = (arr != 0.0) & ~self.dof_mask
        ok = np.all(in_stroke & reach, axis=-1)
        return CheckResult(
            q=q,
            in_stroke=in_stroke,
            overshoot=overshoot,
            reachable=reach,
            unsupported=unsupported,
            ok=ok,
        )

    def absolute(self, q: npt.ArrayLike) -> NDArray[np.float64]:
        """Pin-to-pin length (m) or crank angle from its zero direction (rad), ``(..., n)``."""
        return np.asarray(q, dtype=float) + self.neutral_absolute

    @property
    def legs(self) -> LegSet:
        """The leg set (anchors in SI) for force computations and plots."""
        return self._legs

    @property
    def has_yaw_axis(self) -> bool:
        """True when the last actuator is a direct yaw axis (turntable)."""
        return self._yaw_axis


def _rebuilt(old: Platform, args: _PlatformArgs) -> Platform:
    out = Platform(**args)
    if old.default_preset is not None:
        out = out.with_default_preset(old.default_preset)
    if old.ride_preset is not None:
        out = out.with_ride_preset(old.ride_preset)
    return out


def _default_drives(kinds: tuple[str, ...], q_min: NDArray[np.float64]) -> Drive:
    """Drives for user geometries that name none: 5 mm lead, 10000 pulses/rev (linear) or
    gear 50, 10000 pulses/rev (rotary), homed at the bottom of the usable stroke."""
    parts = []
    for i, kind in enumerate(kinds):
        if kind == "linear":
            parts.append(Drive.linear(0.005, 10000, [q_min[i]]))
        else:
            parts.append(Drive.rotary(50.0, 10000, [q_min[i]]))
    return Drive.concat(*parts)


def _anchors(name: str, value: npt.ArrayLike, n: int) -> NDArray[np.float64]:
    arr = np.asarray(value, dtype=float)
    if arr.shape != (n, 3) or not np.isfinite(arr).all():
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: ({n}, 3) finite numbers (m)")
    return arr


def _names(value: Sequence[str] | None, n: int, prefix: str = "") -> tuple[str, ...]:
    if value is None:
        return tuple(f"{prefix}{i + 1}" for i in range(n))
    return tuple(value)


def _positive(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v) or v <= 0:
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: a finite number > 0")
    return v


def _ranges(name: str, value: npt.ArrayLike, n: int, allowed: str) -> NDArray[np.float64]:
    """``(n, 2)`` rows ``(min, max)`` from one pair for all ``n`` actuators or one pair each,
    finite with ``min < max``; else :class:`ConfigError` naming ``name``, the value and
    ``allowed``."""
    arr = np.asarray(value, dtype=float)
    if arr.shape == (2,):
        arr = np.broadcast_to(arr, (n, 2))
    if arr.shape != (n, 2) or not np.isfinite(arr).all() or np.any(arr[:, 0] >= arr[:, 1]):
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: {allowed}")
    return arr


def _length_stroke(
    legs: LinearLegs, stroke: npt.ArrayLike
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    arr = _ranges(
        "stroke",
        stroke,
        legs.n,
        "(min_length_m, max_length_m) with min < max, or one such pair per leg",
    )
    if np.any(arr[:, 0] <= 0):
        raise ConfigError(f"stroke = {stroke!r} is invalid; allowed: lengths > 0")
    return arr[:, 0] - legs.length0, arr[:, 1] - legs.length0


class LinearLegPlatform(Platform):
    """Platforms whose actuators are all linear legs between base and platform anchors.

    A subclass fixes the leg count :attr:`N_LEGS`, the pose components the legs produce
    :attr:`DOF_MASK` (``[x, y, z, roll, pitch, yaw]``) and the default name; the config
    reader of such a kind is :func:`~motioncue.kinematics.linear_legs_reader`.

    Parameters
    ----------
    base_anchors, platform_anchors
        ``(N_LEGS, 3)`` lower and upper joint centres (m), base and platform frames; leg i
        joins base anchor i to platform anchor i.
    neutral_height
        Height of the platform frame above the base frame at the neutral pose (m).
    stroke
        ``(min_length_m, max_length_m)`` usable pin-to-pin length, or ``(N_LEGS, 2)``.
    drives
        Drives (pulses); default 5 mm lead, 10000 pulses/rev, homed at the usable minimum.
    """

    N_LEGS: int = 6
    DOF_MASK: tuple[bool, ...] = (True,) * 6
    DEFAULT_NAME: str = ""

    def __init__(
        self,
        base_anchors: npt.ArrayLike,
        platform_anchors: npt.ArrayLike,
        neutral_height: float,
        stroke: npt.ArrayLike,
        *,
        drives: Drive | None = None,
        name: str | None = None,
        actuator_names: Sequence[str] | None = None,
        description: str = "",
    ) -> None:
        n = self.N_LEGS
        legs, q_min, q_max = _linear_legs(base_anchors, platform_anchors, neutral_height, stroke, n)
        super().__init__(
            name=self.DEFAULT_NAME if name is None else name,
            actuator_names=_names(actuator_names, n),
            legs=legs,
            leg_pose_mask=list(self.DOF_MASK),
            dof_mask=list(self.DOF_MASK),
            q_min=q_min,
            q_max=q_max,
            drives=drives,
            description=description,
        )


def _linear_legs(
    base_anchors: npt.ArrayLike,
    platform_anchors: npt.ArrayLike,
    neutral_height: float,
    stroke: npt.ArrayLike,
    n: int,
) -> tuple[LinearLegs, NDArray[np.float64], NDArray[np.float64]]:
    """``n`` linear legs from validated anchors (m), and their stroke from neutral (m)."""
    legs = LinearLegs(
        _anchors("base_anchors", base_anchors, n),
        _anchors("platform_anchors", platform_anchors, n),
        _finite("neutral_height", neutral_height),
    )
    q_min, q_max = _length_stroke(legs, stroke)
    return legs, q_min, q_max


class Stewart6Linear(LinearLegPlatform):
    """6-DOF hexapod with six linear actuators (electric cylinders), SI geometry.

    Parameters are those of :class:`LinearLegPlatform` with ``(6, 3)`` anchors.
    """

    N_LEGS = 6
    DOF_MASK = (True,) * 6
    DEFAULT_NAME = "stewart6-linear"


class Seat3(LinearLegPlatform):
    """3-actuator heave/pitch/roll seat: three linear legs, x, y and yaw held by a central
    guide (so the platform frame origin is the centre of rotation).

    Parameters are those of :class:`LinearLegPlatform` with ``(3, 3)`` anchors.
    """

    N_LEGS = 3
    DOF_MASK = (False, False, True, True, True, False)
    DEFAULT_NAME = "seat3"


class Corner4(LinearLegPlatform):
    """4-actuator corner rig: one linear leg under each corner of a rigid cockpit frame; heave,
    pitch and roll, with x, y and yaw held by the frame (its guide or its own stiffness).

    Three degrees of freedom on four legs: the inverse is closed form (each leg's length for
    the pose), the fourth leg follows from the other three. Positions no rigid pose gives
    (they would twist the frame) are found by :meth:`forward` (``converged=False``) and
    replaced by the nearest rigid ones by :meth:`project`. Legs may stand vertical (base and
    platform anchors one above the other) or at a measured angle.

    Parameters are those of :class:`LinearLegPlatform` with ``(4, 3)`` anchors, the platform
    frame origin being the centre the frame pitches and rolls about.
    """

    N_LEGS = 4
    DOF_MASK = (False, False, True, True, True, False)
    DEFAULT_NAME = "corner4"


class Seat2Yaw(Platform):
    """Two linear legs tilting the seat (pitch, roll) about a central universal joint at the
    platform frame origin, on a turntable giving yaw (the IMAX "rotating axis", PA03).

    The turntable carries the tilting mechanism, so the legs see roll and pitch only, and the
    last actuator is the yaw angle itself.

    Parameters
    ----------
    base_anchors, platform_anchors
        ``(2, 3)`` leg joint centres (m), in the turntable frame and the platform frame.
    neutral_height
        Height of the universal joint (platform frame origin) above the base frame (m).
    stroke
        ``(min_length_m, max_length_m)`` of the legs.
    yaw_range
        ``(min_rad, max_rad)`` usable yaw.
    """

    def __init__(
        self,
        base_anchors: npt.ArrayLike,
        platform_anchors: npt.ArrayLike,
        neutral_height: float,
        stroke: npt.ArrayLike,
        yaw_range: npt.ArrayLike,
        *,
        drives: Drive | None = None,
        name: str = "seat2-yaw",
        actuator_names: Sequence[str] | None = None,
        description: str = "",
    ) -> None:
        legs, q_min, q_max = _linear_legs(base_anchors, platform_anchors, neutral_height, stroke, 2)
        yr = np.asarray(yaw_range, dtype=float)
        if yr.shape != (2,) or not np.isfinite(yr).all() or not (yr[0] < 0 < yr[1]):
            raise ConfigError(
                f"yaw_range = {yaw_range!r} is invalid; allowed: (min_rad < 0 < max_rad)"
            )
        super().__init__(
            name=name,
            actuator_names=_names(actuator_names, 3),
            legs=legs,
            leg_pose_mask=[False, False, False, True, True, False],
            dof_mask=[False, False, False, True, True, True],
            q_min=[*q_min, yr[0]],
            q_max=[*q_max, yr[1]],
            drives=drives,
            yaw_axis=True,
            description=description,
        )


class Stewart6Rotary(Platform):
    """6-DOF hexapod with crank-and-rod legs (servo arms), SI geometry.

    Parameters
    ----------
    base_pivots
        ``(6, 3)`` crank pivot centres in the base frame (m).
    crank_axes
        ``(6, 3)`` crank axis directions (unit vectors, normalised here).
    crank_zero_dirs
        ``(6, 3)`` crank direction at angle 0, perpendicular to the axis; the crank angle
        grows by the right-hand rule about the axis.
    crank_length, rod_length
        Scalars or ``(6,)`` (m).
    platform_anchors
        ``(6, 3)`` rod ends in the platform frame (m).
    neutral_height
        Height of the platform frame above the base frame at the neutral pose (m).
    crank_range
        ``(min_rad, max_rad)`` usable crank angle from the zero direction, or ``(6, 2)``.
    """

    def __init__(
        self,
        base_pivots: npt.ArrayLike,
        crank_axes: npt.ArrayLike,
        crank_zero_dirs: npt.ArrayLike,
        crank_length: npt.ArrayLike,
        rod_length: npt.ArrayLike,
        platform_anchors: npt.ArrayLike,
        neutral_height: float,
        crank_range: npt.ArrayLike,
        *,
        drives: Drive | None = None,
        name: str = "stewart6-rotary",
        actuator_names: Sequence[str] | None = None,
        description: str = "",
    ) -> None:
        axes = _anchors("crank_axes", crank_axes, 6)
        norms = np.linalg.norm(axes, axis=1)
        if np.any(norms < 1e-9):
            raise ConfigError(f"crank_axes = {crank_axes!r} is invalid; allowed: nonzero vectors")
        axes = axes / norms[:, None]
        zero = _anchors("crank_zero_dirs", crank_zero_dirs, 6)
        zero = zero - np.einsum("ij,ij->i", zero, axes)[:, None] * axes
        zn = np.linalg.norm(zero, axis=1)
        if np.any(zn < 1e-9):
            raise ConfigError(
                f"crank_zero_dirs = {crank_zero_dirs!r} is invalid; allowed: vectors not "
                "parallel to the crank axes"
            )
        zero = zero / zn[:, None]
        crank = np.broadcast_to(np.asarray(crank_length, dtype=float), (6,))
        rod = np.broadcast_to(np.asarray(rod_length, dtype=float), (6,))
        for i in range(6):
            _positive("crank_length", crank[i])
            _positive("rod_length", rod[i])
        legs = CrankLegs(
            _anchors("base_pivots", base_pivots, 6),
            _anchors("platform_anchors", platform_anchors, 6),
            _finite("neutral_height", neutral_height),
            axes,
            zero,
            crank,
            rod,
        )
        cr = _ranges("crank_range", crank_range, 6, "(min_rad, max_rad), min < max")
        super().__init__(
            name=name,
            actuator_names=_names(actuator_names, 6),
            legs=legs,
            leg_pose_mask=[True] * 6,
            dof_mask=[True] * 6,
            q_min=cr[:, 0] - legs.theta0,
            q_max=cr[:, 1] - legs.theta0,
            drives=drives,
            description=description,
        )


def _finite(name: str, value: float) -> float:
    v = float(value)
    if not math.isfinite(v):
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: a finite number")
    return v
