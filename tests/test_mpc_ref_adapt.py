"""The plans' reference gain that adapts to the drive (``[mpc] ref_adapt_*``, issue 20 item 7):
the tracked fx / fy copy's gain is ``min(ref_scale, c / e)``, ``e`` the classical washout's
causal envelope of the vehicle's force peaks."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import CueingParams, load_cueing
from motioncue.cueing._mpc import MpcCueing, initial_ref_env, reference
from motioncue.cueing._mpc_params import MpcParams

FS = 100.0
ROOT = Path(__file__).resolve().parents[1]
REC = ROOT / "configs" / "recordings" / "chicane-gt.csv"

# streaming against batch: the same arithmetic but numpy's power on a scalar or an array,
# which differ by round-off (ulps, CPU dependent); references are O(1) m/s^2
RTOL_ROUNDOFF, ATOL_ROUNDOFF = 1e-12, 1e-13


def _drive(start: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    a = np.loadtxt(REC, delimiter=",", skiprows=1, max_rows=start + n)[start:]
    return a[:, 1:4].copy(), a[:, 4:7].copy()


def _vehicle(n: int, seed: int) -> np.ndarray:
    """A vehicle motion ``[f - g, w]`` with fx / fy peaks of a few m/s^2 and a few large."""
    rng = np.random.default_rng(seed)
    d = rng.normal(scale=3.0, size=(n, 6))
    d[::97, 0] *= 6.0  # some hard stops ...
    d[::131, 1] *= 5.0  # ... and sharp corners
    return d


def _mp(**kw: object) -> MpcParams:
    base = MpcParams(
        ref_scale=(0.3, 0.5, 0.0, 1.0, 1.0, 1.0),
        ref_limit=(1.7, 2.0, 1e9, 1e9, 1e9, 1e9),
        ref_limit_neg=(1.2, 2.5, 1e9, 1e9, 1e9, 1e9),
        ref_shape=3.0,
        w_vehicle=(0.3, 0.45, 0.0, 0.0, 0.0, 0.0),
    )
    return dataclasses.replace(base, **kw)  # type: ignore[arg-type]


# ---------------------------------------------------------------------- the reference
def test_unset_is_the_fixed_reference_bit_for_bit() -> None:
    d = _vehicle(800, 1)
    mp = _mp()
    assert mp.ref_adapt_peak_m_s2 is None and initial_ref_env(mp) is None
    r0, _ = reference(d, mp, FS)
    env = [5.0, 5.0]  # an envelope handed to a fixed gain is neither used nor touched
    r1, _ = reference(d, mp, FS, None, env)
    np.testing.assert_array_equal(r1, r0)
    assert env == [5.0, 5.0]
    for name in ("mpc-hexapod", "optimal-hexapod"):  # these shipped plans have no such keys
        p = load_cueing(name).mpc
        assert p is not None and p.ref_adapt_peak_m_s2 is None
    q = load_cueing("optimal-hexapod-auto").mpc  # the one that adapts
    assert q is not None and q.ref_adapt_peak_m_s2 == (2.0, 0.0)


def test_a_level_no_force_reaches_changes_nothing() -> None:
    d = _vehicle(800, 2)
    peak = float(np.abs(d[:, :2]).max())
    mp = _mp()
    # c / e > k everywhere: e <= max(start, peak), so c = k (max + 1) is never reached
    c = (0.3 * (peak + 1.0), 0.5 * (peak + 1.0))
    ad = dataclasses.replace(mp, ref_adapt_peak_m_s2=c, ref_adapt_start_m_s2=peak)
    env = initial_ref_env(ad)
    r, _ = reference(d, ad, FS, None, env)
    np.testing.assert_array_equal(r, reference(d, mp, FS)[0])
    assert env is not None and max(env) <= peak  # the envelope never above the largest force
    # one axis off (c = 0): that axis stays fixed, the other one adapts
    half = dataclasses.replace(mp, ref_adapt_peak_m_s2=(0.0, 1.0))
    rh, _ = reference(d, half, FS)
    np.testing.assert_array_equal(rh[:, 0], reference(d, mp, FS)[0][:, 0])
    assert np.abs(rh[:, 1]).max() < np.abs(reference(d, mp, FS)[0][:, 1]).max()


@pytest.mark.parametrize("force", [6.0, -9.0, 25.0])
def test_under_a_sustained_force_the_gain_is_c_over_f(force: float) -> None:
    n = 300
    d = np.zeros((n, 6))
    d[:, 0] = force
    d[:, 1] = -0.5 * force
    c = (1.2, 0.9)
    mp = _mp(ref_adapt_peak_m_s2=c, ref_adapt_start_m_s2=0.0, ref_adapt_tau_s=5.0)
    r, _ = reference(d, mp, FS)
    # from the first sample e = |F|: the gain is min(k, c / |F|); the compressive curve
    # written out, k' d / (1 + |k' d / L|^p)^(1/p), then the blend toward the vehicle
    axes = ((0.3, 1.7, 1.2, 0.3, 1.0), (0.5, 2.0, 2.5, 0.45, 1.0))  # k, L+, L-, wv, we
    for i, (k, lp, ln, wv, we) in enumerate(axes):
        f = d[0, i]
        gain = min(k, c[i] / abs(f))
        y = gain * f
        lim = lp if y > 0 else ln
        curve = y / (1.0 + abs(y / lim) ** 3.0) ** (1.0 / 3.0)
        want = curve + wv / (we + wv) * (f - curve)
        np.testing.assert_allclose(r[:, i], want, rtol=1e-12, atol=0.0)
    # and the same as the fixed-gain reference with ref_scale = c / |F| where that is lower
    k_fixed = [min(0.3, c[0] / abs(force)), min(0.5, c[1] / abs(0.5 * force)), 0.0, 1.0, 1.0, 1.0]
    fixed = _mp(ref_scale=tuple(k_fixed))
    np.testing.assert_allclose(r, reference(d, fixed, FS)[0], rtol=1e-12, atol=1e-15)


def test_after_a_peak_the_envelope_decays_with_tau() -> None:
    n, tau, peak, level = 1500, 4.0, 30.0, 2.0
    d = np.zeros((n, 6))
    d[:, 0] = level
    d[0, 0] = peak
    c, k = 1.5, 1.0  # c / level < k: the gain settles at c / level
    mp = MpcParams(  # linear copy: r = gain d exactly
        ref_scale=(k, 1.0, 0.0, 0.0, 0.0, 0.0),
        ref_adapt_peak_m_s2=(c, 0.0),
        ref_adapt_tau_s=tau,
        ref_adapt_start_m_s2=0.0,
    )
    env = initial_ref_env(mp)
    r, _ = reference(d, mp, FS, None, env)
    t = np.arange(n) / FS
    e = np.maximum(level, peak * np.exp(-t / tau))  # closed form of the envelope
    gain = np.minimum(k, c / e)
    np.testing.assert_allclose(r[:, 0], gain * d[:, 0], rtol=1e-9, atol=0.0)
    # the gain recovers to c / level once the peak has decayed to the level
    t_meet = tau * math.log(peak / level)
    assert r[int(t_meet * FS) + 2, 0] == pytest.approx(c, rel=1e-9)  # c / level * level
    assert r[int(t_meet * FS) - 50, 0] < 0.9 * c
    assert env is not None and env[0] == pytest.approx(level, rel=1e-12)


def test_the_reference_streams_like_the_batch() -> None:
    d = _vehicle(600, 4)
    for split in (0.0, 0.5):
        mp = _mp(
            ref_adapt_peak_m_s2=(2.0, 1.5),
            ref_adapt_tau_s=1.5,
            ref_adapt_start_m_s2=12.0,
            ref_split_hz=split,
            ref_scale_hf=(0.5, 0.5, 0.0, 0.0, 0.0, 0.0),
        )
        batch_env = initial_ref_env(mp)
        batch, lp_b = reference(d, mp, FS, None, batch_env)
        env = initial_ref_env(mp)
        lp = None
        rows = []
        for k in range(d.shape[0]):
            rk, lp = reference(d[k], mp, FS, lp, env)
            rows.append(rk)
        # the envelope is a loop on floats: exactly the batch's; the curve's numpy power
        # differs by an ulp between one sample and an array (so does the fixed reference's,
        # 22 of 3600 numbers on the machine that wrote this): round-off only, and how many
        # ulps depends on the CPU's numpy kernels, so the tolerance is round-off's (1e-12
        # relative), not one machine's ulp count; a gain off by 1e-9 would still fail it
        assert env == batch_env
        np.testing.assert_allclose(np.array(rows), batch, rtol=RTOL_ROUNDOFF, atol=ATOL_ROUNDOFF)
        np.testing.assert_array_equal(lp, lp_b)
        fixed, _ = reference(d, dataclasses.replace(mp, ref_adapt_peak_m_s2=None), FS)
        assert not np.array_equal(batch[:, :2], fixed[:, :2])  # it did adapt


def _adapting(preset: str, **mp: object) -> CueingParams:
    """A bundled plan with its ``[mpc]`` table changed by ``mp``."""
    base = load_cueing(preset)
    assert base.mpc is not None
    return dataclasses.replace(base, mpc=dataclasses.replace(base.mpc, **mp))  # type: ignore[arg-type]


def test_the_mpc_plan_keeps_the_envelope_in_its_state_and_resets_it() -> None:
    params = _adapting(
        "mpc-hexapod", ref_scale=(0.2, 0.3, 1.0, 1.0, 1.0, 1.0), ref_adapt_peak_m_s2=(2.0, 2.5),
        ref_adapt_tau_s=2.0, ref_adapt_start_m_s2=20.0, deadline_ms=1e6,
    )  # fmt: skip
    design = MpcCueing(params, FS)
    f, w = _drive(900, 150)
    state = design.initial_state()
    assert state.ref_env == [20.0, 20.0]
    stream = np.array([design.step(state, fk, wk) for fk, wk in zip(f, w, strict=True)])
    # the envelope after the run is the batch reference's over the held vehicle force
    dv = np.hstack([f, w])
    dv[:, 2] -= 9.80665
    env = initial_ref_env(design.mpc)
    reference(dv, design.mpc, FS, None, env)
    assert state.ref_env == env and env != [20.0, 20.0]
    np.testing.assert_array_equal(design.run(f, w).poses, stream)
    design.reset(state)
    assert state.ref_env == [20.0, 20.0]
    again = np.array([design.step(state, fk, wk) for fk, wk in zip(f, w, strict=True)])
    np.testing.assert_array_equal(again, stream)
    fixed = MpcCueing(
        dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, ref_adapt_peak_m_s2=None)),
        FS,
    )
    assert fixed.initial_state().ref_env is None
    assert not np.array_equal(fixed.run(f, w).poses, stream)


def test_the_optimal_plan_tracks_the_reference_the_streaming_plan_would(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from motioncue.cueing import _optimal
    from motioncue.cueing._optimal import OptimalCueing

    params = _adapting(
        "optimal-hexapod", ref_scale=(0.2, 0.6, 0.0, 0.0, 0.0, 0.0), ref_adapt_peak_m_s2=(2.4, 3.0),
        ref_adapt_tau_s=2.0, ref_adapt_start_m_s2=20.0,
    )  # fmt: skip
    seen: list[np.ndarray] = []

    def spy(d, mp, fs_hz, lp=None, env=None):  # type: ignore[no-untyped-def]
        out = reference(d, mp, fs_hz, lp, env)
        seen.append(out[0])
        return out

    monkeypatch.setattr(_optimal, "reference", spy)
    design = OptimalCueing(params, FS)
    f, w = _drive(900, 300)
    res = design.run(f, w)
    assert seen and res.fallbacks == 0
    dv = np.hstack([res.f_used, res.w_used])
    dv[:, 2] -= 9.80665
    env = initial_ref_env(design.mpc)  # the streaming plan's reference, sample by sample
    stream = np.array([reference(dv[k], design.mpc, FS, None, env)[0] for k in range(len(dv))])
    for r in seen:  # round-off as in the streaming test above
        np.testing.assert_allclose(r, stream, rtol=RTOL_ROUNDOFF, atol=ATOL_ROUNDOFF)
    fixed, _ = reference(dv, dataclasses.replace(design.mpc, ref_adapt_peak_m_s2=None), FS)
    assert not np.allclose(stream[:, 0], fixed[:, 0])


# ---------------------------------------------------------------------- settings
@pytest.mark.parametrize(
    ("kw", "msg"),
    [
        ({"ref_adapt_peak_m_s2": (1.0,)}, r"ref_adapt_peak_m_s2 = \(1.0,\) is invalid; allowed"),
        ({"ref_adapt_peak_m_s2": (-0.1, 1.0)}, r"ref_adapt_peak_m_s2 = .* allowed: .*\[0, 50\]"),
        ({"ref_adapt_peak_m_s2": (1.0, 60.0)}, r"ref_adapt_peak_m_s2 = .* allowed: .*\[0, 50\]"),
        ({"ref_adapt_peak_m_s2": (math.nan, 1.0)}, r"ref_adapt_peak_m_s2 = .* allowed"),
        ({"ref_adapt_tau_s": 0.05}, r"ref_adapt_tau_s = 0.05 is invalid; allowed: \[0.1, 3600.0\]"),
        ({"ref_adapt_tau_s": math.inf}, r"ref_adapt_tau_s = inf is invalid"),
        ({"ref_adapt_start_m_s2": -1.0}, r"ref_adapt_start_m_s2 = -1.0 .* \[0.0, 100.0\]"),
        ({"ref_adapt_start_m_s2": 101.0}, r"ref_adapt_start_m_s2 = 101.0 .* \[0.0, 100.0\]"),
    ],
)
def test_bad_values_are_refused_with_the_key_named(kw: dict[str, object], msg: str) -> None:
    with pytest.raises(ConfigError, match=msg):
        MpcParams(**kw)  # type: ignore[arg-type]


def test_the_keys_load_from_toml_and_the_preset_writer_round_trips(tmp_path: Path) -> None:
    from motioncue.cueing._tune import preset_toml

    text = (ROOT / "configs" / "cueing" / "optimal-hexapod.toml").read_text()
    src = "\n".join(ln for ln in text.splitlines() if not ln.startswith("ref_adapt_")) + "\n"
    keys = "ref_adapt_peak_m_s2 = [2.0, 0.5]\nref_adapt_tau_s = 18.0\nref_adapt_start_m_s2 = 22.0"
    path = tmp_path / "adapt.toml"
    path.write_text(src.replace("[mpc]\n", "[mpc]\n" + keys + "\n"))
    p = load_cueing(path)
    assert p.mpc is not None
    assert p.mpc.ref_adapt_peak_m_s2 == (2.0, 0.5)
    assert (p.mpc.ref_adapt_tau_s, p.mpc.ref_adapt_start_m_s2) == (18.0, 22.0)
    out = tmp_path / "written.toml"
    out.write_text(preset_toml(p, ["round trip"]))
    assert "ref_adapt_peak_m_s2 = [2.0, 0.5]" in out.read_text()
    back = load_cueing(out)
    assert back.mpc == p.mpc
    # unset: the writer adds no such key
    plain = load_cueing("mpc-hexapod")
    assert "ref_adapt" not in preset_toml(plain, ["x"])
    bad = tmp_path / "bad.toml"
    bad.write_text(src.replace("[mpc]\n", "[mpc]\nref_adapt_tau_s = 0.01\n"))
    with pytest.raises(ConfigError, match="ref_adapt_tau_s"):
        load_cueing(bad)
