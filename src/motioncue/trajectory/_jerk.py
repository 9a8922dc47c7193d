"""Causal real-time limiter with a jerk limit (stroke, speed, acceleration and jerk).

Built on the second-order limiter of :mod:`motioncue.trajectory._realtime`, one derivative
up, plus a position safety check by exact simulation of a braking policy:

*Velocity level.* Speed ``v`` is treated as the "position" of a second-order system whose
"stroke" is ``[-v_max, v_max]``, "speed" is the acceleration (``<= a_max``) and
"acceleration" is the jerk (``<= j_max``). The second-order step (same closed-form braking
bound, same proof) turns any wanted next speed into one that keeps ``|v| <= v_max``,
``|a| <= a_max`` and ``|j| <= j_max``, from any admissible ``(v, a)``.

*Braking policy P.* Wanting speed 0 at the velocity level, frame after frame, is a
deterministic state feedback that brings ``(v, a)`` to exactly ``(0, 0)`` (the second-order
chase of a held target lands on it without overshoot) within every limit. A state
``(q, v, a)`` is **admissible** when ``q`` is in stroke, ``(v, a)`` is admissible at the
velocity level, and every position P visits until rest stays in stroke (found by
simulating P, tracking the lowest and highest position since the speed may reverse once
when ``a`` opposes ``v``; or accepted without simulation when a conservative bound on the
excursion already keeps it inside).

*Step.* The candidate is the velocity-level step towards the speed that lands on the
target this frame; when that lands exactly (the velocity-level step passes it through,
allowing its rounding slack, :func:`._realtime._land_slack`: the limiter's own frames fed
back pass again) and the new state is admissible, the target is sent exactly, so a
stream P-admissible at every frame passes bit for bit. Otherwise the limiter searches
(bisection, 10 steps) for the largest wanted speed towards the target whose next state
is admissible and whose stopping point does not pass the target (approach without
overshoot); if none does, it sends P's action, which is admissible by construction
because P is a state feedback (the state it leads to continues the same braking).
Every emitted frame therefore keeps every limit.

Cost: a next state farther inside its band than P can move from any admissible
``(v, a)`` of its speed (:func:`._brake.bound_line`: its line ahead of the motion, its
value at rest behind it) is accepted at once; P's stop is
looked at only when the closed-form one-sided bounds of :mod:`._brake` cannot decide
either (near a stroke end, or near the target while limiting): its exact distance when
it moves one way (:func:`._brake.forward_within`: :func:`._brake.forward_stop` with an
early no), else a simulation until the answer is known. A chase whose budget is past
:func:`_chase_saturation` ends on the band's bound without :func:`._realtime._vcap`
(below it, :func:`_vcap_big`: its saturation budget kept per axis, one call); the
bisection (:func:`_bisect`, only when the full wanted speed is refused) remembers the
states it has decided (saturated wanted speeds repeat the same next state) and ends at a
refused wanted speed whose chase lies beyond the band the other way (every later one is
clipped to the same state). Frames are bit-identical to the full simulation's.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from .._errors import ConfigError, LimitError
from ._brake import (
    bound_line,
    brake_ahead,
    brake_bound,
    forward_within,
    simulate_within,
    stops_within,
)
from ._limits import ActuatorLimits
from ._realtime import _counters_repr, _land_slack, _level_params, _level_step

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["JerkLimiter", "JerkLimiterState"]

_MAX_BRAKE_FRAMES = 1_000_000
_BISECT = 10
# _bisect: a chase value this far (times abig) beyond the band ends the search (see there)
_PAST = 1e-9


class JerkLimiterState:
    """Changing state of a :class:`JerkLimiter`: last frame ``q``, its speed ``v`` and
    acceleration ``a`` (finite differences), the last finite target and the last speed
    wanted at the velocity level; counters as :class:`LimiterState`."""

    __slots__ = (
        "a",
        "clamped_axes",
        "last_target",
        "last_want",
        "max_deviation",
        "n_clamped",
        "n_frames",
        "n_nonfinite",
        "n_simulated",
        "q",
        "v",
    )

    def __init__(self, q: list[float], v: list[float], a: list[float]) -> None:
        self.q, self.v, self.a = q, v, a
        self.last_target = list(q)
        self.last_want = list(v)
        self.n_frames = self.n_clamped = self.n_nonfinite = self.n_simulated = 0
        self.clamped_axes = [0] * len(q)
        self.max_deviation = 0.0

    def __repr__(self) -> str:
        return _counters_repr(self)


@dataclass(frozen=True, eq=False)
class JerkLimiter:
    """Frozen description of a causal limiter with a jerk limit (see module docstring).

    Parameters
    ----------
    limits : ActuatorLimits
        Must have ``j_max``.
    dt_s : float
        Frame period (s), in (0, 1].
    """

    limits: ActuatorLimits
    dt_s: float
    _params: tuple[tuple[float, ...], ...] = field(init=False, repr=False)
    _dt: float = field(init=False, repr=False)
    _inv_dt: float = field(init=False, repr=False)
    _slack: tuple[float, ...] = field(init=False, repr=False)
    _axes: tuple[tuple[float, ...], ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if not (isinstance(self.dt_s, int | float) and 0.0 < self.dt_s <= 1.0):
            raise ConfigError(f"dt_s = {self.dt_s!r} is invalid; allowed: a period in (0, 1] s")
        lim = self.limits
        if lim.j_max is None:
            raise ConfigError("JerkLimiter needs limits with j_max; use RealtimeLimiter")
        dt = float(self.dt_s)
        params = tuple(
            (
                float(lim.q_min[i]),
                float(lim.q_max[i]),
                float(lim.v_max[i]),
                *_level_params(lim.a_max[i], lim.j_max[i], dt),
                float(lim.j_max[i]),
            )
            for i in range(lim.n_actuators)
        )
        object.__setattr__(self, "_params", params)
        # the landing test's slack at the velocity level (accelerations: order 2)
        slacks = tuple(_land_slack(p[4], max(abs(p[0]), abs(p[1])), dt, 2) for p in params)
        object.__setattr__(self, "_slack", slacks)
        # step()'s constants per axis: _params, the landing slack, the budget from which
        # _vcap is at least a_max (_chase_saturation), whether P's braking staircase
        # never meets the +-v_max caps (_brake.stops_within's stair_ok, same expression)
        # and bound_line's (x0, slope, v, a): from |v'| <= v and |a'| <= a, P moves at most
        # x0 + slope |v'| either way, _vcap's saturation budget (from which it is abig) and
        # the largest wanted speed, 2 v_max
        axes = tuple(
            (
                *p,
                sl,
                _chase_saturation(p[3], p[4], p[6]),
                p[3] * p[3] * p[5] + p[3] * dt <= p[2],
                *bound_line(p[2], p[3], p[7], dt),
                p[6] + p[6] * p[6] / (2.0 * p[4]) + p[4],
                2.0 * p[2],
            )
            for p, sl in zip(params, slacks, strict=True)
        )
        object.__setattr__(self, "_axes", axes)
        object.__setattr__(self, "_dt", dt)
        object.__setattr__(self, "_inv_dt", 1.0 / dt)

    @property
    def n_actuators(self) -> int:
        return self.limits.n_actuators

    # ------------------------------------------------------------------ braking policy
    def stopping_offset(self, i: int, v: float, a: float) -> tuple[float, float] | None:
        """Lowest and highest offset (signed, SI) axis ``i`` reaches under the braking
        policy P from ``(v, a)`` until rest (exact simulation; the speed may reverse once
        when ``a`` opposes ``v``); ``None`` if it does not come to rest."""
        _, _, vmax, amax, jdt, half_inv_j, abig, _ = self._params[i]
        dt = float(self.dt_s)
        inv_dt = 1.0 / dt
        d = lo = hi = 0.0
        for _ in range(_MAX_BRAKE_FRAMES):
            if v == 0.0 and a == 0.0:
                return lo, hi
            v, a, _ = _level_step(
                v, a, 0.0, 0.0, -vmax, vmax, amax, jdt, half_inv_j, abig, dt, inv_dt
            )
            d += v * dt
            if d < lo:
                lo = d
            elif d > hi:
                hi = d
        return None

    def _bound(self, i: int, v: float, a: float) -> float:
        """Conservative bound on how far P moves from ``(v, a)`` either way (closed form,
        see :func:`._brake.brake_bound`; checked against the simulation by the tests)."""
        _, _, _, amax, _, _, _, jmax = self._params[i]
        return max(brake_bound(v, a, amax, jmax, float(self.dt_s)))

    def _admissible(
        self, state: JerkLimiterState | None, i: int, q: float, v: float, a: float,
        lo: float, hi: float,
    ) -> bool:  # fmt: skip
        """q in [lo, hi] and P's stopping point too (bound first, then simulation)."""
        if not lo - 1e-9 <= q <= hi + 1e-9:
            return False
        _, _, vmax, amax, jdt, half_inv_j, abig, jmax = self._params[i]
        dt = float(self.dt_s)
        down, up = brake_bound(v, a, amax, jmax, dt)
        if lo <= q - down and q + up <= hi:
            return True
        if state is not None:
            state.n_simulated += 1
        # exact simulation of P, stopped as soon as the answer is known
        return stops_within(q, v, a, lo, hi, vmax, amax, jdt, half_inv_j, abig, jmax, dt)

    # ------------------------------------------------------------------ states
    def is_admissible(
        self, q: ArrayLike, v: ArrayLike | None = None, a: ArrayLike | None = None
    ) -> bool:
        """Whether ``(q, v, a)`` (each (n,)) is admissible (module docstring)."""
        n = self.n_actuators
        qa = np.asarray(q, dtype=float).reshape(-1)
        va = np.zeros(n) if v is None else np.asarray(v, dtype=float).reshape(-1)
        aa = np.zeros(n) if a is None else np.asarray(a, dtype=float).reshape(-1)
        if qa.shape != (n,) or va.shape != (n,) or aa.shape != (n,):
            return False
        dt = float(self.dt_s)
        for i in range(n):
            qmin, qmax, vmax, amax, _jdt, _h, _ab, jmax = self._params[i]
            qi, vi, ai = float(qa[i]), float(va[i]), float(aa[i])
            if not all(math.isfinite(x) for x in (qi, vi, ai)):
                return False
            if abs(vi) > vmax * (1 + 1e-9) or abs(ai) > amax * (1 + 1e-9):
                return False
            # velocity level: able to bring a to 0 without passing +-v_max
            d = _second_order_distance(ai, jmax, dt)
            if (ai > 0 and vi + d > vmax + 1e-9) or (ai < 0 and vi - d < -vmax - 1e-9):
                return False
            if not self._admissible(None, i, qi, vi, ai, qmin, qmax):
                return False
        return True

    def initial_state(
        self, q0: ArrayLike, v0: ArrayLike | None = None, a0: ArrayLike | None = None
    ) -> JerkLimiterState:
        """State after a last frame ``q0`` moving at ``v0`` with acceleration ``a0`` (n,).

        Raises
        ------
        LimitError
            If the state is not admissible.
        """
        n = self.n_actuators
        q = np.asarray(q0, dtype=float).reshape(-1)
        v = np.zeros(n) if v0 is None else np.broadcast_to(np.asarray(v0, float), (n,))
        a = np.zeros(n) if a0 is None else np.broadcast_to(np.asarray(a0, float), (n,))
        if q.shape != (n,):
            raise ConfigError(f"initial state needs {n} positions")
        if not self.is_admissible(q, v, a):
            raise LimitError(
                f"initial state q={q.tolist()} v={v.tolist()} a={a.tolist()} is not admissible"
            )
        return JerkLimiterState([float(x) for x in q], [float(x) for x in v], [float(x) for x in a])

    # ------------------------------------------------------------------ stepping
    def step(self, state: JerkLimiterState, q_target: Sequence[float] | np.ndarray) -> list[float]:
        """Next frame (n,) for a target (n,); updates ``state``. Never returns NaN/inf."""
        if isinstance(q_target, np.ndarray):
            q_target = q_target.tolist()
        qs, vs, accs, lts, lws = state.q, state.v, state.a, state.last_target, state.last_want
        if len(q_target) != len(qs):
            raise ConfigError(f"target has {len(q_target)} values; expected {len(qs)}")
        dt = self._dt
        inv_dt = self._inv_dt
        clamped = False
        n_sim = 0
        n_axes = state.clamped_axes
        max_dev = state.max_deviation
        # _level_step at the velocity level and the admissibility test of _admissible,
        # inlined (a call per candidate costs more than the work): the band of next
        # accelerations depends on (v, a) only, so it is computed once per axis for the
        # landing test and every candidate; same float operations, so the same frames
        for i, axis in enumerate(self._axes):
            (qmin, qmax, vmax, amax, jdt, half_inv_j, abig, jmax, sl, sat, stair_ok,
             reach0, slope, v_in, a_in, big, w_max) = axis  # fmt: skip
            t = float(q_target[i])
            if t - t != 0.0:
                t = lts[i]
                state.n_nonfinite += 1
                finite = False
            else:
                lts[i] = t
                finite = True
            q = qs[i]
            v = vs[i]
            a = accs[i]
            want = (t - q) * inv_dt
            # beyond 2 v_max every wanted speed acts alike; clamping keeps inf/NaN out
            if want > w_max:
                want = w_max
            elif want < -w_max:
                want = -w_max
            # the band [lo, hi] of next accelerations (_level_step: x = v, d = a)
            hi = a + jdt
            if hi > amax:
                hi = amax
            lo = a - jdt
            if lo < -amax:
                lo = -amax
            if hi > 0.0 and v + hi * dt + hi * hi * half_inv_j > vmax:
                cap = _vcap_big((vmax - v) * inv_dt, jdt, abig, big)
                if hi > cap:
                    hi = cap
            if lo < 0.0 and v + lo * dt - lo * lo * half_inv_j < -vmax:
                cap = _vcap_big((v - -vmax) * inv_dt, jdt, abig, big)
                if lo < -cap:
                    lo = -cap
            dd = (want - v) * inv_dt
            dw = (want - lws[i]) * inv_dt
            lws[i] = want  # the target's own speed as seen from the last frame
            if lo - sl <= dd <= hi + sl and -jdt - sl <= dd - dw <= jdt + sl:  # lands
                q1 = t
                if qmin - 1e-9 <= q1 <= qmax + 1e-9:
                    v1 = (q1 - q) * inv_dt
                    a1 = (v1 - v) * inv_dt
                    # P stays inside whatever brake_bound says (its bound_line reach ahead,
                    # x0 behind), else brake_bound decides, else the exact check
                    if (
                        -v_in <= v1 <= v_in
                        and -a_in <= a1 <= a_in
                        and (
                            qmin + reach0 <= q1 <= qmax - (reach0 + slope * v1)
                            if v1 >= 0.0
                            else qmin + (reach0 - slope * v1) <= q1 <= qmax - reach0
                        )
                    ):
                        ok = True
                    else:
                        down, up = brake_bound(v1, a1, amax, jmax, dt)
                        if qmin <= q1 - down and q1 + up <= qmax:
                            ok = True
                        else:
                            n_sim += 1
                            ok = _stops(q1, v1, a1, qmin, qmax, axis, dt)
                    if ok:
                        qs[i] = q1
                        vs[i] = v1
                        accs[i] = a1
                        continue
            # limiting: the largest wanted speed towards the target (held, no feed-forward
            # of its rate) whose next state is admissible and stops before the target
            # (approach without overshoot); first the full one (here), then bisection
            # towards 0 (_bisect)
            lo_w, hi_w = qmin, qmax
            if t > q:
                hi_w = t if t < qmax else qmax
            elif t < q:
                lo_w = t if t > qmin else qmin
            # _level_step(v, a, want, want): lands on want, else the chase clipped to the
            # band; its (want - v) / dt is dd (same operations)
            if lo <= dd <= hi and -jdt <= dd <= jdt:
                vb = want
            else:
                # sign(want - v) _vcap(|want - v| / dt, jdt, abig) with its first test (a
                # saturated chase) inlined; from `sat` on it is >= amax, so the band's bound
                # is the answer whatever its value: abig stands in for it (same clipped dn).
                # dd has the sign of want - v (dt <= 1) and (-e) / dt == -(e / dt) (exact)
                if dd >= sat:
                    dn = abig
                elif dd <= -sat:
                    dn = -abig
                elif dd > 0.0:
                    dn = _vcap_big(dd, jdt, abig, big)
                else:
                    dn = -_vcap_big(-dd, jdt, abig, big)
                if dn > hi:
                    dn = hi
                if dn < lo:
                    dn = lo
                vb = v + dn * dt
            qn = q + vb * dt
            vn = (qn - q) * inv_dt
            an = (vn - v) * inv_dt
            # the next state is admissible (_admissible, inlined): brake_bound's answer, or
            # the exact check where it says no. Where bound_line keeps the side behind the
            # motion inside (brake_bound's bound there is at most x0), brake_bound's answer
            # is its forward side's (brake_ahead: the same operations), or the line's where
            # that keeps the side ahead inside too
            if not lo_w - 1e-9 <= qn <= hi_w + 1e-9:
                ok = False
            elif -v_in <= vn <= v_in and -a_in <= an <= a_in:
                if vn > 0.0 or (vn == 0.0 and an >= 0.0):  # brake_bound's unflipped side
                    if lo_w + reach0 <= qn:
                        ok = (
                            qn <= hi_w - (reach0 + slope * vn)
                            or qn + brake_ahead(vn, an, amax, jmax, dt) <= hi_w
                        )
                    else:
                        down, up = brake_bound(vn, an, amax, jmax, dt)
                        ok = lo_w <= qn - down and qn + up <= hi_w
                elif qn <= hi_w - reach0:
                    ok = lo_w + (reach0 - slope * vn) <= qn or lo_w <= qn - brake_ahead(
                        -vn, -an, amax, jmax, dt
                    )
                else:
                    down, up = brake_bound(vn, an, amax, jmax, dt)
                    ok = lo_w <= qn - down and qn + up <= hi_w
                if not ok:  # the exact check (_stops, inlined)
                    n_sim += 1
                    dec = (
                        forward_within(qn, vn, an, lo_w, hi_w, amax, jdt, dt) if stair_ok else None
                    )
                    if dec is None:
                        dec = simulate_within(qn, vn, an, lo_w, hi_w, vmax, amax, jdt, half_inv_j,
                                              abig, jmax, dt, bool(stair_ok))  # fmt: skip
                    ok = dec
            else:
                down, up = brake_bound(vn, an, amax, jmax, dt)
                if lo_w <= qn - down and qn + up <= hi_w:
                    ok = True
                else:
                    n_sim += 1
                    ok = _stops(qn, vn, an, lo_w, hi_w, axis, dt)
            if not ok:
                qn, vn, an, sims = _bisect(q, v, want, lo, hi, lo_w, hi_w, qn, axis, dt, inv_dt)
                n_sim += sims
            qs[i] = qn
            vs[i] = vn
            accs[i] = an
            if qn != t:
                clamped = True
                n_axes[i] += 1
                if finite:
                    dev = qn - t if qn > t else t - qn  # |qn - t| (t - qn: its exact negation)
                    if dev > max_dev:
                        max_dev = dev
        state.max_deviation = max_dev
        state.n_simulated += n_sim
        state.n_frames += 1
        if clamped:
            state.n_clamped += 1
        return qs[:]  # the frames: each axis' new q

    def run(self, state: JerkLimiterState, q_targets: ArrayLike) -> np.ndarray:
        """Step through targets (N, n); returns the frames (N, n) (same as :meth:`step`)."""
        targets = np.asarray(q_targets, dtype=float)
        if targets.ndim != 2 or targets.shape[1] != self.n_actuators:
            raise ConfigError(
                f"targets have shape {targets.shape}; expected (N, {self.n_actuators})"
            )
        out = np.empty_like(targets)
        for k, row in enumerate(targets.tolist()):
            out[k] = self.step(state, row)
        return out


def _stops(
    q: float, v: float, a: float, lo: float, hi: float, axis: tuple[float, ...], dt: float
) -> bool:
    """Whether P from ``(q, v, a)`` stops within ``[lo, hi]`` (1e-9 tolerance), ``q`` itself
    inside it: :func:`._brake.stops_within` with the axis' constants (``JerkLimiter._axes``),
    its closed-form distance first where the axis allows it."""
    _, _, vmax, amax, jdt, half_inv_j, abig, jmax, _, _, stair_ok, _, _, _, _, _, _ = axis
    if stair_ok:
        ok = forward_within(q, v, a, lo, hi, amax, jdt, dt)
        if ok is not None:
            return ok
    return simulate_within(
        q, v, a, lo, hi, vmax, amax, jdt, half_inv_j, abig, jmax, dt, bool(stair_ok)
    )


def _bisect(
    q: float,
    v: float,
    want: float,
    lo: float,
    hi: float,
    lo_w: float,
    hi_w: float,
    q_want: float,
    axis: tuple[float, ...],
    dt: float,
    inv_dt: float,
) -> tuple[float, float, float, int]:
    """The limited next state ``(q, v, a)`` of one axis of :meth:`JerkLimiter.step` when the
    full wanted speed ``want`` (next position ``q_want``) is not admissible, and the number
    of exact braking checks made: bisection (``_BISECT`` steps) for the largest wanted speed
    in ``[0, want]`` whose next state is admissible within ``[lo_w, hi_w]``, else P's
    action. ``(q, v)``: the last state; ``[lo, hi]``: the band of next accelerations."""
    (_, _, vmax, amax, jdt, half_inv_j, abig, jmax, _, sat, stair_ok, reach0, slope, v_in, a_in,
     big, _) = axis  # fmt: skip
    lo_e = lo_w - 1e-9
    hi_e = hi_w + 1e-9
    n_sim = 0
    best = False
    qn = vn = an = 0.0
    w_lo, w_hi = 0.0, want
    # wanted speeds beyond what one frame can reach give the same next state (the step
    # saturates): remember each decided state (q, v fixed: qb decides it)
    seen = {q_want: False}
    k = 0
    # while the midpoint's chase is saturated as want's was (same sign, budget past sat),
    # its next state is q_want's (the same clipped dn): known not admissible
    d_want = (want - v) * inv_dt
    if d_want >= sat:
        while k < _BISECT and (0.5 * (w_lo + w_hi) - v) * inv_dt >= sat:
            w_hi = 0.5 * (w_lo + w_hi)
            k += 1
    elif d_want <= -sat:
        while k < _BISECT and (0.5 * (w_lo + w_hi) - v) * inv_dt <= -sat:
            w_hi = 0.5 * (w_lo + w_hi)
            k += 1
    # A refused wanted speed whose chase asks for more than the band allows the other way
    # ends the search: its chase value (`raw`, before clipping) is a non-decreasing function
    # of w (of (w - v) / dt: -abig, -_vcap(-x), _vcap(x), abig over the saturation budgets;
    # _vcap rises with its budget and stays below abig before its own saturation), and every
    # later midpoint lies between 0 and it (towards 0: below it when want > 0, above it
    # when want < 0). So for want > 0 and raw below lo by more than _PAST abig (rounding
    # moves raw by parts in 1e15 of abig), every later chase is below lo too, is clipped to
    # the same dn = lo (and does not land: (w - v) / dt <= raw < lo), so it is the same
    # state, refused (seen): the rest of the search only refuses. Mirror for want < 0
    # (raw above hi). The full want counts as such a speed (its state is refused too).
    rising = want > 0.0  # (not `up`: brake_bound's name below)
    lo_past = lo - _PAST * abig
    hi_past = hi + _PAST * abig
    if d_want >= sat:
        raw = abig
    elif d_want <= -sat:
        raw = -abig
    elif d_want > 0.0:
        raw = _vcap_big(d_want, jdt, abig, big)
    else:
        raw = -_vcap_big(-d_want, jdt, abig, big)
    if (raw < lo_past) if rising else (raw > hi_past):
        k = _BISECT
    for _ in range(k, _BISECT):
        w = 0.5 * (w_lo + w_hi)
        # _level_step(v, a, w, w): lands on w, else the chase clipped to the band
        ddw = (w - v) * inv_dt
        if lo <= ddw <= hi and -jdt <= ddw <= jdt:
            vb = w
            past = False
        else:
            # sign(e) _vcap(|e| / dt), e = w - v: ddw has e's sign and (-e) / dt == -ddw;
            # past: whether this chase value is beyond the band the other way (above)
            if ddw > 0.0 and ddw < sat and hi < 0.0:
                # _vcap is >= 0: above a band below 0 it is clipped to hi whatever its
                # value; only its bounds [0, abig] are known, so past from them
                dn = hi
                past = not rising and 0.0 > hi_past
            elif ddw <= 0.0 and ddw > -sat and lo > 0.0:
                dn = lo  # (mirror: in [-abig, 0])
                past = rising and 0.0 < lo_past
            else:
                if ddw >= sat:
                    dn = abig
                elif ddw <= -sat:
                    dn = -abig
                elif ddw > 0.0:
                    dn = _vcap_big(ddw, jdt, abig, big)
                else:
                    dn = -_vcap_big(-ddw, jdt, abig, big)
                past = (dn < lo_past) if rising else (dn > hi_past)
            if dn > hi:
                dn = hi
            if dn < lo:
                dn = lo
            vb = v + dn * dt
        qb = q + vb * dt
        vb = (qb - q) * inv_dt
        ab_ = (vb - v) * inv_dt
        known = seen.get(qb)
        if known is not None:
            ok = known
        else:
            # as JerkLimiter.step: bound_line (ahead and behind), brake_ahead where the side
            # behind is inside, else brake_bound; where those say no, the exact check
            if not lo_e <= qb <= hi_e:
                ok = False
            else:
                if -v_in <= vb <= v_in and -a_in <= ab_ <= a_in:
                    if vb > 0.0 or (vb == 0.0 and ab_ >= 0.0):
                        if lo_w + reach0 <= qb:
                            ok = (
                                qb <= hi_w - (reach0 + slope * vb)
                                or qb + brake_ahead(vb, ab_, amax, jmax, dt) <= hi_w
                            )
                        else:
                            down, up = brake_bound(vb, ab_, amax, jmax, dt)
                            ok = lo_w <= qb - down and qb + up <= hi_w
                    elif qb <= hi_w - reach0:
                        ok = lo_w + (reach0 - slope * vb) <= qb or lo_w <= qb - brake_ahead(
                            -vb, -ab_, amax, jmax, dt
                        )
                    else:
                        down, up = brake_bound(vb, ab_, amax, jmax, dt)
                        ok = lo_w <= qb - down and qb + up <= hi_w
                else:
                    down, up = brake_bound(vb, ab_, amax, jmax, dt)
                    ok = lo_w <= qb - down and qb + up <= hi_w
                if not ok:
                    n_sim += 1
                    dec = (
                        forward_within(qb, vb, ab_, lo_w, hi_w, amax, jdt, dt) if stair_ok else None
                    )
                    if dec is None:
                        dec = simulate_within(qb, vb, ab_, lo_w, hi_w, vmax, amax, jdt, half_inv_j,
                                              abig, jmax, dt, bool(stair_ok))  # fmt: skip
                    ok = dec
            seen[qb] = ok
        if ok:
            best = True
            qn, vn, an = qb, vb, ab_
            w_lo = w
        else:
            w_hi = w
            if past:  # every later midpoint is this state again: refused (above)
                break
    if not best:  # P's action (_level_step(v, a, 0, 0)): admissible by construction
        ddw = (0.0 - v) * inv_dt
        if lo <= ddw <= hi and -jdt <= ddw <= jdt:
            vb = 0.0
        else:
            e = 0.0 - v
            dn = (
                _vcap_big(e * inv_dt, jdt, abig, big)
                if e > 0.0
                else -_vcap_big(-e * inv_dt, jdt, abig, big)
            )
            if dn > hi:
                dn = hi
            if dn < lo:
                dn = lo
            vb = v + dn * dt
        qn = q + vb * dt
        vn = (qn - q) * inv_dt
        an = (vn - v) * inv_dt
    return qn, vn, an, n_sim


def _vcap_big(b: float, adt: float, v_big: float, b_big: float) -> float:
    """:func:`._realtime._vcap` ``(b, adt, v_big)`` (speed units) for a finite ``v_big``,
    its saturation budget ``b_big = v_big + v_big^2 / (2 adt) + adt`` given (precomputed by
    the same expression, so the same float) and :func:`._realtime._stairs` inlined: the same
    operations, the same result."""
    if b <= 0.0:
        return 0.0
    if b >= b_big:
        return v_big
    n = int((math.sqrt(1.0 + 8.0 * b / adt) - 1.0) * 0.5)
    while n > 0 and adt * n * (n + 1) * 0.5 > b:
        n -= 1
    while adt * (n + 1) * (n + 2) * 0.5 <= b:
        n += 1
    return b / (n + 1) + adt * n * 0.5


def _second_order_distance(a: float, j: float, dt: float) -> float:
    """Velocity still gained after a frame at acceleration |a| when braking it at jerk j."""
    a = abs(a)
    jdt = j * dt
    n = math.floor(a / jdt)
    return dt * (n * a - jdt * n * (n + 1) / 2.0)


def _chase_saturation(amax: float, jdt: float, abig: float) -> float:
    """A budget ``b`` (speed units, as :func:`._realtime._vcap`'s) from which ``_vcap(b, jdt,
    abig)`` is at least ``amax`` (so a chase step clipped to the band ``|a| <= amax`` ends on
    the band's bound, whatever the exact value).

    ``_vcap(b) >= amax`` exactly when ``b >= S = amax + sum_{i=1..m} (amax - i jdt)``,
    ``m = floor(amax / jdt)`` (the staircase's budget for ``amax``); the threshold is
    ``S`` plus one part in 1e6, so that ``_vcap``'s rounding (parts in 1e15) cannot bring it
    under ``amax``: ``_vcap`` rises at least ``1 / (n + 1)`` per unit of budget above ``S``.
    No more than ``_vcap``'s own saturation test (``abig``): beyond it ``abig`` is returned.
    """
    m = math.floor(amax / jdt)
    s = (m + 1) * amax - jdt * m * (m + 1) / 2.0
    return min(s * (1.0 + 1e-6), abig + abig * abig / (2.0 * jdt) + jdt)
