"""The tilt's own gain on forward force (``[tilt] forward_ratio``, issue 20).

A race car stops at several times its throttle: with one tilt gain both ways the throttle's
nose-up tilt must be unwound at the tilt's rate limit when a stop starts, and while it is the
rider feels the throttle during the braking. ``forward_ratio = r`` gives a forward force
(``f_x > 0``) the gain ``r kt_x`` and a rearward one ``kt_x``. Oracles: the held tilt of a
sustained force in closed form (``pitch = -asin(kt f / g)`` linear, ``-asin(compress(f, kt,
L+, L-, p) / g)`` compressive, :func:`compress` against its own closed-form inverse), batch
against streaming, ``r = 1`` against the preset without the key, validation, TOML round trip.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing
from motioncue.cueing._filters import compress_inverse
from motioncue.cueing._tune import preset_toml

FS = 100.0
G = 9.80665


def _params(**kw: object) -> CueingParams:
    """The firm default with its rotational and translational cues off (the tilt alone)."""
    base = replace(
        load_cueing("racing-hexapod-firm"),
        f_scale=(0.0, 0.0, 0.0),
        w_scale=(0.0, 0.0, 0.0),
        tilt_lag_fill=0.0,
    )
    return replace(base, **kw)  # type: ignore[arg-type]


def _held_pitch(p: CueingParams, fx: float, n: int = 600) -> float:
    """The tilt's pitch (rad) after ``n / FS`` s of a sustained ``fx`` (m/s^2)."""
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[20:, 0] = fx
    res = ClassicalWashout(p, FS).run(f, np.zeros((n, 3)))
    pitch = res.tilt[:, 1]
    assert abs(pitch[-1] - pitch[-50]) < 1e-9  # settled (low-pass, lead and rate limit)
    return float(pitch[-1])


@pytest.mark.parametrize("ratio", [0.35, 1.0, 1.6])
@pytest.mark.parametrize("fx", [3.0, -3.0, 12.0, -25.0])
def test_compressive_tilt_holds_the_closed_form_with_its_own_forward_gain(
    ratio: float, fx: float
) -> None:
    """Compressive tilt: the held pitch ``-asin(y / g)`` with ``y`` the compressed force of
    gain ``r kt`` forward and ``kt`` rearward, checked through the closed-form inverse:
    ``compress_inverse(y, k) = fx``."""
    p = _params(tilt_forward_ratio=ratio)
    assert p.tilt_scale is not None and p.tilt_shape is not None
    pitch = _held_pitch(p, fx)
    y = -G * math.sin(pitch)  # the force the tilt renders
    assert np.sign(y) == np.sign(fx)
    k = p.tilt_scale[0] * (ratio if fx > 0.0 else 1.0)
    lxp, lxn, _, _ = p.tilt_force_limits_m_s2
    assert compress_inverse(y, k, lxp, lxn, p.tilt_shape) == pytest.approx(fx, rel=1e-7)


@pytest.mark.parametrize("ratio", [0.25, 2.0])
def test_linear_tilt_gain_is_r_kt_forward_and_kt_rearward(ratio: float) -> None:
    """Without ``tilt_shape``: ``pitch = -asin(r kt fx / g)`` forward, ``-asin(kt fx / g)``
    rearward (small forces, inside the soft limit's linear part)."""
    p = _params(
        tilt_forward_ratio=ratio,
        tilt_shape=None,
        tilt_limit_rad=math.radians(30.0),
        intensity_gentle=None,
    )
    assert p.tilt_scale is not None
    kt = p.tilt_scale[0]
    for fx, k in ((4.0, ratio * kt), (-4.0, kt)):
        assert _held_pitch(p, fx) == pytest.approx(-math.asin(k * fx / G), rel=1e-9)


def test_ratio_one_is_the_preset_without_the_key() -> None:
    from test_cueing_classical import random_drive

    p = load_cueing("racing-hexapod-firm")
    assert p.tilt_forward_ratio == 1.0
    f, w = random_drive(1500, seed=3)
    a = ClassicalWashout(p, FS).run(f, w).poses
    b = ClassicalWashout(replace(p, tilt_forward_ratio=0.5), FS).run(f, w).poses
    c = ClassicalWashout(replace(p, tilt_forward_ratio=1.0), FS).run(f, w).poses
    np.testing.assert_allclose(c, a, rtol=0, atol=1e-15)
    assert np.abs(b[:, 4] - a[:, 4]).max() > math.radians(0.5)  # the key does change the tilt


@pytest.mark.parametrize("shape", [True, False])
def test_forward_ratio_batch_equals_streaming(shape: bool) -> None:
    from test_cueing_classical import assert_batch_equals_streaming, random_drive

    p = replace(load_cueing("racing-hexapod-firm"), tilt_forward_ratio=0.45)
    if not shape:
        p = replace(p, tilt_shape=None, intensity_gentle=None)
    f, w = random_drive(2500, seed=7)
    assert_batch_equals_streaming(ClassicalWashout(p, FS), f, w)


@pytest.mark.parametrize("bad", [0.0, -0.5, 4.5, math.nan, math.inf])
def test_forward_ratio_out_of_range_is_rejected_with_value_and_range(bad: float) -> None:
    with pytest.raises(ConfigError, match=r"tilt_forward_ratio = .*each in \(0\.0, 4\.0\]"):
        _params(tilt_forward_ratio=bad)


def test_forward_ratio_needs_the_tilt_scale_and_round_trips(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"tilt_forward_ratio = 0\.5 needs tilt_scale"):
        replace(load_cueing("racing-hexapod"), tilt_scale=None, tilt_forward_ratio=0.5)
    path = tmp_path / "fwd.toml"
    path.write_text(preset_toml(_params(tilt_forward_ratio=0.37)))
    assert load_cueing(path).tilt_forward_ratio == pytest.approx(0.37, rel=1e-15)
    text = path.read_text().replace("forward_ratio = 0.37", "forward_ratio = 5")
    assert "forward_ratio = 5" in text
    path.write_text(text)
    with pytest.raises(ConfigError, match="forward_ratio"):
        load_cueing(path)
