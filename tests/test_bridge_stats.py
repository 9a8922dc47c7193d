"""Bridge.stats: the cheap computation reports the figures of the old one on the same data.

The old ``Bridge.stats`` (until s25) copied each timing window in order, took the jitter as
``np.abs(np.diff(sent) - period)`` (on arrival: minus the stamped intervals) and every
percentile with ``np.percentile``: about 1.2 ms a call, read twice a second from the
bridge's process by the live monitor. Now the loop keeps the jitter per frame and each
window's percentiles come from one partial sort. The oracle here is the old computation,
written out again, on the rings the bridge filled. Tolerance: 1e-12 relative (the two
interpolate the same two order statistics; they may round the position between them
differently).
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline._bridge import Bridge, BridgeConfig, _Ring
from motioncue.pipeline._realtime import GateConfig
from motioncue.telemetry import TelemetrySample
from motioncue.trajectory import ActuatorLimits

REL = 1e-12


def _old_percentile_ms(v: np.ndarray, q: float) -> float:
    return float(np.percentile(v, q) * 1e3) if v.size else math.nan


def _same(new: float, old: float) -> None:
    if math.isnan(old):
        assert math.isnan(new)
    else:
        assert new == pytest.approx(old, rel=REL, abs=1e-15)


@settings(max_examples=200, deadline=None)
@given(
    st.integers(1, 60),
    st.integers(0, 200),
    st.integers(0, 2**32 - 1),
    st.sampled_from(["none", "nan", "inf"]),
)
def test_ring_percentiles_are_numpys_on_the_ordered_window(size, n, seed, bad):
    """Windows empty, partly filled and wrapped (with repeated values and non-finite ones,
    which the old copy dropped): p50, p99, p0, p100 and the maximum as np.percentile."""
    rng = np.random.default_rng(seed)
    ring = _Ring(size)
    for k in range(n):
        x = float(rng.choice([rng.exponential(1e-3), 2e-3]))  # ties as well
        if bad != "none" and k % 5 == 3:
            x = math.nan if bad == "nan" else math.inf
        ring.add(x)
    old = ring.values()  # the old ordered, finite copy
    qs = (0.0, 50.0, 99.0, 100.0)
    got, top = ring.percentiles_ms(qs)
    for q, g in zip(qs, got, strict=True):
        _same(g, _old_percentile_ms(old, q))
    _same(top, float(old.max() * 1e3) if old.size else math.nan)
    assert ring.last(3) == old[-3:].tolist()


class _Source:
    """A telemetry source set by hand."""

    def __init__(self) -> None:
        self.sample: TelemetrySample | None = None
        self.stats = {"samples": 0, "datagrams": 0}

    def put(self, t_s: float, f: tuple[float, float, float]) -> None:
        self.sample = TelemetrySample(t_s, f, (0.0, 0.0, 0.3), False, "test")
        self.stats["samples"] += 1
        self.stats["datagrams"] += 1

    def latest(self) -> TelemetrySample | None:
        return self.sample


class _Null:
    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        pass


def _bridge(**config: Any) -> tuple[Bridge, _Source]:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    src = _Source()
    gate = GateConfig(timeout_s=0.25, fade_out_s=0.05, fade_in_s=0.05)
    cfg = BridgeConfig(gate=gate, **config)
    return Bridge(platform, ctrl, load_cueing("racing"), src, _Null(), lim, cfg), src


def _old_figures(bridge: Bridge) -> dict[str, float]:
    """The old stats' timing figures, computed as it did, from the bridge's rings."""
    sent = bridge._sent_at.values()
    if bridge._arrival:
        stamps = bridge._stamps.values()
        k = min(sent.size, stamps.size)
        jit = np.abs(np.diff(sent[sent.size - k :]) - np.diff(stamps[stamps.size - k :]))
    else:
        jit = np.abs(np.diff(sent) - bridge.period_s)
    recent = sent[-(int(bridge.config.rate_hz) + 1) :]
    rate_out = math.nan
    if recent.size > 1 and recent[-1] > recent[0]:
        rate_out = (recent.size - 1) / float(recent[-1] - recent[0])
    lat = bridge._latency.values()
    age = bridge._age.values()
    fage = bridge._frame_age.values()
    return {
        "rate_out_hz": rate_out,
        "jitter_p99_ms": _old_percentile_ms(jit, 99),
        "latency_p50_ms": _old_percentile_ms(lat, 50),
        "latency_p99_ms": _old_percentile_ms(lat, 99),
        "latency_max_ms": float(lat.max() * 1e3) if lat.size else math.nan,
        "age_p99_ms": _old_percentile_ms(age, 99),
        "frame_age_ms": float(fage[-1] * 1e3) if fage.size else math.nan,
        "frame_age_p50_ms": _old_percentile_ms(fage, 50),
        "frame_age_p99_ms": _old_percentile_ms(fage, 99),
    }


def _compare(bridge: Bridge) -> None:
    new = bridge.stats
    old = _old_figures(bridge)
    for name, value in old.items():
        _same(getattr(new, name), value)


def test_stepped_by_hand_the_figures_are_the_old_ones_before_and_after_the_window_wraps():
    """Frames stepped on an irregular clock (jitter of every size), samples on a 60 Hz
    clock with irregular arrival: compared before any frame, with the window partly
    filled, and after it wrapped twice (stats_window 40)."""
    bridge, src = _bridge(rate_hz=100.0, stats_window=40)
    _compare(bridge)  # no data yet: nan everywhere on both
    rng = np.random.default_rng(5)
    t = time.perf_counter()
    t_sample = t
    for k in range(100):
        t += 0.01 + float(rng.normal(0.0, 0.002))
        if t - t_sample > 1 / 60:
            t_sample = t - float(rng.uniform(0.0, 0.003))
            src.put(t_sample, (float(rng.normal(0.0, 3.0)), 0.0, 9.8))
        bridge.step(t)
        if k in (0, 1, 17, 99):
            _compare(bridge)
    live = bridge.stats
    assert live.frames_sent == 100 and live.state == "live"
    assert math.isfinite(live.jitter_p99_ms) and math.isfinite(live.latency_p99_ms)


def test_frames_on_arrival_jitter_is_the_old_one():
    """The loop on arrival (send intervals against stamped intervals), stopped, then
    compared on the rings it filled; stepped by hand it has no stamps: nan on both."""
    bridge, src = _bridge(rate_hz=250.0, stats_window=64, frame_clock="arrival")
    bridge.step(time.perf_counter())
    _compare(bridge)
    assert math.isnan(bridge.stats.jitter_p99_ms)
    bridge, src = _bridge(rate_hz=250.0, stats_window=64, frame_clock="arrival")
    bridge.start()
    try:
        # until the rings have wrapped (about 0.3 s quiet), not for a fixed time: a loaded
        # machine may run fewer frames in any given wall-clock span
        end = time.perf_counter() + 30.0
        while bridge._stamps.n <= 64 and time.perf_counter() < end:
            src.put(time.perf_counter(), (2.0, -1.0, 9.8))
            time.sleep(1 / 60)
        for _ in range(6):  # and some more samples after the wrap
            src.put(time.perf_counter(), (2.0, -1.0, 9.8))
            time.sleep(1 / 60)
    finally:
        bridge.stop()
    assert bridge._stamps.n > 64  # wrapped
    _compare(bridge)
    assert math.isfinite(bridge.stats.jitter_p99_ms)
