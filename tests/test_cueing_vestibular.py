"""Vestibular models against their published transfer functions; simulator motion; metrics."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue.cueing import (
    DEFAULT_MODEL_SET,
    MODEL_SETS,
    OTOLITH,
    SEMICIRCULAR_CANAL,
    ClassicalWashout,
    evaluate_cueing,
    load_cueing,
    simulator_motion,
)

G = 9.80665
W = np.logspace(-4, 2, 61)


def canal_published(w: np.ndarray) -> np.ndarray:
    """Telban & Cardullo 2005: 5.73*80 s^2 (1+0.06 s) / ((1+80 s)(1+5.73 s)(1+0.005 s))."""
    s = 1j * w
    return 5.73 * 80 * s**2 * (1 + 0.06 * s) / ((1 + 80 * s) * (1 + 5.73 * s) * (1 + 0.005 * s))


def otolith_published(w: np.ndarray) -> np.ndarray:
    """Young & Meiry (1968) with unit gain: (1 + 13.2 s) / ((1 + 5.33 s)(1 + 0.66 s))."""
    s = 1j * w
    return (1 + 13.2 * s) / ((1 + 5.33 * s) * (1 + 0.66 * s))


def test_models_are_the_published_transfer_functions() -> None:
    from scipy import signal

    np.testing.assert_allclose(SEMICIRCULAR_CANAL.response(W), canal_published(W), rtol=1e-12)
    np.testing.assert_allclose(OTOLITH.response(W), otolith_published(W), rtol=1e-12)
    num, den = SEMICIRCULAR_CANAL.transfer_function()
    _, h = signal.freqs(num, den, worN=W)
    np.testing.assert_allclose(h, canal_published(W), rtol=1e-10)


def test_canal_band_shape() -> None:
    g = np.abs(canal_published(np.array([1e-4, 1e-3, 1.0, 2.0, 1e3])))
    assert g[2] == pytest.approx(1.0, abs=0.03)  # unit gain in the mid band
    assert g[3] == pytest.approx(1.0, abs=0.03)
    assert g[1] / g[0] == pytest.approx(100.0, rel=0.01)  # +40 dB/decade below adaptation
    assert g[0] < 1e-4  # a constant rotation is not perceived
    # phase lead at 1 rad/s: (90 - atan 5.73) + (90 - atan 80) + atan 0.06 - atan 0.005 deg
    lead = 90 - math.degrees(math.atan(5.73)) + 90 - math.degrees(math.atan(80.0))
    lead += math.degrees(math.atan(0.06) - math.atan(0.005))
    phase = np.degrees(np.angle(canal_published(np.array([1.0]))))[0]
    assert 10.0 < lead < 15.0
    assert phase == pytest.approx(lead, abs=1e-9)
    # cupula corner: at 1/5.73 rad/s the gain is about 1/sqrt(2) (adaptation adds a little)
    assert abs(canal_published(np.array([1 / 5.73])))[0] == pytest.approx(0.707, abs=0.03)


def test_otolith_band_shape() -> None:
    g = np.abs(otolith_published(np.array([1e-5, 0.4, 100.0, 1000.0])))
    assert g[0] == pytest.approx(1.0, abs=1e-3)  # unit DC gain: steady force felt as is
    assert g[1] > 1.5  # mid-band boost up to 13.2 / 5.33
    assert g[1] < 13.2 / 5.33
    assert g[2] / g[3] == pytest.approx(10.0, rel=0.01)  # -20 dB/decade at high frequency


@pytest.mark.parametrize("fs", [100.0, 1000.0])
def test_discrete_models_match_continuous(fs: float) -> None:
    from scipy import signal

    w = np.logspace(-2, math.log10(2 * math.pi * fs / 50), 40)  # up to fs/50
    for model, published in ((SEMICIRCULAR_CANAL, canal_published), (OTOLITH, otolith_published)):
        _, h = signal.sosfreqz(model.sos(fs), worN=w / fs)
        np.testing.assert_allclose(h, published(w), rtol=0.01)
    # time domain, on a multisine, against lsim of the continuous model
    t = np.arange(int(30 * fs)) / fs
    u = np.sin(0.9 * t) + 0.5 * np.sin(4.1 * t) + 0.3 * np.sin(11.0 * t)  # starts at rest
    for model in (SEMICIRCULAR_CANAL, OTOLITH):
        _, y_c, _ = signal.lsim(model.transfer_function(), u, t)
        y_d = model.apply(u, fs)
        assert np.sqrt(np.mean((y_d - y_c) ** 2)) < 0.01 * np.sqrt(np.mean(y_c**2))


def test_simulator_motion_closed_forms() -> None:
    fs = 1000.0
    n = 4000
    t = np.arange(n) / fs
    # a static pitch: the rider feels gravity tilted, f = R^T [0, 0, g]
    poses = np.zeros((n, 6))
    poses[:, 4] = -0.1
    f, w = simulator_motion(poses, fs)
    np.testing.assert_allclose(f[5:-5], [[G * math.sin(0.1), 0.0, G * math.cos(0.1)]] * (n - 10))
    np.testing.assert_allclose(w[5:-5], 0.0, atol=1e-12)
    # a surge sine: f_x = x''
    poses = np.zeros((n, 6))
    poses[:, 0] = 0.05 * np.sin(3.0 * t)
    f, _ = simulator_motion(poses, fs)
    np.testing.assert_allclose(f[5:-5, 0], -0.45 * np.sin(3.0 * t[5:-5]), atol=1e-5)
    np.testing.assert_allclose(f[5:-5, 2], G, atol=1e-12)
    # a steady yaw rate while rolled: body rates from Euler rates
    roll, r = 0.2, 0.3
    poses = np.zeros((n, 6))
    poses[:, 3] = roll
    poses[:, 5] = r * t
    _, w = simulator_motion(poses, fs)
    np.testing.assert_allclose(w[5:-5], [[0.0, math.sin(roll) * r, math.cos(roll) * r]] * (n - 10))


def test_perfect_cueing_scores_perfectly() -> None:
    fs = 200.0
    t = np.arange(4000) / fs
    poses = np.zeros((4000, 6))
    poses[:, 0] = 0.02 * np.sin(2.0 * t)
    poses[:, 3] = 0.05 * np.sin(1.3 * t)
    poses[:, 5] = 0.1 * np.sin(0.7 * t)
    f, w = simulator_motion(poses, fs)
    ev = evaluate_cueing(f, w, poses, fs, workspace=[0.1, 0.1, 0.1, 0.2, 0.2, 0.2])
    np.testing.assert_allclose(ev.rms_error, 0.0, atol=1e-12)
    for i in (0, 1, 2, 3, 5):
        assert ev.correlation[i] == pytest.approx(1.0)
        assert ev.delay_s[i] == 0.0
    assert ev.false_cue_count.sum() == 0
    np.testing.assert_allclose(ev.workspace_use, [0.2, 0.0, 0.0, 0.25, 0.0, 0.5], rtol=1e-3)


def test_delay_is_found_by_cross_correlation() -> None:
    fs, d = 100.0, 0.15
    t = np.arange(6000) / fs
    w = np.zeros((6000, 3))
    w[:, 2] = 0.4 * np.cos(2.0 * t) + 0.2 * np.cos(5.3 * t)
    poses = np.zeros((6000, 6))
    td = t - d  # the platform's yaw rate is the vehicle's, d seconds late
    poses[:, 5] = 0.2 * np.sin(2.0 * td) + 0.2 / 5.3 * np.sin(5.3 * td)
    f = np.tile([0.0, 0.0, G], (6000, 1))
    ev = evaluate_cueing(f, w, poses, fs)
    assert ev.delay_s[5] == pytest.approx(d, abs=1.01 / fs)
    # the delay itself decorrelates: cos(2 d) ~ 0.96 and cos(5.3 d) ~ 0.70, power weighted
    assert ev.correlation[5] > 0.8


def test_false_cue_counted_with_duration() -> None:
    fs = 100.0
    n = 3000
    t = np.arange(n) / fs
    on = (t >= 5.0) & (t < 8.0)
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[on, 0] = 1.0  # vehicle accelerates forward for 3 s
    # the platform pitches nose down instead, so the rider feels -0.5 x the vehicle's force
    poses = np.zeros((n, 6))
    poses[:, 4] = np.arcsin(0.5 * f[:, 0] / G)
    ev = evaluate_cueing(f, np.zeros((n, 3)), poses, fs)
    # the default model set's otolith (Telban & Cardullo 2005)
    perceived = MODEL_SETS[DEFAULT_MODEL_SET].otolith[0].apply(f[:, 0], fs)
    np.testing.assert_allclose(ev.perceived_sim[:, 0], -0.5 * perceived, atol=1e-12)
    # a false cue wherever |0.5 perceived| > 0.17: the onset and the undershoot after it
    mask = np.abs(0.5 * perceived) > 0.17
    edges = np.count_nonzero(mask[1:] & ~mask[:-1]) + int(mask[0])
    assert edges == 2
    assert ev.false_cue_count[0] == edges
    assert ev.false_cue_time_s[0] == pytest.approx(np.count_nonzero(mask) / fs)
    assert ev.false_cue_time_s[0] > 3.0
    assert ev.false_cue_count[[1, 2]].sum() == 0


def test_washout_run_evaluates_reasonably() -> None:
    """A sustained braking on the racing preset: the cue has the vehicle's sign."""
    fs = 100.0
    design = ClassicalWashout(load_cueing("racing"), fs_hz=fs)
    n = 2000
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[200:1200, 0] = -6.0
    res = design.run(f, np.zeros((n, 3)))
    ev = evaluate_cueing(res.f_used, res.w_used, res.poses, fs, workspace=design.params.workspace)
    assert ev.correlation[0] > 0.8
    assert np.all(np.isfinite(ev.workspace_use)) and ev.workspace_use.max() < 1.0
    assert ev.workspace_use[4] > 0.3
