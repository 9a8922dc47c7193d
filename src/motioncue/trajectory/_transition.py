"""Time-optimal, limit-respecting transitions (toppra) and park / unpark / resume helpers.

A transition follows a smooth geometric path ``pose(s)``, ``s in [0, 1]``: the straight line
in pose coordinates between two poses, or a natural cubic spline through keyframes (knots at
normalised cumulative chord length) when timing is free. The actuator path
``q(s) = inverse(pose(s))`` is sampled densely and given to toppra with per-actuator speed and
acceleration limits; toppra returns the fastest ``s(t)`` (piecewise constant ``s''``) that
starts and ends at rest. Frames are sampled at ``rate_hz`` from ``t = 0`` (the start pose)
to the first frame at or after the end, which is the end pose exactly; ``q`` of each frame
is the inverse kinematics of its pose (not a spline approximation).

Every transition is then checked with the finite differences of
:mod:`motioncue.trajectory._limits`, starting from and ending at rest. If a check fails
(toppra only enforces the limits at its grid points, so a curved path can exceed them
slightly in between), the transition is recomputed with limits scaled by 0.97, up to 8 times;
the scale used is reported (``limit_scale``; the first attempt uses ``1 - 1e-5``, room for
toppra's own solver tolerance).

*Fallback* (always feasible): when the pose path leaves the actuator stroke or the kinematic
workspace, toppra finds no time parametrisation (its solver fails on some well-posed paths),
or the retries still break a limit, the move goes in a straight line in actuator space
through the same end positions (and keyframes), each piece rest to rest, timed by the
discrete limiter of :mod:`motioncue.trajectory._realtime` (:class:`JerkLimiter` with a jerk
limit) on the path parameter: a trapezoidal (S-curve) profile whose frames keep every
actuator's limits exactly, since each actuator moves the same fraction of its own distance.
The stroke is a box, so the line stays inside it when its ends are. ``Transition.fallback``
says why it was taken (empty when the time-optimal path was used); only end positions
outside the stroke raise :class:`~motioncue.LimitError`, and no frame that breaks a limit is
returned.

*From or to motion* (:func:`transition` with ``v_from`` / ``v_to``, e.g. a cue still moving
at its end on its way to park): no toppra; one quintic per pose component from the given
position and velocity to the other end's, zero acceleration at both ends, over the shortest
whole-frame duration that keeps each component within an acceleration target and every frame
within the limits (see :func:`transition`).

toppra knows no jerk limit. With a jerk limit in ``limits``, the sampled frames are passed
through the :class:`JerkLimiter` from rest, which then settles on the end position at rest;
frames it changed leave the geometric path slightly (their poses come from the forward
kinematics), ``duration_s`` becomes the time of the last frame, and the check includes jerk.
"""

from __future__ import annotations

import importlib
import itertools
import logging
import math
import sys
import types
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast, overload

import numpy as np

from .._errors import ConfigError, LimitError
from ._jerk import JerkLimiter, JerkLimiterState
from ._limits import ActuatorLimits, LimitCheck, check_trajectory
from ._realtime import LimiterState, RealtimeLimiter, braking_distance

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..kinematics import Platform

PathFn = Callable[[np.ndarray], np.ndarray]
"""A path: parameter values ``s`` (...) in [0, 1] -> positions (..., n) or poses (..., 6)."""
PoseOfQ = Callable[[np.ndarray, np.ndarray | None], np.ndarray]
"""Forward kinematics: positions (n,) and a pose guess (6,) or None -> pose (6,)."""

__all__ = [
    "Transition",
    "brake_to_rest",
    "park_path",
    "resume_path",
    "transition",
    "transition_q",
    "transition_through",
    "unpark_path",
]

_MAX_GROWTHS = 12
"""A move from motion grows its duration by 1.25 at most this many times (15x) to meet the
limits: beyond that, the motion at its ends is what breaks them, and time does not help."""
_RETRY_SCALE = 0.97
_RETRIES = 8
_MAX_SETTLE_FRAMES = 100_000


@dataclass(frozen=True, eq=False)
class Transition:
    """Frames of a transition, sampled at the output rate.

    Attributes
    ----------
    t_s : ndarray, (M,)
        Frame times from the start (s); ``t_s[0] = 0`` is the start pose itself.
    q : ndarray, (M, n)
        Actuator positions (SI).
    poses : ndarray, (M, 6)
        Poses of the frames (NaN rows only for actuator-space transitions built by
        :func:`transition_q`, which have no pose).
    duration_s : float
        Continuous time-optimal duration (the last frame is at ``ceil(duration * rate)``).
    limit_scale : float
        Factor the limits were scaled by to pass the discrete check (1.0 = full limits).
    check : LimitCheck
        Finite-difference check of ``q`` with rest before the first and after the last frame.
    fallback : str
        Why the straight line in actuator space was used instead of the time-optimal path
        (one sentence, for reports); empty when it was not.
    shortened : str
        For a move from or to motion (:func:`transition` with ``v_from`` / ``v_to``): why it
        was made shorter than its acceleration target allows, and its peak acceleration then
        (one sentence, for reports); empty when it was not.
    """

    t_s: np.ndarray
    q: np.ndarray
    poses: np.ndarray
    duration_s: float
    limit_scale: float
    check: LimitCheck
    fallback: str = ""
    shortened: str = ""

    @property
    def n_frames(self) -> int:
        return int(self.t_s.size)


def _pose_path(poses: np.ndarray) -> PathFn:
    """Callable s -> pose (.., 6) through the keyframes, s in [0, 1]."""
    from scipy.interpolate import CubicSpline

    if poses.shape[0] == 2:
        a, b = poses[0], poses[1]
        return lambda s: a + np.asarray(s)[..., None] * (b - a)
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(poses, axis=0), axis=1))]
    if np.any(np.diff(chord) <= 0):
        raise ConfigError("keyframes must differ from their neighbours")
    spline = CubicSpline(chord / chord[-1], poses, axis=0, bc_type="natural")
    return lambda s: spline(np.clip(s, 0.0, 1.0))


class _DeferredPyplot(types.ModuleType):
    """Stands for :mod:`matplotlib.pyplot` in ``sys.modules`` until an attribute of it is
    used, which imports the real module (once; every later use goes to it).

    toppra imports ``matplotlib.pyplot`` when it is imported, for plotting helpers the moves
    never call: about 0.4 s of CPU per process that times a move (pyplot's own import,
    measured with ``python -X importtime``). Dunder lookups (``__file__``, ``__path__``, made
    by tools that walk ``sys.modules``) do not import it; they see a module without them.
    Setting or deleting an attribute (``monkeypatch.setattr(plt, "close", ...)`` in code that
    imported the placeholder) goes to the real module too, where later imports will look.
    """

    def _real(self) -> types.ModuleType:
        if sys.modules.get(self.__name__) is self:
            del sys.modules[self.__name__]
        return importlib.import_module(self.__name__)

    def __getattr__(self, attr: str) -> Any:
        if attr.startswith("__") and attr.endswith("__"):
            raise AttributeError(attr)
        return getattr(self._real(), attr)

    def __setattr__(self, attr: str, value: Any) -> None:
        if attr.startswith("__") and attr.endswith("__"):
            super().__setattr__(attr, value)
        else:
            setattr(self._real(), attr, value)

    def __delattr__(self, attr: str) -> None:
        if attr.startswith("__") and attr.endswith("__"):
            super().__delattr__(attr)
        else:
            delattr(self._real(), attr)


def _defer_pyplot() -> None:
    """Put a :class:`_DeferredPyplot` in place of ``matplotlib.pyplot`` before toppra is
    imported (nothing to do once either is imported). Called where toppra is imported, so that
    a process that times no move imports neither. matplotlib itself is imported (toppra's
    ``import matplotlib.pyplot`` would import it anyway), so that ``matplotlib.pyplot`` is also
    the placeholder's attribute, as after a real import."""
    if "toppra" in sys.modules or "matplotlib.pyplot" in sys.modules:
        return
    try:
        import matplotlib
    except ImportError:  # toppra then goes without pyplot (its own fallback)
        return
    placeholder = _DeferredPyplot("matplotlib.pyplot")
    sys.modules["matplotlib.pyplot"] = placeholder
    matplotlib.pyplot = placeholder


def _time_parametrise(
    ss: np.ndarray, qs: np.ndarray, limits: ActuatorLimits, scale: float, n_grid: int
) -> tuple[np.ndarray, np.ndarray]:
    """toppra on the spline through (ss, qs): gridpoints and s-dot at them (rest to rest)."""
    _defer_pyplot()  # toppra's import of pyplot, which the moves never use
    import toppra as ta
    import toppra.algorithm as algo
    import toppra.constraint as constraint

    path = ta.SplineInterpolator(ss, qs)
    v = limits.v_max * scale
    a = limits.a_max * scale
    cons = [
        constraint.JointVelocityConstraint(np.stack([-v, v], axis=1)),
        constraint.JointAccelerationConstraint(np.stack([-a, a], axis=1)),
    ]
    # uniform grid, refined geometrically near both ends where short acceleration phases
    # of long moves live (a phase shorter than a grid interval would be stretched); toppra
    # can fail on the tiny end intervals of an ill-conditioned path, so the plain uniform
    # grid is the fallback
    uniform = np.linspace(0.0, 1.0, n_grid + 1)
    ends = np.geomspace(1e-5, 1.0 / n_grid, 16)
    refined = np.unique(np.concatenate([uniform, ends, 1.0 - ends]))
    sd = None
    logger = logging.getLogger("toppra")
    level = logger.level
    logger.setLevel(logging.ERROR)  # a failed grid is handled here, not worth a warning
    try:
        for grid in (refined, uniform):
            inst = algo.TOPPRA(cons, path, gridpoints=grid, parametrizer="ParametrizeConstAccel")
            _sdd, sd, _v = inst.compute_parameterization(0.0, 0.0)
            if sd is not None:
                break
    finally:
        logger.setLevel(level)
    if sd is None:
        raise LimitError("toppra found no feasible time parametrisation for this path")
    return grid, np.maximum(np.asarray(sd, dtype=float), 0.0)


def _sample_s(grid: np.ndarray, sd: np.ndarray, rate_hz: float) -> tuple[np.ndarray, float]:
    """s at frame times k / rate for constant s'' between gridpoints; returns (s, duration)."""
    ds = np.diff(grid)
    dt_seg = 2.0 * ds / np.maximum(sd[:-1] + sd[1:], 1e-300)
    t_grid = np.r_[0.0, np.cumsum(dt_seg)]
    duration = float(t_grid[-1])
    m = math.ceil(duration * rate_hz - 1e-9) + 1
    t = np.arange(m) / rate_hz
    seg = np.clip(np.searchsorted(t_grid, t, side="right") - 1, 0, ds.size - 1)
    tau = np.minimum(t - t_grid[seg], dt_seg[seg])
    u = (sd[seg + 1] ** 2 - sd[seg] ** 2) / (2.0 * ds[seg])
    s = grid[seg] + sd[seg] * tau + 0.5 * u * tau**2
    s = np.clip(s, 0.0, 1.0)
    s[-1] = 1.0
    return s, duration


def _check(q: np.ndarray, rate_hz: float, limits: ActuatorLimits) -> LimitCheck:
    dt = 1.0 / rate_hz
    padded = np.concatenate([q, q[-1:], q[-1:]])  # rest after the end
    return check_trajectory(padded, dt, limits.without_jerk(), history=np.stack([q[0], q[0]]))


def _run(
    q_of_s: PathFn,
    pose_of_s: PathFn,
    limits: ActuatorLimits,
    rate_hz: float,
    n_grid: int,
    pose_of_q: PoseOfQ | None = None,
    knots_q: np.ndarray | None = None,
    knots_pose: np.ndarray | None = None,
) -> Transition:
    """The time-optimal transition along ``q_of_s``, else the straight-line fallback through
    ``knots_q`` (K, n) (default: the path's two ends), whose poses are ``knots_pose``."""
    if not (isinstance(rate_hz, int | float) and 1.0 <= rate_hz <= 10000.0):
        raise ConfigError(f"rate_hz = {rate_hz!r} is invalid; allowed: [1, 10000] Hz")
    ss = np.linspace(0.0, 1.0, max(4 * n_grid, 64) + 1)
    qs = q_of_s(ss)
    knots = qs[[0, -1]] if knots_q is None else np.asarray(knots_q, dtype=float)
    if not np.all(np.isfinite(qs)):
        why = "the pose path leaves the kinematic workspace"
    elif np.any(qs < limits.q_min - 1e-12) or np.any(qs > limits.q_max + 1e-12):
        why = "the pose path leaves the actuator stroke"
    else:
        if np.max(np.abs(qs - qs[0])) == 0.0:  # nothing to move
            q0 = qs[:1].copy()
            return Transition(
                t_s=np.zeros(1), q=q0, poses=pose_of_s(np.zeros(1)), duration_s=0.0,
                limit_scale=1.0, check=_check(q0, rate_hz, limits),
            )  # fmt: skip
        scale = 1.0 - 1e-5  # room for toppra's solver tolerance (about 1e-6 on the speed)
        why = ""
        for _ in range(_RETRIES + 1):
            try:
                grid, sd = _time_parametrise(ss, qs, limits, scale, n_grid)
            except LimitError:
                why = "toppra found no time-optimal timing on the pose path"
                break
            s, duration = _sample_s(grid, sd, rate_hz)
            q = q_of_s(s)
            chk = _check(q, rate_hz, limits)
            if chk.ok:
                tr = Transition(
                    t_s=np.arange(s.size) / rate_hz, q=q, poses=pose_of_s(s),
                    duration_s=duration, limit_scale=scale, check=chk,
                )  # fmt: skip
                if limits.j_max is None:
                    return tr
                try:
                    return _jerk_smooth(tr, limits, rate_hz, pose_of_q)
                except LimitError as exc:
                    why = f"the jerk limiter could not follow the time-optimal path ({exc})"
                    break
            scale *= _RETRY_SCALE
        else:
            why = (
                "the time-optimal timing still broke the limits between its grid points at "
                f"{scale / _RETRY_SCALE:.2f} of them"
            )
    return _line_fallback(knots, limits, rate_hz, pose_of_q, why, knots_pose)


def _s_profile(limits_1d: ActuatorLimits, dt: float) -> np.ndarray:
    """Frames of a path parameter s from 0 to 1, rest to rest, within ``limits_1d`` (one
    axis, stroke [0, 1]): the discrete limiter chasing a target held at 1."""
    state: LimiterState | JerkLimiterState
    step: Callable[[], list[float]]
    if limits_1d.j_max is None:
        rt = RealtimeLimiter(limits_1d, dt)
        state = rt_state = rt.initial_state([0.0])
        step = lambda: rt.step(rt_state, [1.0])  # noqa: E731
    else:
        jl = JerkLimiter(limits_1d, dt)
        state = jl_state = jl.initial_state([0.0])
        step = lambda: jl.step(jl_state, [1.0])  # noqa: E731
    out = [0.0]
    for _ in range(_MAX_SETTLE_FRAMES):
        out.append(step()[0])
        accelerating = isinstance(state, JerkLimiterState) and any(state.a)
        at_rest = not any(state.v) and not accelerating
        if state.q[0] == 1.0 and at_rest:
            return np.asarray(out)
    raise LimitError("the straight-line fallback did not settle at its end position")


def _line_fallback(
    knots: np.ndarray,
    limits: ActuatorLimits,
    rate_hz: float,
    pose_of_q: PoseOfQ | None,
    why: str,
    knots_pose: np.ndarray | None = None,
) -> Transition:
    """Rest-to-rest straight lines in actuator space through ``knots`` (K, n), each timed by
    the discrete limiter on its path parameter (see the module docstring); the frames at the
    knots get the poses ``knots_pose`` (K, 6), the others forward kinematics."""
    dt = 1.0 / rate_hz
    if not np.all(np.isfinite(knots)):
        raise LimitError(f"{why}, and a position it must pass has no finite value")
    for k, qk in enumerate(knots):
        out = np.flatnonzero((qk < limits.q_min - 1e-12) | (qk > limits.q_max + 1e-12))
        if out.size:
            i = int(out[0])
            where = "start" if k == 0 else ("end" if k == len(knots) - 1 else f"keyframe {k}")
            rotary = limits.kinds[i] == "rotary"
            unit, scale = ("deg", 180.0 / math.pi) if rotary else ("mm", 1e3)
            raise LimitError(
                f"{why}, and the move's {where} puts actuator {limits.names[i]} at "
                f"{qk[i] * scale:.2f} {unit}, outside its usable stroke "
                f"[{limits.q_min[i] * scale:.2f}, {limits.q_max[i] * scale:.2f}] {unit}"
            )
    pieces = [knots[:1]]
    at_knot = {0: 0}  # frame index -> knot index
    n_frames = 1
    for kb, (qa, qb) in enumerate(itertools.pairwise(knots), start=1):
        d = qb - qa
        moving = np.abs(d) > 0.0
        if not np.any(moving):
            continue
        dm = np.abs(d[moving])
        # a hair inside: each actuator moves |d_i| s, so its speed, acceleration and jerk
        # are |d_i| times those of s
        shrink = 1.0 - 1e-9
        v_s = float(np.min(limits.v_max[moving] / dm)) * shrink
        a_s = float(np.min(limits.a_max[moving] / dm)) * shrink
        j_s = None if limits.j_max is None else float(np.min(limits.j_max[moving] / dm)) * shrink
        one = ActuatorLimits(
            np.array([-1e-12]), np.array([1.0 + 1e-12]), np.array([v_s]), np.array([a_s]),
            None if j_s is None else np.array([j_s]),
        )  # fmt: skip
        s = _s_profile(one, dt)
        q = qa + s[:, None] * d
        q[-1] = qb
        pieces.append(q[1:])
        n_frames += len(q) - 1
        at_knot[n_frames - 1] = kb
    q = np.concatenate(pieces)
    chk = _check_full(q, rate_hz, limits)
    if not chk.ok:  # not expected: the profile keeps the limits by construction
        raise LimitError(f"the straight-line fallback breaks a limit: {chk}")
    poses = np.full((q.shape[0], 6), np.nan)
    if pose_of_q is not None:
        guess = None
        for k in range(q.shape[0]):
            if knots_pose is not None and k in at_knot:
                poses[k] = knots_pose[at_knot[k]]
            else:
                poses[k] = pose_of_q(q[k], guess)
            guess = poses[k]
    return Transition(
        t_s=np.arange(q.shape[0]) / rate_hz, q=q, poses=poses,
        duration_s=(q.shape[0] - 1) / rate_hz, limit_scale=1.0, check=chk,
        fallback=f"{why}: moved in a straight line in actuator space instead (rest to rest, "
        f"{(q.shape[0] - 1) / rate_hz:.2f} s)",
    )  # fmt: skip


def _check_full(q: np.ndarray, rate_hz: float, limits: ActuatorLimits) -> LimitCheck:
    """The finite-difference check with rest before and after, jerk included when limited."""
    dt = 1.0 / rate_hz
    padded = np.concatenate([q, q[-1:], q[-1:], q[-1:]])
    return check_trajectory(padded, dt, limits, history=np.stack([q[0], q[0], q[0]]))


def _jerk_smooth(
    tr: Transition, limits: ActuatorLimits, rate_hz: float, pose_of_q: PoseOfQ | None
) -> Transition:
    """Pass a toppra transition through the :class:`JerkLimiter` from rest and let it
    settle on the end position at rest (toppra knows no jerk limit)."""
    dt = 1.0 / rate_hz
    jl = JerkLimiter(limits, dt)
    state = jl.initial_state(tr.q[0])
    rows = [tr.q[0].tolist()]
    for row in tr.q[1:].tolist():
        rows.append(jl.step(state, row))
    end = tr.q[-1].tolist()
    for _ in range(_MAX_SETTLE_FRAMES):
        if state.q == end and not any(state.v) and not any(state.a):
            break
        rows.append(jl.step(state, end))
    else:
        raise LimitError("the jerk-limited transition did not settle at its end position")
    q = np.asarray(rows, dtype=float)
    poses = np.full((q.shape[0], 6), np.nan)
    m = tr.q.shape[0]
    same = np.zeros(q.shape[0], dtype=bool)
    same[:m] = np.all(q[:m] == tr.q, axis=1)
    poses[:m][same[:m]] = tr.poses[same[:m]]
    if pose_of_q is not None:
        guess = tr.poses[0]
        for k in range(q.shape[0]):
            if same[k]:
                guess = poses[k]
                continue
            poses[k] = pose_of_q(q[k], guess)
            guess = poses[k]
    padded = np.concatenate([q, q[-1:], q[-1:], q[-1:]])
    chk = check_trajectory(padded, dt, limits, history=np.stack([q[0], q[0], q[0]]))
    if not chk.ok:
        raise LimitError(f"jerk-limited transition breaks a limit: {chk}")
    return Transition(
        t_s=np.arange(q.shape[0]) / rate_hz, q=q, poses=poses,
        duration_s=(q.shape[0] - 1) / rate_hz, limit_scale=tr.limit_scale, check=chk,
    )  # fmt: skip


def transition(
    platform: Platform,
    pose_from: ArrayLike,
    pose_to: ArrayLike,
    limits: ActuatorLimits,
    rate_hz: float,
    *,
    n_grid: int = 100,
    v_from: ArrayLike | None = None,
    v_to: ArrayLike | None = None,
    accel_max: ArrayLike | None = None,
    accept: Callable[[np.ndarray], bool] | None = None,
) -> Transition:
    """Move from ``pose_from`` to ``pose_to`` (6,).

    At rest at both ends (``v_from`` and ``v_to`` omitted or zero): the fastest move along a
    straight pose line (toppra, see the module docstring).

    From or to motion: ``v_from`` / ``v_to`` (6,) are the pose velocities (m/s, rad/s) at the
    first / last frame, so a move can continue a motion (a cue still moving at its end, on
    its way to park) or end in one (a ramp that hands over to a cue already moving), with no
    velocity step. Each pose component follows the quintic with the given position and
    velocity and zero acceleration at both ends (so no acceleration step either), all
    components over one duration ``T``, a whole number of frames: the shortest that keeps
    each component's acceleration within ``accel_max`` (6,) (m/s^2, rad/s^2; e.g. the
    perception thresholds, so the whole move is felt as one gentle motion) and every frame
    within ``limits`` (``T`` grows by 1.25, up to 15x, until the finite-difference check, with
    the motion continued at ``v_from`` before the first frame and at ``v_to`` after the last,
    passes).
    Where the path leaves the workspace (or ``accept(poses)`` is false), ``T`` shrinks by 0.8
    until it does not (an overshoot along the initial velocity shrinks with ``T``; the acceleration
    grows): ``Transition.shortened`` says so, with the peak acceleration.

    Raises
    ------
    LimitError
        At rest: when the line leaves the workspace/stroke, or no limit-respecting timing
        was found. From motion: when no duration keeps the frames in the workspace and within
        the limits.
    """
    a = _pose6("pose_from", pose_from)
    b = _pose6("pose_to", pose_to)
    va = np.zeros(6) if v_from is None else _pose6("v_from", v_from)
    vb = np.zeros(6) if v_to is None else _pose6("v_to", v_to)
    if np.any(va) or np.any(vb):
        if accel_max is None:
            raise ConfigError("a transition from or to motion needs accel_max (6,)")
        acc = _pose6("accel_max", accel_max)
        if np.any(acc <= 0.0):
            raise ConfigError(f"accel_max = {acc.tolist()} is invalid; allowed: 6 numbers > 0")
        return _moving_transition(platform, a, va, b, vb, limits, rate_hz, acc, accept)
    return transition_through(platform, np.stack([a, b]), limits, rate_hz, n_grid=n_grid)


def quintic_poses(
    pose_from: np.ndarray,
    v_from: np.ndarray,
    pose_to: np.ndarray,
    v_to: np.ndarray,
    duration_s: float,
    t_s: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Poses (M, 6) and accelerations (M, 6) at times ``t_s`` (M,) in ``[0, duration_s]`` of
    the quintic per component with position and velocity ``pose_from, v_from`` at 0 and
    ``pose_to, v_to`` at ``duration_s``, and zero acceleration at both.

    With ``tau = t / T``, ``D = pose_to - pose_from``, ``a = v_from T``, ``b = v_to T``:
    ``p = pose_from + a tau + (10 D - 6 a - 4 b) tau^3 + (-15 D + 8 a + 7 b) tau^4
    + (6 D - 3 a - 3 b) tau^5``.
    """
    T = float(duration_s)
    tau = np.clip(np.asarray(t_s, dtype=float) / T, 0.0, 1.0)[:, None]
    d = pose_to - pose_from
    a, b = v_from * T, v_to * T
    c3, c4, c5 = 10 * d - 6 * a - 4 * b, -15 * d + 8 * a + 7 * b, 6 * d - 3 * a - 3 * b
    pos = pose_from + a * tau + c3 * tau**3 + c4 * tau**4 + c5 * tau**5
    acc = (6 * c3 * tau + 12 * c4 * tau**2 + 20 * c5 * tau**3) / (T * T)
    return pos, acc


def _quintic_duration(
    d: np.ndarray, v_from: np.ndarray, v_to: np.ndarray, accel_max: np.ndarray
) -> float:
    """Shortest ``T`` (s) whose :func:`quintic_poses` keeps every component's acceleration
    within ``accel_max``: the acceleration is ``(A(tau) D + B(tau) v_from T + C(tau) v_to T)
    / T^2``, decreasing in ``T`` for every ``tau``; bisection on a fine ``tau`` grid."""
    tau = np.linspace(0.0, 1.0, 401)[:, None]
    ka = 60 * tau - 180 * tau**2 + 120 * tau**3  # coefficient of D
    kb = -36 * tau + 96 * tau**2 - 60 * tau**3  # of v_from T
    kc = -24 * tau + 84 * tau**2 - 60 * tau**3  # of v_to T

    def peak_ratio(T: float) -> float:
        acc = (ka * d + (kb * v_from + kc * v_to) * T) / (T * T)
        return float(np.max(np.abs(acc) / accel_max))

    lo, hi = 1e-3, 1.0
    while peak_ratio(hi) > 1.0 and hi < 1e4:
        hi *= 2.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if peak_ratio(mid) > 1.0 else (lo, mid)
    return hi


def _moving_transition(
    platform: Platform,
    pose_from: np.ndarray,
    v_from: np.ndarray,
    pose_to: np.ndarray,
    v_to: np.ndarray,
    limits: ActuatorLimits,
    rate_hz: float,
    accel_max: np.ndarray,
    accept: Callable[[np.ndarray], bool] | None,
) -> Transition:
    """:func:`transition` from or to motion (see there)."""
    if not (isinstance(rate_hz, int | float) and 1.0 <= rate_hz <= 10000.0):
        raise ConfigError(f"rate_hz = {rate_hz!r} is invalid; allowed: [1, 10000] Hz")
    if limits.n_actuators != platform.n_actuators:
        raise ConfigError(
            f"limits have {limits.n_actuators} actuators; platform has {platform.n_actuators}"
        )
    mask = np.asarray(platform.dof_mask, dtype=bool)
    pose_from, pose_to = np.where(mask, pose_from, 0.0), np.where(mask, pose_to, 0.0)
    v_from, v_to = np.where(mask, v_from, 0.0), np.where(mask, v_to, 0.0)
    dt = 1.0 / rate_hz
    target = _quintic_duration(pose_to - pose_from, v_from, v_to, accel_max)
    T = max(math.ceil(target * rate_hz - 1e-9), 2) * dt
    shortened = False
    why = ""
    growths = 0
    for _ in range(60):
        m = round(T * rate_hz)
        t = np.arange(m + 1) * dt
        poses, acc = quintic_poses(pose_from, v_from, pose_to, v_to, T, t)
        poses[-1] = pose_to
        q = np.asarray(platform.inverse(poses), dtype=float)
        inside = bool(
            np.all(np.isfinite(q))
            and np.all(q >= limits.q_min - 1e-12)
            and np.all(q <= limits.q_max + 1e-12)
            and (accept is None or accept(poses))
        )
        if not inside:
            if m <= 2:
                why = "no duration keeps the move from motion in the workspace"
                break
            T = min(math.floor(m * 0.8), m - 1) * dt  # shorter: less overshoot
            shortened = True
            continue
        before = np.asarray(platform.inverse(pose_from - np.outer([3, 2, 1], v_from) * dt))
        after = np.asarray(platform.inverse(pose_to + np.outer([1, 2, 3], v_to) * dt))
        chk = check_trajectory(np.concatenate([q, after]), dt, limits, history=before)
        if chk.ok:
            note = ""
            if shortened:
                ratio = np.max(np.abs(acc), axis=0) / accel_max
                i = int(np.argmax(ratio))
                dof = ("x", "y", "z", "roll", "pitch", "yaw")[i]
                unit = "m/s^2" if i < 3 else "rad/s^2"
                note = (
                    f"shortened by the workspace from {target:.2f} s to {T:.2f} s: peak "
                    f"acceleration {ratio[i] * accel_max[i]:.3f} {unit} on {dof}, "
                    f"{ratio[i]:.1f} times its target {accel_max[i]:.3f}"
                )
            return Transition(
                t_s=t, q=q, poses=poses, duration_s=T, limit_scale=1.0, check=chk,
                shortened=note,
            )  # fmt: skip
        # the actuator limit this duration breaks most (as a share of it)
        over = max(("speed", chk.speed), ("acceleration", chk.accel), ("jerk", chk.jerk),
                   key=lambda kv: kv[1])  # fmt: skip
        if shortened:  # shortened for the workspace, and now too fast for the actuators
            why = (
                f"the move from motion, shortened to {T:.2f} s by the workspace, would exceed "
                f"an actuator {over[0]} limit by {over[1]:.0%}"
            )
            break
        growths += 1
        if growths > _MAX_GROWTHS:
            why = (
                f"the move from motion exceeds an actuator {over[0]} limit by {over[1]:.0%} "
                f"even at {T:.2f} s"
            )
            break
        T = math.ceil(T * 1.25 * rate_hz) * dt
    raise LimitError(why or "no duration keeps the move from motion within the limits")


def transition_through(
    platform: Platform,
    keyframes: ArrayLike,
    limits: ActuatorLimits,
    rate_hz: float,
    *,
    n_grid: int = 100,
) -> Transition:
    """Fastest move through keyframe poses (K, 6), K >= 2, timing free, rest at both ends.

    Pose components the platform cannot produce (``~platform.dof_mask``) are set to zero.
    """
    poses = np.asarray(keyframes, dtype=float)
    if poses.ndim != 2 or poses.shape[1] != 6 or poses.shape[0] < 2:
        raise ConfigError(f"keyframes have shape {poses.shape}; expected (K >= 2, 6)")
    if not np.all(np.isfinite(poses)):
        raise ConfigError("keyframes contain NaN or inf")
    if limits.n_actuators != platform.n_actuators:
        raise ConfigError(
            f"limits have {limits.n_actuators} actuators; platform has {platform.n_actuators}"
        )
    if poses.shape[0] > 2 and np.any(np.all(np.diff(poses, axis=0) == 0, axis=1)):
        raise ConfigError("keyframes must differ from their neighbours")
    # components the machine cannot produce are held at zero (as the inverse kinematics
    # does), so that the poses returned are the poses the frames produce
    poses = np.where(np.asarray(platform.dof_mask, dtype=bool), poses, 0.0)
    # keyframes that differ only in what the machine cannot produce coincide now: one of
    # each run of equal ones is kept (the move passes there once)
    keep = np.r_[True, np.any(np.diff(poses, axis=0) != 0.0, axis=1)]
    poses = poses[keep]
    if poses.shape[0] == 1:
        poses = np.vstack([poses, poses])  # nothing to move: one frame
    pose_of_s = _pose_path(poses)

    def q_of_s(s: np.ndarray) -> np.ndarray:
        return np.asarray(platform.inverse(pose_of_s(s)), dtype=float)

    def pose_of_q(q: np.ndarray, guess: np.ndarray | None) -> np.ndarray:
        # the nearest rigid pose; a corner rig's line between two rigid positions twists
        # its frame by a second-order amount, which this pose does not show
        return np.asarray(platform.forward(q, guess=guess).pose, dtype=float)

    knots_q = np.asarray(platform.inverse(poses), dtype=float)
    return _run(q_of_s, pose_of_s, limits, rate_hz, n_grid, pose_of_q, knots_q, poses)


def transition_q(
    q_from: ArrayLike, q_to: ArrayLike, limits: ActuatorLimits, rate_hz: float, *, n_grid: int = 100
) -> Transition:
    """Fastest straight-line move in actuator space between two positions (n,), at rest."""
    a = np.asarray(q_from, dtype=float).reshape(-1)
    b = np.asarray(q_to, dtype=float).reshape(-1)
    if a.shape != (limits.n_actuators,) or b.shape != a.shape:
        raise ConfigError(f"q_from/q_to need {limits.n_actuators} values each")

    def q_of_s(s: np.ndarray) -> np.ndarray:
        q: np.ndarray = a + np.asarray(s)[..., None] * (b - a)
        return q

    def pose_of_s(s: np.ndarray) -> np.ndarray:
        return np.full((*np.shape(s), 6), np.nan)

    return _run(q_of_s, pose_of_s, limits, rate_hz, n_grid)


def _pose6(name: str, pose: ArrayLike) -> np.ndarray:
    arr = np.asarray(pose, dtype=float).reshape(-1)
    if arr.shape != (6,) or not np.all(np.isfinite(arr)):
        raise ConfigError(f"{name} = {arr.tolist()} is invalid; allowed: 6 finite numbers")
    return arr


# ------------------------------------------------------------------------ park / unpark
@overload
def brake_to_rest(
    limiter: RealtimeLimiter, state: LimiterState, max_frames: int = 100000
) -> np.ndarray: ...
@overload
def brake_to_rest(
    limiter: JerkLimiter, state: JerkLimiterState, max_frames: int = 100000
) -> np.ndarray: ...
def brake_to_rest(
    limiter: RealtimeLimiter | JerkLimiter,
    state: LimiterState | JerkLimiterState,
    max_frames: int = 100000,
) -> np.ndarray:
    """Frames (M, n) that bring a moving limiter state to rest as fast as the limits allow.

    :class:`RealtimeLimiter`: each axis heads for its own stopping point ``q + D(v)`` (the
    discrete braking distance, inside the stroke for an admissible state), which the
    limiter reaches at rest by braking at full deceleration. :class:`JerkLimiter`: each
    frame asks to stay where the last frame is, which makes it apply its braking policy.
    ``state`` is advanced; M = 0 if already at rest.
    """
    lim = limiter.limits
    frames: list[list[float]] = []
    if isinstance(limiter, JerkLimiter):
        jstate = cast(JerkLimiterState, state)
        while (any(jstate.v) or any(jstate.a)) and len(frames) < max_frames:
            frames.append(limiter.step(jstate, list(jstate.q)))
    else:
        state = cast(LimiterState, state)
        target = [
            q + math.copysign(braking_distance(v, float(lim.a_max[i]), limiter.dt_s), v)
            for i, (q, v) in enumerate(zip(state.q, state.v, strict=True))
        ]
        while any(v != 0.0 for v in state.v) and len(frames) < max_frames:
            frames.append(limiter.step(state, target))
    return np.asarray(frames, dtype=float).reshape(-1, lim.n_actuators)


def park_path(
    platform: Platform,
    limits: ActuatorLimits,
    rate_hz: float,
    *,
    pose_from: ArrayLike | None = None,
    q_from: ArrayLike | None = None,
    v_from: ArrayLike | None = None,
    a_from: ArrayLike | None = None,
) -> Transition:
    """Frames from the current state to the parked pose ``platform.pose_park``.

    Give the current pose (at rest), or the last frame sent ``q_from`` (n,) with its speed
    ``v_from`` (n,) (and acceleration ``a_from`` (n,) when the limits have a jerk limit): a
    moving platform first brakes to rest (:func:`brake_to_rest`), then follows a
    time-optimal transition to park. Times continue across both parts; ``t_s[0]`` is the
    first frame after ``q_from``.
    """
    dt = 1.0 / rate_hz
    head = np.zeros((0, limits.n_actuators))
    hist = None
    if q_from is not None:
        q_f = np.asarray(q_from, dtype=float).reshape(-1)
        v_f = (
            np.zeros_like(q_f)
            if v_from is None
            else np.broadcast_to(np.asarray(v_from, float), q_f.shape)
        )
        a_f = (
            np.zeros_like(q_f)
            if a_from is None
            else np.broadcast_to(np.asarray(a_from, float), q_f.shape)
        )
        state: LimiterState | JerkLimiterState
        if limits.j_max is None:
            rt = RealtimeLimiter(limits, dt)
            state = rt_state = rt.initial_state(q_f, v_f)
            head = brake_to_rest(rt, rt_state)
        else:
            jl = JerkLimiter(limits, dt)
            state = jl_state = jl.initial_state(q_f, v_f, a_f)
            head = brake_to_rest(jl, jl_state)
        q_rest = np.asarray(state.q)
        fk = platform.forward(q_rest, guess=None if pose_from is None else pose_from)
        if not fk.ok:
            raise LimitError(f"cannot find the pose of q = {q_rest.tolist()} (FK failed)")
        start = np.asarray(fk.pose, dtype=float)
        q_m1 = q_f - v_f * dt  # the frames sent before q_from (speed, acceleration)
        hist = np.stack([q_m1 - (v_f - a_f * dt) * dt, q_m1, q_f])
    elif pose_from is not None:
        start = _pose6("pose_from", pose_from)
    else:
        raise ConfigError("park_path needs pose_from or q_from")
    tr = transition(platform, start, platform.pose_park, limits, rate_hz)
    if head.shape[0] == 0:
        return tr
    poses_head = np.array([platform.forward(q, guess=start).pose for q in head])
    q = np.concatenate([head, tr.q[1:]])
    poses = np.concatenate([poses_head, tr.poses[1:]])
    t = np.arange(q.shape[0]) / rate_hz + dt
    padded = np.concatenate([q, q[-1:], q[-1:], q[-1:]])
    chk = check_trajectory(padded, dt, limits, history=hist)
    if not chk.ok:
        raise LimitError(f"park path breaks a limit: {chk}")
    return Transition(t, q, poses, tr.duration_s + head.shape[0] * dt, tr.limit_scale, chk)


def unpark_path(
    platform: Platform, limits: ActuatorLimits, rate_hz: float, pose_to: ArrayLike | None = None
) -> Transition:
    """Frames from the parked pose to ``pose_to`` (default neutral, zeros), at rest."""
    target = np.zeros(6) if pose_to is None else _pose6("pose_to", pose_to)
    return transition(platform, platform.pose_park, target, limits, rate_hz)


def resume_path(
    platform: Platform,
    pose_from: ArrayLike,
    pose_to: ArrayLike,
    limits: ActuatorLimits,
    rate_hz: float,
) -> Transition:
    """Frames from a paused pose to the pose the ride resumes at (both at rest)."""
    return transition(platform, pose_from, pose_to, limits, rate_hz)
