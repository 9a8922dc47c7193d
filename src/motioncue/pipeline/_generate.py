"""Offline ride generation: recording -> cueing -> workspace -> IK -> limits -> frames.

One function, :func:`generate_ride`, runs the whole chain on arrays and returns the ride with
a :class:`GenerateReport` of every stage (what was clamped, optimised and how far, how long
each stage took). Frames are verified independently against the limits table before a ride
is returned: an unsafe ride is never produced (``LimitError``).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, NotRequired, TypedDict

import numpy as np

from .._errors import LimitError
from ..cueing import GRAVITY_M_S2, CueingParams, Rig
from ..cueing._vestibular import THRESHOLDS
from ..trajectory import ActuatorLimits, limit_ride, transition, transition_through
from ..trajectory._derive import planning_limits, pulse_rounding_limits
from ._chain import cue_recording, deliver
from ._ridefile import Ride
from ._verify import FrameCheck, check_frames

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ..output import Controller
    from ..telemetry import Recording
    from ..trajectory import OptimisedRide, PulsesRow, Transition
    from ._inputs import Keyframes

__all__ = [
    "JOIN_ACCEL_M_S2",
    "JOIN_ACCEL_RAD_S2",
    "JOIN_HEAD_M",
    "JOIN_MAX_S",
    "RAMP_ACCEL",
    "RAMP_SPEED",
    "GenerateReport",
    "JoinEntry",
    "Progress",
    "generate_ride",
    "pulse_rounding_limits",
]

RAMP_SPEED = 0.3
"""Ramps between park and the ride use this fraction of the speed limits ..."""
RAMP_ACCEL = 0.1
"""... and of the acceleration limits: a rider is lifted from park gently (about 0.1 g on the
bundled hexapod), not at the machine's full capability."""

JOIN_ACCEL_M_S2 = THRESHOLDS[:3]
"""Acceleration target (m/s^2, x, y, z) of the move between park and a cue still moving at its
first or last sample (and the deceleration of the fallback join that brings it to rest before
a ramp): the otolith perception thresholds, the translational part of
:data:`motioncue.cueing._vestibular.THRESHOLDS` (Reid & Nahon 1985)."""
JOIN_HEAD_M = 0.5
"""Distance (m) of a seated rider's head from the platform's rotation centre, for the time
over which a rotation is brought to rest: over ``T`` the rotation rate ``w`` tilts the rider a
further ``w T / 2`` (felt as ``g w T / 2``) and swings the head with a peak tangential
acceleration ``1.5 w h / T``; their sum is least at ``T = sqrt(3 h / g)`` (0.39 s), for any
``w``."""
JOIN_MAX_S = 2.0
"""Longest time (s) a join segment between the cue and a ramp may take (the fallback join,
:func:`_join_to_rest`). Where this or the workspace does not allow the time above, the segment
is shorter and its deceleration higher (still continuous: no velocity step)."""
JOIN_ACCEL_RAD_S2 = JOIN_ACCEL_M_S2[0] / JOIN_HEAD_M
"""Angular acceleration (rad/s^2) of the moves between a moving cue and park: it swings a
seated rider's head (:data:`JOIN_HEAD_M`) with the surge perception threshold."""

Progress = Callable[[str, float], None]
"""``progress(stage_description, fraction_done)``."""


class JoinEntry(TypedDict):
    """How the cue met one ramp (:attr:`GenerateReport.joins`, ``ride.notes["joins"]``).

    Attributes
    ----------
    end : str
        ``"start"`` or ``"end"`` of the cue.
    kind : str
        ``"at rest"``, ``"from motion"`` or ``"stop then ramp"``.
    duration_s : float
        The join's length (s).
    shortened : str
        Why the workspace made it faster than its acceleration target; empty when it did not.
    limits : str, optional
        ``"ramp"`` or ``"full"``: the limits a join from motion kept (that kind only).
    """

    end: str
    kind: str
    duration_s: float
    shortened: str
    limits: NotRequired[str]


@dataclass(frozen=True, eq=False)
class GenerateReport:
    """What each stage did.

    Attributes
    ----------
    t_s : ndarray, (N,)
        Frame times of the whole ride (ramp in, cue, ramp out; a ramp meets a cue still
        moving at its end with its velocity, see :func:`_ramp`; should that fail, a join
        segment brings the cue to rest first, see :data:`JOIN_ACCEL_M_S2`).
    cue_slice : slice
        Frames of the cued part (between the ramps).
    f_vehicle, w_vehicle : ndarray, (M, 3)
        Resampled vehicle motion of the cued part.
    poses_cue : ndarray, (M, 6)
        Washout output.
    poses : ndarray, (N, 6)
        Poses after workspace limiting (ramps and joins included).
    q_desired, q : ndarray, (N, n)
        Actuator positions before and after the offline limits (SI).
    bad_samples : int
        Input samples the washout held (NaN, inf, spikes).
    poses_clamped : int
        Cue poses outside the workspace, scaled back toward neutral.
    max_pose_scale_loss : float
        Largest fraction of a pose removed by workspace limiting (0 = none).
    optimisation : OptimisedRide
        The :class:`motioncue.trajectory.OptimisedRide` of the limits stage.
    frame_check : FrameCheck
        Independent finite-difference check of the frames against the limits table.
    cue_rate_hz : float
        The rate the cueing ran at: the frame rate, or below it for an algorithm that
        declares a ``max_rate_hz`` (:class:`motioncue.cueing.CueingEntry`), whose poses were
        then splined to the frames.
    stage_s : dict[str, float]
        Wall time per stage.
    transition_fallbacks : tuple of str
        One sentence per ramp that could not follow its time-optimal pose path and moved in a
        straight line in actuator space instead.
    joins : tuple of JoinEntry
        How the cue met each ramp (``"end"``: ``"start"`` or ``"end"``; ``"kind"``: ``"at
        rest"``, ``"from motion"`` (one move between the moving cue and park, see
        :func:`_ramp`) or ``"stop then ramp"`` (the fallback: :func:`_join_to_rest`, then
        the ramp); ``"duration_s"``; ``"shortened"``: why the workspace made it faster
        than its acceleration target, empty when it did not). Also ``ride.notes["joins"]``.
    """

    t_s: np.ndarray
    cue_slice: slice
    f_vehicle: np.ndarray
    w_vehicle: np.ndarray
    poses_cue: np.ndarray
    poses: np.ndarray
    q_desired: np.ndarray
    q: np.ndarray
    bad_samples: int
    poses_clamped: int
    max_pose_scale_loss: float
    optimisation: OptimisedRide
    frame_check: FrameCheck
    cue_rate_hz: float
    stage_s: dict[str, float] = field(default_factory=dict)
    transition_fallbacks: tuple[str, ...] = ()
    joins: tuple[JoinEntry, ...] = ()


def _finish(
    q_desired: np.ndarray,
    platform: Platform,
    tight: ActuatorLimits,
    table: list[PulsesRow],
    dt: float,
) -> tuple[OptimisedRide, np.ndarray, np.ndarray, np.ndarray, FrameCheck]:
    """Offline limits (casadi), whole pulses, and the independent check every ride must pass.

    The ride starts from the park position at rest. Returns ``(optimisation, q, pulses, t_s,
    check)``; raises :class:`LimitError` rather than return frames that break a limit.
    """
    opt = limit_ride(q_desired, dt, tight, q0=platform.q_park, v0=np.zeros(platform.n_actuators))
    q = np.asarray(opt.q, dtype=float)
    pulses = platform.drives.to_pulses(q)
    # a ride ends at rest at park (the desired frames do): the solver's tolerance can leave
    # the last frames a pulse away when park lies on a stroke end (an interior-point solution
    # stays inside its bounds); those trailing frames are set to park, and the check below
    # judges the result like every frame
    park = platform.drives.to_pulses(np.asarray(platform.q_park, dtype=float))
    k = len(pulses)
    while k > 0 and np.max(np.abs(pulses[k - 1] - park)) <= 1:
        k -= 1
    if k < len(pulses) and np.all(q_desired[-1] == q_desired[-2]):
        pulses[k:] = park
        q = q.copy()
        q[k:] = platform.drives.from_pulses(pulses[k:])
    t_s = np.arange(len(q)) * dt
    check = check_frames(t_s, pulses, table, start_at_rest=True)
    if not check.ok:
        raise LimitError(f"generated frames fail the independent limits check: {check.summary()}")
    return opt, q, pulses, t_s, check


def _ride_limits(
    platform: Platform, controller: Controller, rate_hz: float, limits: ActuatorLimits | None
) -> tuple[ActuatorLimits, list[PulsesRow], ActuatorLimits]:
    """Checked before any work: the rate (the controller's clock must carry it), the limits
    (default: the platform's with the controller's), their pulse table and the planning
    limits (tightened for the pulse rounding, park kept inside)."""
    controller.check_rate(rate_hz)
    if limits is None:
        limits = ActuatorLimits.from_platform(platform, controller, rate_hz=rate_hz)
    return (
        limits,
        limits.to_pulses_table(platform),
        planning_limits(limits, platform, 1.0 / rate_hz),
    )


def _to_rest(pose: np.ndarray, v: np.ndarray, dur_s: np.ndarray, n: int, dt: float) -> np.ndarray:
    """Poses ``(n, 6)`` at ``dt, 2 dt, .., n dt`` after ``pose`` (6,) of a move that starts
    with velocity ``v`` (6,) and brings each component ``i`` to rest at ``dur_s[i]`` (s, > 0;
    held from then on): velocity ``v (1 - 3 tau^2 + 2 tau^3)``, ``tau = min(t / dur_s, 1)``,
    so the acceleration ``-6 v tau (1 - tau) / dur_s`` is zero at both ends and at most
    ``1.5 |v| / dur_s``; the position is its exact integral."""
    t = np.arange(1, n + 1)[:, None] * dt
    tau = np.minimum(t / dur_s, 1.0)
    out: np.ndarray = pose + dur_s * v * (tau - tau**3 + tau**4 / 2.0)
    return out


def _end_velocity(poses: np.ndarray, dt: float) -> np.ndarray:
    """The pose velocity (6,) at the last of ``poses (M >= 3, 6)``: that of the quadratic
    through the last three; a rotation rate whose step in one frame swings the head
    (:data:`JOIN_HEAD_M`) by less than the threshold counts as rest (zero)."""
    p2, p1, p0 = poses[-3], poses[-2], poses[-1]
    vel: np.ndarray = (3.0 * p0 - 4.0 * p1 + p2) / (2.0 * dt)
    swing = np.abs(vel[3:]) * JOIN_HEAD_M / dt > JOIN_ACCEL_M_S2[0]
    vel[3:] = np.where(swing, vel[3:], 0.0)
    return vel


def _ramp(
    platform: Platform,
    cue: np.ndarray,
    end: str,
    tight: ActuatorLimits,
    gentle: ActuatorLimits,
    rate_hz: float,
) -> tuple[Transition, JoinEntry, np.ndarray]:
    """The move between park and the cue's ``end`` (``"start"`` or ``"end"``), its
    :attr:`GenerateReport.joins` entry, and the fallback join segment (empty unless used;
    frames between the cue and the ramp, in ride order).

    A cue at rest there: the gentle time-optimal ramp (:data:`RAMP_SPEED`,
    :data:`RAMP_ACCEL`). A cue still moving: one move from the cue's last pose and velocity
    to park (at the start: from park to the cue's first pose and velocity), each pose
    component's acceleration within the perception thresholds (:data:`JOIN_ACCEL_M_S2`,
    :data:`JOIN_ACCEL_RAD_S2`) unless the workspace forces it faster (then ``"shortened"``
    says so), every frame within ``gentle`` (``"limits": "ramp"``; where the cue's own motion
    at its end breaks those, within ``tight``: ``"full"``) and in the workspace (the chain's
    limiting would move none of its poses). Should no such move exist, the old way: the cue
    brought to rest by :func:`_join_to_rest`, then the gentle ramp.
    """
    dt = 1.0 / rate_hz
    park = np.asarray(platform.pose_park, dtype=float)
    at_end = end == "end"
    seq = cue if at_end else cue[::-1]
    vel = _end_velocity(seq, dt) if len(seq) >= 3 else np.zeros(6)
    if not at_end:
        vel = -vel  # the velocity of the forward-time cue at its first pose
    edge = seq[-1]
    entry: JoinEntry = {"end": end, "kind": "at rest", "duration_s": 0.0, "shortened": ""}
    empty = np.empty((0, 6))

    def ramp_at_rest(pose: np.ndarray) -> Transition:
        if at_end:
            return transition(platform, pose, park, gentle, rate_hz)
        return transition(platform, park, pose, gentle, rate_hz)

    if not np.any(vel):
        tr = ramp_at_rest(edge)
        entry["duration_s"] = float(tr.t_s[-1])
        return tr, entry, empty
    accel = np.concatenate([np.asarray(JOIN_ACCEL_M_S2, dtype=float), [JOIN_ACCEL_RAD_S2] * 3])

    def in_workspace(poses: np.ndarray) -> bool:
        return deliver(platform, poses, tight, rate_hz, actuator_limits=False).clamped == 0

    why = ""
    # within the ramps' gentle limits where the cue's own motion allows, else the full ones
    for lim, name in ((gentle, "ramp"), (tight, "full")):
        try:
            if at_end:
                tr = transition(platform, edge, park, lim, rate_hz, v_from=vel,
                                accel_max=accel, accept=in_workspace)  # fmt: skip
            else:
                tr = transition(platform, park, edge, lim, rate_hz, v_to=vel,
                                accel_max=accel, accept=in_workspace)  # fmt: skip
        except LimitError as exc:
            why = str(exc)
            continue
        entry["kind"] = "from motion"
        entry["duration_s"] = float(tr.t_s[-1])
        entry["shortened"] = tr.shortened
        entry["limits"] = name
        return tr, entry, empty
    seg, halvings = _join_to_rest(platform, seq, tight, rate_hz)
    rest = seg[-1] if len(seg) else edge
    tr = ramp_at_rest(rest)
    entry["kind"] = "stop then ramp"
    entry["duration_s"] = float(tr.t_s[-1] + len(seg) * dt)
    entry["shortened"] = (
        f"{why}; the cue was brought to rest first, its join halved {halvings} time(s) "
        "by the workspace"
        if halvings
        else f"{why}; the cue was brought to rest first"
    )
    return tr, entry, seg if at_end else seg[::-1]


def _join_to_rest(
    platform: Platform, poses: np.ndarray, tight: ActuatorLimits, rate_hz: float
) -> tuple[np.ndarray, int]:
    """The segment ``(n, 6)`` (``n = 0`` when the cue ends at rest) that continues the cue
    ``poses (M, 6)`` from its last pose and velocity to rest, so that the ramp back to park
    starts where the cue has stopped instead of at a velocity step.

    Each translation is brought to rest in the shortest time that keeps its deceleration
    within :data:`JOIN_ACCEL_M_S2`, each rotation in ``sqrt(3 h / g)`` (:data:`JOIN_HEAD_M`),
    all within :data:`JOIN_MAX_S`; the times are halved while the workspace limiting would
    move one of the segment's poses (the segment stays what the platform delivers; its
    deceleration is then higher). The segment goes through the same workspace limiting and
    actuator-limit planning as the cue. Returns the segment and how many times its times
    were halved.
    """
    dt = 1.0 / rate_hz
    if len(poses) < 3:
        return np.empty((0, 6)), 0
    p0 = poses[-1]
    # the velocity at the last pose of the quadratic through the last three. Its
    # acceleration is not carried on: a cue that ends (or, reversed, starts) accelerating
    # hard (a tilt-coordination onset) would swing a long way before coming back to rest
    vel = (3.0 * p0 - 4.0 * poses[-2] + poses[-3]) / (2.0 * dt)
    # a rotation rate whose step in one frame swings the head by less than the threshold
    # is at rest already
    swing = np.abs(vel[3:]) * JOIN_HEAD_M / dt > JOIN_ACCEL_M_S2[0]
    dur_s = np.concatenate([
        1.5 * np.abs(vel[:3]) / np.asarray(JOIN_ACCEL_M_S2),
        np.where(swing, np.sqrt(3.0 * JOIN_HEAD_M / GRAVITY_M_S2), dt),
    ])  # fmt: skip
    dur_s = np.minimum(dur_s, JOIN_MAX_S)
    halvings = 0
    while True:
        dur_s = np.maximum(dur_s, dt)
        n = int(np.ceil(np.max(dur_s) * rate_hz - 1e-9))
        if n < 2:
            return np.empty((0, 6)), halvings
        seg = _to_rest(p0, vel, dur_s, n, dt)
        if deliver(platform, seg, tight, rate_hz, actuator_limits=False).clamped == 0:
            return seg, halvings
        dur_s = dur_s / 2.0
        halvings += 1


def generate_ride(
    recording: Recording,
    platform: Platform,
    controller: Controller,
    cueing: CueingParams,
    *,
    rate_hz: float = 100.0,
    limits: ActuatorLimits | None = None,
    source: str = "",
    platform_name: str | None = None,
    controller_name: str | None = None,
    progress: Progress | None = None,
) -> tuple[Ride, GenerateReport]:
    """Turn a vehicle-motion recording into a ride file's frames.

    Parameters
    ----------
    recording : motioncue.telemetry.Recording
        Vehicle specific force and angular velocity (any sample times).
    platform : motioncue.kinematics.Platform
    controller
        A controller description from :func:`motioncue.output.load_controller`.
    cueing : motioncue.cueing.CueingParams
        The preset; its ``algorithm`` picks the cueing algorithm
        (:func:`motioncue.cueing.make_cueing`).
    rate_hz : float
        Output frame rate.
    limits : motioncue.trajectory.ActuatorLimits, optional
        Default: derived from the platform and controller.

    Returns
    -------
    ride, report
    """

    def step(name: str, frac: float) -> None:
        if progress is not None:
            progress(name, frac)

    stage_s: dict[str, float] = {}
    clock = time.perf_counter()

    def lap(name: str) -> None:
        nonlocal clock
        now = time.perf_counter()
        stage_s[name] = now - clock
        clock = now

    limits, table, tight = _ride_limits(platform, controller, rate_hz, limits)
    dt = 1.0 / rate_hz

    step("cueing", 0.1)
    # the offline chain's cueing and workspace stages (motioncue.pipeline._chain); the
    # casadi ride optimisation below stands for the live actuator limiter. An algorithm that
    # declares a highest rate (a plan) cues below a faster frame rate, and the frames take
    # their poses from a spline through its poses
    rig = Rig(platform, limits, controller.name)
    wres, poses_cued, rec, cue_hz = cue_recording(cueing, recording, rate_hz, rig)
    lap("cueing")
    step("workspace", 0.2)
    delivered = deliver(platform, poses_cued, tight, rate_hz, actuator_limits=False)
    plim = delivered.workspace
    poses_cue_ok = delivered.poses
    lap("workspace")
    step("ramps", 0.35)
    gentle = tight.scaled(speed=RAMP_SPEED, accel=RAMP_ACCEL)
    # a cue in motion at either end is met by a move that starts (ends) at its velocity
    # (see _ramp); a cue at rest by the gentle time-optimal ramp
    ramp_in, join_in_note, join_in = _ramp(platform, poses_cue_ok, "start", tight, gentle, rate_hz)
    ramp_out, join_out_note, join_out = _ramp(platform, poses_cue_ok, "end", tight, gentle, rate_hz)
    joins = (join_in_note, join_out_note)
    fallbacks = [
        f"ramp {name}: {tr.fallback}"
        for name, tr in (("out of park", ramp_in), ("back to park", ramp_out))
        if tr.fallback
    ]
    lap("ramps")
    step("inverse kinematics", 0.45)
    # ... and one more frame at park, so the ride ends at rest there
    poses = np.concatenate(
        [
            ramp_in.poses[:-1],
            join_in,
            poses_cue_ok,
            join_out,
            ramp_out.poses[1:],
            ramp_out.poses[-1:],
        ]
    )
    q_desired = platform.inverse(poses)
    lap("inverse kinematics")
    step("actuator limits (casadi)", 0.5)
    # planned one pulse rounding inside ``tight``: rounding the plan to whole pulses then
    # keeps every frame inside ``tight``, which is what the player's live limiter enforces, so
    # a ride at its limits is replayed frame for frame (no frame clamped on the way out)
    planned = planning_limits(tight, platform, dt, real=limits)
    opt, q, pulses, t_s, check = _finish(q_desired, platform, planned, table, dt)
    lap("actuator limits, pulses and check")
    n_in = len(ramp_in.poses) - 1 + len(join_in)
    cue = slice(n_in, n_in + len(poses_cue_ok))
    clamped = delivered.clamped
    loss = float(np.max(1.0 - np.asarray(plim.scale, dtype=float), initial=0.0))
    n_frames = len(t_s)
    ride = Ride(
        platform=platform_name or platform.name,
        controller=controller_name or controller.name,
        rate_hz=rate_hz,
        actuator_names=platform.actuator_names,
        t_s=t_s,
        pulses=pulses,
        dout=np.zeros(n_frames, dtype=np.uint16),
        dacs=np.zeros((n_frames, 2), dtype=np.uint16),
        limits={"actuators": table},
        source=source,
        notes={
            "cue_frames": [cue.start, cue.stop],
            "bad_samples": int(wres.bad_samples),
            "poses_clamped": clamped,
            "max_deviation_si": float(opt.max_deviation),
            "optimisation_status": str(opt.status),
            "frame_check": check.summary(),
            "transition_fallbacks": fallbacks,
            "joins": [dict(j) for j in joins],
        },
    )
    step("done", 1.0)
    report = GenerateReport(
        t_s=t_s,
        cue_slice=cue,
        f_vehicle=rec.f,
        w_vehicle=rec.w,
        poses_cue=np.asarray(poses_cued),
        poses=poses,
        q_desired=q_desired,
        q=q,
        bad_samples=int(wres.bad_samples),
        poses_clamped=clamped,
        max_pose_scale_loss=loss,
        optimisation=opt,
        frame_check=check,
        stage_s=stage_s,
        transition_fallbacks=tuple(fallbacks),
        joins=joins,
        cue_rate_hz=cue_hz,
    )
    return ride, report


def _stretch(q: np.ndarray, factor: float, rate_hz: float, n_out: int) -> np.ndarray:
    """Resample a rest-to-rest move ``q (M, n)`` slowed down by ``factor >= 1`` to ``n_out``
    frames: speeds scale by ``1/factor`` and accelerations by ``1/factor^2``."""
    from scipy.interpolate import CubicSpline

    if len(q) < 2:
        # no move (two keyframes at one pose): hold it. Checked before the division: the
        # caller's factor is then 0 / 1, and 0 / 0 in the times would be NaN
        return np.repeat(q[:1], n_out, axis=0)
    t_src = np.arange(len(q)) / rate_hz
    t_new = np.minimum(np.arange(n_out) / rate_hz / factor, t_src[-1])
    spline = CubicSpline(t_src, q, axis=0, bc_type="clamped")
    out = spline(t_new)
    out[-1] = q[-1]
    return np.asarray(out)


def generate_keyframe_ride(
    keyframes: Keyframes,
    platform: Platform,
    controller: Controller,
    *,
    rate_hz: float = 100.0,
    limits: ActuatorLimits | None = None,
    source: str = "",
    platform_name: str | None = None,
    controller_name: str | None = None,
) -> tuple[Ride, dict[str, Any]]:
    """A ride through authored pose keyframes, without cueing.

    Timing rule: when no keyframe has a time, the ride is the time-optimal move through all of
    them (toppra, not stopping at keyframes). When times are given, the platform reaches each
    keyframe at its time, at rest: each segment is the time-optimal rest-to-rest move slowed
    down to fill its interval; a segment that cannot be done in its interval arrives late by the
    overrun (counted in ``late_keyframes``), and later keyframes shift by it. A keyframe with a
    free time (empty cell) is reached as soon as possible. The ride starts and ends parked.
    Effect outputs (``dout``, DACs) switch at the frame each keyframe is reached.

    Time base: the keyframe times are the times of the ride's content. The ramp out of park
    comes before the content, so the content's t = 0 is at ride time ``content_start_s``
    (``notes["content_start_s"]`` of the ride, ``info["content_start_s"]``), and a keyframe
    timed ``t`` is reached at ride time ``content_start_s + t`` (the first keyframe is never
    late: the ramp is given the time it needs).

    Every keyframe is checked before any work: one the platform cannot reach is refused with
    its number (1-based, as in the file), its time and the actuator (1-based, by name) that
    cannot get there.

    Returns
    -------
    ride, info
        ``info`` has ``late_keyframes``, ``max_late_s``, ``keyframe_frames``,
        ``content_start_s`` and ``transition_fallbacks`` (one sentence per move that could not
        follow its time-optimal pose path and went in a straight line in actuator space).

    Raises
    ------
    LimitError
        A keyframe the platform cannot reach (named with the actuator).
    """
    limits, table, tight = _ride_limits(platform, controller, rate_hz, limits)
    dt = 1.0 / rate_hz
    poses = np.asarray(keyframes.poses, dtype=float)
    times = np.asarray(keyframes.t_s, dtype=float)
    park = np.asarray(platform.pose_park, dtype=float)
    _check_keyframes_reachable(platform, poses, times)
    content_start = 0.0
    segments: list[np.ndarray] = []
    arrive: list[int] = []
    late = 0
    max_late = 0.0
    fallbacks: list[str] = []

    def note(what: str, tr: Transition) -> Transition:
        if tr.fallback:
            fallbacks.append(f"{what}: {tr.fallback}")
        return tr

    if not np.any(np.isfinite(times)):
        tr = note(
            "the move through the keyframes",
            transition_through(platform, np.vstack([park, poses, park]), tight, rate_hz),
        )
        q_all = tr.q
        # frames at which each keyframe is reached: nearest path samples
        q_kf = platform.inverse(poses)
        for qk in q_kf:
            arrive.append(int(np.argmin(np.linalg.norm(q_all - qk, axis=1))))
    else:
        gentle = tight.scaled(speed=RAMP_SPEED, accel=RAMP_ACCEL)
        first = note("ramp to keyframe 1", transition(platform, park, poses[0], gentle, rate_hz))
        move = np.vstack([first.q, first.q[-1:]])  # arrive, then one frame at rest
        need = len(move) - 1
        # the content's t = 0 comes after as many frames as the ramp out of park needs
        t0_frames = max(round(times[0] * rate_hz), 0) if np.isfinite(times[0]) else 0
        lead = max(need - t0_frames, 0)
        content_start = round(lead * dt, 9)
        wait = lead + t0_frames - need
        segments.append(np.vstack([np.repeat(move[:1], max(wait, 0), axis=0), move]))
        n_frames = len(segments[0])
        arrive.append(n_frames - 1)
        for k in range(1, len(poses)):
            tr = note(
                f"keyframe {k} to {k + 1}",
                transition(platform, poses[k - 1], poses[k], tight, rate_hz),
            )
            need = len(tr.q) - 1
            if np.isfinite(times[k]) and np.isfinite(times[k - 1]):
                slot = round((times[k] - times[k - 1]) * rate_hz)
            else:
                slot = need
            if slot - 1 < need:
                late += 1
                max_late = max(max_late, (need + 1 - slot) * dt)
                seg = np.vstack([tr.q, tr.q[-1:]])
            else:
                # arrive one frame early and hold, so the keyframe's frame is at rest there
                seg = _stretch(tr.q, (slot - 1) / max(need, 1), rate_hz, slot)
                seg = np.vstack([seg, seg[-1:]])
            segments.append(seg[1:])
            n_frames += len(seg) - 1
            arrive.append(n_frames - 1)
        back = note("ramp back to park", transition(platform, poses[-1], park, gentle, rate_hz))
        segments.append(back.q[1:])
        q_all = np.concatenate(segments)
    q_all = np.vstack([q_all, q_all[-1:]])  # one more frame at park: the ride ends at rest
    opt, q, pulses, t_s, check = _finish(q_all, platform, tight, table, dt)
    dout = np.zeros(len(q), dtype=np.int64)
    dacs = np.zeros((len(q), 2), dtype=np.int64)
    for k, frame in enumerate(arrive):
        dout[frame:] = keyframes.dout[k]
        dacs[frame:] = keyframes.dacs[k]
    dout[arrive[-1] + 1 :] = 0  # effects off while parking
    dacs[arrive[-1] + 1 :] = 0
    ride = Ride(
        platform=platform_name or platform.name,
        controller=controller_name or controller.name,
        rate_hz=rate_hz,
        actuator_names=platform.actuator_names,
        t_s=t_s,
        pulses=pulses,
        dout=dout,
        dacs=dacs,
        limits={"actuators": table},
        source=source,
        notes={
            "keyframe_frames": arrive,
            "content_start_s": content_start,
            "late_keyframes": late,
            "max_late_s": max_late,
            "optimisation_status": str(opt.status),
            "frame_check": check.summary(),
            "transition_fallbacks": fallbacks,
        },
    )
    return ride, {
        "transition_fallbacks": fallbacks,
        "late_keyframes": late,
        "max_late_s": max_late,
        "keyframe_frames": arrive,
        "content_start_s": content_start,
    }


def _check_keyframes_reachable(platform: Platform, poses: np.ndarray, times: np.ndarray) -> None:
    """Refuse the first keyframe the platform cannot reach, naming it and the actuator."""
    for k, pose in enumerate(poses):
        res = platform.check(pose)
        if bool(res.ok):
            continue
        bad = [i for i in range(len(res.q)) if not (res.reachable[i] and res.in_stroke[i])]
        # the actuator furthest out (an unreachable one first)
        i = max(bad, key=lambda j: (not res.reachable[j], abs(float(res.overshoot[j]))))
        linear = platform.actuator_kinds[i] == "linear"
        scale, unit = (1e3, "mm") if linear else (180.0 / np.pi, "deg")
        why = (
            "cannot reach it (geometry)"
            if not res.reachable[i]
            else f"would leave its stroke by {float(res.overshoot[i]) * scale:+.1f} {unit}"
        )
        when = f"t={times[k]:g} s" if np.isfinite(times[k]) else "free time"
        others = f" (and {len(bad) - 1} more actuator(s))" if len(bad) > 1 else ""
        name = str(platform.actuator_names[i])
        label = f"actuator {i + 1}" + ("" if name == str(i + 1) else f" ({name})")
        raise LimitError(f"keyframe {k + 1} ({when}) is not reachable: {label} {why}{others}")
