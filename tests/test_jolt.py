"""The jolt figure (session 31): a perceived motion's rms above 2 Hz, in thresholds.

Checked against closed forms (a sinusoid well above the band's edge gives ``a / sqrt(2) /
thr`` times the filter's gain there, a constant nothing, a slow swing next to nothing),
linearity, and as the ``jolt_*`` columns of ``compare``; refused input is one ConfigError.
What it found (``optimal-hexapod-auto``'s steps of acceleration) is tests/test_optimal_jerk.py.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import JOLT_CUTOFF_HZ, jolt

FS = 100.0


def _gain(f_hz: float) -> float:
    """|H|^2 of the 4th-order Butterworth high-pass at f (run forwards and backwards)."""
    return 1.0 / (1.0 + (JOLT_CUTOFF_HZ / f_hz) ** 8)


@pytest.mark.parametrize("f_hz", [5.0, 8.0, 15.0])
def test_a_fast_sinusoid_gives_its_rms_in_thresholds(f_hz: float) -> None:
    t = np.arange(4000) / FS
    a, thr = 0.3, 0.17
    p = (a * np.sin(2 * np.pi * f_hz * t))[:, None]
    want = a / math.sqrt(2.0) / thr * _gain(f_hz)
    assert jolt(p, FS, [thr])[0] == pytest.approx(want, rel=2e-3)


def test_steady_and_slow_motion_give_next_to_nothing() -> None:
    t = np.arange(6000) / FS
    p = np.column_stack([np.full_like(t, 3.0), 3.0 * np.sin(2 * np.pi * 0.2 * t)])
    j = jolt(p, FS, [0.17, 0.17])
    assert j[0] < 1e-9
    assert j[1] < 0.01 * 3.0 / math.sqrt(2) / 0.17  # under 1 % of the swing's own rms


def test_it_is_linear_and_per_channel() -> None:
    rng = np.random.default_rng(4)
    p = rng.normal(size=(3000, 3))
    j = jolt(p, FS, [1.0, 1.0, 1.0])
    np.testing.assert_allclose(jolt(2.5 * p, FS, [1.0, 1.0, 1.0]), 2.5 * j, rtol=1e-12)
    np.testing.assert_allclose(jolt(p, FS, [1.0, 2.0, 4.0]), j / [1.0, 2.0, 4.0], rtol=1e-12)
    # white noise: the share of its power above 2 Hz of the 50 Hz band, about 0.96
    assert np.all((j > 0.9) & (j < 1.0)), j


@pytest.mark.parametrize(
    ("p", "fs", "thr"),
    [(np.zeros(100), FS, [1.0]), (np.zeros((100, 2)), FS, [1.0]),
     (np.zeros((100, 1)), FS, [0.0]), (np.zeros((100, 1)), 3.0, [1.0]),
     (np.zeros((100, 1)), float("nan"), [1.0])],
)  # fmt: skip
def test_bad_input_is_one_config_error(p: np.ndarray, fs: float, thr: list[float]) -> None:
    with pytest.raises(ConfigError, match="jolt"):
        jolt(p, fs, thr)


def test_a_short_record_is_nan() -> None:
    assert np.isnan(jolt(np.ones((10, 2)), FS, [1.0, 1.0])).all()
