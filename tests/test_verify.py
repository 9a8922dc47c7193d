"""The independent frame checker flags exactly what exceeds a limit."""

from __future__ import annotations

import numpy as np

from motioncue.pipeline._verify import check_frames


def _table(n: int = 2) -> dict:
    return {
        "actuators": [
            {"stroke_pulses": [0, 1000], "max_speed_pulses_s": 1000.0, "max_accel_pulses_s2": 1e4}
            for _ in range(n)
        ]
    }


def test_feasible_trapezoid_passes() -> None:
    dt = 0.01
    t = np.arange(200) * dt
    # accelerate at 1e4 for 10 frames (v = 1000), coast, stays within the 0..1000 stroke
    v = np.minimum(np.arange(200) * 1e4 * dt, 1000.0)
    v[60:] = 0.0
    v[50:60] = 1000.0 - np.arange(1, 11) * 1e4 * dt
    p = np.cumsum(v * dt)
    res = check_frames(t, np.stack([p, p / 2], axis=1), _table())
    assert res.ok, res.summary()
    assert abs(res.accel_use[0] - 1.0) < 1e-9


def test_each_limit_is_caught() -> None:
    t = np.arange(10) * 0.01
    base = np.full((10, 2), 500.0)
    over_stroke = base.copy()
    over_stroke[5, 1] = 1001
    res = check_frames(t, over_stroke, _table())
    assert not res.ok and res.stroke_use[1] > 1 and res.stroke_use[0] <= 1
    step = base.copy()
    step[5:, 0] += 11  # 1100 pulses/s for one frame
    res = check_frames(t, step, _table())
    assert not res.ok and res.speed_use[0] > 1 and res.worst_frame["speed"] == 5
    kink = base.copy()
    kink[5:, 0] += np.arange(5) * 2.0  # 200 p/s speed change in one frame -> 2e4 p/s^2
    res = check_frames(t, kink, _table())
    assert res.speed_use[0] <= 1 and res.accel_use[0] > 1 and not res.ok


def test_nan_is_never_ok() -> None:
    p = np.full((5, 2), 500.0)
    p[2, 0] = np.nan
    assert not check_frames(np.arange(5) * 0.01, p, _table()).ok
