"""Live-loop building blocks: deadline ticker, cue gate fades, statistics."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.pipeline._realtime import CueGate, GateConfig, LoopStats, Ticker


def test_ticker_keeps_absolute_deadlines() -> None:
    ticker = Ticker(0.005)
    deadlines = [ticker.wait() for _ in range(40)]
    arrived = time.perf_counter()
    np.testing.assert_allclose(np.diff(deadlines), 0.005, atol=1e-12)
    assert arrived >= deadlines[-1]
    assert abs((deadlines[-1] - ticker.t0) - 40 * 0.005) < 1e-9


def test_ticker_skips_missed_deadlines_instead_of_bursting() -> None:
    ticker = Ticker(0.002)
    ticker.wait()
    time.sleep(0.02)  # overrun by ~10 periods
    d1 = ticker.wait()
    d2 = ticker.wait()
    assert ticker.missed >= 8
    assert d2 - d1 == pytest.approx(0.002)


def test_ticker_rejects_bad_period() -> None:
    with pytest.raises(ConfigError, match="period_s"):
        Ticker(0.0)


def _run_gate(
    gate: CueGate, dt: float, steps: int, packet_at: float | None, paused: bool, t0: float
) -> tuple[list[float], float]:
    gains = []
    t = t0
    for _ in range(steps):
        t += dt
        last = t if packet_at is None else packet_at
        gains.append(gate.update(t, last, paused))
    return gains, t


def test_gate_fades_in_smoothly_then_out_on_loss() -> None:
    cfg = GateConfig(timeout_s=0.25, fade_in_s=2.0, fade_out_s=1.0)
    gate = CueGate(cfg)
    dt = 0.01
    gains, t = _run_gate(gate, dt, 300, None, False, 0.0)  # packets every tick
    g = np.asarray(gains)
    assert g[0] < 0.01 and g[-1] == 1.0
    assert np.all(np.diff(g) >= 0)
    # Rate bound of the raised cosine: max slope pi / (2 * fade_in_s).
    assert np.max(np.diff(g)) / dt <= math.pi / (2 * cfg.fade_in_s) + 1e-9
    # 2 s fade reached at 2.0 s (200 ticks)
    assert g[198] < 1.0 and g[200] == 1.0
    # Packets stop at t: still live until the timeout, then fades out within fade_out_s.
    gains, _ = _run_gate(gate, dt, 200, t, False, t)
    g = np.asarray(gains)
    assert np.all(g[:24] == 1.0)
    assert g[-1] == 0.0 and gate.parked
    assert np.all(np.diff(g) <= 0)
    assert gate.fade_outs == 1 and gate.fade_ins == 1


def test_gate_pause_parks_and_resume_ramps() -> None:
    gate = CueGate(GateConfig(fade_in_s=0.5, fade_out_s=0.5))
    _, t = _run_gate(gate, 0.01, 100, None, False, 0.0)
    assert gate.gain == 1.0
    _, t = _run_gate(gate, 0.01, 100, None, True, t)
    assert gate.parked
    gains, _ = _run_gate(gate, 0.01, 100, None, False, t)
    assert 0.0 < gains[0] < 0.01 and gains[-1] == 1.0


def test_gate_config_validation() -> None:
    with pytest.raises(ConfigError, match="fade_in_s"):
        GateConfig(fade_in_s=-1.0)


def test_loop_stats_percentiles() -> None:
    stats = LoopStats()
    for k in range(101):
        stats.tick(k * 0.01 + (0.002 if k == 50 else 0.0))
        stats.latency(k * 1e-5)
    s = stats.summary(0.01)
    assert s["latency_p99_ms"] == pytest.approx(np.percentile(np.arange(101) * 1e-5, 99) * 1e3)
    assert s["jitter_p99_ms"] == pytest.approx(2.0, rel=0.05)
    assert s["rate_hz"] == pytest.approx(100.0, rel=1e-6)
