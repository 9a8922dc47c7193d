"""Is this ride fit for the rig about to be driven? Checked before anything is sent.

A ride file is untrusted input: it may have been made for another platform or controller, by
an older motioncue with other limits, edited, or damaged. :func:`check_ride_for` checks it
against the rig about to be driven (the platform and controller configs as loaded now, and
the limits derived from them now), in this order, and refuses with the first problem:

1. **Actuators.** The ride's actuator names (count, order and names) are the platform's, and
   the controller drives that many axes.
2. **Made for this rig.** The ride's ``platform`` and ``controller`` names are the names of
   the configs about to be used. A ride whose names differ is refused, naming both, unless
   the limits table stored in the ride is exactly the table the rig allows now (the same
   configs under another name or path). Rule of thumb for users: play a ride with the
   platform and controller it was generated for; regenerate it for another rig.
3. **Timing.** ``rate_hz`` passes the controller's own ``check_rate`` (its frame-rate cap;
   whole-ms periods for MBOX and IMAX; the EasySmc link budget), and every step of
   ``t_s`` is ``1 / rate_hz`` (relative tolerance 1e-9, plus the float rounding of long
   rides).
4. **Outputs.** ``dout`` and the DACs are within what the controller's frames carry
   (``controller.dout_max`` / ``dac_max``): MBOX 24 output bits and DACs up to Fn078 /
   Fn079; IMAX Y01..Y12 (``dout <= 0xFFF``) and no DACs; EasySmc 16 output bits per unit
   and no DACs.
5. **Limits, on the controller's clock.** The frames are checked by the independent
   finite-difference checker (:func:`~motioncue.pipeline.check_frames`) against the limits
   table of the current limits (``limits.to_pulses_table(platform)``, already divided by the
   controller's catch-up factor), starting at rest and ending at rest (a rest frame is added
   before the first and after the last frame). The frame times are those the controller
   reads (``controller.time_resolution_s``: whole milliseconds for MBOX and IMAX), so a ride
   whose rounded periods make it faster than the limits is refused, and frames sharing one
   time stamp are refused. The message names the worst
   actuator, the quantity, its value against the limit, and the frame.

Refusals are :class:`~motioncue.ConfigError` (1-4, the ride does not belong to this rig) or
:class:`~motioncue.LimitError` (5, the rig cannot do it).

Before those, :func:`check_ride_integrity` asks whether the ride is the one ``generate``
made: a ride whose content no longer matches its digest (``"edited"``), or that carries none
(``"unsigned"``: made before rides had one, or rewritten by another program), is refused
unless the user says it was edited on purpose (``play --accept-edited``). An accepted edited
ride must still be a rigid platform's: the forward kinematics of every frame must find a pose
whose leg positions are the frame's within the pulse rounding (:func:`rigidity_residuals`).
That catches leg positions no rigid frame can take (one actuator moved alone on a corner rig,
positions no pose reaches); on a platform with as many actuators as degrees of freedom (a
hexapod, the seats) nearly any in-stroke set of positions is some pose (swapped columns of a
hexapod ride are a pose 80 mm sideways), so there the digest is the check, and the note of an
accepted ride says how far the recovered poses go.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from .._errors import ConfigError, LimitError
from ._ridefile import Ride
from ._verify import check_frames, limits_arrays

if TYPE_CHECKING:  # types only: the checker runs no planner code
    from ..kinematics import Platform
    from ..output import Controller
    from ..trajectory import ActuatorLimits, PulsesRow

__all__ = ["check_ride_for", "check_ride_integrity", "rigidity_residuals", "wire_times_s"]


def wire_times_s(t_s: np.ndarray, controller: Controller) -> np.ndarray:
    """Frame times as the controller reads them: rounded to its time resolution from the
    first frame (whole ms for MBOX and IMAX, whose frames carry a u32 ms time); the times
    themselves for a controller whose frames carry none."""
    t = np.asarray(t_s, dtype=float)
    res = controller.time_resolution_s
    if res:
        return np.asarray(np.rint((t - t[0]) / res) * res, dtype=float)
    return t


def check_ride_for(
    ride: Ride,
    platform: Platform,
    controller: Controller,
    limits: ActuatorLimits,
    *,
    platform_name: str,
    controller_name: str,
) -> None:
    """Refuse a ride that does not belong to, or is unsafe on, the rig about to be driven.

    Parameters
    ----------
    ride : Ride
        As returned by :func:`~motioncue.pipeline.load_ride`.
    platform : motioncue.kinematics.Platform
    controller
        From :func:`motioncue.output.load_controller`.
    limits : motioncue.trajectory.ActuatorLimits
        The limits of the rig now (from the platform and controller above).
    platform_name, controller_name : str
        The names (or paths) the platform and controller were loaded by.

    Raises
    ------
    ConfigError
        Another rig's ride (actuators, names), a rate the controller cannot carry,
        ``rate_hz`` not matching ``t_s``, outputs out of range. Both values are named.
    LimitError
        Frames outside the current limits on the controller's clock (worst actuator,
        quantity and frame named).
    """
    names = tuple(platform.actuator_names)
    if tuple(ride.actuator_names) != names:
        raise ConfigError(
            f"ride actuators {list(ride.actuator_names)} are not the actuators "
            f"{list(names)} of platform {platform_name!r}"
        )
    n_axes = int(controller.n_axes)
    if n_axes != len(names):
        raise ConfigError(
            f"controller {controller_name!r} drives {n_axes} axes; the ride and platform "
            f"{platform_name!r} have " + platform.axes_text
        )
    table = limits.to_pulses_table(platform)
    _check_identity(ride, table, platform_name, controller_name)
    _check_timing(ride, controller, controller_name)
    _check_outputs(ride, controller, controller_name)
    _check_limits(ride, controller, controller_name, table)


def _check_identity(
    ride: Ride, table: list[PulsesRow], platform_name: str, controller_name: str
) -> None:
    same_table = ride.limits.get("actuators") == table
    for what, made_for, now in (
        ("platform", ride.platform, platform_name),
        ("controller", ride.controller, controller_name),
    ):
        if made_for != now and not same_table:
            raise ConfigError(
                f"the ride was made for {what} {made_for!r}, not {now!r}, and its limits "
                f"table differs from what {now!r} allows; play it with --{what} {made_for} "
                f"or generate the ride again for {now!r}"
            )


def _check_timing(ride: Ride, controller: Controller, controller_name: str) -> None:
    # the controller's own rule: its frame-rate cap and, for whole-ms time stamps, a period
    # of whole milliseconds (ConfigError naming the rates it can carry)
    controller.check_rate(ride.rate_hz)
    if ride.n_frames < 2:
        return
    period = 1.0 / ride.rate_hz
    steps = np.diff(ride.t_s)
    tol = 1e-9 * period + 8.0 * np.finfo(float).eps * np.abs(ride.t_s[1:])
    bad = np.abs(steps - period) > tol
    if np.any(bad):
        k = int(np.flatnonzero(bad)[0])
        raise ConfigError(
            f"ride rate_hz = {ride.rate_hz:g} Hz (period {period * 1e3:.6g} ms) does not match "
            f"its frame times: frames {k} and {k + 1} are {steps[k] * 1e3:.9g} ms apart"
        )


def _check_outputs(ride: Ride, controller: Controller, controller_name: str) -> None:
    dout_max = int(ride.dout.max(initial=0))
    dacs_max = ride.dacs.max(axis=0, initial=0)
    dout_top = int(controller.dout_max)
    dac_top = tuple(int(d) for d in controller.dac_max)
    dac_what = "its DAC full scale" if any(dac_top) else "none: the controller has no DACs"
    if dout_max > dout_top:
        k = int(np.argmax(ride.dout > dout_top))
        raise ConfigError(
            f"ride dout = {int(ride.dout[k]):#x} at frame {k} is outside what controller "
            f"{controller_name!r} carries (0 .. {dout_top:#x})"
        )
    for i in (0, 1):
        if int(dacs_max[i]) > dac_top[i]:
            k = int(np.argmax(ride.dacs[:, i] > dac_top[i]))
            raise ConfigError(
                f"ride DAC{i + 1} = {int(ride.dacs[k, i])} at frame {k} is above the "
                f"{dac_top[i]} controller {controller_name!r} allows ({dac_what})"
            )


def _check_limits(
    ride: Ride, controller: Controller, controller_name: str, table: list[PulsesRow]
) -> None:
    t = wire_times_s(ride.t_s, controller)
    if ride.n_frames > 1:
        dt = np.diff(t)
        if np.any(dt <= 0):
            k = int(np.flatnonzero(dt <= 0)[0])
            raise LimitError(
                f"frames {k} and {k + 1} of the ride carry the same time stamp "
                f"{t[k] * 1e3:.0f} ms on controller {controller_name!r}'s 1 ms clock; "
                f"{ride.rate_hz:g} Hz is too fast for it"
            )
        last = float(dt[-1])
    else:
        last = 1.0 / ride.rate_hz
    # rest after the last frame: one more frame at the same position, one period later
    t_ext = np.append(t, t[-1] + last)
    p_ext = np.vstack([ride.pulses, ride.pulses[-1:]]).astype(float)
    check = check_frames(t_ext, p_ext, table, start_at_rest=True)
    if check.ok:
        return
    raise LimitError(
        f"the ride leaves the limits of the rig it is about to drive "
        f"(on controller {controller_name!r}'s clock): "
        f"{_worst(t_ext, p_ext, table, ride.actuator_names, ride.n_frames)}; "
        f"{check.summary()}"
    )


def _worst(
    t: np.ndarray, p: np.ndarray, table: list[PulsesRow], names: Sequence[str], n_frames: int
) -> str:
    """The worst violation: actuator, quantity, value against limit, frame (for messages)."""
    lim = limits_arrays(table)
    mid = 0.5 * (lim["hi"] + lim["lo"])
    half = np.maximum(0.5 * (lim["hi"] - lim["lo"]), 0.5)
    v = np.zeros_like(p)
    v[1:] = np.diff(p, axis=0) / np.diff(t)[:, None]  # v[k]: into frame k; at rest before 0
    a = np.zeros_like(p)
    a[0] = v[0]
    a[1:] = np.diff(v, axis=0) / np.diff(t)[:, None]
    uses = {
        "stroke": np.abs(p - mid) / half,
        "speed": np.abs(v) / lim["v"],
        "acceleration": np.abs(a) / lim["a"],
    }
    best: tuple[float, str, int, int] = (-1.0, "stroke", 0, 0)
    for quantity, u in uses.items():
        k, i = np.unravel_index(int(np.argmax(u)), u.shape)
        if float(u[k, i]) > best[0]:
            best = (float(u[k, i]), quantity, int(k), int(i))
    _, what, frame, axis = best
    use = float(uses[what][frame, axis])
    if what == "stroke":
        detail = (
            f"position {p[frame, axis]:.0f} pulses outside the stroke "
            f"[{lim['lo'][axis]:.0f}, {lim['hi'][axis]:.0f}]"
        )
    elif what == "speed":
        detail = f"speed {abs(v[frame, axis]):.6g} > {lim['v'][axis]:.6g} pulses/s"
    else:
        detail = f"acceleration {abs(a[frame, axis]):.6g} > {lim['a'][axis]:.6g} pulses/s^2"
    where = (
        f"frame {frame} (t = {t[frame]:.3f} s)"
        if frame < n_frames
        else "after the last frame (the ride does not end at rest)"
    )
    return f"actuator {names[axis]!r} {what} {use:.3f} x its limit at {where}: {detail}"


def check_ride_integrity(
    ride: Ride, platform: Platform, *, accept_edited: bool = False, name: str = "the ride"
) -> list[str]:
    """Refuse a ride changed after it was made, unless ``accept_edited``; then check that
    its frames are a rigid platform's.

    Parameters
    ----------
    ride : Ride
        As returned by :func:`~motioncue.pipeline.load_ride` (``ride.integrity``); a ride
        made in memory (``"made"``) or read intact passes at once.
    platform : motioncue.kinematics.Platform
        The platform about to be driven (for the forward kinematics).
    accept_edited : bool
        The user says the ride was edited on purpose (``play --accept-edited``).
    name : str
        What to call the ride in messages (its file name).

    Returns
    -------
    list of str
        Notes for the user (one line each): empty for an intact ride; for an accepted edited
        one, what was accepted and how far the recovered poses go.

    Raises
    ------
    ConfigError
        An edited or unsigned ride without ``accept_edited`` (what to do is said).
    LimitError
        An accepted edited ride with a frame no rigid pose gives (frame, time, actuator,
        distance in pulses against the rounding allowance).
    """
    state = ride.integrity
    if state in ("made", "intact"):
        return []
    if state == "edited":
        what = (
            "its content does not match the digest generate wrote: it was changed after it "
            "was made (edited, or damaged)"
        )
    else:
        what = (
            "it carries no digest: made by a motioncue from before rides had one, or rewritten "
            "by another program"
        )
    if not accept_edited:
        raise ConfigError(
            f"{name} was not played: {what}; generate it again, or, if it was edited on "
            "purpose, play it with --accept-edited (its frames must then still be a rigid "
            "platform's)"
        )
    names = tuple(platform.actuator_names)
    if tuple(ride.actuator_names) != names:
        return []  # another rig's ride: check_ride_for refuses it, naming both
    allowed = _rounding_allowance(platform)
    residual, poses = rigidity_residuals(ride.pulses, platform, allowance_pulses=allowed)
    worst = np.where(np.isnan(residual), 0.0, residual).max(axis=1)
    if np.any(worst > allowed):
        k = int(np.argmax(worst > allowed))
        axis = int(np.argmax(residual[k]))
        far = worst[k]
        distance = "no pose reaches them" if not math.isfinite(far) else f"{far:.1f} pulses"
        raise LimitError(
            f"{name} (edited) is no rigid platform's: at frame {k} (t = {ride.t_s[k]:.3f} s) "
            f"no pose of {platform.name} gives its actuator "
            f"positions (actuator {names[axis]!r}: {distance} from the nearest rigid pose; "
            f"pulse rounding allows {allowed:.2f}); nothing was sent"
        )
    return [
        f"{name} was accepted as edited (--accept-edited; {what}); its frames are a rigid "
        f"platform's within the pulse rounding ({allowed:.2f} pulses); {_pose_span(poses)}"
    ]


def rigidity_residuals(
    pulses: np.ndarray, platform: Platform, *, allowance_pulses: float | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """How far each frame's actuator positions are from a rigid pose, in pulses.

    Forward kinematics (:meth:`~motioncue.kinematics.Platform.forward`, warm-started from the
    previous frame's pose; repeated frames computed once) finds a pose for each frame's
    positions, inverse kinematics gives that pose's positions, and the difference is
    converted back to pulses. The platform's spare axes (held at 0, not part of the frame)
    are left out.

    Parameters
    ----------
    pulses : ndarray, shape (N, n)
        Frames in the platform's actuator order.
    platform : motioncue.kinematics.Platform
    allowance_pulses : float, optional
        When given, the iteration stops as soon as every actuator is within this many pulses
        of the pose found (so a value at or below it means "within the allowance", not the
        least distance), and the frames after the first one above it are not computed
        (NaN). Without it, the forward kinematics' own tolerance (least distances).

    Returns
    -------
    residual : ndarray, shape (N, n - spare_axes)
        ``|inverse(pose) - q|`` per actuator (pulses); ``inf`` where no pose reaches the
        positions; NaN for frames not computed.
    poses : ndarray, shape (N, 6)
        The poses found (m, rad); NaN for frames not computed.
    """
    p = np.asarray(pulses)
    n_rigid = int(platform.n_actuators) - int(platform.spare_axes)
    q = np.asarray(platform.drives.from_pulses(p.astype(np.int64)), dtype=float)
    ppu = np.abs(np.asarray(platform.drives.pulses_per_unit, dtype=float))[:n_rigid]
    tol = 1e-12  # Platform.forward's default
    if allowance_pulses is not None:
        tol = allowance_pulses / float(np.max(ppu))  # the strictest actuator's
    # first: the first frame of each distinct row; inverse: each frame's distinct row
    unique, first, inverse = np.unique(p, axis=0, return_index=True, return_inverse=True)
    inverse = np.asarray(inverse).reshape(-1)
    res_u = np.full((len(unique), n_rigid), np.nan)
    pose_u = np.full((len(unique), 6), np.nan)
    guess = None
    for j in np.argsort(first):  # in time order, so the warm start is the previous frame
        qk = q[first[j]]
        fk = platform.forward(qk, guess, tol=tol)
        pose_u[j] = fk.pose
        if math.isfinite(fk.residual):
            back = np.asarray(platform.inverse(fk.pose), dtype=float)
            res_u[j] = np.abs(back[:n_rigid] - qk[:n_rigid]) * ppu
            guess = fk.pose
        else:
            res_u[j] = np.inf
        if allowance_pulses is not None and not np.max(res_u[j]) <= allowance_pulses:
            break
    return res_u[inverse], pose_u[inverse]


def _rounding_allowance(platform: Platform) -> float:
    """Largest distance (pulses) from a rigid pose that pulse rounding alone can make: each
    position is off by at most half a pulse, and the least-squares projection of those
    errors moves no actuator by more than their 2-norm, ``0.5 sqrt(n)`` (n actuators of the
    frame); plus 1e-3 pulse for the iteration's own tolerance."""
    n_rigid = int(platform.n_actuators) - int(platform.spare_axes)
    return 0.5 * math.sqrt(n_rigid) + 1e-3


def _pose_span(poses: np.ndarray) -> str:
    """``poses reach x +-12.7 mm, ...``: the largest excursion of each pose component."""
    peak = np.max(np.abs(poses), axis=0)
    parts = [f"{n} {peak[i] * 1e3:.1f} mm" for i, n in enumerate("xyz")]
    parts += [
        f"{n} {math.degrees(peak[i + 3]):.1f} deg" for i, n in enumerate(("roll", "pitch", "yaw"))
    ]
    return "the poses recovered from its frames reach +-(" + ", ".join(parts) + ")"
