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


def test_irregular_frame_times_are_judged_by_the_mean_of_the_two_intervals() -> None:
    """Closed form: samples of p = a t^2 / 2 at any times have exactly acceleration ``a``
    by the change of speed over the mean of the two intervals (the controllers' definition,
    frames on arrival); a limit just below ``a`` is caught, one at ``a`` is kept."""
    rng = np.random.default_rng(3)
    t = np.concatenate([[0.0], np.cumsum(rng.integers(2, 7, 200) * 1e-3)])
    a = 3000.0  # pulses/s^2
    p = (0.5 * a * t**2)[:, None] + np.zeros((1, 1))
    table = [{"stroke_pulses": [-1e9, 1e9], "max_speed_pulses_s": 1e9, "max_accel_pulses_s2": a}]
    chk = check_frames(t, p, table)
    np.testing.assert_allclose(chk.accel_use, 1.0, rtol=1e-9)
    table[0]["max_accel_pulses_s2"] = a * 0.999
    assert not check_frames(t, p, table).ok
