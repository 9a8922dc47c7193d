"""How the loopback tests judge a step (``tests/_loopback.step_delays_ms``), on frames made
here: a step the frames follow is counted with its delay, one they never follow is missed, and
one whose window the frames stopped in (a stopped process) or whose frames before were not
quiet cannot be judged. The latency acceptance asserts no missed step; this keeps that
assertion able to fail."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _loopback as lb

PERIOD_MS = 4  # 250 Hz frames
STEP_MS = 400  # the step's send time, on the frames' clock (t_ns = stamp)


def _frames(
    react_ms: float | None, stop_ms: tuple[int, int] | None = None, busy_before: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Frames every 4 ms for 2 s, one actuator at rest, then (``react_ms`` after the step)
    accelerating at 1e8 pulses/s^2; ``stop_ms``: no frame sent in that span; ``busy_before``:
    the acceleration jumps every frame before the step."""
    stamp = np.arange(0, 2000, PERIOD_MS)
    if stop_ms is not None:
        stamp = stamp[(stamp < stop_ms[0]) | (stamp >= stop_ms[1])]
    t_s = stamp * 1e-3
    pos = np.zeros(len(stamp))
    if react_ms is not None:
        t0 = (STEP_MS + react_ms) * 1e-3
        pos = 0.5 * 1e8 * np.clip(t_s - t0, 0.0, None) ** 2
    if busy_before:
        pos = pos + np.where(stamp < STEP_MS, 1e3 * (np.arange(len(stamp)) % 2), 0.0)
    return stamp.astype(np.int64) * 1_000_000, stamp, pos[:, None]


def _judge(frames: tuple[np.ndarray, np.ndarray, np.ndarray]) -> tuple[np.ndarray, int, int]:
    t_ns, stamp, pos = frames
    return lb.step_delays_ms(t_ns, stamp, pos, [STEP_MS * 1_000_000], window_ms=300.0)


def test_a_step_the_frames_follow_is_counted_with_its_delay() -> None:
    delays, unjudged, missed = _judge(_frames(20.0))
    assert (unjudged, missed) == (0, 0)
    assert len(delays) == 1 and 20.0 <= delays[0] <= 20.0 + 3 * PERIOD_MS, delays


def test_a_step_the_frames_never_follow_is_missed() -> None:
    assert _judge(_frames(None))[1:] == (0, 1)
    assert _judge(_frames(500.0))[1:] == (0, 1)  # later than the window


def test_a_step_whose_window_the_frames_stopped_in_is_not_judged() -> None:
    # the process stopped 100 ms after the step for 1 s: the frames after it cannot say
    assert _judge(_frames(None, stop_ms=(STEP_MS + 100, STEP_MS + 1100)))[1:] == (1, 0)
    # a stop shorter than stall_ms (50 ms) is no excuse
    assert _judge(_frames(None, stop_ms=(STEP_MS + 100, STEP_MS + 140)))[1:] == (0, 1)


def test_a_step_after_unquiet_frames_is_not_judged() -> None:
    assert _judge(_frames(20.0, busy_before=True))[1:] == (1, 0)
