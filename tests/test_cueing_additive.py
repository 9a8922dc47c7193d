"""The additive tilt of the classical washout (``[tilt] additive = true``, issue 20).

With the additive tilt the translational channel is fed the scaled force *plus* the tilt
coordination's own gravity in the platform frame, so it renders its own (high-passed)
cue on top of the tilt instead of driving against a tilt stronger than its target.
Oracles: exact cancellation when the translational force is zero (a closed form: the
attitude is the tilt, so ``R (R^T g) - g = 0``), batch against streaming, and the
classical design as the contrast (the same input moves its translation).
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing

G = 9.80665


def _additive(**kw: object) -> CueingParams:
    reach = tuple(math.radians(v) for v in (12.0, 11.0, 13.0, 10.0))
    base = replace(
        load_cueing("racing-hexapod"),
        f_shape=(2.0, 3.0, 1.5),
        f_limit_m_s2=(1.0, 1.2, 2.0),
        tilt_scale=(0.3, 0.4),
        tilt_shape=2.0,
        tilt_reach_rad=(reach[0], reach[1], reach[2], reach[3]),
        tilt_reach_use=0.8,
        tilt_rate_limit_rad_s=math.radians(20.0),
        lead_s=(0.15, 0.08),
        tilt_additive=True,
    )
    return replace(base, **kw)  # type: ignore[arg-type]


@pytest.mark.parametrize("head_mm", [(0.0, 0.0, 0.0), (80.0, -30.0, 650.0)])
def test_additive_washout_batch_equals_streaming(head_mm: tuple[float, float, float]) -> None:
    from test_cueing_classical import assert_batch_equals_streaming, random_drive

    p = _additive(head_offset_m=tuple(v * 1e-3 for v in head_mm))
    design = ClassicalWashout(p, fs_hz=100.0)
    f, w = random_drive(3000, seed=7)
    assert_batch_equals_streaming(design, f, w, 701)


def _cornering(n: int = 1500) -> tuple[np.ndarray, np.ndarray]:
    """A braking-then-cornering drive without rotation: 1.2 g back, then 1.5 g right."""
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[100:500, 0] = -12.0
    f[400:1200, 1] = -15.0  # rightward is -y (y points left)
    return f, np.zeros((n, 3))


def test_without_translational_force_the_additive_translation_stays_at_neutral() -> None:
    f, w = _cornering()
    p = _additive(f_scale=(0.0, 0.0, 0.0))
    res = ClassicalWashout(p, 100.0).run(f, w)
    tilt = np.abs(res.tilt).max(axis=0)
    assert tilt[0] > math.radians(5.0) and tilt[1] > math.radians(5.0)  # it does tilt
    # attitude = tilt and R (R^T g) - g = 0: nothing reaches the translational filters
    np.testing.assert_allclose(res.poses[:, :3], 0.0, rtol=0, atol=1e-12)
    # the classical (complementary) design: the translation drives against the same tilt
    classic = ClassicalWashout(replace(p, tilt_additive=False), 100.0).run(f, w)
    np.testing.assert_allclose(classic.tilt, res.tilt, rtol=0, atol=1e-15)
    assert np.abs(classic.poses[:, :2]).max() > 0.02  # tens of mm


def test_additive_translation_is_the_scaled_force_alone() -> None:
    """To first order the additive translation is the classical translation of the same
    preset without tilt (the tilt's gravity cancels whatever the tilt does)."""
    f, w = _cornering()
    f[:, :2] *= 0.05  # small: far from every compression bend, small angles
    p = _additive(f_shape=None, f_limit_m_s2=(50.0, 50.0, 50.0), tilt_shape=None,
                  tilt_reach_rad=None, tilt_limit_rad=math.radians(30.0))  # fmt: skip
    res = ClassicalWashout(p, 100.0).run(f, w)
    flat = replace(p, tilt_scale=(0.0, 0.0), tilt_additive=False)
    ref = ClassicalWashout(flat, 100.0).run(f, w)
    assert np.abs(ref.poses[:, :2]).max() > 1e-3
    assert np.abs(res.tilt).max() > math.radians(0.5)
    # differences are second order in the angles (a 1-2 deg tilt: below 1 %)
    np.testing.assert_allclose(res.poses[:, :2], ref.poses[:, :2], rtol=0,
                               atol=0.01 * np.abs(ref.poses[:, :2]).max())  # fmt: skip


def test_additive_key_is_read_and_needs_the_tilts_own_scale(tmp_path: Path) -> None:
    src = Path(__file__).resolve().parents[1] / "configs" / "cueing" / "racing-hexapod.toml"
    text = src.read_text()
    assert load_cueing(src).tilt_additive is False
    ok = tmp_path / "add.toml"
    ok.write_text(text.replace("[tilt]\n", "[tilt]\nadditive = true\n"))
    assert load_cueing(ok).tilt_additive is True
    bad = tmp_path / "bad.toml"
    no_scale = "\n".join(ln for ln in text.splitlines() if not ln.startswith("scale = "))
    bad.write_text(no_scale.replace("[tilt]\n", "[tilt]\nadditive = true\n"))
    with pytest.raises(ConfigError, match="tilt_additive"):
        load_cueing(bad)
    typo = tmp_path / "typo.toml"
    typo.write_text(text.replace("[tilt]\n", '[tilt]\nadditive = "yes"\n'))
    with pytest.raises(ConfigError, match="additive"):
        load_cueing(typo)


def test_a_tuned_preset_keeps_the_additive_tilt(tmp_path: Path) -> None:
    from motioncue.cueing._tune import preset_toml

    p = _additive()
    out = tmp_path / "tuned.toml"
    out.write_text(preset_toml(p))
    back = load_cueing(out)
    assert back.tilt_additive is True
    f, w = _cornering()
    got = ClassicalWashout(back, 100.0).run(f, w).poses
    np.testing.assert_allclose(got, ClassicalWashout(p, 100.0).run(f, w).poses, rtol=0, atol=1e-9)
    assert "additive" not in preset_toml(replace(p, tilt_additive=False))
