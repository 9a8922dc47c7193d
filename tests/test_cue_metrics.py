"""Cue metrics (motioncue.cueing.cue_metrics) against closed forms.

Perceived motion is built directly (no vestibular model), so each figure is known without the
implementation: a scaled copy (share = gain = k, correlation 1, no reversal), a delayed copy
of a sine of whole periods (gain = correlation = cos(w tau), share 1, reversals on a known
share of the phase), a mirrored copy (reversals wherever both are above threshold) and a
platform at rest (share 0, every perceptible sample missed).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.cueing import cue_masks, cue_metrics, cue_score, get_model_set

THR = np.asarray(get_model_set("telban-cardullo-2005").thresholds)
N_PERIOD = 400  # samples per period of the test sine
PERIODS = 25


def _sine(amp_thr: float, phase: float = 0.0) -> np.ndarray:
    """(N, 6): a sine of ``amp_thr`` thresholds on every channel, whole periods."""
    n = N_PERIOD * PERIODS
    theta = 2 * math.pi * np.arange(n) / N_PERIOD + phase
    return amp_thr * THR * np.sin(theta)[:, None]


def _above(amp_thr: float) -> float:
    """Share of the phase with |A sin| > thr: 1 - 2 asin(thr/A)/pi."""
    return 1.0 - 2.0 * math.asin(1.0 / amp_thr) / math.pi


# phase quantisation: one sample in N_PERIOD per crossing, four crossings per period
TOL_PHASE = 4.0 / N_PERIOD


@pytest.mark.parametrize("k", [0.05, 0.3, 1.0, 2.5])
def test_scaled_copy(k: float) -> None:
    a = 8.0
    v = _sine(a)
    m = cue_metrics(v, k * v, THR, clamped_share=0.25)
    np.testing.assert_allclose(m.rendered_share, k, rtol=1e-12)
    np.testing.assert_allclose(m.gain, k, rtol=1e-12)
    np.testing.assert_allclose(m.correlation, 1.0, atol=1e-12)
    assert np.all(m.reversals == 0.0) and np.all(m.false_cues == 0.0)
    # missed: thr < |v| <= thr / k; spurious: thr / k < |v| <= thr (closed form in phase)
    missed = max(0.0, _above(a) - (_above(a * k) if a * k > 1 else 0.0))
    spurious = max(0.0, (_above(a * k) if a * k > 1 else 0.0) - _above(a))
    np.testing.assert_allclose(m.missed, missed, atol=TOL_PHASE)
    np.testing.assert_allclose(m.spurious, spurious, atol=TOL_PHASE)
    np.testing.assert_allclose(m.vehicle_above, _above(a), atol=TOL_PHASE)
    assert m.clamped == 0.25 and m.n_samples == v.shape[0]


@pytest.mark.parametrize("lag", [20, 100, 150])
def test_delayed_copy(lag: int) -> None:
    a = 6.0
    v = _sine(a)
    p = np.roll(v, lag, axis=0)  # whole periods: a circular shift is an exact delay
    m = cue_metrics(v, p, THR)
    phi = 2 * math.pi * lag / N_PERIOD
    np.testing.assert_allclose(m.rendered_share, 1.0, rtol=1e-12)
    np.testing.assert_allclose(m.gain, math.cos(phi), atol=1e-9)
    np.testing.assert_allclose(m.correlation, math.cos(phi), atol=1e-9)
    # reversals: sin(t) sin(t - phi) < 0 on a share phi/pi of the phase (phi <= pi); both
    # above threshold removes |sin| <= x around each zero of either: where they overlap
    # in sign-opposite windows, the window (0, phi) per half period loses asin(x) at each end
    x = 1.0 / a
    win = max(0.0, phi - 2.0 * math.asin(x))
    np.testing.assert_allclose(m.reversals, win / math.pi, atol=TOL_PHASE)
    assert math.isnan(m.clamped)


def test_quarter_period_delay_reverses_half_the_time_minus_the_thresholds() -> None:
    # p = -cos: opposite to sin on half the phase; both above x on 1/2 - 2 asin(x)/pi of it
    a = 4.0
    v = _sine(a)
    m = cue_metrics(v, np.roll(v, N_PERIOD // 4, axis=0), THR)
    expected = 0.5 - 2.0 * math.asin(1.0 / a) / math.pi
    np.testing.assert_allclose(m.reversals, expected, atol=TOL_PHASE)
    np.testing.assert_allclose(m.gain, 0.0, atol=1e-9)


@pytest.mark.parametrize("k", [0.1, 0.5, 1.0])
def test_mirrored_copy(k: float) -> None:
    a = 10.0
    v = _sine(a)
    m = cue_metrics(v, -k * v, THR)
    np.testing.assert_allclose(m.rendered_share, k, rtol=1e-12)
    np.testing.assert_allclose(m.gain, -k, rtol=1e-12)
    np.testing.assert_allclose(m.correlation, -1.0, atol=1e-12)
    both = _above(a * k) if a * k > 1 else 0.0  # k <= 1: |k v| > thr implies |v| > thr
    np.testing.assert_allclose(m.reversals, both, atol=TOL_PHASE)
    np.testing.assert_allclose(m.false_cues, both, atol=TOL_PHASE)  # all false = reversals
    assert np.all(m.spurious == 0.0)
    # exact check on the samples: reversal wherever both are above threshold
    masks = cue_masks(v, -k * v, THR)
    both_mask = (np.abs(v) > THR) & (np.abs(k * v) > THR)
    assert np.array_equal(masks.reversal, both_mask)
    assert np.array_equal(masks.false, both_mask)


def test_mirrored_and_amplified_false_cues_include_spurious_ones() -> None:
    a, k = 3.0, 3.0
    v = _sine(a)
    m = cue_metrics(v, -k * v, THR)
    np.testing.assert_allclose(m.reversals, _above(a), atol=TOL_PHASE)
    np.testing.assert_allclose(m.spurious, _above(a * k) - _above(a), atol=TOL_PHASE)
    np.testing.assert_allclose(m.false_cues, _above(a * k), atol=TOL_PHASE)
    assert m.reversals_any == pytest.approx(float(m.reversals.max()), abs=TOL_PHASE)


def test_platform_at_rest() -> None:
    a = 5.0
    v = _sine(a)
    v[:, 2] = 0.0  # a channel the vehicle never uses
    m = cue_metrics(v, np.zeros_like(v), THR)
    active = [0, 1, 3, 4, 5]
    np.testing.assert_array_equal(m.rendered_share[active], 0.0)
    np.testing.assert_array_equal(m.gain[active], 0.0)
    assert math.isnan(m.rendered_share[2]) and math.isnan(m.gain[2])
    assert np.all(np.isnan(m.correlation))
    np.testing.assert_allclose(m.missed[active], _above(a), atol=TOL_PHASE)
    np.testing.assert_array_equal(m.missed, m.vehicle_above)
    assert m.reversals_any == m.spurious_any == m.false_any == 0.0
    assert m.missed_any == pytest.approx(float(m.missed.max()), abs=1e-12)


def test_fields_agree_with_the_score_and_pool_over_drives() -> None:
    rng = np.random.default_rng(3)
    v = rng.standard_normal((3000, 6)) * THR * 3
    p = 0.4 * v + rng.standard_normal((3000, 6)) * THR
    m = cue_metrics(v, p, THR)
    s = cue_score(v, p, THR)
    np.testing.assert_allclose(m.correlation, s.correlation, atol=1e-12)
    assert m.false_any == pytest.approx(s.false_fraction, abs=1e-12)
    # pooling is concatenation: the pooled share is the RMS ratio over all samples
    m1 = cue_metrics(v[:1000], p[:1000], THR)
    m2 = cue_metrics(v[1000:], p[1000:], THR)
    pooled = np.sqrt(
        (m1.rendered_share**2 * np.sum(v[:1000] ** 2, 0) + m2.rendered_share**2
         * np.sum(v[1000:] ** 2, 0)) / np.sum(v**2, 0)
    )  # fmt: skip
    np.testing.assert_allclose(m.rendered_share, pooled, rtol=1e-12)
    d = m.to_dict()
    assert d["rendered_share"]["fy"] == pytest.approx(float(m.rendered_share[1]))
    assert d["clamped"] is None and d["n_samples"] == 3000
    assert "fx" in m.table() and "clamped -" in m.table()


def test_empty_run_and_bad_input() -> None:
    m = cue_metrics(np.zeros((0, 6)), np.zeros((0, 6)), THR)
    assert m.n_samples == 0 and m.missed_any == 0.0
    assert np.all(np.isnan(m.rendered_share))
    with pytest.raises(ConfigError, match=r"\(N, 6\)"):
        cue_metrics(np.zeros((5, 6)), np.zeros((4, 6)), THR)
    with pytest.raises(ConfigError, match="thresholds"):
        cue_metrics(np.zeros((5, 6)), np.zeros((5, 6)), np.zeros(6))
    with pytest.raises(ConfigError, match="finite"):
        cue_metrics(np.full((5, 6), np.nan), np.zeros((5, 6)), THR)
    with pytest.raises(ConfigError, match="clamped share"):
        cue_metrics(np.zeros((5, 6)), np.zeros((5, 6)), THR, clamped_share=1.5)
