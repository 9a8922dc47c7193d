"""Trapezoidal pulse-rate profile of one EasySmc move (manual 5.1.1, "加速度 A, 匀速, 加速度 B").

A move of ``D`` pulses (along its longest axis) starts at the start frequency ``F0``,
accelerates at ``A`` (Hz/s) to the feed ``F``, runs at ``F``, and decelerates at ``B`` back to
``F0`` where it ends. When ``F <= F0`` there is no ramp: the move runs at ``F`` throughout
(decision recorded in ``MANUAL_DECISIONS``). When ``D`` is too short to reach ``F`` the profile
is triangular with the peak rate the distance allows.

The frame encoder (host) and the emulator (controller) both use these functions, so a timed
frame lasts the same on both sides; the tests check them against numerical integration.
"""

from __future__ import annotations

import math

from ..._errors import LimitError

__all__ = ["feed_for_duration", "max_distance", "move_duration_s", "move_progress"]


def _peak(distance: float, feed: float, f0: float, a: float, b: float) -> float:
    """Highest pulse rate reached (``feed`` or the triangular peak)."""
    if feed <= f0:
        return feed
    ramp = (feed * feed - f0 * f0) * (0.5 / a + 0.5 / b)
    if ramp <= distance:
        return feed
    return math.sqrt(f0 * f0 + distance / (0.5 / a + 0.5 / b))


def move_duration_s(
    distance: float, feed_hz: float, f0_hz: float, a_hz_s: float, b_hz_s: float
) -> float:
    """Duration in seconds of a move of ``distance`` pulses (>= 0)."""
    if distance <= 0:
        return 0.0
    if feed_hz <= 0:
        raise LimitError(f"feed {feed_hz} Hz must be positive for a move of {distance} pulses")
    if feed_hz <= f0_hz:
        return distance / feed_hz
    peak = _peak(distance, feed_hz, f0_hz, a_hz_s, b_hz_s)
    t_ramps = (peak - f0_hz) * (1.0 / a_hz_s + 1.0 / b_hz_s)
    d_ramps = (peak * peak - f0_hz * f0_hz) * (0.5 / a_hz_s + 0.5 / b_hz_s)
    return t_ramps + max(distance - d_ramps, 0.0) / peak


def move_progress(
    distance: float, feed_hz: float, f0_hz: float, a_hz_s: float, b_hz_s: float, t_s: float
) -> tuple[float, float]:
    """Pulses done and current pulse rate ``t_s`` seconds into the move.

    Returns
    -------
    (done, rate) : tuple of float
        ``done`` in ``[0, distance]``; ``rate`` in Hz (0 once the move is over).
    """
    total = move_duration_s(distance, feed_hz, f0_hz, a_hz_s, b_hz_s)
    if t_s <= 0:
        return 0.0, 0.0
    if t_s >= total:
        return float(distance), 0.0
    if feed_hz <= f0_hz:
        return feed_hz * t_s, feed_hz
    peak = _peak(distance, feed_hz, f0_hz, a_hz_s, b_hz_s)
    ta = (peak - f0_hz) / a_hz_s
    tb = (peak - f0_hz) / b_hz_s
    tc = total - ta - tb
    if t_s < ta:
        return f0_hz * t_s + 0.5 * a_hz_s * t_s * t_s, f0_hz + a_hz_s * t_s
    da = f0_hz * ta + 0.5 * a_hz_s * ta * ta
    if t_s < ta + tc:
        return da + peak * (t_s - ta), peak
    u = t_s - ta - tc
    return da + peak * tc + peak * u - 0.5 * b_hz_s * u * u, peak - b_hz_s * u


def max_distance(
    duration_s: float, feed_cap_hz: float, f0_hz: float, a_hz_s: float, b_hz_s: float
) -> float:
    """Longest move (pulses, real) that lasts at most ``duration_s`` with a feed of at most
    ``feed_cap_hz``.

    The move starts at the start frequency ``F0``, ramps at ``A`` and ``B`` and never runs
    faster than the cap ``F``; with ``k = 1/A + 1/B``:

    * ``F <= F0``: no ramp, the whole move at ``F``: ``D = F T``;
    * ``T <= (F - F0) k`` (the cap cannot be reached in time): a triangle whose peak is
      ``F0 + T / k``: ``D = F0 T + T^2 / (2 k)``;
    * otherwise a trapezoid at the cap: ``D = F T - (F - F0)^2 k / 2``.

    :func:`feed_for_duration` finds a feed of at most ``F`` for every distance up to this
    one (and :func:`move_duration_s` of that feed is ``duration_s``); one pulse more needs
    a feed above ``F`` or accelerations above ``A``, ``B``.
    """
    t = float(duration_s)
    if not t > 0:
        return 0.0
    if feed_cap_hz <= f0_hz:
        return feed_cap_hz * t
    k = 1.0 / a_hz_s + 1.0 / b_hz_s
    if t <= (feed_cap_hz - f0_hz) * k:
        return f0_hz * t + t * t / (2.0 * k)
    return feed_cap_hz * t - (feed_cap_hz - f0_hz) ** 2 * k / 2.0


def feed_for_duration(
    distance: float, duration_s: float, f0_hz: float, a_hz_s: float, b_hz_s: float
) -> float:
    """Feed (Hz, real) that makes a move of ``distance`` pulses last ``duration_s``.

    Raises
    ------
    LimitError
        When even an unbounded feed cannot cover the distance in time with accelerations
        ``A`` and ``B`` from the start frequency (the message gives the largest distance).
    """
    if distance <= 0:
        return 0.0
    if not duration_s > 0:
        raise LimitError(f"a move of {distance} pulses needs a positive duration")
    if distance <= f0_hz * duration_s:
        return distance / duration_s
    k = 1.0 / a_hz_s + 1.0 / b_hz_s
    disc = duration_s * duration_s - 2.0 * k * (distance - f0_hz * duration_s)
    if disc < 0:
        d_max = f0_hz * duration_s + duration_s * duration_s / (2.0 * k)
        raise LimitError(
            f"{distance:.0f} pulses in {duration_s * 1e3:.1f} ms needs more than accelerations "
            f"A={a_hz_s:.0f} / B={b_hz_s:.0f} Hz/s from {f0_hz:.0f} Hz allow "
            f"(at most {d_max:.1f} pulses)"
        )
    return f0_hz + (duration_s - math.sqrt(disc)) / k
