"""Effect layer: closed forms for each effect, refusals, bad channels, and frames that stay
inside the limits table when the effects are added to the cue in the bridge."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.output.mbox._messages import MotionFrame, decode
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._effects import (
    ENGINE_HEAVE_M,
    MIN_RATE_HZ,
    ROAD_ANGLE_MAX_RAD,
    ROAD_HEAVE_M_PER_M_S,
    ROAD_HEAVE_MAX_M,
    ROAD_PITCH_RAD_PER_M_S,
    ROAD_ROLL_RAD_PER_M_S,
    ROAD_SMOOTH_HZ,
    SHIFT_PITCH_RAD,
    SHIFT_PULSE_S,
    EffectGains,
    make_effects,
)
from motioncue.pipeline._realtime import GateConfig
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import TelemetrySample
from motioncue.trajectory import ActuatorLimits

G = 9.80665


def _sample(**extra: object) -> TelemetrySample:
    return TelemetrySample(0.0, (0.0, 0.0, G), (0.0, 0.0, 0.0), False, "test", **extra)  # type: ignore[arg-type]


def _run(gains: EffectGains, samples: list[TelemetrySample], rate_hz: float = 250.0) -> np.ndarray:
    fx = make_effects(gains, rate_hz)
    assert fx is not None
    st_ = fx.initial_state()
    return np.array([fx.step(st_, s) for s in samples])


@pytest.mark.parametrize(
    ("gains", "msg"),
    [
        (dict(engine=-0.1), r"engine = -0.1 is invalid; allowed: 0..3"),
        (dict(road=math.nan), r"road = nan is invalid"),
        (dict(shift=3.5), r"shift = 3.5 is invalid; allowed: 0..3"),
    ],
)
def test_bad_gains_are_named(gains: dict[str, float], msg: str) -> None:
    with pytest.raises(ConfigError, match=msg):
        EffectGains(**gains)


def test_effects_are_refused_below_100_hz_and_absent_when_off() -> None:
    assert make_effects(EffectGains(), 50.0) is None  # nothing on: nothing to refuse
    with pytest.raises(ConfigError, match=r"effects \(engine, shift\) need frames at >= 100 Hz"):
        make_effects(EffectGains(engine=1.0, shift=0.5), 60.0)
    assert make_effects(EffectGains(road=1.0), MIN_RATE_HZ) is not None
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl)
    with pytest.raises(ConfigError, match=r"need frames at >= 100 Hz; the bridge runs at 50 Hz"):
        Bridge(platform, ctrl, load_cueing("racing"), _NoSource(), _ListTransport(), lim,
               BridgeConfig(rate_hz=50.0), effects=EffectGains(road=1.0))  # fmt: skip


def test_engine_is_a_sine_at_the_firing_frequency_with_the_load_amplitude() -> None:
    """Closed form: z = g A (rpm / rpm_max) sin(2 pi (rpm/30) t); fitted by least squares."""
    rate, rpm, top, gain = 250.0, 2400.0, 6000.0, 1.5
    z = _run(EffectGains(engine=gain), [_sample(rpm=rpm, rpm_max=top)] * 500, rate)[:, 0]
    t = np.arange(1, 501) / rate
    hz = rpm / 30.0  # 80 Hz < 0.4 x 250
    basis = np.column_stack([np.sin(2 * np.pi * hz * t), np.cos(2 * np.pi * hz * t)])
    coef, *_ = np.linalg.lstsq(basis, z, rcond=None)
    assert math.hypot(*coef) == pytest.approx(gain * ENGINE_HEAVE_M * rpm / top, rel=1e-9)
    np.testing.assert_allclose(basis @ coef, z, atol=1e-12)
    # independent check of the frequency: the FFT peak
    spec = np.abs(np.fft.rfft(z))
    assert np.fft.rfftfreq(len(z), 1 / rate)[np.argmax(spec)] == pytest.approx(hz, abs=0.5)


def test_engine_frequency_is_kept_below_the_frames_nyquist_and_rpm_max_defaults() -> None:
    z = _run(EffectGains(engine=1.0), [_sample(rpm=9000.0)] * 1000, 100.0)[:, 0]
    spec = np.abs(np.fft.rfft(z))
    assert np.fft.rfftfreq(len(z), 1 / 100.0)[np.argmax(spec)] == pytest.approx(40.0, abs=0.2)
    t = np.arange(1, 1001) / 100.0
    basis = np.column_stack([np.sin(2 * np.pi * 40.0 * t), np.cos(2 * np.pi * 40.0 * t)])
    coef, *_ = np.linalg.lstsq(basis, z, rcond=None)
    assert math.hypot(*coef) == pytest.approx(ENGINE_HEAVE_M, rel=1e-9)  # 9000 > 8000: full


def test_road_follows_a_first_order_step_response_to_the_closed_form_targets() -> None:
    sv = (0.2, 0.1, 0.05, -0.05)  # FL, FR, RL, RR
    gain, rate, n = 0.5, 250.0, 100
    out = _run(EffectGains(road=gain), [_sample(suspension_velocity_m_s=sv)] * n, rate)
    fl, fr, rl, rr = sv
    target = np.array([
        gain * ROAD_HEAVE_M_PER_M_S * sum(sv) / 4,
        gain * ROAD_ROLL_RAD_PER_M_S * ((fl + rl) - (fr + rr)) / 2,  # left bump: right down
        -gain * ROAD_PITCH_RAD_PER_M_S * ((fl + fr) - (rl + rr)) / 2,  # front bump: nose up
    ])  # fmt: skip
    assert target[1] > 0 and target[2] < 0
    t = np.arange(1, n + 1) / rate
    expected = target[None, :] * (1 - np.exp(-2 * np.pi * ROAD_SMOOTH_HZ * t))[:, None]
    np.testing.assert_allclose(out, expected, rtol=1e-9, atol=1e-15)


def test_road_is_clipped_to_its_amplitude() -> None:
    out = _run(EffectGains(road=2.0), [_sample(suspension_velocity_m_s=(9, 9, -9, -9))] * 400)
    assert out[-1, 0] == pytest.approx(0.0, abs=1e-12)  # mean suspension velocity 0
    assert out[-1, 2] == pytest.approx(-2.0 * ROAD_ANGLE_MAX_RAD, rel=1e-9)
    out = _run(EffectGains(road=2.0), [_sample(suspension_velocity_m_s=(9, 9, 9, 9))] * 400)
    assert out[-1, 0] == pytest.approx(2.0 * ROAD_HEAVE_MAX_M, rel=1e-9)


def test_gear_changes_give_a_half_sine_pitch_pulse() -> None:
    rate = 250.0
    gears = [2] * 10 + [3] * 60 + [2] * 60 + [0] * 30 + [1] * 30
    out = _run(EffectGains(shift=1.0), [_sample(gear=g) for g in gears], rate)[:, 2]
    n_pulse = round(SHIFT_PULSE_S * rate)
    up = out[10 : 10 + n_pulse]
    x = np.arange(n_pulse) / n_pulse
    np.testing.assert_allclose(up, SHIFT_PITCH_RAD * np.sin(np.pi * x), atol=1e-15)
    down = out[70 : 70 + n_pulse]
    np.testing.assert_allclose(down, -SHIFT_PITCH_RAD * np.sin(np.pi * x), atol=1e-15)
    assert np.all(out[:10] == 0) and np.all(out[10 + n_pulse : 70] == 0)
    assert np.all(out[130:] == 0)  # into neutral and out of it: no pulse


def test_missing_channels_are_silent_and_bad_ones_counted() -> None:
    fx = make_effects(EffectGains(engine=1, road=1, shift=1), 250.0)
    assert fx is not None
    st_ = fx.initial_state()
    assert fx.step(st_, _sample()) == (0.0, 0.0, 0.0)
    bad = _sample(rpm=math.nan)  # the sample cleans it to "unknown": silent, not bad
    assert fx.step(st_, bad) == (0.0, 0.0, 0.0) and st_.bad_channels == 0


@given(
    rpm=st.floats(allow_nan=True, allow_infinity=True),
    top=st.floats(allow_nan=True, allow_infinity=True),
    gear=st.one_of(st.none(), st.integers(-5, 30)),
    sv=st.one_of(st.none(), st.tuples(*[st.floats(allow_nan=True, allow_infinity=True)] * 4)),
    gains=st.tuples(*[st.floats(0, 3)] * 3),
)
def test_any_channels_give_bounded_finite_offsets(
    rpm: float, top: float, gear: int | None, sv: tuple | None, gains: tuple
) -> None:
    s = TelemetrySample(0.0, (0, 0, G), (0, 0, 0), False, "test", rpm, top, gear, sv)
    fx = make_effects(EffectGains(*gains), 100.0)
    if fx is None:
        return
    st_ = fx.initial_state()
    for _ in range(3):
        z, roll, pitch = fx.step(st_, s)
        assert all(math.isfinite(v) for v in (z, roll, pitch))
        assert abs(z) <= gains[0] * ENGINE_HEAVE_M + gains[1] * ROAD_HEAVE_MAX_M + 1e-15
        assert abs(roll) <= gains[1] * ROAD_ANGLE_MAX_RAD + 1e-15
        assert abs(pitch) <= gains[1] * ROAD_ANGLE_MAX_RAD + gains[2] * SHIFT_PITCH_RAD + 1e-15


# -- in the bridge ------------------------------------------------------------------------
class _NoSource:
    def __init__(self) -> None:
        self.stats: dict[str, int] = {}

    def latest(self) -> None:
        return None


class _ListTransport:
    def __init__(self) -> None:
        self.sent: list[bytes] = []

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self.sent.append(data)


class _Timeline:
    def __init__(self, samples: list[TelemetrySample]) -> None:
        self.samples, self.now, self.stats = samples, -math.inf, {"samples": 0}

    def latest(self) -> TelemetrySample | None:
        arrived = [s for s in self.samples if s.t_s <= self.now]
        return arrived[-1] if arrived else None


def _bridge_frames(effects: EffectGains | None, rate: float = 250.0) -> tuple[np.ndarray, ...]:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    rng = np.random.default_rng(3)
    samples = []
    for k in range(180):  # 3 s at 60 Hz: a hard corner, a rough road, the engine, shifts
        t = k / 60.0
        sv = tuple(float(v) for v in rng.normal(0.0, 2.0, 4))
        samples.append(TelemetrySample(
            t, (3.0 * math.sin(2 * t), 6.0, G), (0.0, 0.0, 0.5), False, "test",
            rpm=7000.0, rpm_max=8000.0, gear=2 + (k // 40) % 3, suspension_velocity_m_s=sv,
        ))  # fmt: skip
    src, tr = _Timeline(samples), _ListTransport()
    gate = GateConfig(timeout_s=0.25, fade_out_s=0.3, fade_in_s=0.3)
    bridge = Bridge(platform, ctrl, load_cueing("racing"), src, tr, lim,
                    BridgeConfig(rate, gate), effects=effects)  # fmt: skip
    n = int(3.8 * rate)
    for k in range(1, n + 1):
        src.now = k / rate
        bridge.step(k / rate, stopping=k > 3.0 * rate)
    frames = [decode(d) for d in tr.sent]
    assert all(isinstance(f, MotionFrame) for f in frames)
    t = np.array([f.time_ms for f in frames], dtype=float) / 1e3  # type: ignore[union-attr]
    p = np.array([f.positions for f in frames], dtype=float)  # type: ignore[union-attr]
    chk = check_frames(t, p, lim.to_pulses_table(platform), start_at_rest=True)
    assert chk.ok, chk.summary()
    return t, p


def test_effects_in_the_bridge_reach_the_frames_and_stay_inside_the_limits() -> None:
    """The limiter treats the sum: at full gains on a rough road in a hard corner the frames
    still pass the independent frame check, and they differ from the frames without."""
    _, plain = _bridge_frames(None)
    _, shaken = _bridge_frames(EffectGains(engine=3.0, road=3.0, shift=3.0))
    assert plain.shape == shaken.shape
    diff = np.abs(shaken - plain).max()
    assert diff >= 5  # pulses: the effects did reach the wire
    # and the high-frequency content is there: frame-to-frame changes grow
    assert (
        np.abs(np.diff(shaken, 2, axis=0)).mean() > 1.5 * np.abs(np.diff(plain, 2, axis=0)).mean()
    )
