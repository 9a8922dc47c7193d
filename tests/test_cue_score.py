"""The cue score (motioncue.cueing.cue_score) against closed forms of its terms.

Each case builds perceived motion whose score terms are known without the implementation:
identical motion (score 0), a scaled copy (correlation 1, J/J0 = 1 - k), no motion (J/J0 = 1,
the whole active correlation lost, every above-threshold sample missed), a mirrored copy
(correlation -1, a false cue wherever the vehicle's motion is above threshold).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.cueing import (
    CORRELATION_WEIGHTS,
    FALSE_CUE_WEIGHT,
    MISSED_CUE_WEIGHT,
    cue_score,
    get_model_set,
)

THR = np.asarray(get_model_set("telban-cardullo-2005").thresholds)


def _vehicle(n: int = 4000, seed: int = 0) -> np.ndarray:
    """Perceived vehicle motion: slow sines of ten thresholds on fx, fy, wz, small elsewhere."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 100.0
    pv = np.zeros((n, 6))
    pv[:, 0] = 10 * THR[0] * np.sin(0.7 * t + 0.3)
    pv[:, 1] = 10 * THR[1] * np.sin(1.1 * t)
    pv[:, 5] = 10 * THR[5] * np.sin(0.4 * t + 1.0)
    pv[:, 2] = 0.2 * THR[2] * rng.standard_normal(n)  # below threshold: inactive
    return pv


def _j(err: np.ndarray) -> float:
    return math.sqrt(float(np.mean(np.sum(np.square(err / THR), axis=1))) / 6.0)


def test_identical_motion_scores_zero() -> None:
    pv = _vehicle()
    s = cue_score(pv, pv.copy(), THR)
    assert s.score == pytest.approx(0.0, abs=1e-12)
    assert s.active.tolist() == [True, True, False, False, False, True]


@pytest.mark.parametrize("k", [0.1, 0.5, 0.9])
def test_scaled_copy_keeps_the_shape_and_loses_one_minus_k(k: float) -> None:
    pv = _vehicle()
    s = cue_score(pv, k * pv, THR)
    assert s.correlation_term == pytest.approx(0.0, abs=1e-12)
    assert s.relative_error == pytest.approx(1.0 - k, rel=1e-12)  # J0 = J(pv) > 1 here
    assert s.false_fraction == 0.0
    active = [0, 1, 5]
    above = np.abs(pv[:, active]) > THR[active]
    missed = above & ~(np.abs(k * pv[:, active]) > THR[active])
    assert s.missed_fraction == pytest.approx(float(missed.mean(axis=0).mean()), abs=1e-12)
    expected = (1.0 - k) + MISSED_CUE_WEIGHT * s.missed_fraction
    assert s.score == pytest.approx(expected, rel=1e-12)


def test_no_motion_loses_everything_but_gives_no_false_cue() -> None:
    pv = _vehicle()
    s = cue_score(pv, np.zeros_like(pv), THR)
    assert s.relative_error == pytest.approx(1.0, rel=1e-12)
    assert s.correlation_term == pytest.approx(1.0)  # constant simulator: correlation 0
    assert s.false_fraction == 0.0
    active = [0, 1, 5]
    frac = (np.abs(pv[:, active]) > THR[active]).mean(axis=0).mean()
    assert s.missed_fraction == pytest.approx(float(frac), abs=1e-12)


def test_mirrored_motion_is_a_false_cue_wherever_the_vehicle_is_perceived() -> None:
    pv = _vehicle()
    s = cue_score(pv, -pv, THR)
    assert np.allclose(s.correlation[[0, 1, 5]], -1.0)
    assert s.correlation_term == pytest.approx(2.0)
    j0 = _j(pv)
    assert s.relative_error == pytest.approx(_j(-2 * pv) / max(j0, 1.0), rel=1e-12)
    wrong = np.any(np.abs(pv) > THR, axis=1)  # the inactive fz channel never exceeds it
    assert s.false_fraction == pytest.approx(float(wrong.mean()), abs=1e-12)
    assert s.score == pytest.approx(
        s.relative_error + 2.0 + FALSE_CUE_WEIGHT * s.false_fraction, rel=1e-12
    )


def test_correlation_term_weights_fx_fy_over_the_others() -> None:
    pv = _vehicle()
    ps = pv.copy()
    ps[:, 5] = 0.0  # yaw lost: 1 - rho = 1 on wz only
    s = cue_score(pv, ps, THR)
    cw = np.asarray(CORRELATION_WEIGHTS)[[0, 1, 5]]
    assert s.correlation_term == pytest.approx(cw[2] / cw.sum(), rel=1e-12)
    ps = pv.copy()
    ps[:, 0] = 0.0  # fx lost instead: costs more
    assert cue_score(pv, ps, THR).correlation_term == pytest.approx(cw[0] / cw.sum())
    assert cw[0] > cw[2]


def test_quiet_vehicle_floors_j0_at_one_threshold() -> None:
    pv = np.zeros((500, 6))
    ps = np.zeros((500, 6))
    ps[:, 0] = 0.5 * THR[0]
    s = cue_score(pv, ps, THR)
    assert not s.active.any() and s.correlation_term == 0.0 and s.missed_fraction == 0.0
    assert s.relative_error == pytest.approx(_j(ps), rel=1e-12)  # J / 1


@pytest.mark.parametrize(
    ("pv", "ps", "thr", "message"),
    [
        (np.zeros((5, 6)), np.zeros((5, 5)), THR, r"two \(N, 6\) arrays"),
        (np.zeros((5, 6)), np.full((5, 6), np.nan), THR, "finite"),
        (np.zeros((5, 6)), np.zeros((5, 6)), np.zeros(6), "thresholds"),
    ],
)
def test_bad_input_is_a_config_error(
    pv: np.ndarray, ps: np.ndarray, thr: np.ndarray, message: str
) -> None:
    with pytest.raises(ConfigError, match=message):
        cue_score(pv, ps, thr)
