"""Up-sampling of low-rate telemetry to the frame rate (issue 13, item 1).

Games send motion at 20-120 Hz; the bridge runs its cueing and frames at 100-500 Hz. Each
frame needs the vehicle's specific force ``f`` and angular velocity ``w`` *at the frame's
time*. An :class:`Upsampler` is told every new sample (:meth:`~Upsampler.update`) and
answers for any time (:meth:`~Upsampler.value_at`). Three are registered in
:data:`UPSAMPLERS`:

``hold``
    The newest sample until the next one (what the bridge did before): a step at every
    sample, of the signal's whole change over a telemetry period, and on average half a
    telemetry period of lag.
``interpolate``
    Linear interpolation between the last two samples, one telemetry period late: no steps,
    but exactly one telemetry period of lag.
``extrapolate``
    Bounded extrapolation corrected on the next sample (the default of ``motioncue bridge``):
    from each new sample the signal goes on along the slope of the parabola through the
    last three samples (``1.5 s[n] - 0.5 s[n-1]`` with ``s`` the secant slopes); the
    slope's change per sample is bounded (``slope_rate_max``, a bound on the second
    derivative: m/s^4 for ``f``, rad/s^3 for ``w``), so that a step in the telemetry (a
    kerb, a crash) overshoots by at most ``slope_rate_max * T^2 * 1.5`` instead of by the
    step itself; extrapolation stops (holds) ``1.5 T`` after the last sample. When the next
    sample arrives the difference ``e`` between where the output is and where the new line
    starts is blended out linearly over one telemetry period ``T``, so the output is
    continuous (no step) and moves from the first frame after the sample. A difference
    larger than ``jump`` (per channel: 0.5 m/s^2 for ``f``, 0.05 rad/s for ``w``) is a
    surprise, not an extrapolation error (a kerb, a crash, a step in the test's lateral g):
    all of it beyond ``jump`` passes at once and only ``+-jump`` is blended out over the
    period, so a step in the telemetry reaches the next frame instead of a period later,
    while the small corrections of smooth motion stay spread over a period.

Sample times are the arrival stamps of the datagrams, which jitter by a fraction of a
millisecond on a loaded PC; a 3 % error of a 16.7 ms interval would be a 3 % error of the
slope. So the slopes use the estimated telemetry period ``T`` (the mean of the intervals of
the current regular run, then an exponential mean of gain 0.005; a new rate restarts it) and
the extrapolation starts at a smoothed sample time (a first-order phase-locked loop on the
arrival stamps, gain 0.05), not at the raw stamp.

A bridge that computes each frame's cue ahead of the wall clock (``BridgeConfig.lead_ms``)
has already used the extrapolation past a new sample's arrival; it passes that time as
``t_from`` and the blend starts there, so the values it is given stay continuous.

Measured (``benchmarks/bench_bridge.py --upsample-only``; 60 Hz telemetry of a sine with
arrival jitter 0.3-0.8 ms, 250 Hz frames): see the README's figures table.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Protocol

from .._errors import ConfigError

__all__ = [
    "UPSAMPLERS",
    "ExtrapolatingUpsampler",
    "HoldUpsampler",
    "InterpolatingUpsampler",
    "Upsampler",
    "make_upsampler",
]

#: telemetry intervals outside this range (s) are gaps or duplicates, not the period
_PERIOD_MIN_S = 0.001
_PERIOD_MAX_S = 0.2
#: gains of the exponential means of the period and of the sample clock (_PeriodEstimate)
_PERIOD_GAIN = 0.005
_CLOCK_GAIN = 0.05


class Upsampler(Protocol):
    """What the bridge needs to turn samples at the game's rate into values per frame.

    Values are plain float sequences of a fixed length ``n`` (the bridge uses 6:
    ``f`` (3, m/s^2) then ``w`` (3, rad/s)); times are ``perf_counter`` seconds.
    """

    def update(self, t_s: float, x: Sequence[float], t_from: float = math.nan) -> None:
        """A new sample ``x (n,)`` stamped ``t_s``; stamps never decrease. ``t_from``: the
        latest time a value was already given out for (a bridge that computes its cue ahead
        of the wall clock has used the old extrapolation past ``t_s``); the output stays
        continuous from there. nan (default) or before ``t_s``: from ``t_s``."""
        ...

    def value_at(self, t_s: float, out: list[float]) -> None:
        """Write the value at time ``t_s`` (any time after the first sample) into ``out``."""
        ...

    def reset(self) -> None:
        """Forget every sample (the next :meth:`update` starts afresh)."""
        ...


class _PeriodEstimate:
    """Running mean of the telemetry period and a smoothed (phase-locked) sample clock.

    The period is the plain mean of the intervals of the current regular run until it has
    :data:`_PERIOD_GAIN` ``** -1`` of them, then an exponential mean with that gain; the clock
    likewise with :data:`_CLOCK_GAIN`. Arrival stamps jitter by a fraction of a millisecond:
    a 0.5 ms jitter moved a 0.05-gain estimate of a 16.7 ms period by about 0.5 %, and every
    slope with it. Three intervals in a row more than 25 % off the estimate (the game changed
    its rate) restart the mean.
    """

    __slots__ = ("n", "n_run", "off", "period_s", "ref_s", "t_last")

    def __init__(self) -> None:
        self.n = 0
        self.n_run = 0  # intervals in the current mean
        self.off = 0  # consecutive intervals far from the estimate
        self.period_s = math.nan
        self.ref_s = math.nan
        self.t_last = math.nan

    def update(self, t_s: float) -> bool:
        """Take a sample stamp; True when it continues a regular stream (no gap)."""
        regular = False
        if self.n == 0:
            self.ref_s = t_s
        else:
            dt = t_s - self.t_last
            if _PERIOD_MIN_S <= dt <= _PERIOD_MAX_S and not (
                self.period_s == self.period_s and dt > 3.0 * self.period_s
            ):
                if (
                    self.period_s == self.period_s
                    and abs(dt - self.period_s) > 0.25 * self.period_s
                ):
                    self.off += 1
                    if self.off >= 3:  # a new rate: start the mean afresh
                        self.period_s, self.n_run, self.off = math.nan, 0, 0
                else:
                    self.off = 0
                self.n_run += 1
                if self.period_s != self.period_s:  # nan: the first interval
                    self.period_s = dt
                else:
                    self.period_s += max(1.0 / self.n_run, _PERIOD_GAIN) * (dt - self.period_s)
                    regular = True
                self.ref_s += self.period_s
                self.ref_s += max(1.0 / self.n_run, _CLOCK_GAIN) * (t_s - self.ref_s)
                # the smoothed clock stays within a period behind, a quarter ahead
                self.ref_s = min(t_s + 0.25 * self.period_s, max(self.ref_s, t_s - self.period_s))
            else:
                self.ref_s = t_s
        self.t_last = t_s
        self.n += 1
        return regular


class HoldUpsampler:
    """The newest sample, held until the next one (zero-order hold)."""

    def __init__(self, n: int = 6) -> None:
        self.n = n
        self._x = [0.0] * n

    def update(self, t_s: float, x: Sequence[float], t_from: float = math.nan) -> None:
        self._x = [float(v) for v in x]

    def value_at(self, t_s: float, out: list[float]) -> None:
        out[:] = self._x

    def reset(self) -> None:
        self._x = [0.0] * self.n


class InterpolatingUpsampler:
    """Linear interpolation between the last two samples, one telemetry period late."""

    def __init__(self, n: int = 6) -> None:
        self.n = n
        self.reset()

    def reset(self) -> None:
        self._clock = _PeriodEstimate()
        self._x0 = [0.0] * self.n
        self._x1 = [0.0] * self.n

    def update(self, t_s: float, x: Sequence[float], t_from: float = math.nan) -> None:
        first = self._clock.n == 0
        self._clock.update(t_s)
        self._x0 = [float(v) for v in x] if first else self._x1
        self._x1 = [float(v) for v in x]

    def value_at(self, t_s: float, out: list[float]) -> None:
        c = self._clock
        period = c.period_s
        r = 1.0 if period != period else min(1.0, max(0.0, (t_s - c.ref_s) / period))
        out[:] = [a + r * (b - a) for a, b in zip(self._x0, self._x1, strict=True)]


class ExtrapolatingUpsampler:
    """Bounded extrapolation, corrected smoothly on the next sample (module docstring).

    Parameters
    ----------
    slope_rate_max : sequence of float, shape (n,)
        Bound on the change of the extrapolation slope per second for each channel
        (the signal's second derivative: m/s^4 for a specific force, rad/s^3 for an
        angular velocity), each > 0.
    horizon : float
        Extrapolate at most this many telemetry periods past the last sample, in
        [1, 4]; then hold.
    jump : sequence of float, shape (n,), optional
        Corrections are clipped to ``+-jump`` (the channel's unit) before the blend: the
        rest of a surprise passes at once (module docstring); each > 0, ``inf`` for never
        (the default).
    """

    def __init__(
        self,
        slope_rate_max: Sequence[float],
        horizon: float = 1.5,
        jump: Sequence[float] | None = None,
    ) -> None:
        rates = [float(v) for v in slope_rate_max]
        if not rates or not all(math.isfinite(v) and v > 0 for v in rates):
            raise ConfigError(
                f"slope_rate_max = {list(slope_rate_max)!r} is invalid; allowed: finite > 0"
            )
        jumps = [math.inf] * len(rates) if jump is None else [float(v) for v in jump]
        if len(jumps) != len(rates) or not all(v > 0 for v in jumps):
            raise ConfigError(
                f"jump = {jump!r} is invalid; allowed: {len(rates)} values > 0 (inf: never)"
            )
        self.jump = tuple(jumps)
        if not (math.isfinite(horizon) and 1.0 <= horizon <= 4.0):
            raise ConfigError(f"horizon = {horizon!r} is invalid; allowed: [1, 4] periods")
        self.n = len(rates)
        self.slope_rate_max = tuple(rates)
        self.horizon = float(horizon)
        self.reset()

    def reset(self) -> None:
        n = self.n
        self._clock = _PeriodEstimate()
        self._x = [0.0] * n  # newest sample
        self._secant = [0.0] * n  # last secant slope (per estimated period)
        self._slope = [0.0] * n  # slope used for the extrapolation
        self._err = [0.0] * n  # correction still to blend out, at _t_switch
        self._t_switch = math.nan

    def _line(self, t_s: float, i: int) -> float:
        c = self._clock
        h = t_s - c.ref_s
        cap = self.horizon * c.period_s
        if h > cap:  # nan period (one sample so far): the comparison is False
            h = cap
        return self._x[i] + self._slope[i] * h

    def update(self, t_s: float, x: Sequence[float], t_from: float = math.nan) -> None:
        c = self._clock
        n = self.n
        if c.n == 0:
            c.update(t_s)
            self._x = [float(v) for v in x]
            self._t_switch = t_s
            return
        # the blend starts where the output was last given out: when the sample arrives,
        # or later if values past its arrival were already used (t_from)
        t_c = t_from if t_from > t_s else t_s  # False for nan
        before = [0.0] * n
        self.value_at(t_c, before)
        regular = c.update(t_s)
        period = c.period_s
        for i in range(n):
            xi = float(x[i])
            if regular:
                s = (xi - self._x[i]) / period
                want = 1.5 * s - 0.5 * self._secant[i]
                step = self.slope_rate_max[i] * period
                d = self._slope[i]
                self._slope[i] = d + min(step, max(-step, want - d))
                self._secant[i] = s
            else:  # a gap or the second sample: no trend to follow yet
                self._secant[i] = (xi - self._x[i]) / period if period == period else 0.0
                self._slope[i] = 0.0
            self._x[i] = xi
        self._t_switch = t_c
        for i in range(n):
            err = before[i] - self._line(t_c, i)
            err = err if math.isfinite(err) else 0.0
            cap = self.jump[i]
            self._err[i] = cap if err > cap else (-cap if err < -cap else err)

    def value_at(self, t_s: float, out: list[float]) -> None:
        period = self._clock.period_s
        if period == period:
            w = 1.0 - (t_s - self._t_switch) / period
            w = 0.0 if w < 0.0 else (1.0 if w > 1.0 else w)
        else:
            w = 0.0
        for i in range(self.n):
            out[i] = self._line(t_s, i) + w * self._err[i]


def _extrapolating() -> ExtrapolatingUpsampler:
    # f: up to 2000 m/s^4 (a 4 g sine at 1.1 Hz); w: up to 500 rad/s^3
    return ExtrapolatingUpsampler((2000.0,) * 3 + (500.0,) * 3, jump=(0.5,) * 3 + (0.05,) * 3)


#: name -> factory of an upsampler of the bridge's 6 channels (f then w)
UPSAMPLERS: dict[str, Callable[[], Upsampler]] = {
    "hold": HoldUpsampler,
    "interpolate": InterpolatingUpsampler,
    "extrapolate": _extrapolating,
}


def make_upsampler(name: str) -> Upsampler:
    """A fresh upsampler by its registered name (``hold``, ``interpolate``, ``extrapolate``)."""
    try:
        factory = UPSAMPLERS[name]
    except KeyError:
        raise ConfigError(
            f"upsample = {name!r} is unknown; allowed: {', '.join(sorted(UPSAMPLERS))}"
        ) from None
    return factory()
