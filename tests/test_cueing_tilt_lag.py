"""The tilt's lag (issue 20): the joint rate limit of roll and pitch (``[tilt] rate_mix``)
and the share of the tilt's lag the translation renders (``[tilt] lag_fill``).

A hexapod's legs feel roll and pitch rates together: in some legs they add. One box limit
per axis is either slow for a pure tilt or too fast for both at once (the actuators' speed:
the limiter then changes frames). With rows ``(a_k, b_k)`` the tilt is kept to
``max_k(a_k |roll'| + b_k |pitch'|) <= rate_limit``. Oracles: the closed-form ramp of a
step (slope ``r / max_k a_k`` for roll alone, ``r / max_k(a_k + b_k)`` for a diagonal step),
the invariant on random targets, batch against streaming, the TOML round trip. Lag fill: the
translational filter's input against its closed form ``-k g sin(pitch* - pitch)``.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing
from motioncue.cueing._classical import rate_mix_step
from motioncue.cueing._tune import preset_toml

ROWS = ((0.213, 1.0), (0.76, 0.684), (0.973, 0.316))  # stewart6-linear's legs, normalised
FS = 100.0
G = 9.80665


def _params(**kw: object) -> CueingParams:
    base = replace(
        load_cueing("racing-hexapod"),
        tilt_scale=(1.0, 1.0),
        tilt_wn_rad_s=40.0,  # a fast low-pass: the rate limit is what shapes the step
        tilt_limit_rad=math.radians(30.0),
        soft_knee=1.0,
        tilt_rate_limit_rad_s=math.radians(20.0),
        tilt_accel_limit_rad_s2=None,
        tilt_rate_mix=ROWS,
        lead_s=None,
    )
    return replace(base, **kw)  # type: ignore[arg-type]


def _step(fx: float, fy: float, n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[20:, 0] = fx
    f[20:, 1] = fy
    return f, np.zeros((n, 3))


def _slope(x: np.ndarray) -> float:
    """Largest rate of a tilt signal (rad/s)."""
    return float(np.abs(np.diff(x)).max() * FS)


@pytest.mark.parametrize("k", [1.0, 2.0])  # rows as given, and doubled (binding alone too)
@pytest.mark.parametrize(
    ("fx", "fy", "axis", "col"),
    [(0.0, -1.5, 0, "a"), (-1.5, 0.0, 1, "b"), (-1.5, -1.5, 0, "a+b")],
)
def test_a_step_ramps_at_the_closed_form_rate(
    fx: float, fy: float, axis: int, col: str, k: float
) -> None:
    rows = tuple((k * a, k * b) for a, b in ROWS)
    weight = max({"a": a, "b": b, "a+b": a + b}[col] for a, b in rows)
    p = _params(tilt_rate_mix=rows)
    tilt = ClassicalWashout(p, FS).run(*_step(fx, fy)).tilt
    r = p.tilt_rate_limit_rad_s
    # each axis alone is also held to r: roll alone at r / max_k a_k, at most r
    expected = r / max(1.0, weight)
    assert _slope(tilt[:, axis]) == pytest.approx(expected, rel=1e-9)
    # the ramp holds that rate until the target is near: many samples at the slope
    steps = np.abs(np.diff(tilt[:, axis])) * FS
    assert np.count_nonzero(np.isclose(steps, expected, rtol=1e-9)) >= 10
    # without the mix both axes ramp at r each
    free = ClassicalWashout(replace(p, tilt_rate_mix=None), FS).run(*_step(fx, fy)).tilt
    assert _slope(free[:, axis]) == pytest.approx(r, rel=1e-9)


@pytest.mark.parametrize("accel_deg_s2", [None, 300.0])
def test_random_targets_keep_the_joint_rate(accel_deg_s2: float | None) -> None:
    rng = np.random.default_rng(3)
    n = 3000
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[:, :2] = np.repeat(rng.uniform(-2.5, 2.5, size=(n // 50, 2)), 50, axis=0)
    accel = None if accel_deg_s2 is None else math.radians(accel_deg_s2)
    p = _params(tilt_accel_limit_rad_s2=accel)
    tilt = ClassicalWashout(p, FS).run(f, np.zeros((n, 3))).tilt
    rate = np.abs(np.diff(tilt, axis=0)) * FS
    joint = np.max([a * rate[:, 0] + b * rate[:, 1] for a, b in ROWS], axis=0)
    r = p.tilt_rate_limit_rad_s
    slack = 0.0 if accel is None else max(a + b for a, b in ROWS) * accel / FS
    assert joint.max() <= r + slack + 1e-12
    assert joint.max() > 0.9 * r  # the limit is reached, not avoided
    if accel is not None:
        acc = np.abs(np.diff(tilt, n=2, axis=0)) * FS * FS
        assert acc.max() <= accel * (1 + 1e-9)


def test_rate_mix_step_scales_only_above_the_limit() -> None:
    assert rate_mix_step(0.001, -0.002, 0.0, 0.0, ROWS, 0.01, 0.0) == (0.001, -0.002)
    ur, up = rate_mix_step(0.01, -0.01, 0.0, 0.0, ROWS, 0.005, 0.0)
    c = 0.005 / max(a * 0.01 + b * 0.01 for a, b in ROWS)
    assert (ur, up) == pytest.approx((0.01 * c, -0.01 * c), rel=1e-12)


@pytest.mark.parametrize("accel", [None, 2.0])
def test_batch_equals_streaming(accel: float | None) -> None:
    from test_cueing_classical import assert_batch_equals_streaming, random_drive

    design = ClassicalWashout(_params(tilt_accel_limit_rad_s2=accel, lead_s=(0.05, 0.02)), FS)
    f, w = random_drive(2500, seed=11)
    assert_batch_equals_streaming(design, f, w, 613)


def test_toml_round_trip_and_bad_rows(tmp_path: Path) -> None:
    p = _params()
    path = tmp_path / "mix.toml"
    path.write_text(preset_toml(p))
    assert load_cueing(path).tilt_rate_mix == ROWS
    with pytest.raises(ConfigError, match="tilt_rate_mix"):
        _params(tilt_rate_mix=((0.0, 0.0),))
    with pytest.raises(ConfigError, match="tilt_rate_mix"):
        _params(tilt_rate_mix=((1.0, -0.5),))
    with pytest.raises(ConfigError, match="tilt_rate_mix"):
        _params(tilt_rate_mix=())
    bad = path.read_text().replace("rate_mix = [", 'rate_mix = ["x", ')
    path.write_text(bad)
    with pytest.raises(ConfigError, match="rate_mix"):
        load_cueing(path)


# -- the lag fill ([tilt] lag_fill): the translation renders a share of the tilt's lag --------
def _braking(n: int = 600) -> tuple[np.ndarray, np.ndarray]:
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[50:150, 0] = -20.0  # a 1 s stop of 2 g
    return f, np.zeros((n, 3))


def _fill(k: float, **kw: object) -> CueingParams:
    return _params(
        tilt_additive=True,
        tilt_lag_fill=k,
        f_scale=(0.0, 0.0, 0.0),
        w_scale=(0.0, 0.0, 0.0),
        tilt_scale=(0.12, 0.12),
        trans_wb_rad_s=(0.0, 0.0, 1.0),
        **kw,
    )


@pytest.mark.parametrize("k", [0.4, 1.0])
def test_lag_fill_feeds_the_translation_minus_k_g_sin_of_the_lag(k: float) -> None:
    """Closed form (pure pitch, no translational force): the translational filter's input is
    ``a_x = -k g sin(pitch* - pitch)``; ``pitch*`` is the tilt without its rate limit (a
    second run with a limit it never reaches), ``pitch`` the delivered tilt."""
    from scipy.signal import sosfilt

    f, w = _braking()
    design = ClassicalWashout(_fill(k), FS)
    res = design.run(f, w)
    free = ClassicalWashout(_fill(k, tilt_rate_limit_rad_s=1e3, tilt_rate_mix=None), FS)
    target = free.run(f, w).tilt[:, 1]
    lag = target - res.tilt[:, 1]
    assert np.abs(lag).max() > math.radians(3.0)  # the rate limit does delay the tilt
    a_x = -k * G * np.sin(lag)
    x = sosfilt(np.array(design.trans[0]), a_x)
    np.testing.assert_allclose(res.poses[:, 0], x, rtol=0, atol=1e-9)
    # and nothing else moves: no lateral or vertical translation from a pure pitch
    assert np.abs(res.poses[:, 1]).max() < 1e-12
    # without the fill the additive translation stays at neutral (its own force is 0)
    still = ClassicalWashout(_fill(0.0), FS).run(f, w)
    assert np.abs(still.poses[:, :3]).max() < 1e-12
    # the fill's cue has the vehicle's sign at the onset: forward surge (-x is back) while
    # the nose comes up late: the braking force (fx < 0) is rendered by a = x'' < 0
    onset = slice(50, 60)
    assert (a_x[onset] <= 0.0).all() and a_x[onset].min() < -0.1


def test_lag_fill_batch_equals_streaming() -> None:
    from test_cueing_classical import assert_batch_equals_streaming, random_drive

    p = replace(_fill(0.6), f_scale=(0.05, 0.1, 0.1), w_scale=(0.3, 0.3, 0.1), lead_s=(0.05, 0.02))
    design = ClassicalWashout(p, FS)
    f, w = random_drive(2500, seed=5)
    assert_batch_equals_streaming(design, f, w)


def test_lag_fill_needs_the_additive_tilt_and_round_trips(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="tilt_lag_fill"):
        _params(tilt_lag_fill=0.5)
    with pytest.raises(ConfigError, match="tilt_lag_fill"):
        _fill(1.5)
    path = tmp_path / "fill.toml"
    path.write_text(preset_toml(_fill(0.35)))
    assert load_cueing(path).tilt_lag_fill == pytest.approx(0.35, rel=1e-15)
