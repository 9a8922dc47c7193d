"""Frames on arrival (issue 13, item 1): frames at any whole ms keep the limits on the
controller's clock.

Oracles: an independent finite-difference check on the frames' own time stamps
(``_loopback.check_limits``: speed over each interval, acceleration as the change of speed
over the mean of the two intervals, as the controllers and emulators define it), the SC-MBOX
emulator fed the same datagrams (its own violations), and the bridge against the emulator
over loopback.
"""

from __future__ import annotations

import dataclasses
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError, TransportError
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox
from motioncue.pipeline._arrival import ArrivalOutputStage
from motioncue.pipeline._bridge import BridgeConfig
from motioncue.trajectory import ActuatorLimits

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _loopback as lb
from test_bridge import ListTransport, _check_trace, _decode_frames, _mbox_setup, live_rig

PLATFORM, CTRL, LIM = _mbox_setup()


def _stage(tr: Any, rate_hz: float = 250.0, min_ms: int = 2) -> ArrivalOutputStage:
    return ArrivalOutputStage(PLATFORM, CTRL, LIM, rate_hz, tr, min_interval_ms=min_ms)


def _check(tr: ListTransport, park_at_end: bool = True) -> tuple[np.ndarray, np.ndarray]:
    t, p = _decode_frames(tr.sent)
    stamps = np.round(t * 1000).astype(np.int64)
    v_use, a_use, in_stroke = lb.check_limits(stamps, p, LIM.to_pulses_table(PLATFORM))
    assert in_stroke and v_use <= 1.0 + 1e-9 and a_use <= 1.0 + 1e-9, (v_use, a_use)
    park = PLATFORM.drives.to_pulses(PLATFORM.q_park)
    np.testing.assert_array_equal(p[0], park)  # opens at rest, parked
    if park_at_end:
        np.testing.assert_array_equal(p[-1], park)
        np.testing.assert_array_equal(p[-2], park)
    # the emulator judges the same datagrams on its own clock
    emu = mbox.MboxEmulator(CTRL)
    t0 = 100.0
    for data, ms in zip(tr.sent, stamps, strict=True):
        emu.handle(data, t0 + ms * 1e-3)
    assert emu.violations == [], emu.violations[:3]
    return stamps, p


@settings(max_examples=40, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.integers(2, 12),  # ms after the previous frame
            st.sampled_from(["far", "near", "nan"]),
            st.integers(0, 2**31),
        ),
        min_size=5,
        max_size=120,
    )
)
def test_any_whole_ms_intervals_keep_the_limits(plan: list[tuple[int, str, int]]) -> None:
    """Wild targets (beyond the stroke, NaN) at random intervals >= min_interval_ms, then
    the park at the nominal period: every frame inside the limits on its own stamps."""
    tr = ListTransport()
    stage = _stage(tr)
    lo, hi = LIM.q_min, LIM.q_max
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    for ticks, kind, seed in plan:
        rng = np.random.default_rng(seed)
        if kind == "far":
            q = mid + 1.5 * half * rng.uniform(-1, 1, mid.size)
        elif kind == "near":
            q = np.asarray(stage.q) + 0.002 * rng.uniform(-1, 1, mid.size)
        else:
            q = np.full(mid.size, math.nan)
        stage.emit(q, ticks=ticks)
    n = 0
    while not stage.parked:
        stage.park_step()
        n += 1
        assert n <= stage.park_frames_bound()
    stamps, _ = _check(tr)
    assert np.all(np.diff(stamps) >= 2)
    assert list(np.diff(stamps[1 : len(plan) + 1])) == [t for t, _, _ in plan[1:]]


def test_a_feasible_slow_target_is_followed_at_every_interval() -> None:
    """A slow sine in actuator space, frames at 4, 4, 4, 5 ms: the frames are on the
    target (the limiter passes a feasible stream through; the fine-grid interpolation of a
    smooth target is smooth)."""
    tr = ListTransport()
    stage = _stage(tr)
    q0 = np.asarray(PLATFORM.q_park, dtype=float)
    stamp, got, want = 0, [], []
    for k in range(400):
        ticks = 5 if k % 4 == 3 else 4
        stamp += ticks
        q = q0 + 0.01 * (1 - math.cos(2 * math.pi * 0.5 * stamp * 1e-3))
        got.append(np.asarray(stage.emit(q, ticks=ticks)))
        want.append(PLATFORM.drives.to_pulses(q))
    err = np.abs(np.array(got[50:]) - np.array(want[50:]))
    assert err.max() <= 1  # rounding only
    _check(tr, park_at_end=False)


def test_refusals_are_named() -> None:
    with pytest.raises(ConfigError, match="whole-ms period"):
        _stage(ListTransport(), rate_hz=300.0)
    with pytest.raises(ConfigError, match="min_interval_ms"):
        _stage(ListTransport(), min_ms=5)
    with pytest.raises(ConfigError, match="jerk"):
        jerky = dataclasses.replace(LIM, j_max=np.full(PLATFORM.n_actuators, 500.0))
        ArrivalOutputStage(PLATFORM, CTRL, jerky, 250.0, ListTransport())
    easy = load_platform("seat3")
    ctrl = load_controller("easysmc")
    lim = ActuatorLimits.from_platform(easy, ctrl)
    with pytest.raises(ConfigError, match="whole-ms"):
        ArrivalOutputStage(easy, ctrl, lim, 100.0, ListTransport())
    with pytest.raises(ConfigError, match="frame_clock"):
        BridgeConfig(frame_clock="wobbly")
    stage = _stage(ListTransport())
    stage.emit(PLATFORM.q_park, ticks=4)
    with pytest.raises(LimitError, match=">= 2 ms"):
        stage.emit(PLATFORM.q_park, ticks=1)


def test_a_failed_frame_leaves_the_stage_where_the_link_left_it() -> None:
    tr = ListTransport()
    stage = _stage(tr)
    target = np.asarray(PLATFORM.q_park) + 0.01
    for _ in range(10):
        stage.emit(target, ticks=3)
    before = (stage.q.copy(), stage.frames, stage.last_stamp_ms, len(tr.sent))
    tr.fail_after = len(tr.sent)
    with pytest.raises(TransportError):
        stage.emit(target, ticks=5)
    np.testing.assert_array_equal(stage.q, before[0])
    assert (stage.frames, stage.last_stamp_ms, len(tr.sent)) == before[1:]
    tr.fail_after = None
    while not stage.parked:
        stage.park_step()
    _check(tr)


@pytest.mark.parametrize(("kind", "year"), [("mbox", 2024), ("imax", 2023)])
def test_the_bridge_on_arrival_drives_the_emulator_within_the_limits(kind: str, year: int) -> None:
    """Real F1 packets at 60 Hz, frames on arrival at 250 Hz nominal: the emulator finds no
    violation on its clock (nor the finite-difference check of the trace), the run opens
    and ends parked, frames come between the regular ones, and the stats have figures."""
    with live_rig(kind, 250.0, year, frame_clock="arrival") as (
        bridge,
        _sender,
        emu,
        platform,
        lim,
    ):
        end = time.monotonic() + 3.0
        while time.monotonic() < end and bridge.stats.state != "live":
            time.sleep(0.02)
        time.sleep(1.5)
        live = bridge.stats
    final = bridge.stats
    assert final.state == "stopped" and final.error is None
    assert live.state == "live"
    tr = _check_trace(emu, platform, lim)
    stamps = np.round(np.asarray(tr.t_s) * 1000).astype(np.int64)
    gaps = np.diff(stamps)
    assert gaps.min() >= 2
    # frames on arrival between the regular ones (on an idle machine 4, 4, 4, 5 ms: locked
    # on the 60 Hz packets; on a loaded one late wake-ups also give 2, 3 and 6 ms). How
    # many gaps keep the regular 4 ms is the loop's timing (a fresh clone's run with a core
    # busy gave 34 %), judged by make bench (bench_latency: output jitter on arrival with a
    # core saturated), not here
    assert np.mean(gaps != 4) > 0.05 and np.any(gaps == 4)
    assert math.isfinite(live.jitter_p99_ms) and math.isfinite(live.frame_age_p50_ms)
