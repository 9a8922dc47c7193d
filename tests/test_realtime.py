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
    # on the grid t0 + k * period; a busy machine that stops this thread for a whole period
    # makes the ticker skip deadlines (counted, see the next test), never drift off the grid
    steps = np.diff(deadlines) / 0.005
    np.testing.assert_allclose(steps, np.rint(steps), atol=1e-9)
    assert np.all(np.rint(steps) >= 1)
    assert arrived >= deadlines[-1]
    k_last = (deadlines[-1] - ticker.t0) / 0.005
    assert abs(k_last - round(k_last)) < 1e-6
    assert round(k_last) == 40 + ticker.missed  # every deadline fired or counted as missed


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


def _thread_slice_ns() -> int | None:
    """The calling thread's scheduler slice as the kernel reports it (None: not shown)."""
    import threading

    path = f"/proc/self/task/{threading.get_native_id()}/sched"
    try:
        with open(path) as fh:
            for line in fh:
                if line.startswith("se.slice"):
                    return int(line.split(":")[1])
    except OSError:
        return None
    return None


def test_a_short_slice_is_granted_to_the_calling_thread_only() -> None:
    """Checked on the kernel's own report (/proc/.../sched), in a thread of its own so that
    the test process keeps its slice; the policy stays SCHED_OTHER."""
    import os
    import platform
    import sys
    import threading

    from motioncue.pipeline._realtime import request_short_slice

    if not sys.platform.startswith("linux"):
        assert request_short_slice(1e-4) is not None  # a note, never an exception
        return
    out: dict[str, object] = {}

    def run() -> None:
        out["note"] = request_short_slice(2e-4)
        out["slice"] = _thread_slice_ns()
        out["policy"] = os.sched_getscheduler(0)

    main_before = _thread_slice_ns()
    th = threading.Thread(target=run)
    th.start()
    th.join()
    assert out["note"] is None, out
    assert out["policy"] == os.SCHED_OTHER
    major, minor = (int(x) for x in platform.release().split(".")[:2])
    if (major, minor) >= (6, 12):  # custom slices of fair tasks (EEVDF)
        assert out["slice"] == 200_000, out
        assert _thread_slice_ns() == main_before != 200_000


def test_a_short_slice_outside_the_kernel_bounds_is_refused() -> None:
    from motioncue.pipeline._realtime import request_short_slice

    for bad in (0.0, 5e-5, 0.2, float("nan"), float("inf")):
        with pytest.raises(ConfigError, match="slice_s"):
            request_short_slice(bad)
