"""The compressive scaling of the classical washout (issue 20, Build item 3).

The curve against its closed form and its inverse, its shape (odd, monotone, continuous
slope, bounded), the washout with every compressive key on (streaming = batch, the steady
tilt of a sustained force against the closed form, per direction of the platform's reach),
old presets unchanged, and the platform's tilt reach against a brute-force check.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.analysis._tune import tilt_reach
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing
from motioncue.cueing._filters import compress, compress_array, compress_inverse
from motioncue.kinematics import load_platform
from motioncue.trajectory import reachable

G = 9.80665


def _closed(x: np.ndarray, k: float, lp: float, ln: float, p: float) -> np.ndarray:
    lim = np.where(x > 0, lp, ln)
    return k * x / (1.0 + np.abs(k * x / lim) ** p) ** (1.0 / p)


@pytest.mark.parametrize(("k", "lp", "ln", "p"), [(1.0, 2.0, 2.0, 2.0), (0.3, 1.5, 0.7, 1.0),
                                                  (2.0, 0.5, 0.5, 6.0)])  # fmt: skip
def test_curve_matches_its_closed_form_and_inverse(
    k: float, lp: float, ln: float, p: float
) -> None:
    x = np.linspace(-40.0, 40.0, 2001)
    y = compress_array(x, k, lp, ln, p)
    np.testing.assert_allclose(y, _closed(x, k, lp, ln, p), rtol=1e-14, atol=1e-15)
    scalar = np.array([compress(v, k, lp, ln, p) for v in x.tolist()])
    np.testing.assert_allclose(scalar, y, rtol=1e-15, atol=0.0)
    # the closed-form inverse gives the input back (where the curve is not yet flat: near
    # the limit a rounding of y is a large change of x)
    cond = np.abs(y) < 0.95 * np.where(y > 0, lp, ln)
    back = np.array([compress_inverse(v, k, lp, ln, p) for v in y[cond].tolist()])
    np.testing.assert_allclose(back, x[cond], rtol=1e-9, atol=1e-12)


def test_curve_is_odd_monotone_bounded_with_a_continuous_slope() -> None:
    k, lim, p = 0.8, 1.2, 2.5
    x = np.linspace(-30.0, 30.0, 60001)
    y = compress_array(x, k, lim, lim, p)
    np.testing.assert_allclose(compress_array(-x, k, lim, lim, p), -y, rtol=0, atol=1e-15)
    assert np.all(np.diff(y) > 0.0)
    assert np.all(np.abs(y) < lim)
    assert abs(compress(1e6, k, lim, lim, p) - lim) < 1e-6 * lim
    # slope: finite differences against the analytic k (1 + |kx/L|^p)^(-1/p - 1)
    h = x[1] - x[0]
    slope = np.gradient(y, h)
    analytic = k * (1.0 + np.abs(k * x / lim) ** p) ** (-1.0 / p - 1.0)
    np.testing.assert_allclose(slope[1:-1], analytic[1:-1], atol=2e-6)
    # continuous: no jump anywhere, and gain k at zero from both sides
    assert np.max(np.abs(np.diff(slope))) < 1e-3
    assert compress(1e-9, k, lim, 0.3, p) / 1e-9 == pytest.approx(k, rel=1e-9)
    assert compress(-1e-9, k, lim, 0.3, p) / -1e-9 == pytest.approx(k, rel=1e-9)
    # small cues pass nearly whole: within 1 % of k x below 0.2 L / k (p = 2.5)
    small = np.abs(k * x) < 0.2 * lim
    assert np.all(np.abs(y[small] - k * x[small]) <= 0.01 * np.abs(k * x[small]) + 1e-15)


def _compressive(base: CueingParams) -> CueingParams:
    reach = tuple(math.radians(v) for v in (12.0, 11.0, 13.0, 10.0))
    return replace(
        base,
        f_shape=(2.0, 3.0, 1.5),
        w_shape=(2.0, 2.0, 4.0),
        f_limit_m_s2=(1.0, 1.2, 2.0),
        tilt_scale=(0.4, 0.5),
        tilt_shape=2.0,
        tilt_reach_rad=(reach[0], reach[1], reach[2], reach[3]),
        tilt_reach_use=0.8,
        tilt_rate_limit_rad_s=math.radians(20.0),
        lead_s=(0.15, 0.08),
    )


@pytest.mark.parametrize("fs", [100.0, 1000.0])
def test_compressive_washout_batch_equals_streaming(fs: float) -> None:
    from test_cueing_classical import assert_batch_equals_streaming, random_drive

    design = ClassicalWashout(_compressive(load_cueing("racing-hexapod")), fs_hz=fs)
    f, w = random_drive(4000, seed=int(fs) + 1)
    assert_batch_equals_streaming(design, f, w, 777)


@pytest.mark.parametrize(("axis", "sign"), [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)])
def test_sustained_force_tilts_to_the_compressed_angle_of_its_direction(
    axis: int, sign: float
) -> None:
    p = _compressive(load_cueing("racing-hexapod"))
    p = replace(p, tilt_accel_limit_rad_s2=None, w_scale=(0.0, 0.0, 0.0))
    fs = 100.0
    n = 3000
    f = np.tile([0.0, 0.0, G], (n, 1))
    force = sign * 25.0  # 2.5 g: far into the compression
    f[100:, axis] = force
    res = ClassicalWashout(p, fs).run(f, np.zeros((n, 3)))
    rn, rp, pn, pp = p.tilt_limits_rad
    assert p.tilt_scale is not None and p.tilt_shape is not None
    if axis == 0:  # forward force: nose up (pitch < 0), reach pitch-; backward: pitch+
        lim = G * math.sin(pn if sign > 0 else pp)
        want = -math.asin(compress(force, p.tilt_scale[0], lim, lim, p.tilt_shape) / G)
        got = res.tilt[-1, 1]
        bound = pn if sign > 0 else pp
    else:  # rightward force: roll+, reach roll+; leftward: roll-
        lim = G * math.sin(rp if sign > 0 else rn)
        want = math.asin(compress(force, p.tilt_scale[1], lim, lim, p.tilt_shape) / G)
        got = res.tilt[-1, 0]
        bound = rp if sign > 0 else rn
    assert got == pytest.approx(want, abs=1e-9)
    assert abs(got) < bound
    assert abs(got) > 0.8 * bound  # 2.5 g uses most of what this direction allows
    # never beyond the reach of its direction, on the way either
    tilt = res.tilt[:, 1 if axis == 0 else 0]
    assert np.all(np.abs(tilt) <= bound + 1e-12)


def test_old_presets_read_the_same_and_bad_keys_are_refused() -> None:
    p = load_cueing("racing")
    assert p.f_shape is None and p.w_shape is None and p.tilt_shape is None
    with pytest.raises(ConfigError, match="tilt_shape"):
        replace(p, tilt_shape=2.0, tilt_reach_rad=None)
    with pytest.raises(ConfigError, match="f_shape"):
        replace(p, f_shape=(0.5, 2.0, 2.0))
    with pytest.raises(ConfigError, match="tilt_reach_use"):
        replace(p, tilt_reach_use=1.5)


def test_tilt_reach_is_the_last_reachable_pure_tilt() -> None:
    platform = load_platform("stewart6-linear")
    reach = tilt_reach(platform)
    for i, (axis, sign) in enumerate([(3, -1.0), (3, 1.0), (4, -1.0), (4, 1.0)]):
        assert math.radians(5.0) < reach[i] < math.radians(30.0)
        angles = np.linspace(0.0, reach[i], 50)
        poses = np.zeros((50, 6))
        poses[:, axis] = sign * angles
        assert reachable(platform, poses).all()
        beyond = np.zeros((1, 6))
        beyond[0, axis] = sign * (reach[i] + math.radians(0.011))
        assert not reachable(platform, beyond).any()
    # the hexapod is mirror-symmetric about its x-z plane: roll reach alike both ways
    assert reach[0] == pytest.approx(reach[1], abs=math.radians(0.011))


def test_lead_section_matches_the_continuous_lead_at_its_prewarp_frequency() -> None:
    from scipy.signal import sosfreqz

    from motioncue.cueing._params import LEAD_GAIN

    p = _compressive(load_cueing("racing-hexapod"))
    fs = 100.0
    design = ClassicalWashout(p, fs)
    assert p.lead_s is not None
    for tau, sec in zip(p.lead_s, design.lead, strict=True):
        w = 1.0 / tau
        _, h = sosfreqz(np.array([sec]), worN=[w / (2 * math.pi)], fs=fs)
        want = (1 + 1j * w * tau) / (1 + 1j * w * tau / LEAD_GAIN)
        assert abs(h[0] - want) < 1e-12
        _, h0 = sosfreqz(np.array([sec]), worN=[0.0], fs=fs)
        assert abs(h0[0] - 1.0) < 1e-12  # no gain on a sustained force
    # a force step: the output jumps above the step and settles on it (the lead's shape)
    n = 300
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[10:, 1] = 1.0
    q = replace(p, tilt_shape=None, tilt_reach_rad=None, f_shape=None, tilt_scale=(1.0, 1.0),
                f_scale=(1.0, 1.0, 1.0), f_limit_m_s2=(50.0, 50.0, 50.0), lead_s=(0.1, 0.1),
                tilt_rate_limit_rad_s=20.0, tilt_accel_limit_rad_s2=None)  # fmt: skip
    plain = replace(q, lead_s=None)
    a = ClassicalWashout(q, fs).run(f, np.zeros((n, 3))).tilt[:, 0]
    b = ClassicalWashout(plain, fs).run(f, np.zeros((n, 3))).tilt[:, 0]
    assert np.all(a[10:40] >= b[10:40]) and a[12] > b[12]
    assert a[-1] == pytest.approx(b[-1], abs=1e-9)


def test_combined_roll_and_pitch_stay_inside_the_quadrant_ellipse() -> None:
    p = _compressive(load_cueing("racing-hexapod"))
    p = replace(p, tilt_accel_limit_rad_s2=None, w_scale=(0.0, 0.0, 0.0), lead_s=None)
    fs, n = 100.0, 3000
    f = np.tile([0.0, 0.0, G], (n, 1))
    f[100:, 0] = -25.0  # hard braking: nose down, pitch+
    f[100:, 1] = 25.0  # and a hard right-hand force: roll+
    res = ClassicalWashout(p, fs).run(f, np.zeros((n, 3)))
    _rn, rp, _pn, pp = p.tilt_limits_rad
    assert p.tilt_scale is not None and p.tilt_shape is not None
    # each alone: the compressed angle of its direction (as in the test above)
    lx, ly = G * math.sin(pp), G * math.sin(rp)
    pitch_alone = -math.asin(compress(-25.0, p.tilt_scale[0], lx, lx, p.tilt_shape) / G)
    roll_alone = math.asin(compress(25.0, p.tilt_scale[1], ly, ly, p.tilt_shape) / G)
    q = (roll_alone / rp) ** 2 + (pitch_alone / pp) ** 2
    assert q > 1.0  # together they would leave the ellipse
    roll, pitch = res.tilt[-1]
    assert roll == pytest.approx(roll_alone / math.sqrt(q), abs=1e-9)
    assert pitch == pytest.approx(pitch_alone / math.sqrt(q), abs=1e-9)
    assert (roll / rp) ** 2 + (pitch / pp) ** 2 == pytest.approx(1.0, abs=1e-9)
    # streaming gives the same
    design = ClassicalWashout(p, fs)
    state = design.initial_state()
    for a, b in zip(f.tolist(), np.zeros((n, 3)).tolist(), strict=True):
        design.step(state, a, b, None)
    np.testing.assert_allclose(state.tilt, res.tilt[-1], rtol=0, atol=1e-12)
