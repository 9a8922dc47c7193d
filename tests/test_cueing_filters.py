"""Washout filters against the continuous transfer functions; limiter building blocks."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from motioncue.cueing import ClassicalWashout, load_cueing
from motioncue.cueing._filters import (
    rate_limit_array,
    rate_limit_step,
    soft_limit,
    soft_limit_array,
    tustin_section,
)

G = 9.80665
FREQS_HZ = (0.03, 0.11, 0.27, 0.6, 1.3, 2.9)


def multisine(fs: float, seconds: float, amp: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(int(seconds * fs)) / fs
    rng = np.random.default_rng(11)
    x = sum(
        amp * np.sin(2 * np.pi * f * t + p)
        for f, p in zip(FREQS_HZ, rng.uniform(0, 2 * np.pi, len(FREQS_HZ)), strict=True)
    )
    return t, np.asarray(x) / len(FREQS_HZ)


def rel_rms(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.sqrt(np.mean(b**2)))


def continuous(num: tuple[float, ...], den: tuple[float, ...], t: np.ndarray, u: np.ndarray):
    from scipy import signal

    _, y, _ = signal.lsim((num, den), u, t)
    return y


@pytest.mark.parametrize("fs", [100.0, 1000.0])
@pytest.mark.parametrize("preset", ["racing", "flight"])
def test_sections_match_continuous_transfer_functions(fs: float, preset: str) -> None:
    from scipy import signal

    design = ClassicalWashout(load_cueing(preset), fs_hz=fs)
    t, u = multisine(fs, 40.0)
    tfs = design.continuous()
    cases = [("tilt", tfs["tilt"][0], [design.tilt_lp])]
    cases += [(f"rot{i}", tfs["rot"][i], [design.rot[i]]) for i in range(3)]
    cases += [(f"trans{i}", tfs["trans"][i], list(design.trans[i])) for i in range(3)]
    for name, (num, den), secs in cases:
        y_d = signal.sosfilt(np.array(secs), u)
        y_c = continuous(num, den, t, u)
        assert rel_rms(y_d, y_c) < 0.01, name


@pytest.mark.parametrize("fs", [100.0, 1000.0])
def test_whole_washout_matches_continuous_model_in_linear_range(fs: float) -> None:
    """Small heave and yaw inputs: the washout is linear there (no limiting, T = I, R f = f)."""
    params = load_cueing("racing")
    design = ClassicalWashout(params, fs_hz=fs)
    t, u = multisine(fs, 40.0)
    n = len(t)
    f = np.tile([0.0, 0.0, G], (n, 1))
    w = np.zeros((n, 3))
    f[:, 2] += 1.0 * u
    w[:, 2] = 0.2 * u
    poses = design.run(f, w).poses
    tfs = design.continuous()
    z_c = continuous(*tfs["trans"][2], t, params.f_scale[2] * 1.0 * u)
    yaw_c = continuous(*tfs["rot"][2], t, params.w_scale[2] * 0.2 * u)
    assert rel_rms(poses[:, 2], z_c) < 0.01
    assert rel_rms(poses[:, 5], yaw_c) < 0.01
    # and the tilt channel with a force small enough for the rate limiter to stay idle
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[:, 0] = 0.05 * u
    pitch = design.run(f, np.zeros((n, 3))).poses[:, 4]
    lp = continuous(*tfs["tilt"][0], t, params.f_scale[0] * 0.05 * u)
    assert rel_rms(pitch, -np.arcsin(lp / G)) < 0.01


def test_tustin_prewarp_is_exact_at_the_warp_frequency() -> None:
    fs = 50.0
    for num, den, w0 in [
        ((1.0, 0.0, 0.0), (1.0, 2.0 * 0.7 * 6.0, 36.0), 6.0),
        ((1.0,), (1.0, 0.8), 0.8),
        ((1.0, 0.0), (1.0, 3.0, 9.0), 3.0),
    ]:
        b0, b1, b2, a0, a1, a2 = tustin_section(num, den, fs, w0)
        assert a0 == 1.0
        z = np.exp(-1j * w0 / fs)  # z^-1 on the unit circle at w0
        h_d = (b0 + b1 * z + b2 * z**2) / (1 + a1 * z + a2 * z**2)
        h_c = np.polyval(num, 1j * w0) / np.polyval(den, 1j * w0)
        assert abs(h_d - h_c) < 1e-10 * abs(h_c)
    with pytest.raises(ValueError, match="Nyquist"):
        tustin_section((1.0,), (1.0, 400.0), fs, 400.0)


@pytest.mark.parametrize("knee", [0.5, 0.7, 1.0])
def test_soft_limit_shape(knee: float) -> None:
    lim = 2.0
    x = np.linspace(-20, 20, 4001)
    y = soft_limit_array(x, lim, knee)
    np.testing.assert_allclose(y, [soft_limit(v, lim, knee) for v in x], rtol=0, atol=1e-15)
    assert np.abs(y).max() <= lim
    np.testing.assert_array_equal(y, -soft_limit_array(-x, lim, knee))  # odd
    assert (np.diff(y) >= 0).all()  # monotone
    inside = np.abs(x) <= knee * lim
    np.testing.assert_array_equal(y[inside], x[inside])
    if knee < 1.0:  # slope 1 on both sides of the knee (C1)
        a, h = knee * lim, 1e-6
        assert (soft_limit(a + h, lim, knee) - soft_limit(a, lim, knee)) / h == pytest.approx(
            1.0, abs=1e-5
        )
        assert soft_limit(1e300, lim, knee) == pytest.approx(lim)


def loop(x: np.ndarray, step: float, y0: float) -> np.ndarray:
    out, prev = [], y0
    for v in x.tolist():
        prev = rate_limit_step(v, prev, step)
        out.append(prev)
    return np.array(out)


@settings(max_examples=80)
@given(
    x=hnp.arrays(
        np.float64,
        st.integers(0, 400),
        elements=st.floats(-5, 5, allow_nan=False),
    ),
    step=st.floats(1e-4, 2.0),
    y0=st.floats(-5, 5),
    walk=st.booleans(),
)
def test_rate_limit_array_equals_loop(x: np.ndarray, step: float, y0: float, walk: bool) -> None:
    if walk:
        x = np.cumsum(x) * 0.1
    y = rate_limit_array(x, step, y0)
    np.testing.assert_allclose(y, loop(x, step, y0), rtol=0, atol=1e-12)
    if len(x):
        assert np.abs(np.diff(np.concatenate([[y0], y]))).max() <= step * (1 + 1e-12) + 1e-15


def test_rate_limit_long_ramps() -> None:
    x = np.concatenate([np.zeros(10), np.ones(50000), -np.ones(3), np.zeros(20000)])
    np.testing.assert_allclose(rate_limit_array(x, 1e-4, 0.0), loop(x, 1e-4, 0.0), atol=1e-12)


def test_rate_limit_choppy_then_calm() -> None:
    """Noise near the rate limit (scalar stretches), then smooth ramps (segments) again."""
    rng = np.random.default_rng(6)
    t = np.arange(20000)
    x = np.where(t < 8000, 1e-3 * t + rng.normal(0, 2e-3, t.size), np.sin(t * 1e-3))
    for step in (1e-3, 5e-4):
        np.testing.assert_allclose(rate_limit_array(x, step, 0.3), loop(x, step, 0.3), atol=1e-12)


@pytest.mark.parametrize("seed", range(5))
def test_tustin_section_equals_scipy_bilinear_with_the_prewarped_rate(seed: int) -> None:
    """The substitution is written out (importing scipy.signal costs ~0.9 s at every start):
    the section equals scipy.signal.bilinear's at fs' = K / 2, for random proper transfer
    functions of order 1 and 2 (numerators of every degree up to the order)."""
    from scipy.signal import bilinear

    rng = np.random.default_rng(seed)
    fs = float(rng.uniform(20.0, 1000.0))
    for order in (1, 2):
        for n_num in range(1, order + 2):
            den = (1.0, *rng.uniform(0.1, 20.0, order))
            num = tuple(rng.normal(size=n_num))
            w0 = float(rng.uniform(0.01, 0.9) * np.pi * fs)
            got = tustin_section(num, den, fs, w0)
            k = w0 / np.tan(w0 / (2.0 * fs))
            b, a = bilinear(np.trim_zeros(np.asarray(num), "f"), den, fs=k / 2.0)
            b = np.concatenate([b, np.zeros(3 - len(b))]) / a[0]
            a = np.concatenate([a, np.zeros(3 - len(a))]) / a[0]
            want = (b[0], b[1], b[2], 1.0, a[1], a[2])
            np.testing.assert_allclose(got, want, rtol=1e-11, atol=1e-12 * max(abs(b).max(), 1))
            got_2fs = tustin_section(num, den, fs, None)  # no prewarp: K = 2 fs
            b, a = bilinear(np.trim_zeros(np.asarray(num), "f"), den, fs=fs)
            b = np.concatenate([b, np.zeros(3 - len(b))]) / a[0]
            a = np.concatenate([a, np.zeros(3 - len(a))]) / a[0]
            np.testing.assert_allclose(got_2fs, (b[0], b[1], b[2], 1.0, a[1], a[2]),
                                       rtol=1e-11, atol=1e-12 * max(abs(b).max(), 1))  # fmt: skip
