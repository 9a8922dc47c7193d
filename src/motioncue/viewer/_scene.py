"""Geometry of a platform for drawing: base anchors, legs (with crank tips), top, stroke use.

Poses are ``[x, y, z, roll, pitch, yaw]`` (m, rad) from the neutral pose, ISO 8855 axes,
``R = Rz(yaw) Ry(pitch) Rx(roll)`` (see :mod:`motioncue.kinematics`). Points are in the
base frame (m): a platform anchor is ``[x, y, z + h] + R p_i`` with ``h`` the neutral
height of the legs (:attr:`motioncue.kinematics.Platform.legs`). On a platform with a yaw
turntable the legs see the pose without yaw, and the whole drawing turns with the yaw axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError

if TYPE_CHECKING:
    from ..kinematics import FKResult, Platform

__all__ = ["Scene", "at_rest", "outline_order", "scene_from_poses", "scene_from_q", "stroke_use"]

REST_TOLERANCE = 0.005
"""An actuator within this fraction of its usable stroke of its park position is at rest."""


@dataclass(frozen=True, eq=False)
class Scene:
    """A platform's drawing over time.

    Attributes
    ----------
    t_s : (N,) array
        Times (s).
    poses : (N, 6) array
        Poses (m, rad) from neutral.
    q : (N, n) array
        Actuator positions from neutral (m for linear, rad for rotary actuators).
    base : (N, L, 3) array
        Base-fixed end of each leg (m, base frame); L legs (a yaw axis is not a leg).
    joint : (N, L, 3) array or None
        Crank tips (m) of rotary legs; None for linear legs.
    top : (N, L, 3) array
        Platform anchors (m).
    centre : (N, 3) array
        Platform frame origin (m); ``forward`` (N, 3): a point ahead of it along the
        platform's x axis, at 0.6 x the top anchors' radius (m), to show the heading.
    use : (N, n) array
        Stroke use per actuator, 0 at neutral, 1 at either end (:func:`stroke_use`).
    rest : (N, n) bool array or None
        Actuators at their park position (:func:`at_rest`): drawn as at rest, not by their
        stroke use (a parked leg sits near its bottom end by design).
    order : tuple of int
        The legs in the order that draws the base and top outlines without crossing
        (:func:`outline_order`).
    seat : (N, 3, 3) array or None
        A traction-loss slider (:attr:`~motioncue.kinematics.Platform.traction_loss_arm_m`):
        the seat's arm from its pin through the pivot to a point ahead (m), turned by the
        pose's yaw on the top frame; None without a slider.
    rail : (N, 2, 3) array or None
        The ends of the slider's slot (m), on the top frame; None without a slider.
    """

    t_s: NDArray[np.float64]
    poses: NDArray[np.float64]
    q: NDArray[np.float64]
    base: NDArray[np.float64]
    joint: NDArray[np.float64] | None
    top: NDArray[np.float64]
    centre: NDArray[np.float64]
    forward: NDArray[np.float64]
    use: NDArray[np.float64]
    rest: NDArray[np.bool_] | None = None
    order: tuple[int, ...] = ()
    seat: NDArray[np.float64] | None = None
    rail: NDArray[np.float64] | None = None


def stroke_use(platform: Platform, q: ArrayLike) -> NDArray[np.float64]:
    """Fraction of the usable stroke in use: ``max(q / q_max, q / q_min)``, ``(..., n)``.

    0 at the neutral pose, 1 on the stroke's end at either side (more beyond it); ``q_min``
    is negative and ``q_max`` positive (:class:`~motioncue.kinematics.Platform`).
    """
    qa = np.asarray(q, dtype=float)
    lo = np.asarray(platform.q_min, dtype=float)
    hi = np.asarray(platform.q_max, dtype=float)
    return np.asarray(np.maximum(qa / hi, qa / lo), dtype=float)


def at_rest(platform: Platform, q: ArrayLike) -> NDArray[np.bool_]:
    """Which actuators are at their park position, ``(..., n)`` bool.

    At rest: within :data:`REST_TOLERANCE` of the usable stroke (``q_max - q_min``) of
    ``platform.q_park``. Stroke use (:func:`stroke_use`) is the distance from mid-stroke, so
    a parked leg near its bottom end reads 90 % or more; the drawings show such a leg as at
    rest (grey) instead of by its use.
    """
    qa = np.asarray(q, dtype=float)
    park = np.asarray(platform.q_park, dtype=float)
    span = np.asarray(platform.q_max, dtype=float) - np.asarray(platform.q_min, dtype=float)
    out: NDArray[np.bool_] = np.abs(qa - park) <= REST_TOLERANCE * span + 1e-12
    return out


def outline_order(anchors: ArrayLike) -> tuple[int, ...]:
    """Indices of ``anchors (L, 3)`` by angle about their centre in the x-y plane.

    The legs of a platform are numbered as the controller's axes (a corner rig: front left,
    front right, rear left, rear right), which is not the order around the frame; joining
    the anchors in this order draws the outline without crossing itself.
    """
    a = np.asarray(anchors, dtype=float)
    if a.shape[0] < 3:
        return tuple(range(a.shape[0]))
    d = a[:, :2] - a[:, :2].mean(axis=0)
    return tuple(int(i) for i in np.argsort(np.arctan2(d[:, 1], d[:, 0]), kind="stable"))


def _rotation(angles: NDArray[np.float64]) -> NDArray[np.float64]:
    from ..kinematics._rotation import rotation_matrix

    return rotation_matrix(angles)


def _check_times(t_s: ArrayLike, n: int) -> NDArray[np.float64]:
    t = np.asarray(t_s, dtype=float)
    if t.shape != (n,) or n < 1:
        raise ConfigError(f"times must have shape ({n},) with N >= 1; got {t.shape}")
    if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        raise ConfigError("times must be finite and strictly increasing")
    return t


def scene_from_poses(platform: Platform, t_s: ArrayLike, poses: ArrayLike) -> Scene:
    """The drawing of ``poses (N, 6)`` at times ``t_s (N,)``; actuators by inverse kinematics.

    Raises
    ------
    ConfigError
        Shapes that do not match, times not strictly increasing, non-finite poses.
    """
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[1] != 6:
        raise ConfigError(f"poses must have shape (N, 6); got {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ConfigError("poses hold NaN or inf")
    t = _check_times(t_s, p.shape[0])
    p = p * np.asarray(platform.dof_mask, dtype=float)
    q = np.asarray(platform.inverse(p), dtype=float).reshape(p.shape[0], -1)
    return _scene(platform, t, p, q)


def scene_from_q(platform: Platform, t_s: ArrayLike, q: ArrayLike) -> Scene:
    """The drawing of actuator positions ``q (N, n)``; poses by forward kinematics.

    Each frame's forward kinematics starts from the previous pose (frames of a ride are
    close). Positions rounded to pulses (a corner rig's redundant leg twists the frame by up
    to about a pulse) are drawn at the nearest rigid pose.

    Raises
    ------
    ConfigError
        Shapes that do not match, non-finite positions, or positions no rigid pose gives
        within the rounding (one pulse of each drive).
    """
    qa = np.asarray(q, dtype=float)
    n = int(platform.n_actuators)
    if qa.ndim != 2 or qa.shape[1] != n:
        raise ConfigError(f"actuator positions must have shape (N, {n}); got {qa.shape}")
    t = _check_times(t_s, qa.shape[0])
    poses = np.empty((qa.shape[0], 6))
    guess = None
    for k in range(qa.shape[0]):
        fk = platform.forward(qa[k], guess)
        if not fk.ok:
            raise ConfigError(
                f"frame {k} (t = {t[k]:.3f} s): {fk_miss(platform, qa[k], fk)}; is this the "
                "ride's platform?"
            )
        poses[k] = fk.pose
        guess = fk.pose
    return _scene(platform, t, poses, qa)


def fk_miss(platform: Platform, q: NDArray[np.float64], fk: FKResult) -> str:
    """Why positions ``q`` are no rigid pose's: the actuator farthest from the nearest rigid
    pose, in mm or deg and in pulses (one line, no traceback)."""
    names = platform.actuator_names
    i = fk.worst
    rotary = platform.actuator_kinds[i] == "rotary"
    unit, scale = ("deg", 180.0 / np.pi) if rotary else ("mm", 1e3)
    r = fk.residuals
    if r is None or not np.isfinite(r[i]):
        return (
            f"no pose puts the actuators at {np.round(q, 6).tolist()} (from neutral): "
            "a leg cannot reach"
        )
    pulses = abs(float(r[i])) / float(platform.q_rounding[i])
    return (
        f"no rigid pose puts the actuators at {np.round(q, 6).tolist()} (from neutral) within "
        f"the rounding: the nearest leaves actuator {names[i]!r} {float(r[i]) * scale:+.4g} "
        f"{unit} ({pulses:.3g} pulses) away"
    )


def _scene(
    platform: Platform, t: NDArray[np.float64], poses: NDArray[np.float64], q: NDArray[np.float64]
) -> Scene:
    legs = platform.legs
    yaw_axis = bool(platform.has_yaw_axis)
    leg_pose = poses.copy()
    if yaw_axis:
        leg_pose[:, 5] = 0.0
    rot = _rotation(leg_pose[:, 3:])
    origin = leg_pose[:, :3] + np.array([0.0, 0.0, legs.height])
    top = origin[:, None, :] + np.einsum("nij,lj->nli", rot, legs.plat)
    base = np.broadcast_to(legs.base, top.shape).copy()
    tips = legs.joints(q[:, : legs.n])  # the leg set says how its legs are drawn
    joint = None if tips is None else base + tips
    spread = float(np.max(np.linalg.norm(legs.plat[:, :2], axis=1), initial=0.1)) or 0.1
    forward = origin + 0.6 * spread * rot[:, :, 0]
    # a turntable turns the whole machine; a traction-loss slider turns the seat only
    arm = platform.traction_loss_arm_m
    if yaw_axis and arm is None:
        turn = _rotation(np.column_stack([np.zeros((len(t), 2)), poses[:, 5]]))

        def spin(a: NDArray[np.float64]) -> NDArray[np.float64]:
            return np.asarray(np.einsum("nij,n...j->n...i", turn, a), dtype=float)

        top, base, origin, forward = spin(top), spin(base), spin(origin), spin(forward)
        joint = None if joint is None else spin(joint)
    use = stroke_use(platform, q)
    for name, arr in (("top", top), ("use", use)):
        if not np.all(np.isfinite(arr)):
            raise ConfigError(f"the drawing's {name} is not finite (NaN or inf in the input)")
    seat = rail = None
    if arm is not None:
        seat, rail = _slider(platform, float(arm), rot, origin, poses[:, 5])
    order = outline_order(legs.base)
    rest = at_rest(platform, q)
    return Scene(t, poses, q, base, joint, top, origin, forward, use, rest, order, seat, rail)


def _slider(
    platform: Platform,
    arm: float,
    rot: NDArray[np.float64],
    origin: NDArray[np.float64],
    yaw: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The traction-loss seat's arm ``(N, 3, 3)`` and slot ``(N, 2, 3)`` in the base frame.

    The seat turns by ``yaw`` about a vertical pivot at the top frame's origin; its pin, at
    ``arm`` behind the pivot, runs in a sideways slot at ``x = -arm`` (so the pin sits at
    ``y = -arm tan(yaw)``, the slider's ``q = arm tan(yaw)`` of
    :class:`~motioncue.kinematics.Platform`). The slot is as long as the slider's usable
    stroke.
    """
    k = platform.legs.n  # the slider is the actuator after the legs
    half = float(max(abs(platform.q_min[k]), abs(platform.q_max[k])))
    tan = np.tan(np.clip(yaw, -1.5, 1.5))
    n = yaw.shape[0]
    local = np.zeros((n, 3, 3))
    local[:, 0, 0] = -arm  # the pin
    local[:, 0, 1] = -arm * tan
    local[:, 2, 0] = 0.6 * arm * np.cos(yaw)  # a point ahead of the pivot
    local[:, 2, 1] = 0.6 * arm * np.sin(yaw)
    slot = np.zeros((n, 2, 3))
    slot[:, :, 0] = -arm
    slot[:, 0, 1], slot[:, 1, 1] = -half, half
    seat = origin[:, None, :] + np.einsum("nij,nkj->nki", rot, local)
    rail = origin[:, None, :] + np.einsum("nij,nkj->nki", rot, slot)
    return seat, rail


def finite_or_none(x: float) -> float | None:
    """``x`` when finite, else None (JSON has no NaN)."""
    return x if math.isfinite(x) else None
