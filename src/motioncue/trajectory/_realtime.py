"""Causal real-time actuator limiter: one frame at a time, plain floats, deterministic.

Model
-----
The limiter works on the frame grid ``dt`` with the finite-difference definitions of
:mod:`motioncue.trajectory._limits`. Its state is the last frame sent, ``q[k-1]``, and the
last speed, ``v[k-1] = (q[k-1] - q[k-2]) / dt``. Choosing the next frame is choosing the
next speed ``v``; the frame is ``q[k] = q[k-1] + v dt``.

*Discrete braking distance.* From speed ``v > 0``, braking at full deceleration gives the
speeds ``v - a dt, v - 2 a dt, ...`` until zero, so the distance still travelled after the
current frame is ``D(v) = dt * sum_{i>=1} max(v - i a dt, 0)``. A state is **admissible**
when ``q`` is in stroke, ``|v| <= v_max``, ``q + D(v) <= q_max`` if ``v > 0`` and
``q - D(-v) >= q_min`` if ``v < 0``.

*Allowed next speeds.* ``v`` must satisfy ``|v| <= v_max``, ``|v - v[k-1]| <= a dt`` and keep
the next state admissible: ``v dt + D(v) <= q_max - q[k-1]`` (for ``v > 0``, and the mirror
image for ``v < 0``). ``f(v) = v dt + D(v)`` is continuous and increasing, so this is an
upper bound ``v <= V(q_max - q[k-1])`` with the closed form, for ``B = budget / dt`` and
``n`` the largest integer with ``a dt n (n+1) / 2 <= B``::

    V = B / (n + 1) + a dt n / 2

The allowed set is an interval ``[lo, hi]`` and is never empty from an admissible state:
the braking speed ``max(v[k-1] - a dt, 0)`` (or its mirror) is in it, because
``(v - a dt) dt + D(v - a dt) = D(v)``. By induction every emitted frame is in stroke and
within the speed and acceleration limits, whatever the targets are.

*Choice inside the interval.* With ``vd = (target - q[k-1]) / dt`` the speed that reaches
the target this frame and ``vt = (target - previous target) / dt`` the target's own speed:
if ``vd`` is in ``[lo, hi]`` and ``|vd - vt| <= a dt`` (the frame lands on the target moving
about as the target does) the target is sent **exactly**, so a feasible target stream
passes through bit for bit (there ``q[k-1]`` equals the previous target, hence
``vd == vt``). Both tests allow a slack (:func:`_land_slack`): a stream the limiter
itself sent reaches its bounds exactly, and the finite differences recomputed from its
frames miss them by rounding (a few 1e-15 m/s at a hexapod's scale); without the slack
such a frame would be limited again, and the limited frame lands millimetres away (a
2000-frame hexapod ride fed back: 529 frames limited, up to 7 mm). The slack is one part
in 1e10 of ``a dt`` (ten times inside the checker's tolerance), or the rounding of
positions at the stroke's scale where that is larger (``4 ulp(|q|) / dt``).
Otherwise the limiter chases the target: ``vt + sign(e) V(|e|)`` with
``e = target - q[k-1]``, clipped to ``[lo, hi]``; for a held target this is the discrete
time-optimal approach that stops on it without overshoot. Non-finite targets are replaced
by the last finite target (counted).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._errors import ConfigError, LimitError
from ._limits import ActuatorLimits

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ._jerk import JerkLimiterState

__all__ = ["LimiterState", "RealtimeLimiter", "braking_distance", "braking_speed_cap"]

# RealtimeLimiter.run: frames checked at once where the stream lands on its targets (a
# window that doubles up to _MAX_WINDOW while every frame lands), and how many frames in a
# row step() must land on every axis before run() tries that again after a frame it changed
_FIRST_WINDOW = 64
_MAX_WINDOW = 4096
_CALM_FRAMES = 8
# the landing test's slack, as a fraction of the per-frame change ddt (module docstring)
_LAND_SLACK = 1e-10


def braking_distance(v: float, a_max: float, dt_s: float) -> float:
    """Distance still travelled after a frame at speed ``|v|`` when braking at ``a_max``.

    ``D(v) = dt * sum_{i>=1} max(|v| - i a dt, 0)`` (see module docstring).
    """
    v = abs(v)
    adt = a_max * dt_s
    n = math.floor(v / adt)
    return dt_s * (n * v - adt * n * (n + 1) / 2.0)


def braking_speed_cap(budget: float, a_max: float, dt_s: float) -> float:
    """Largest speed ``v >= 0`` with ``v dt + D(v) <= budget`` (0 if ``budget <= 0``)."""
    return _vcap(budget / dt_s, a_max * dt_s, math.inf)


def _vcap(b: float, adt: float, v_big: float = math.inf) -> float:
    """Largest v >= 0 with v + D(v)/dt <= b, all in speed units (b = budget/dt).

    Returns ``v_big`` instead when the answer is at least ``v_big`` (callers pass a speed
    above every limit, which also keeps huge budgets out of the integer search).
    """
    if b <= 0.0:
        return 0.0
    if v_big < math.inf:
        if b >= v_big + v_big * v_big / (2.0 * adt) + adt:
            return v_big
    elif not b < 1e200:
        return math.inf
    n = _stairs(b, adt)
    return b / (n + 1) + adt * n * 0.5


def _stairs(b: float, adt: float) -> int:
    """The number ``n`` of whole steps of ``adt`` in the staircase of budget ``b > 0``: the
    largest ``n >= 0`` with ``adt n (n + 1) / 2 <= b`` (closed form, then corrected for
    rounding). :func:`_vcap` is ``b / (n + 1) + adt n / 2``."""
    n = int((math.sqrt(1.0 + 8.0 * b / adt) - 1.0) * 0.5)
    while n > 0 and adt * n * (n + 1) * 0.5 > b:
        n -= 1
    while adt * (n + 1) * (n + 2) * 0.5 <= b:
        n += 1
    return n


def _level_params(d_max: float, dd_max: float, dt: float) -> tuple[float, float, float, float]:
    """``(d_max, ddt, half_inv, d_big)`` of :func:`_level_step` for a derivative bounded by
    ``d_max`` that changes at most ``dd_max`` per second (speed and acceleration for
    positions; acceleration and jerk for speeds), at frame period ``dt`` (s)."""
    return float(d_max), float(dd_max) * dt, 0.5 / float(dd_max), 2.0 * float(d_max)


def _land_slack(ddt: float, q_scale: float, dt: float, order: int) -> float:
    """Slack of :func:`_level_step`'s landing test (module docstring): ``_LAND_SLACK`` of
    ``ddt``, or the rounding of a difference of order ``order`` (1: speeds, 2: accelerations)
    recomputed from positions of magnitude ``q_scale`` (m), ``4 order ulp(q_scale) / dt^order``,
    whichever is larger."""
    return max(_LAND_SLACK * ddt, 4.0 * order * math.ulp(q_scale) / dt**order)


def _level_step(
    x: float,
    d: float,
    want: float,
    want_prev: float,
    x_min: float,
    x_max: float,
    d_max: float,
    ddt: float,
    half_inv: float,
    d_big: float,
    dt: float,
    inv_dt: float,
    slack: float = 0.0,
) -> tuple[float, float, bool]:
    """One step of a causal limiter at one derivative level; ``(x', d', landed exactly)``.

    ``x`` is bounded to ``[x_min, x_max]``, its difference ``d = (x[k] - x[k-1]) / dt`` to
    ``|d| <= d_max``, and ``d`` changes by at most ``ddt`` a step, so that braking at that
    rate still stops inside the bounds (``half_inv = 1 / (2 ddt / dt)``, ``d_big`` above
    every limit; see :func:`_vcap`). The step lands on ``want`` when allowed, else approaches
    it as fast as it may (``want_prev``: the previous wanted value); the landing test
    allows ``slack`` of rounding (:func:`_land_slack`). Positions with speeds
    (:class:`RealtimeLimiter`: ``x = q``, ``d = v``) and speeds with accelerations
    (:class:`~motioncue.trajectory._jerk.JerkLimiter`: ``x = v``, ``x_min = -v_max``).
    """
    hi = d + ddt
    if hi > d_max:
        hi = d_max
    lo = d - ddt
    if lo < -d_max:
        lo = -d_max
    if hi > 0.0 and x + hi * dt + hi * hi * half_inv > x_max:
        cap = _vcap((x_max - x) * inv_dt, ddt, d_big)
        if hi > cap:
            hi = cap
    if lo < 0.0 and x + lo * dt - lo * lo * half_inv < x_min:
        cap = _vcap((x - x_min) * inv_dt, ddt, d_big)
        if lo < -cap:
            lo = -cap
    dd = (want - x) * inv_dt
    dw = (want - want_prev) * inv_dt
    if lo - slack <= dd <= hi + slack and -ddt - slack <= dd - dw <= ddt + slack:
        return want, dd, True
    e = want - x
    if e > 0.0:
        dn = dw + _vcap(e * inv_dt, ddt, d_big)
    else:
        dn = dw - _vcap(-e * inv_dt, ddt, d_big)
    if dn > hi:
        dn = hi
    if dn < lo:
        dn = lo
    xn = x + dn * dt
    return xn, (xn - x) * inv_dt, False


class LimiterState:
    """Changing state of a :class:`RealtimeLimiter` (one per stream).

    Attributes
    ----------
    q : list of float, (n,)
        Last frame sent.
    v : list of float, (n,)
        Last speed ``(q[k-1] - q[k-2]) / dt``.
    last_target : list of float, (n,)
        Last finite target (used in place of NaN/inf targets).
    n_frames, n_clamped, n_nonfinite : int
        Frames stepped; frames where at least one axis was modified; non-finite target
        values replaced.
    clamped_axes : list of int, (n,)
        Per-axis count of modified frames.
    max_deviation : float
        Largest ``|q_out - target|`` over modified frames with finite targets (SI).
    """

    __slots__ = (
        "clamped_axes",
        "last_target",
        "max_deviation",
        "n_clamped",
        "n_frames",
        "n_nonfinite",
        "q",
        "v",
    )

    def __init__(self, q: list[float], v: list[float]) -> None:
        self.q = q
        self.v = v
        self.last_target = list(q)
        self.n_frames = 0
        self.n_clamped = 0
        self.n_nonfinite = 0
        self.clamped_axes = [0] * len(q)
        self.max_deviation = 0.0

    def copy(self) -> LimiterState:
        s = LimiterState(list(self.q), list(self.v))
        s.last_target = list(self.last_target)
        s.n_frames, s.n_clamped, s.n_nonfinite = self.n_frames, self.n_clamped, self.n_nonfinite
        s.clamped_axes = list(self.clamped_axes)
        s.max_deviation = self.max_deviation
        return s

    def __repr__(self) -> str:
        return _counters_repr(self)


def _counters_repr(state: LimiterState | JerkLimiterState) -> str:
    """``Name(n_frames=, n_clamped=, n_nonfinite=, max_deviation=)`` of a limiter's state."""
    return (
        f"{type(state).__name__}(n_frames={state.n_frames}, n_clamped={state.n_clamped}, "
        f"n_nonfinite={state.n_nonfinite}, max_deviation={state.max_deviation:.3g})"
    )


@dataclass(frozen=True, eq=False)
class RealtimeLimiter:
    """Frozen description of a causal limiter for one frame period.

    Parameters
    ----------
    limits : ActuatorLimits
        Stroke, speed and acceleration per actuator. With a jerk limit this class raises
        :class:`~motioncue.ConfigError`: use :class:`JerkLimiter` (or pass
        ``limits.without_jerk()`` explicitly).
    dt_s : float
        Frame period (s), in (0, 1].

    Notes
    -----
    Use ``state = rt.initial_state(q0)`` then ``q = rt.step(state, target)`` per frame.
    """

    limits: ActuatorLimits
    dt_s: float
    _params: tuple[tuple[float, ...], ...] = field(init=False, repr=False)
    _dt: float = field(init=False, repr=False)
    _inv_dt: float = field(init=False, repr=False)
    _arrays: tuple[np.ndarray, ...] = field(init=False, repr=False)
    _slack: tuple[float, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (isinstance(self.dt_s, int | float) and 0.0 < self.dt_s <= 1.0):
            raise ConfigError(f"dt_s = {self.dt_s!r} is invalid; allowed: a period in (0, 1] s")
        if self.limits.j_max is not None:
            raise ConfigError(
                "RealtimeLimiter does not enforce jerk limits; use JerkLimiter, or pass "
                "limits.without_jerk() explicitly"
            )
        lim = self.limits
        dt = float(self.dt_s)
        params = tuple(
            (
                float(lim.q_min[i]),
                float(lim.q_max[i]),
                *_level_params(lim.v_max[i], lim.a_max[i], dt),
            )
            for i in range(lim.n_actuators)
        )
        object.__setattr__(self, "_params", params)
        object.__setattr__(self, "_dt", dt)
        object.__setattr__(self, "_inv_dt", 1.0 / dt)
        slacks = tuple(_land_slack(p[3], max(abs(p[0]), abs(p[1])), dt, 1) for p in params)
        object.__setattr__(self, "_slack", slacks)
        # the same numbers per axis as arrays (q_min, q_max, d_max, ddt, half_inv, slack): run()
        columns = np.array([(*p[:5], s) for p, s in zip(params, slacks, strict=True)]).T
        object.__setattr__(self, "_arrays", tuple(columns[j].copy() for j in range(6)))

    @property
    def n_actuators(self) -> int:
        return self.limits.n_actuators

    # ------------------------------------------------------------------ states
    def is_admissible(self, q: ArrayLike, v: ArrayLike | None = None) -> bool:
        """Whether ``(q, v)`` is a state from which the limits can always be kept.

        Rounding slack: 1e-9 (SI) on positions and stopping points (float round-off in
        the speed, divided by dt, moves the discrete stopping point by ~1e-12 per frame near
        a stroke end), one part in 1e9 on speeds.
        """
        lim, dt = self.limits, self._dt
        qa = np.asarray(q, dtype=float).reshape(-1)
        va = np.zeros_like(qa) if v is None else np.asarray(v, dtype=float).reshape(-1)
        if qa.shape != (lim.n_actuators,) or va.shape != qa.shape:
            return False
        for i in range(lim.n_actuators):
            qi, vi = float(qa[i]), float(va[i])
            if not (math.isfinite(qi) and math.isfinite(vi)):
                return False
            if not lim.q_min[i] - 1e-9 <= qi <= lim.q_max[i] + 1e-9:
                return False
            if abs(vi) > lim.v_max[i] * (1.0 + 1e-9):
                return False
            d = braking_distance(vi, float(lim.a_max[i]), dt)
            if vi > 0 and qi + d > lim.q_max[i] + 1e-9:
                return False
            if vi < 0 and qi - d < lim.q_min[i] - 1e-9:
                return False
        return True

    def initial_state(self, q0: ArrayLike, v0: ArrayLike | None = None) -> LimiterState:
        """State for a stream whose last sent frame is ``q0`` (n,) moving at ``v0`` (n,).

        ``v0`` may be a scalar (same speed on every axis; default 0, at rest).

        Raises
        ------
        LimitError
            If ``(q0, v0)`` is not admissible (outside the stroke, too fast, or unable to
            stop before a stroke end).
        """
        n = self.n_actuators
        q = np.asarray(q0, dtype=float).reshape(-1)
        v = np.zeros(n) if v0 is None else np.asarray(v0, dtype=float).reshape(-1)
        if v.size == 1:
            v = np.full(n, float(v[0]))
        if q.shape != (n,) or v.shape != (n,):
            raise ConfigError(f"initial state needs {n} positions and speeds")
        if not self.is_admissible(q, v):
            raise LimitError(
                f"initial state q={q.tolist()} v={v.tolist()} is not admissible for stroke "
                f"[{self.limits.q_min.tolist()}, {self.limits.q_max.tolist()}], "
                f"v_max={self.limits.v_max.tolist()}, a_max={self.limits.a_max.tolist()}"
            )
        return LimiterState([float(x) for x in q], [float(x) for x in v])

    # ------------------------------------------------------------------ stepping
    def step(self, state: LimiterState, q_target: Sequence[float] | np.ndarray) -> list[float]:
        """Next frame (n,) for a target (n,); updates ``state``. Never returns NaN/inf."""
        if isinstance(q_target, np.ndarray):
            q_target = q_target.tolist()
        if len(q_target) != len(state.q):
            raise ConfigError(f"target has {len(q_target)} values; expected {len(state.q)}")
        dt = self._dt
        inv_dt = self._inv_dt
        qs = state.q
        vs = state.v
        lts = state.last_target
        out = [0.0] * len(qs)
        clamped = False
        i = 0
        slacks = self._slack
        for qmin, qmax, vmax, adt, half_inv_a, vbig in self._params:
            t = float(q_target[i])
            tp = lts[i]
            if t - t != 0.0:  # NaN or +-inf
                t = tp
                state.n_nonfinite += 1
                finite = False
            else:
                lts[i] = t
                finite = True
            qn, vn, landed = _level_step(
                qs[i], vs[i], t, tp, qmin, qmax, vmax, adt, half_inv_a, vbig, dt, inv_dt,
                slacks[i],
            )  # fmt: skip
            if not landed:
                clamped = True
                state.clamped_axes[i] += 1
                if finite:
                    dev = abs(qn - t)
                    if dev > state.max_deviation:
                        state.max_deviation = dev
            qs[i] = qn
            vs[i] = vn
            out[i] = qn
            i += 1
        state.n_frames += 1
        if clamped:
            state.n_clamped += 1
        return out

    def run(self, state: LimiterState, q_targets: ArrayLike) -> np.ndarray:
        """Step through a whole stream of targets (N, n); returns the frames (N, n).

        Same numbers and the same final ``state`` as calling :meth:`step` frame by frame.
        Where the stream lands on its targets (the usual case: no limit reached), whole
        stretches of frames are checked at once (:meth:`_landed_prefix`: the same float
        operations as :func:`_level_step`, on arrays); every other frame is :meth:`step`.
        """
        targets = np.asarray(q_targets, dtype=float)
        if targets.ndim != 2 or targets.shape[1] != self.n_actuators:
            raise ConfigError(
                f"targets have shape {targets.shape}; expected (N, {self.n_actuators})"
            )
        out = np.empty_like(targets)
        n_total = targets.shape[0]
        step = self.step
        k = 0
        calm = _CALM_FRAMES  # frames in a row that step() landed on every axis
        window = _FIRST_WINDOW
        while k < n_total:
            if calm >= _CALM_FRAMES:
                block = targets[k : k + window]
                m = self._landed_prefix(state, block)
                out[k : k + m] = block[:m]
                k += m
                if m == block.shape[0]:
                    window = min(2 * window, _MAX_WINDOW)
                    continue
                window, calm = _FIRST_WINDOW, 0
            clamped, nonfinite = state.n_clamped, state.n_nonfinite
            out[k] = step(state, targets[k].tolist())
            landed = state.n_clamped == clamped and state.n_nonfinite == nonfinite
            calm = calm + 1 if landed else 0
            k += 1
        return out

    def _landed_prefix(self, state: LimiterState, block: np.ndarray) -> int:
        """How many leading frames of ``block`` (m, n) :meth:`step` would send exactly as
        targeted on every axis (finite targets, no stroke-end budget to apply, the landing
        test of :func:`_level_step` passed); advances ``state`` over those frames.

        Each frame's inputs (last frame, last speed, last target) are those the previous
        frames leave when they land, and the checks are :func:`_level_step`'s float
        operations in its order on float64 arrays (IEEE, as on Python floats), so a frame
        counted here is one :meth:`step` sends unchanged; a frame whose stroke-end test
        is true (where :func:`_vcap` may lower a bound) ends the prefix, and :meth:`step`
        decides it.
        """
        if block.shape[0] == 0:
            return 0
        q_min, q_max, d_max, ddt, half_inv, slack = self._arrays
        dt, inv_dt = self._dt, self._inv_dt
        with np.errstate(invalid="ignore", over="ignore"):
            x = np.concatenate([np.asarray([state.q]), block[:-1]])
            want_prev = np.concatenate([np.asarray([state.last_target]), block[:-1]])
            dd = (block - x) * inv_dt
            d = np.concatenate([np.asarray([state.v]), dd[:-1]])
            dw = (block - want_prev) * inv_dt
            hi = d + ddt
            hi = np.where(hi > d_max, d_max, hi)
            lo = d - ddt
            lo = np.where(lo < -d_max, -d_max, lo)
            ok = np.isfinite(block)
            ok &= ~((hi > 0.0) & (x + hi * dt + hi * hi * half_inv > q_max))
            ok &= ~((lo < 0.0) & (x + lo * dt - lo * lo * half_inv < q_min))
            ok &= (lo - slack <= dd) & (dd <= hi + slack)
            e = dd - dw
            ok &= (-ddt - slack <= e) & (e <= ddt + slack)
        rows = ok.all(axis=1)
        m = block.shape[0] if rows.all() else int(np.argmin(rows))
        if m:
            state.q[:] = block[m - 1].tolist()
            state.v[:] = dd[m - 1].tolist()
            state.last_target[:] = block[m - 1].tolist()
            state.n_frames += m
        return m
