"""Classical washout: the tilt gain that adapts to the drive (``tilt_adapt_peak_m_s2``).

Oracles: a fixed-gain washout (under a sustained force the adaptive gain is the closed form
``c / F``, so the adaptive run equals the fixed run with ``tilt_scale = c / F``); the
envelope's closed form after a peak (``e = P d^k``, ``d = exp(-1 / (fs tau))``); the
streaming ``step`` against the batch ``run`` and blocks of it; a ``c`` no force reaches
changes nothing; the preset file round trip; bad values refused with the key named.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing
from motioncue.cueing._classical import _adapt_gain
from motioncue.cueing._tune import preset_toml

G = 9.80665
FS = 100.0


def _firm(**kw: object) -> CueingParams:
    """The bundled default with the tilt's own gains raised (the adaptive gain lowers them)."""
    p = load_cueing("racing-hexapod-firm")
    base: dict[str, object] = dict(tilt_scale=(0.5, 0.4), intensity_gentle=None)
    base.update(kw)
    return dataclasses.replace(p, **base)  # type: ignore[arg-type]


def _drive(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    box = np.ones(40) / 40
    f = np.zeros((n, 3))
    f[:, 0] = np.convolve(rng.normal(0, 9, n), box, "same") + 6 * np.sign(
        np.sin(np.arange(n) / 170.0)
    )
    f[:, 1] = np.convolve(rng.normal(0, 9, n), box, "same")
    f[:, 2] = G + np.convolve(rng.normal(0, 2, n), box, "same")
    w = np.convolve(rng.normal(0, 0.3, 3 * n), np.ones(25) / 25, "same").reshape(n, 3)
    f[7, 0] = np.nan  # held: the envelope sees the held sample, in both paths
    return f, w


def test_step_equals_run_and_blocks() -> None:
    p = _firm(tilt_adapt_peak_m_s2=(1.1, 0.9), tilt_adapt_tau_s=12.0)
    design = ClassicalWashout(p, fs_hz=FS)
    f, w = _drive(4000, 3)
    res = design.run(f, w)
    state = design.initial_state()
    out = [0.0] * 6
    pairs = zip(f.tolist(), w.tolist(), strict=True)
    rows = np.array([list(design.step(state, a, b, out)) for a, b in pairs])
    # round-off only (the two paths order a few sums differently)
    np.testing.assert_allclose(rows, res.poses, rtol=1e-10, atol=1e-12)
    again = design.initial_state()
    parts = [design.run(f[a : a + 613], w[a : a + 613], again).poses for a in range(0, 4000, 613)]
    np.testing.assert_allclose(np.concatenate(parts), res.poses, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(again.tilt_env, state.tilt_env, rtol=1e-12, atol=0.0)
    # and it did adapt: the envelope holds the drive's peaks, above c / kt on both axes
    assert again.tilt_env[0] * 0.5 > 1.1 and again.tilt_env[1] * 0.4 > 0.9


def test_a_level_no_force_reaches_changes_nothing() -> None:
    f, w = _drive(3000, 5)
    kt = 0.5
    peak = float(np.nanmax(np.abs(f[:, :2])))
    on = ClassicalWashout(_firm(tilt_adapt_peak_m_s2=(kt * peak * 1.01, 50.0)), fs_hz=FS)
    off = ClassicalWashout(_firm(), fs_hz=FS)
    np.testing.assert_array_equal(on.run(f, w).poses, off.run(f, w).poses)


@pytest.mark.parametrize("force", [-8.0, 5.0, 12.0])
def test_a_sustained_force_gets_the_gain_c_over_f(force: float) -> None:
    """From its first sample a constant force is its own envelope (started at 0), so the gain
    is c / |F|: the run equals the fixed-gain washout with that gain (forward ratio
    included)."""
    c = 1.2
    n = 600
    f = np.zeros((n, 3))
    f[:, 0] = force
    f[:, 1] = -0.6 * force
    f[:, 2] = G
    w = np.zeros((n, 3))
    adaptive = _firm(tilt_adapt_peak_m_s2=(c, c), tilt_forward_ratio=0.6, tilt_adapt_start_m_s2=0)
    fixed = _firm(tilt_scale=(c / abs(force), c / abs(0.6 * force)), tilt_forward_ratio=0.6)
    got = ClassicalWashout(adaptive, fs_hz=FS).run(f, w)
    want = ClassicalWashout(fixed, fs_hz=FS).run(f, w)
    np.testing.assert_allclose(got.poses, want.poses, rtol=1e-9, atol=1e-12)
    assert np.abs(got.tilt[-1]).max() > 0.01  # a tilt that is there to compare


def test_after_a_peak_the_gain_recovers_as_the_closed_form() -> None:
    tau, c, kt, peak = 2.0, 1.0, 0.4, 9.0
    n = 1500
    f = np.zeros(n)
    f[100] = peak
    f[101:] = 0.5  # small: below the decaying envelope throughout
    env = [0.0, 0.0]
    got = _adapt_gain(f, c, kt, tau, FS, env, 0)
    d = math.exp(-1.0 / (FS * tau))
    k = np.arange(n) - 100
    e = np.where(k >= 0, peak * d ** np.maximum(k, 0), 0.0)
    e = np.maximum(e, np.where(k > 0, 0.5, 0.0))
    want = np.where(kt * e > c, c / np.maximum(kt * e, 1e-300), 1.0)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0.0)
    # the gain is back to kt once the peak has decayed to c / kt: tau ln(kt P / c) later
    back = 100 + math.ceil(FS * tau * math.log(kt * peak / c))
    assert got[back - 2] < 1.0 and np.all(got[back + 1 :] == 1.0)
    assert env[0] == pytest.approx(max(0.5, peak * d ** (n - 101)), rel=1e-12)


@pytest.mark.parametrize("start", [0.0, 9.80665, 25.0])
def test_the_envelope_starts_at_its_prior_and_decays(start: float) -> None:
    p = _firm(tilt_adapt_peak_m_s2=(1.0, 1.0), tilt_adapt_tau_s=4.0, tilt_adapt_start_m_s2=start)
    design = ClassicalWashout(p, fs_hz=FS)
    state = design.initial_state()
    assert state.tilt_env == [start, start]
    n = 250
    f = np.zeros((n, 3))
    f[:, 2] = G
    design.run(f, np.zeros((n, 3)), state)
    want = start * math.exp(-1.0 / (FS * 4.0)) ** n
    np.testing.assert_allclose(state.tilt_env, [want, want], rtol=1e-12, atol=0.0)
    design.reset(state)
    assert state.tilt_env == [start, start]
    # without the adaptive gain the envelope is not used and stays 0
    assert ClassicalWashout(_firm(), fs_hz=FS).initial_state().tilt_env == [0.0, 0.0]


def test_preset_file_round_trip(tmp_path) -> None:
    p = _firm(tilt_adapt_peak_m_s2=(1.05, 0.0), tilt_adapt_tau_s=13.7, tilt_adapt_start_m_s2=21.5)
    path = tmp_path / "adaptive.toml"
    path.write_text(preset_toml(p))
    back = load_cueing(path)
    assert back.tilt_adapt_peak_m_s2 == pytest.approx(p.tilt_adapt_peak_m_s2, rel=1e-12)
    assert back.tilt_adapt_tau_s == pytest.approx(13.7, rel=1e-12)
    assert back.tilt_adapt_start_m_s2 == pytest.approx(21.5, rel=1e-12)


@pytest.mark.parametrize(
    ("kw", "needle"),
    [
        (dict(tilt_adapt_peak_m_s2=(-1.0, 1.0)), "tilt_adapt_peak_m_s2"),
        (dict(tilt_adapt_peak_m_s2=(1.0, math.nan)), "tilt_adapt_peak_m_s2"),
        (dict(tilt_adapt_peak_m_s2=(1.0,)), "two numbers"),
        (dict(tilt_adapt_tau_s=0.0), "tilt_adapt_tau_s"),
        (dict(tilt_adapt_start_m_s2=-1.0), "tilt_adapt_start_m_s2"),
        (
            dict(
                tilt_adapt_peak_m_s2=(1.0, 1.0),
                tilt_scale=None,
                tilt_shape=None,
                tilt_additive=False,
                tilt_lag_fill=0.0,
            ),
            "adapt_peak.*needs tilt_scale",
        ),
    ],
)
def test_bad_values_are_refused_with_the_key(kw: dict[str, object], needle: str) -> None:
    with pytest.raises(ConfigError, match=needle):
        _firm(**kw)
