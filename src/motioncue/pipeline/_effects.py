"""Effect layer: small high-frequency heave, roll and pitch from telemetry, on top of the cue.

Rig tools add what washout cueing leaves out because it is too small or too fast to be a
sustained acceleration: the engine's vibration, the road's texture and kerbs, the jolt of a
gear change. Each effect is a pose offset ``[0, 0, z, roll, pitch, 0]`` (m, rad) added to the
cued pose *before* workspace limiting, so the workspace limiter and the actuator limiter
treat the sum: an effect never takes a frame outside the limits, it only uses the room the
cue leaves.

Effects (each with a gain, 0 = off, 1 = the nominal amplitude below, at most
:data:`MAX_GAIN`):

``engine``
    Heave vibration ``A_engine * gain * load * sin(phase)`` with ``load = rpm / rpm_max``
    (``rpm / 8000`` when the game does not give the maximum), at the firing frequency of a
    four-stroke four-cylinder engine, ``rpm / 30`` Hz, kept between 10 Hz and 0.4 x the frame
    rate (below the Nyquist frequency of the frames). Needs ``TelemetrySample.rpm``.
``road``
    Road texture and kerbs from the suspension velocities (FL, FR, RL, RR; m/s, positive
    compressing): heave ``K_heave * mean``, roll ``K_roll * (left - right)`` (a bump under the
    left wheels lifts the left side: right side down, ISO roll +), pitch
    ``-K_pitch * (front - rear)`` (a bump under the front lifts the nose: ISO pitch -), each
    clipped to its amplitude and smoothed by a first-order low-pass at
    :data:`ROAD_SMOOTH_HZ` so a 60 Hz sample-and-hold does not step. Needs
    ``TelemetrySample.suspension_velocity_m_s``.
``shift``
    A half-sine pitch pulse of :data:`SHIFT_PULSE_S` when the gear changes between two forward
    gears: nose down (ISO pitch +) on an upshift, up on a downshift. Needs
    ``TelemetrySample.gear``.

A channel the game does not report leaves its effect silent (no error). The layer only runs
where the controller streams at :data:`MIN_RATE_HZ` or more: below that the frames cannot
carry the frequencies and :func:`make_effects` refuses with a :class:`ConfigError`. The
design is frozen; all that changes from frame to frame is in :class:`EffectsState`.
"""

from __future__ import annotations

import math
from collections.abc import MutableSequence
from dataclasses import dataclass, field, fields
from typing import Protocol

from .._errors import ConfigError

__all__ = [
    "EFFECT_NAMES",
    "MAX_GAIN",
    "MIN_RATE_HZ",
    "EffectGains",
    "Effects",
    "EffectsState",
    "make_effects",
]

MIN_RATE_HZ = 100.0
"""Lowest frame rate the effect layer runs at (Hz)."""

MAX_GAIN = 3.0
"""Largest gain of one effect."""

EFFECT_NAMES = ("engine", "road", "shift")

ENGINE_HEAVE_M = 0.0004
"""Engine vibration amplitude at gain 1 and full rpm (m)."""
ENGINE_MIN_HZ = 10.0
ENGINE_RPM_DEFAULT_MAX = 8000.0

ROAD_HEAVE_M_PER_M_S = 0.004
"""Road heave per m/s of mean suspension velocity (m per m/s)."""
ROAD_HEAVE_MAX_M = 0.003
ROAD_ROLL_RAD_PER_M_S = 0.006
ROAD_PITCH_RAD_PER_M_S = 0.006
ROAD_ANGLE_MAX_RAD = 0.005
ROAD_SMOOTH_HZ = 25.0

SHIFT_PITCH_RAD = 0.006
"""Gear-change pulse amplitude at gain 1 (rad, about 0.34 degree)."""
SHIFT_PULSE_S = 0.08


class EffectSample(Protocol):
    """What the layer reads from a :class:`~motioncue.telemetry.TelemetrySample`.

    Every member is required: a sample has them all, NaN or None where the game does not
    send the channel (the sample's defaults), which the layer reads as "no such channel".
    """

    @property
    def rpm(self) -> float: ...
    @property
    def rpm_max(self) -> float: ...
    @property
    def gear(self) -> int | None: ...
    @property
    def suspension_velocity_m_s(self) -> tuple[float, float, float, float] | None: ...


@dataclass(frozen=True)
class EffectGains:
    """Per-effect gains: 0 = off, 1 = nominal, up to :data:`MAX_GAIN`.

    Attributes
    ----------
    engine, road, shift : float
        Gain of each effect (dimensionless), in [0, 3].
    """

    engine: float = 0.0
    road: float = 0.0
    shift: float = 0.0

    def __post_init__(self) -> None:
        for f in fields(self):
            v = getattr(self, f.name)
            if not (isinstance(v, int | float) and math.isfinite(v) and 0.0 <= v <= MAX_GAIN):
                raise ConfigError(
                    f"effect gain {f.name} = {v!r} is invalid; allowed: 0..{MAX_GAIN:g}"
                )

    @property
    def enabled(self) -> bool:
        """True when any effect has a gain above 0."""
        return self.engine > 0.0 or self.road > 0.0 or self.shift > 0.0


@dataclass
class EffectsState:
    """What the effect layer carries from frame to frame."""

    engine_phase_rad: float = 0.0
    road: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])  # z, roll, pitch
    last_gear: int | None = None
    shift_left_s: float = 0.0
    shift_sign: float = 0.0
    bad_channels: int = 0
    """Frames where a reported channel was not finite (the effect was silent)."""


@dataclass(frozen=True)
class Effects:
    """The effect layer at one frame rate (build it with :func:`make_effects`).

    Attributes
    ----------
    gains : EffectGains
    rate_hz : float
        Frame rate (Hz), >= :data:`MIN_RATE_HZ`.
    """

    gains: EffectGains
    rate_hz: float

    def initial_state(self) -> EffectsState:
        return EffectsState()

    def reset(self, state: EffectsState) -> None:
        """Forget everything (the bridge calls it while parked)."""
        state.engine_phase_rad = 0.0
        state.road[:] = [0.0, 0.0, 0.0]
        state.last_gear = None
        state.shift_left_s = 0.0
        state.shift_sign = 0.0

    def step(self, state: EffectsState, sample: EffectSample) -> tuple[float, float, float]:
        """Advance one frame; return the offsets ``(z_m, roll_rad, pitch_rad)``."""
        dt = 1.0 / self.rate_hz
        g = self.gains
        z = roll = pitch = 0.0
        # engine
        rpm = sample.rpm
        if g.engine > 0.0 and math.isfinite(rpm) and rpm > 0.0:
            rpm_max = sample.rpm_max
            top = rpm_max if math.isfinite(rpm_max) and rpm_max > 0.0 else ENGINE_RPM_DEFAULT_MAX
            load = min(rpm / top, 1.0)
            hz = min(max(rpm / 30.0, ENGINE_MIN_HZ), 0.4 * self.rate_hz)
            state.engine_phase_rad = (state.engine_phase_rad + 2.0 * math.pi * hz * dt) % (
                2.0 * math.pi
            )
            z += g.engine * ENGINE_HEAVE_M * load * math.sin(state.engine_phase_rad)
        elif g.engine > 0.0 and not math.isnan(rpm):
            state.bad_channels += 1
        # road texture and kerbs
        sv = sample.suspension_velocity_m_s
        road = state.road
        if g.road > 0.0:
            target = (0.0, 0.0, 0.0)
            if sv is not None:
                fl, fr, rl, rr = sv
                if all(math.isfinite(v) for v in sv):
                    target = (
                        _clip(g.road * ROAD_HEAVE_M_PER_M_S * (fl + fr + rl + rr) / 4.0,
                              g.road * ROAD_HEAVE_MAX_M),
                        _clip(g.road * ROAD_ROLL_RAD_PER_M_S * ((fl + rl) - (fr + rr)) / 2.0,
                              g.road * ROAD_ANGLE_MAX_RAD),
                        _clip(-g.road * ROAD_PITCH_RAD_PER_M_S * ((fl + fr) - (rl + rr)) / 2.0,
                              g.road * ROAD_ANGLE_MAX_RAD),
                    )  # fmt: skip
                else:
                    state.bad_channels += 1
            alpha = 1.0 - math.exp(-2.0 * math.pi * ROAD_SMOOTH_HZ * dt)
            for i in range(3):
                road[i] += alpha * (target[i] - road[i])
            z += road[0]
            roll += road[1]
            pitch += road[2]
        # gear change
        gear = sample.gear
        if g.shift > 0.0:
            last = state.last_gear
            if isinstance(gear, int) and isinstance(last, int) and gear != last:
                if gear > 0 and last > 0:
                    state.shift_left_s = SHIFT_PULSE_S
                    state.shift_sign = 1.0 if gear > last else -1.0
            if state.shift_left_s > 0.0:
                x = 1.0 - state.shift_left_s / SHIFT_PULSE_S
                pitch += state.shift_sign * g.shift * SHIFT_PITCH_RAD * math.sin(math.pi * x)
                state.shift_left_s = max(0.0, state.shift_left_s - dt)
            state.last_gear = gear if isinstance(gear, int) else state.last_gear
        return z, roll, pitch

    def add(
        self, state: EffectsState, sample: EffectSample, gain: float, pose: MutableSequence[float]
    ) -> None:
        """Advance one frame and add ``gain`` x the offsets to ``pose`` (6,) in place.

        ``gain`` is the bridge's fade gain (0..1), so the effects fade with the cue.
        """
        z, roll, pitch = self.step(state, sample)
        pose[2] += gain * z
        pose[3] += gain * roll
        pose[4] += gain * pitch


def _clip(x: float, limit: float) -> float:
    return max(-limit, min(limit, x))


def make_effects(gains: EffectGains, rate_hz: float) -> Effects | None:
    """The effect layer for a frame rate, or None when every gain is 0.

    Raises
    ------
    ConfigError
        Effects are on and ``rate_hz`` is below :data:`MIN_RATE_HZ`.
    """
    if not gains.enabled:
        return None
    if not (math.isfinite(rate_hz) and rate_hz >= MIN_RATE_HZ):
        on = ", ".join(n for n in EFFECT_NAMES if getattr(gains, n) > 0.0)
        raise ConfigError(
            f"effects ({on}) need frames at >= {MIN_RATE_HZ:g} Hz; the bridge runs at "
            f"{rate_hz:g} Hz: raise --rate (if the controller allows it) or set the effect "
            "gains to 0"
        )
    return Effects(gains, float(rate_hz))
