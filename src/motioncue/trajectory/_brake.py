"""Fast admissibility test for :class:`~motioncue.trajectory.JerkLimiter` (private).

The limiter's position safety rests on simulating its braking policy P until rest. This
module gives the same yes/no answer with far less work:

* :func:`brake_bound` gives closed-form, conservative bounds ``(down, up)`` on how far P
  moves below and above the start from ``(v, a)``. Forward: the continuous time-optimal
  braking distance from the peak speed ``|v| + a^2/(2 j)`` (plus ``|a| dt`` while ``a``
  still pushes on; trapezoidal or triangular acceleration profile, whose distance is half
  the peak speed times the stopping time), less the part of that profile already behind
  when ``a`` is braking, plus one frame at the peak speed for the discrete rounding.
  Backward: zero unless ``a`` opposes ``v`` strongly enough to reverse the speed, then the
  same from the reverse peak. Over 50,000 random admissible states the simulated
  excursions stayed within the bounds even without the padding frame; the tests compare
  them again.
* :func:`forward_stop` gives P's exact stopping distance (its discrete S-curve stop: the
  acceleration ramped down by ``j dt`` a frame, held at ``-a_max``, then the braking
  staircase in closed form) whenever P keeps moving one way, for limits whose braking
  never meets the +-v_max caps; :func:`stops_within` then decides with it alone.
* Otherwise :func:`stops_within` simulates P exactly, returning as soon as the answer is known:
  *no* the moment a visited position leaves the band (the exact extent can only be
  wider); once P runs its final braking staircase (``|a|`` falling by ``j dt`` a frame
  onto rest, monotone positions, last one in closed form) *yes* if its end is inside and
  *no* if it is more than 1e-9 beyond the tolerance (rounding is far smaller); with limits
  that rule the staircase out, *yes* the moment the bound from the current state keeps
  every later position inside. Its answer is the exact simulation's whenever the bound
  holds; the tests compare the two on random states near and far from the stroke ends.
"""

from __future__ import annotations

import math

from ._realtime import _stairs, _vcap

_MAX_BRAKE_FRAMES = 1_000_000
_PAD_FRAMES = 1.0
_EPS = 1e-9


def brake_bound(v: float, a: float, amax: float, jmax: float, dt: float) -> tuple[float, float]:
    """Conservative bounds ``(down, up)`` (m, both >= 0) on how far P moves below and
    above the start from speed ``v`` (m/s) and acceleration ``a`` (m/s^2), with limits
    ``amax`` (m/s^2), ``jmax`` (m/s^3) and frame period ``dt`` (s)."""
    flip = v < 0.0 or (v == 0.0 and a < 0.0)
    if flip:
        v, a = -v, -a
    a2 = amax * amax
    rev = 0.0
    if a >= 0.0:  # speed still rises to its peak while a is wound down
        vp = v + a * a * 0.5 / jmax + a * dt
        fwd = vp * (a / jmax + _PAD_FRAMES * dt)
    else:  # already braking; may reverse once when a strongly opposes v
        vp = v + a * a * 0.5 / jmax
        fwd = vp * _PAD_FRAMES * dt
        t1 = -a / jmax
        if v >= a * a * 0.5 / jmax:
            # on the braking profile from (vp, 0): what is left of it, the part covered
            # while a went from 0 to its present value taken off
            fwd -= vp * t1 - jmax * t1 * t1 * t1 / 6.0
        else:  # stops while a is wound back (then reverses): at most v for that time
            fwd += v * t1
            vp = 0.0
        vr = a * a * 0.5 / jmax - a * dt - v
        if vr > 0.0:
            rev = vr * (-a / jmax + _PAD_FRAMES * dt)
            # + braking distance from (vr, 0): half the speed times the stopping time
            if vr * jmax >= a2:
                rev += 0.5 * vr * (vr / amax + amax / jmax)
            else:
                rev += vr * math.sqrt(vr / jmax)
    # + braking distance from (vp, 0): half the speed times the stopping time
    if vp * jmax >= a2:
        fwd += 0.5 * vp * (vp / amax + amax / jmax)
    else:
        fwd += vp * math.sqrt(vp / jmax)
    return (fwd, rev) if flip else (rev, fwd)


def brake_ahead(v: float, a: float, amax: float, jmax: float, dt: float) -> float:
    """:func:`brake_bound`'s bound (m) ahead of the motion for ``v > 0``, or ``v == 0`` and
    ``a >= 0`` (its ``up``; flipped states: pass ``-v, -a`` for its ``down``), by the same
    float operations in the same order, without the side behind."""
    a2 = amax * amax
    if a >= 0.0:
        vp = v + a * a * 0.5 / jmax + a * dt
        fwd = vp * (a / jmax + _PAD_FRAMES * dt)
    else:
        vp = v + a * a * 0.5 / jmax
        fwd = vp * _PAD_FRAMES * dt
        t1 = -a / jmax
        if v >= a * a * 0.5 / jmax:
            fwd -= vp * t1 - jmax * t1 * t1 * t1 / 6.0
        else:
            fwd += v * t1
            vp = 0.0
    if vp * jmax >= a2:
        fwd += 0.5 * vp * (vp / amax + amax / jmax)
    else:
        fwd += vp * math.sqrt(vp / jmax)
    return fwd


def bound_line(
    vmax: float, amax: float, jmax: float, dt: float
) -> tuple[float, float, float, float]:
    """``(x0, slope, v, a)``: every ``brake_bound(v', a', amax, jmax, dt)`` with ``|v'| <= v``
    and ``|a'| <= a`` is at most ``x0 + slope |v'|`` (m), both ways, where ``v`` and ``a``
    are ``vmax`` (m/s) and ``amax`` (m/s^2) with one part in 1e6 to spare (the rounding of
    speeds recomputed from positions is far smaller).

    From :func:`brake_bound`'s terms, for ``|v'| = s``: the peak speed is at most ``V(s) =
    s + a^2 / (2 j) + a dt`` (``a' >= 0``; less when braking, and the reverse peak
    ``a^2 / (2 j) + |a| dt`` is less too), the profile's first part at most
    ``V (a / j + dt)`` (when braking only the padding frame plus a part that is taken off,
    or ``s |a'| / j``), and the braking distance from ``V`` rises with ``V``. So
    ``X(s) = V(s) (a / j + dt) + brake(V(s))`` bounds them all; it is convex in ``s`` (the
    braking distance is ``V^1.5 / sqrt(j)`` then a parabola, meeting with equal slopes),
    so below its chord from ``s = 0`` to ``s = v``: the line, with one part in 1e9 and
    1e-12 m added for the rounding of both computations.

    Behind the motion (below for ``v' > 0``, above for ``v' < 0``, both ways at
    ``v' = 0``) the bound is at most ``x0``: for ``v' > 0`` brake_bound's backward term is
    zero unless ``a' < 0``, and then its reverse peak ``a'^2 / (2 j) - a' dt - v'`` is below
    ``V(0) = a^2 / (2 j) + a dt``, its first part ``vr (|a'| / j + dt)`` below
    ``V(0) (a / j + dt)`` and its braking distance below that from ``V(0)``: ``X(0)``
    (``v' < 0`` mirrors it). At ``v' = 0`` the one nonzero side is the forward bound from
    speed 0, the line's value there.
    """
    v = vmax * (1.0 + 1e-6)
    a = amax * (1.0 + 1e-6)
    pad = _PAD_FRAMES * dt

    def x_of(s: float) -> float:
        peak = s + a * a * 0.5 / jmax + a * dt
        x = peak * (a / jmax + pad)
        if peak * jmax >= amax * amax:
            return x + 0.5 * peak * (peak / amax + amax / jmax)
        return x + peak * math.sqrt(peak / jmax)

    x0 = x_of(0.0) * (1.0 + 1e-9) + 1e-12
    x1 = x_of(v) * (1.0 + 1e-9) + 1e-12
    return x0, (x1 - x0) / v * (1.0 + 1e-9), v, a


def forward_stop(v: float, a: float, amax: float, jdt: float, dt: float) -> float | None:
    """Signed distance (m) P travels from speed ``v`` (m/s) and acceleration ``a`` (m/s^2)
    until rest, when it keeps moving one way; ``None`` when it brakes harder than its
    jerk allows at some frame (``a`` opposes ``v`` so strongly that the speed may reverse:
    then only the simulation knows). ``jdt = j_max dt`` (m/s^2 a frame).

    Valid for limits whose braking never meets the +-v_max caps
    (``amax^2 / (2 j_max) + amax dt <= v_max``, ``stair_ok`` in :func:`stops_within`).

    The discrete S-curve stop of P, in speed-per-frame units ``b = |v| / dt``: with
    ``S(c) = (m + 1) c - jdt m (m + 1) / 2``, ``m = floor(c / jdt)``, the speed that a braking
    staircase starting at deceleration ``c`` (then ``c - jdt``, ``c - 2 jdt``...) removes,
    P lowers ``a`` by ``jdt`` a frame (at most to ``-amax``, then holds it) while
    ``b > S(-a_next)`` (the staircase from the next deceleration would not stop in time;
    that is ``vcap(b) > -a_next``), then runs the staircase from ``u = vcap(b)``: speeds
    ``b - k u + jdt k (k - 1) / 2`` for ``k = 1..n`` and rest, ``n`` the staircase's
    length (:func:`._realtime._vcap`), a distance ``dt^2 (n b - u n (n + 1) / 2 +
    jdt (n - 1) n (n + 1) / 6)``. The ramp and hold frames are summed one by one (no
    square root, a few operations each); the staircase in closed form. Compared with the
    frame-by-frame simulation in tests/test_limiter_jerk.py (1e-12 m).
    """
    flip = v < 0.0 or (v == 0.0 and a < 0.0)
    if flip:
        v, a = -v, -a
    b = v / dt
    total = 0.0  # sum of b over the frames so far (distance / dt^2)
    for _ in range(_MAX_BRAKE_FRAMES):
        dn = a - jdt
        if dn < -amax:
            dn = -amax
        c = -dn  # the deceleration of the next frame if P keeps lowering a
        if c < 0.0:
            ramp = True  # a still above jdt: it comes down whatever the speed
        elif c == 0.0:
            ramp = b > 0.0
        else:
            m = math.floor(c / jdt)
            ramp = b > (m + 1) * c - jdt * m * (m + 1) * 0.5
        if ramp:
            a = dn
            b += a
            total += b
            continue
        up = a + jdt
        if up > amax:
            up = amax
        if up < 0.0:  # brakes harder than the staircase asks unless vcap(b) >= -up
            m = math.floor(-up / jdt)
            if b < (m + 1) * -up - jdt * m * (m + 1) * 0.5:
                return None
        if b <= 0.0:
            break
        # the braking staircase from u = vcap(b) (as _vcap: b = (n + 1) u - jdt n (n + 1) / 2)
        n = _stairs(b, jdt)
        u = b / (n + 1) + jdt * n * 0.5
        total += n * b - u * n * (n + 1) * 0.5 + jdt * (n - 1) * n * (n + 1) / 6.0
        break
    else:
        return None
    d = total * dt * dt
    return -d if flip else d


def forward_within(
    q: float, v: float, a: float, lo: float, hi: float, amax: float, jdt: float, dt: float
) -> bool | None:
    """:func:`stops_within`'s answer from :func:`forward_stop`'s distance: whether
    ``q + forward_stop(v, a, amax, jdt, dt)`` lies in ``[lo - 1e-9, hi + 1e-9]``; ``None``
    where :func:`forward_stop` has no distance (then only the simulation knows).

    The same float operations as :func:`forward_stop` and the same final test, with one
    early *no*: the ramp and hold frames add positive speeds (``b > S(c) >= c`` before a
    frame lowers ``b`` by ``c``), so the running sum only grows, and so does the distance
    the staircase then adds (a sum of positive speeds; its closed form's rounding is parts
    in 1e16 of it). Once the sum alone puts P more than 1e-9 beyond the tolerance ahead
    (``room``), the final position is outside too: *no*. Where :func:`forward_stop` would
    have found no distance after that frame, the simulation :func:`stops_within` falls back
    to visits the same positions up to rounding (far below 1e-9) and says *no* the moment
    one leaves the band: the same answer. Valid where :func:`forward_stop` is."""
    flip = v < 0.0 or (v == 0.0 and a < 0.0)
    if flip:
        v, a = -v, -a
        room = (q - (lo - _EPS - _EPS)) / (dt * dt)
    else:
        room = (hi + _EPS + _EPS - q) / (dt * dt)
    b = v / dt
    total = 0.0  # sum of b over the frames so far (distance / dt^2)
    floor = math.floor
    # forward_stop's loop by the phases of P's ramp (same tests, same sums): a coming down
    # from above jdt (c < 0: whatever the speed), lowered while b > S(c), then held at
    # -amax while b > S(amax) (one S, a tight loop; its frames, at most b / amax, are not
    # counted against _MAX_BRAKE_FRAMES); each phase's end leaves for the staircase
    for _ in range(_MAX_BRAKE_FRAMES):
        dn = a - jdt
        if dn > 0.0:
            pass  # c = -dn < 0: a still above jdt, it comes down whatever the speed
        elif dn < -amax:
            m = floor(amax / jdt)
            hold = (m + 1) * amax - jdt * m * (m + 1) * 0.5
            if b > hold:
                a = -amax
                b += a
                total += b
                if total > room:
                    return False  # already more than 1e-9 beyond the tolerance ahead
                while b > hold:
                    b += a
                    total += b
                    if total > room:
                        return False
            break
        elif dn == 0.0:
            if not b > 0.0:
                break
        else:
            c = -dn  # the deceleration of the next frame if P keeps lowering a
            m = floor(c / jdt)
            if not b > (m + 1) * c - jdt * m * (m + 1) * 0.5:
                break
        a = dn
        b += a
        total += b
        if total > room:
            return False  # already more than 1e-9 beyond the tolerance ahead
    else:
        return None
    up = a + jdt
    if up > amax:
        up = amax
    if up < 0.0:  # brakes harder than the staircase asks unless vcap(b) >= -up
        m = floor(-up / jdt)
        if b < (m + 1) * -up - jdt * m * (m + 1) * 0.5:
            return None
    if b > 0.0:
        n = _stairs(b, jdt)
        u = b / (n + 1) + jdt * n * 0.5
        total += n * b - u * n * (n + 1) * 0.5 + jdt * (n - 1) * n * (n + 1) / 6.0
    d = total * dt * dt
    return lo - _EPS <= q + (-d if flip else d) <= hi + _EPS


def stops_within(
    q: float,
    v: float,
    a: float,
    lo: float,
    hi: float,
    vmax: float,
    amax: float,
    jdt: float,
    half_inv_j: float,
    abig: float,
    jmax: float,
    dt: float,
) -> bool:
    """Whether every position P visits from ``(q, v, a)`` until rest lies in
    ``[lo - 1e-9, hi + 1e-9]`` (exact simulation with early exits; see module docstring).

    ``q`` itself is not checked. Parameters as in ``JerkLimiter._params``.
    """
    lo_e = lo - _EPS
    hi_e = hi + _EPS
    # the -v_max/+v_max cap of a braking step cannot bind (see the staircase below)
    stair_ok = amax * amax * half_inv_j + amax * dt <= vmax
    if stair_ok and lo_e <= q <= hi_e:
        # P moving one way: its positions run monotonically from q to q + the distance
        dist = forward_stop(v, a, amax, jdt, dt)
        if dist is not None:
            return lo_e <= q + dist <= hi_e
    return simulate_within(q, v, a, lo, hi, vmax, amax, jdt, half_inv_j, abig, jmax, dt, stair_ok)


def simulate_within(
    q: float,
    v: float,
    a: float,
    lo: float,
    hi: float,
    vmax: float,
    amax: float,
    jdt: float,
    half_inv_j: float,
    abig: float,
    jmax: float,
    dt: float,
    stair_ok: bool,
) -> bool:
    """:func:`stops_within` by simulation alone (its answer where :func:`forward_stop` has
    none); ``stair_ok`` as computed there (``amax^2 / (2 j_max) + amax dt <= v_max``)."""
    inv_dt = 1.0 / dt
    lo_e = lo - _EPS
    hi_e = hi + _EPS
    big = abig + abig * abig / (2.0 * jdt) + jdt
    stair = 0
    mag = 0.0
    d = 0.0
    for _ in range(_MAX_BRAKE_FRAMES):
        if v == 0.0 and a == 0.0:
            return True
        # one velocity-level step of P (want 0, previous want 0), as _realtime._level_step
        up = a + jdt
        if up > amax:
            up = amax
        dn = a - jdt
        if dn < -amax:
            dn = -amax
        if up > 0.0 and v + up * dt + up * up * half_inv_j > vmax:
            cap = _vcap((vmax - v) * inv_dt, jdt, abig)
            if up > cap:
                up = cap
        if dn < 0.0 and v + dn * dt - dn * dn * half_inv_j < -vmax:
            cap = _vcap((v + vmax) * inv_dt, jdt, abig)
            if dn < -cap:
                dn = -cap
        ad = (0.0 - v) * inv_dt
        if dn <= ad <= up and -jdt <= ad <= jdt:
            v, a = 0.0, ad
        else:
            e = 0.0 - v
            # _vcap(|e| / dt, jdt, abig), inlined (same operations, same result)
            bud = e * inv_dt if e > 0.0 else -e * inv_dt
            n = 0
            if bud <= 0.0:
                an = 0.0
            elif bud >= big:
                an = abig
            else:
                n = _stairs(bud, jdt)
                an = bud / (n + 1) + jdt * n * 0.5
            mag = an
            if not e > 0.0:
                an = -an
            if n > 0 and dn <= an <= up:
                stair = n  # an unclipped braking staircase step (below)
            if an > up:
                an = up
            if an < dn:
                an = dn
            vn = v + an * dt
            a = (vn - v) * inv_dt
            v = vn
        d += v * dt
        x = q + d
        if x < lo_e or x > hi_e:
            return False
        if stair and stair_ok:
            # braking staircase (as _vcap lays it out): |a| falls by jdt a frame and the
            # speed lands on 0 after `stair` more frames, keeping its sign, so the positions
            # are monotone and the last is x + s (closed form; the simulation only differs
            # by rounding, far below the 1e-9 tolerance). The guards keep P's +-v_max caps
            # out of the way.
            va = -v if v < 0.0 else v
            if 0.0 < va and va + jdt * dt + jdt * jdt * half_inv_j <= vmax:
                m = float(stair)
                s = dt * (m * va - dt * (mag * m * (m + 1.0) * 0.5
                                         - jdt * m * (m + 1.0) * (m + 2.0) / 6.0))  # fmt: skip
                end = x - s if v < 0.0 else x + s
                if lo <= end <= hi:
                    return True
                if end < lo_e - _EPS or end > hi_e + _EPS:
                    return False  # the last position leaves the band (rounding << 1e-9)
            stair = 0
        elif not stair_ok:
            # no staircase exit with these limits: the bound is the only early "yes" (with
            # it, the staircase exit settles most states sooner, so it is not tried there)
            down, up = brake_bound(v, a, amax, jmax, dt)
            if lo <= x - down and x + up <= hi:
                return True
    return False
