"""The offline chain, written once: cueing -> workspace -> actuator limits -> FK.

Every offline user of a cueing algorithm runs the same stages a ride goes through, on
arrays at the frame rate:

1. :func:`run_cueing`: the algorithm's whole-recording run, with the input it actually used
   (bad samples held); :func:`cue_recording` runs it on a recording at the algorithm's own
   rate (a plan's highest, its poses splined to the frames: ``generate``, ``cue``);
2. :func:`deliver`: workspace limiting (:func:`motioncue.trajectory.limit_pose`) with the
   actuator limits already tightened for the controller's pulse rounding (by the caller:
   :func:`motioncue.trajectory.pulse_rounding_limits`, or ``planning_limits`` where a ride
   starts and ends at park), then, optionally, the actuator speed/acceleration (and jerk)
   limits the live bridge applies (:class:`~motioncue.trajectory.RealtimeLimiter`, or
   :class:`~motioncue.trajectory.JerkLimiter` with a jerk limit), from the neutral pose at
   rest, mapped back to poses by forward kinematics on the frames they changed.

:func:`offline_chain` is both. Its users: ``generate`` (workspace only: the ride's own
casadi optimisation replaces the real-time limiter), ``compare`` and ``omct`` (both stages),
``tune`` (workspace only: the candidates' frames are judged against the limits instead).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..cueing import CueingParams, CueingResult, Rig, cueing_entry, make_cueing
from ..telemetry._recording import Recording, resample
from ..trajectory import JerkLimiter, RealtimeLimiter, limit_pose

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits, PoseLimitResult

__all__ = [
    "ChainRun",
    "Cued",
    "Delivered",
    "ReportsUsedInput",
    "RunsRecordings",
    "cue_recording",
    "deliver",
    "offline_chain",
    "run_cueing",
]


class RunsRecordings(Protocol):
    """What the chain needs of a cueing design: a whole-recording run."""

    def run(self, f: ArrayLike, w: ArrayLike) -> CueingResult:
        """Poses (N, 6) for ``f``, ``w`` (N, 3) at the design's rate."""
        ...


@runtime_checkable
class ReportsUsedInput(Protocol):
    """A run's result that also gives the input as the algorithm used it (bad samples held).

    An optional capability of a :class:`~motioncue.cueing.CueingResult` (the bundled
    algorithms have it; a plug-in's result need not): :func:`run_cueing` takes the given
    input for a result without it.
    """

    @property
    def f_used(self) -> NDArray[np.float64]:
        """(N, 3) specific force as used (m/s^2)."""
        ...

    @property
    def w_used(self) -> NDArray[np.float64]:
        """(N, 3) angular velocity as used (rad/s)."""
        ...


@dataclass(frozen=True, eq=False)
class Cued:
    """The cueing stage's output.

    Attributes
    ----------
    result : CueingResult
        What the algorithm's run returned.
    poses : (N, 6) array
        Its poses (m, rad).
    f_used, w_used : (N, 3) arrays
        The input as the algorithm used it (bad samples held; the given input when the
        algorithm does not report it).
    bad_samples : int
    """

    result: CueingResult
    poses: NDArray[np.float64]
    f_used: NDArray[np.float64]
    w_used: NDArray[np.float64]
    bad_samples: int


@dataclass(frozen=True, eq=False)
class Delivered:
    """What the platform delivers of requested poses.

    Attributes
    ----------
    workspace : PoseLimitResult
        Workspace limiting of the requested poses.
    clamped : int
        Poses workspace limiting scaled back (status not ``"ok"``).
    poses : (N, 6) array
        Delivered poses (m, rad): the workspace's, with forward kinematics of the limiter's
        output on the frames it changed.
    q : (N, n) array
        Delivered actuator positions (SI).
    actuator_limited : int
        Frames the actuator limiter changed (0 without it).
    limiter_clamped : int
        Frames the limiter counted as clamped (its state's ``n_clamped``; 0 without it).
    """

    workspace: PoseLimitResult
    clamped: int
    poses: NDArray[np.float64]
    q: NDArray[np.float64]
    actuator_limited: int
    limiter_clamped: int


@dataclass(frozen=True, eq=False)
class ChainRun:
    """Both stages of :func:`offline_chain`."""

    cued: Cued
    delivered: Delivered


def run_cueing(design: RunsRecordings, f: ArrayLike, w: ArrayLike) -> Cued:
    """The cueing stage: ``design.run(f, w)`` and the input it used."""
    res = design.run(f, w)
    # an algorithm may hold bad input samples; the evaluation compares against what it used
    if isinstance(res, ReportsUsedInput):
        f_used = np.asarray(res.f_used, dtype=float)
        w_used = np.asarray(res.w_used, dtype=float)
    else:
        f_used = np.asarray(f, dtype=float)
        w_used = np.asarray(w, dtype=float)
    return Cued(res, np.asarray(res.poses, dtype=float), f_used, w_used, int(res.bad_samples))


def cue_recording(
    params: CueingParams, recording: Recording, rate_hz: float, rig: Rig | None = None
) -> tuple[Cued, NDArray[np.float64], Recording, float]:
    """The cueing stage on a recording for frames at ``rate_hz``, at the algorithm's rate.

    An algorithm that declares a highest rate (``max_rate_hz`` of its registry entry, a plan)
    runs on the recording resampled to :meth:`~motioncue.cueing.CueingEntry.cue_rate_hz`,
    and the frames' poses come from a C2 cubic spline through its poses (past its last
    sample, the last pose held); any other runs at ``rate_hz``.

    Returns
    -------
    cued : Cued
        The stage's output at the cue rate.
    poses : (N, 6) array
        The poses at the frames (``recording`` resampled to ``rate_hz``; m, rad).
    at_rate : Recording
        ``recording`` resampled to ``rate_hz``.
    cue_rate_hz : float
    """
    at_rate = resample(recording, rate_hz)
    cue_hz = cueing_entry(params.algorithm).cue_rate_hz(rate_hz)
    at_cue = at_rate if cue_hz == rate_hz else resample(recording, cue_hz)
    cued = run_cueing(make_cueing(params, cue_hz, rig), at_cue.f, at_cue.w)
    poses = cued.poses
    if cue_hz != rate_hz:
        poses = _splined(cued.poses, np.asarray(at_cue.t_s), np.asarray(at_rate.t_s))
    return cued, poses, at_rate, cue_hz


def _splined(
    poses: NDArray[np.float64], t_cue_s: NDArray[np.float64], t_frames_s: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Poses ``(M, 6)`` at the times ``t_cue_s`` at the frame times (a C2 cubic spline, so
    the frames' accelerations are continuous; past the last cue sample its pose is held)."""
    from scipy.interpolate import CubicSpline

    if len(t_cue_s) < 2:
        return np.repeat(poses[:1], len(t_frames_s), axis=0)
    spline = CubicSpline(t_cue_s, poses, axis=0)
    return np.asarray(spline(np.clip(t_frames_s, t_cue_s[0], t_cue_s[-1])), dtype=float)


def deliver(
    platform: Platform,
    poses: NDArray[np.float64],
    tight: ActuatorLimits,
    rate_hz: float,
    *,
    actuator_limits: bool = True,
) -> Delivered:
    """Workspace limiting and (``actuator_limits``) the live actuator limiter with FK.

    Parameters
    ----------
    platform : Platform
    poses : (N, 6) array
        Requested poses (m, rad).
    tight : ActuatorLimits
        Limits already tightened for the pulse rounding.
    rate_hz : float
        Frame rate (Hz).
    actuator_limits : bool
        Also run the real-time actuator limiter from the neutral pose at rest.
    """
    lim = limit_pose(platform, poses, limits=tight)
    clamped = int(np.count_nonzero(np.asarray(lim.status) != "ok"))
    q_target = np.asarray(lim.q, dtype=float)
    out = np.array(lim.pose, dtype=float)
    if not actuator_limits or not len(out):
        return Delivered(lim, clamped, out, q_target, 0, 0)
    dt = 1.0 / rate_hz
    q0 = np.asarray(platform.inverse(np.zeros(6)), dtype=float)
    if tight.j_max is None:
        limiter = RealtimeLimiter(tight, dt)
        state = limiter.initial_state(q0)
        q_out = np.asarray(limiter.run(state, q_target), dtype=np.float64)
        n_clamped = state.n_clamped
    else:
        jerk = JerkLimiter(tight, dt)
        jstate = jerk.initial_state(q0)
        q_out = np.asarray(jerk.run(jstate, q_target), dtype=np.float64)
        n_clamped = jstate.n_clamped
    changed = np.flatnonzero(np.any(q_out != q_target, axis=1))
    for k in changed.tolist():
        out[k] = np.asarray(platform.forward(q_out[k], guess=out[k]).pose, dtype=float)
    return Delivered(lim, clamped, out, q_out, int(changed.size), int(n_clamped))


def offline_chain(
    design: RunsRecordings,
    f: ArrayLike,
    w: ArrayLike,
    platform: Platform,
    tight: ActuatorLimits,
    rate_hz: float,
    *,
    actuator_limits: bool = True,
) -> ChainRun:
    """:func:`run_cueing` then :func:`deliver` of its poses (see the module docstring)."""
    cued = run_cueing(design, f, w)
    return ChainRun(
        cued, deliver(platform, cued.poses, tight, rate_hz, actuator_limits=actuator_limits)
    )
