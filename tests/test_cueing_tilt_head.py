"""Classical washout: own tilt gain, tilt acceleration limit, rider's head offset.

Oracles: closed forms (the time-optimal trapezoid/triangle of a step under rate and
acceleration limits), :func:`scipy.signal.lsim` of the continuous filters the design
documents, and the streaming ``step`` against the batch ``run``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue import ConfigError
from motioncue.cueing import ClassicalWashout, CueingParams, load_cueing
from motioncue.cueing._classical import rate_accel_limit_step

G = 9.80665
D2R = math.pi / 180.0


def _drive(n: int, fs: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    f = np.stack(
        [
            4 * np.sin(0.7 * t) + 3 * np.sign(np.sin(0.23 * t)) + rng.normal(0, 0.3, n),
            5 * np.sin(0.4 * t + 1) + rng.normal(0, 0.3, n),
            G + 2 * np.sin(3.0 * t) + rng.normal(0, 0.3, n),
        ],
        axis=1,
    )
    w = np.stack(
        [0.6 * np.sin(1.3 * t), 0.3 * np.sin(0.7 * t), 0.8 * np.sign(np.sin(0.11 * t))], axis=1
    )
    f[5, 0] = np.nan
    w[40, 2] = -np.inf
    f[n // 2, 2] = 1e9
    return f, w


def _featured(preset: str, **kw: object) -> CueingParams:
    base = dict(
        tilt_scale=(0.45, 0.6),
        tilt_accel_limit_rad_s2=25.0 * D2R,
        head_offset_m=(0.1, -0.05, 0.8),
        tilt_limit_rad=20.0 * D2R,
    )
    base.update(kw)
    return dataclasses.replace(load_cueing(preset), **base)  # type: ignore[arg-type]


def _stream(design: ClassicalWashout, f: np.ndarray, w: np.ndarray) -> np.ndarray:
    state = design.initial_state()
    out = [0.0] * 6
    rows = np.empty((len(f), 6))
    for i, (fi, wi) in enumerate(zip(f.tolist(), w.tolist(), strict=True)):
        rows[i] = design.step(state, fi, wi, out)
    return rows


@pytest.mark.parametrize("preset", ["racing-hexapod", "flight", "cinema-seat-3dof"])
@pytest.mark.parametrize("fs", [100.0, 1000.0])
def test_step_equals_run_with_every_new_feature_on(preset: str, fs: float) -> None:
    design = ClassicalWashout(_featured(preset), fs_hz=fs)
    f, w = _drive(3000, fs, seed=int(fs) + len(preset))
    res = design.run(f, w)
    # round-off only: the per-sample and the vectorised paths order their sums differently,
    # and a tilt of 0.1 rad has differed by 1.3e-12 after 1300 samples on one CPU's kernels
    # (1e-10 relative is far below a pulse: 0.1 rad is ~1e5 pulses)
    np.testing.assert_allclose(_stream(design, f, w), res.poses, rtol=1e-10, atol=1e-12)
    # continuing in blocks from the state gives the same again
    state = design.initial_state()
    parts = [design.run(f[a : a + 701], w[a : a + 701], state).poses for a in range(0, 3000, 701)]
    np.testing.assert_allclose(np.concatenate(parts), res.poses, rtol=1e-10, atol=1e-12)
    # and the features did change the numbers (the comparison above is not vacuous)
    plain = ClassicalWashout(load_cueing(preset), fs_hz=fs).run(f, w).poses
    assert np.abs(plain - res.poses).max() > 1e-3


def test_reset_clears_the_new_state() -> None:
    design = ClassicalWashout(_featured("racing"), fs_hz=100.0)
    f, w = _drive(500, 100.0, 3)
    state = design.initial_state()
    first = design.run(f, w, state).poses
    assert any(state.tilt_rate) and any(state.omega) and any(state.attitude)
    design.reset(state)
    assert state.tilt_rate == [0.0, 0.0] and state.omega == [0.0] * 3
    np.testing.assert_array_equal(design.run(f, w, state).poses, first)


# -- tilt acceleration limit ----------------------------------------------------------------
@settings(max_examples=300, deadline=None)
@given(
    targets=st.lists(st.floats(-0.5, 0.5), min_size=1, max_size=60),
    rate=st.floats(0.01, 2.0),
    accel=st.floats(0.01, 50.0),
    fs=st.sampled_from([50.0, 100.0, 1000.0]),
)
def test_follower_never_exceeds_its_rate_or_acceleration(
    targets: list[float], rate: float, accel: float, fs: float
) -> None:
    """Property: whatever the target, |step| <= r/fs and |step change| <= a/fs^2."""
    st_max, sa = rate / fs, accel / (fs * fs)
    prev, u = 0.0, 0.0
    for x in targets:
        for _ in range(5):  # hold each target a few samples
            u_new = rate_accel_limit_step(x, prev, u, st_max, sa)
            assert abs(u_new) <= st_max * (1 + 1e-12)
            assert abs(u_new - u) <= sa * (1 + 1e-9) + 1e-18
            prev, u = prev + u_new, u_new


def test_washout_tilt_acceleration_stays_within_the_limit() -> None:
    """On drives with force steps (the rate limit alone would give rate steps)."""
    fs = 200.0
    a_lim, r_lim = 15.0 * D2R, 8.0 * D2R
    for seed in range(6):
        p = _featured("racing-hexapod", tilt_accel_limit_rad_s2=a_lim, tilt_wn_rad_s=30.0)
        p = dataclasses.replace(p, tilt_rate_limit_rad_s=r_lim)
        f, w = _drive(4000, fs, seed)
        tilt = ClassicalWashout(p, fs_hz=fs).run(f, w).tilt
        rate = np.diff(tilt, axis=0, prepend=0.0) * fs
        acc = np.diff(rate, axis=0, prepend=0.0) * fs
        assert np.abs(rate).max() <= r_lim * (1 + 1e-9)
        assert np.abs(acc).max() <= a_lim * (1 + 1e-6)
        assert np.abs(acc).max() > 0.9 * a_lim  # the limit is reached, so it was tested
    # without the acceleration limit the same drive has rate steps far above it
    plain = dataclasses.replace(p, tilt_accel_limit_rad_s2=None)
    tilt = ClassicalWashout(plain, fs_hz=fs).run(f, w).tilt
    acc = np.diff(np.diff(tilt, axis=0, prepend=0.0) * fs, axis=0, prepend=0.0) * fs
    assert np.abs(acc).max() > 10 * a_lim


def _profile(theta: float, r: float, a: float, t: np.ndarray) -> np.ndarray:
    """Time-optimal rest-to-rest move by ``theta`` under rate ``r`` and acceleration ``a``
    (by hand: trapezoid if ``theta >= r^2/a``, else triangle)."""
    if theta >= r * r / a:
        t1, t2 = r / a, theta / r  # end of acceleration, start of braking
        total = t2 + t1
        peak = r
    else:
        t1 = math.sqrt(theta / a)
        t2, total, peak = t1, 2 * t1, a * t1
    x = np.where(t <= t1, 0.5 * a * t * t, 0.5 * a * t1 * t1 + peak * (t - t1))
    x = np.where(t >= t2, theta - 0.5 * a * np.clip(total - t, 0, None) ** 2, x)
    return np.where(t >= total, theta, x)


@pytest.mark.parametrize("theta_deg", [12.0, 2.0])  # trapezoid, triangle
def test_step_target_gives_the_hand_computed_trapezoid_or_triangle(theta_deg: float) -> None:
    fs, r, a = 1000.0, 10.0 * D2R, 20.0 * D2R  # r^2/a = 5 deg
    theta = theta_deg * D2R
    n = int(3.0 * fs)
    prev, u, y = 0.0, 0.0, []
    for _ in range(n):
        u = rate_accel_limit_step(theta, prev, u, r / fs, a / fs**2)
        prev += u
        y.append(prev)
    t = np.arange(1, n + 1) / fs
    expected = _profile(theta, r, a, t)
    # within the distance one sample moves at full rate; an overshoot below one acceleration
    # step a/fs^2 (where braking starts between two samples); settled exactly on the target
    assert np.abs(np.array(y) - expected).max() <= r / fs
    assert max(y) <= theta + a / fs**2 and y[-1] == theta
    # the same through the washout: a fast tilt filter and a force step of the right size
    p = dataclasses.replace(
        load_cueing("racing"),
        tilt_scale=(1.0, 1.0),
        tilt_wn_rad_s=600.0,
        tilt_rate_limit_rad_s=r,
        tilt_accel_limit_rad_s2=a,
        tilt_limit_rad=40.0 * D2R,
        soft_knee=1.0,
    )
    f = np.tile([G * math.sin(theta), 0.0, G], (n, 1))  # pitch target -theta
    tilt = ClassicalWashout(p, fs_hz=fs).run(f, np.zeros((n, 3))).tilt[:, 1]
    # the filter's settling (a few ms) shifts the start by a few samples at most
    assert np.abs(-tilt - expected).max() <= 8 * r / fs
    assert abs(-tilt[-1] - theta) < 1e-6


# -- tilt gain --------------------------------------------------------------------------------
def test_tilt_gain_is_separate_from_the_translational_scale() -> None:
    """Oracle: lsim of the documented tilt low-pass on k_t f_x / g (small angles, no limit)."""
    from scipy import signal

    fs = 500.0
    base = load_cueing("racing")  # hand-written: f_scale 0.4, f_limit 5, no tilt accel limit
    p = dataclasses.replace(
        base, tilt_scale=(0.6, 0.5), tilt_rate_limit_rad_s=5.0, tilt_limit_rad=60.0 * D2R
    )
    t = np.arange(int(6 * fs)) / fs
    fx = 1.2 * np.sin(1.1 * t) * (t < 4)
    fy = -1.0 * (t > 1)
    f = np.column_stack([fx, fy, np.full_like(t, G)])
    tilt = ClassicalWashout(p, fs_hz=fs).run(f, np.zeros_like(f)).tilt
    wt, zt = p.tilt_wn_rad_s, p.tilt_zeta
    lp = signal.lti([wt * wt], [1.0, 2 * zt * wt, wt * wt])
    lx = signal.lsim(lp, 0.6 * fx, t)[1]
    ly = signal.lsim(lp, 0.5 * fy, t)[1]
    np.testing.assert_allclose(tilt[:, 1], -np.arcsin(lx / G), atol=2e-3 * D2R * 60)
    np.testing.assert_allclose(tilt[:, 0], np.arcsin(ly / G), atol=2e-3 * D2R * 60)
    # steady lateral tilt: asin(0.5 * 1.0 / g), not asin(0.4 * 1.0 / g) of the force scale
    assert tilt[-1, 0] == pytest.approx(-math.asin(0.5 / G), rel=1e-4)
    # a big force: the tilt is not squashed by the translational force limit (5 m/s^2)
    big = np.tile([9.0, 0.0, G], (int(3 * fs), 1))
    own = ClassicalWashout(p, fs_hz=fs).run(big, np.zeros_like(big)).tilt[-1, 1]
    assert own == pytest.approx(-math.asin(0.6 * 9.0 / G), rel=1e-4)


def test_tilt_gain_equal_to_the_force_scale_changes_nothing_below_the_force_limit() -> None:
    fs = 100.0
    base = load_cueing("racing")  # f_scale 0.4, limit 5, knee 0.7: identity below 3.5
    same = dataclasses.replace(base, tilt_scale=(0.4, 0.4))
    t = np.arange(2000) / fs
    f = np.column_stack([4 * np.sin(0.5 * t), 3 * np.cos(0.3 * t), np.full_like(t, G)])
    w = np.zeros_like(f)
    a = ClassicalWashout(base, fs_hz=fs).run(f, w).poses
    b = ClassicalWashout(same, fs_hz=fs).run(f, w).poses
    np.testing.assert_array_equal(a, b)


# -- head offset -------------------------------------------------------------------------------
def test_head_offset_first_order_is_minus_h_times_high_passed_pitch() -> None:
    """Hand derivation (module docstring): head ``h_z`` above the origin, pitch only:
    ``W' x h = [h_z theta'', 0, 0]``, so ``x_h - x_0 = -h_z H_T(s) theta`` to first order,
    with ``H_T = s^2/(s^2 + 2 zeta wn s + wn^2) * s/(s + wb)``. Oracle: lsim of ``H_T``."""
    from scipy import signal

    fs = 1000.0
    hz = 0.9
    base = dataclasses.replace(load_cueing("racing"), f_scale=(0.0, 0.0, 0.0))
    head = dataclasses.replace(base, head_offset_m=(0.0, 0.0, hz))
    t = np.arange(int(8 * fs)) / fs
    wy = 0.1 * np.sin(2.0 * t) * (t < 5)
    w = np.column_stack([np.zeros_like(t), wy, np.zeros_like(t)])
    f = np.column_stack([np.zeros_like(t), np.zeros_like(t), np.full_like(t, G)])
    p0 = ClassicalWashout(base, fs_hz=fs).run(f, w).poses
    ph = ClassicalWashout(head, fs_hz=fs).run(f, w).poses
    np.testing.assert_array_equal(p0[:, 3:], ph[:, 3:])  # rotation untouched
    pitch = ph[:, 4]
    assert np.abs(pitch).max() > 0.5 * D2R
    wn, zeta, wb = base.trans_wn_rad_s[0], base.trans_zeta[0], base.trans_wb_rad_s[0]
    ht = signal.lti(
        [1.0, 0.0, 0.0, 0.0], np.polymul([1.0, 2 * zeta * wn, wn * wn], [1.0, wb]).tolist()
    )
    expected = signal.lsim(ht, -hz * pitch, t)[1]
    dx = ph[:, 0] - p0[:, 0]
    assert np.abs(dx).max() > 1e-4
    # nose down (positive pitch) swings the head forward: the origin moves back at first
    k = int(np.argmax(pitch > 0.2 * D2R))
    assert dx[k] < 0
    assert np.abs(dx - expected).max() <= 0.02 * np.abs(expected).max()
    np.testing.assert_array_equal(p0[:, 1], ph[:, 1])  # no lateral term from pitch alone


def test_head_offset_centripetal_term_by_hand() -> None:
    """First samples from rest, roll only, head ``h_y`` to the left, by hand:
    ``W = [phi', 0, 0]``, ``W x (W x h) = [0, -phi'^2 h_y, 0]``, ``W' x h = [0, 0, phi'' h_y]``.
    The translational input difference is ``-R [0, -phi'^2 h_y, phi'' h_y]``; through the
    first translational sample (``y[0] = b0 x[0]`` of each section) that gives the pose."""
    fs = 100.0
    hy = 0.4
    base = dataclasses.replace(load_cueing("racing"), f_scale=(0.0, 0.0, 0.0))
    head = dataclasses.replace(base, head_offset_m=(0.0, hy, 0.0))
    d0, dh = ClassicalWashout(base, fs_hz=fs), ClassicalWashout(head, fs_hz=fs)
    s0, sh = d0.initial_state(), dh.initial_state()
    q0 = d0.step(s0, (0.0, 0.0, G), (0.3, 0.0, 0.0))
    qh = dh.step(sh, (0.0, 0.0, G), (0.3, 0.0, 0.0))
    phi = qh[3]
    assert phi > 0 and qh[4] == 0.0 and qh[5] == 0.0
    rate = phi * fs  # backward difference from rest
    acc = rate * fs
    fo = np.array([0.0, rate * rate * hy, -acc * hy])  # -(W' x h + W x (W x h))
    c, s = math.cos(phi), math.sin(phi)
    a = np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) @ fo  # R = Rx(phi)
    for axis, sec in ((1, dh.trans[1]), (2, dh.trans[2])):
        gain = sec[0][0] * sec[1][0]  # first output of two sections from rest
        assert qh[axis] - q0[axis] == pytest.approx(gain * a[axis], rel=1e-9, abs=1e-15)
    assert qh[0] == q0[0]


# -- configuration -----------------------------------------------------------------------------
def _variant(tmp_path, old: str, new: str):  # type: ignore[no-untyped-def]
    from motioncue._config import find_config

    text = find_config("cueing", "racing").read_text()
    assert old in text
    path = tmp_path / "v.toml"
    path.write_text(text.replace(old, new, 1))
    return path


def test_new_keys_load_in_si_and_default_to_neutral(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # the hand-written generic preset (the tuned ones set every key)
    p = load_cueing("racing")
    assert p.algorithm == "classical"
    assert p.tilt_scale is None and p.tilt_accel_limit_rad_s2 is None
    assert p.head_offset_m == (0.0, 0.0, 0.0)
    path = _variant(
        tmp_path,
        "limit_deg = 12.0",
        "limit_deg = 12.0\nscale = [0.3, 0.25]\naccel_limit_deg_s2 = 30.0",
    )
    text = path.read_text() + "\n[head]\noffset_mm = [100.0, 0.0, 750.0]\n"
    path.write_text(text)
    q = load_cueing(path)
    assert q.tilt_scale == (0.3, 0.25)
    assert q.tilt_accel_limit_rad_s2 == pytest.approx(30.0 * D2R)
    assert q.head_offset_m == pytest.approx((0.1, 0.0, 0.75))


@pytest.mark.parametrize(
    ("old", "new", "match"),
    [
        ("limit_deg = 12.0", "limit_deg = 12.0\naccel_limit_deg_s = 3.0", "unknown key"),
        ("limit_deg = 12.0", "limit_deg = 12.0\naccel_limit_deg_s2 = 0.0", "accel_limit_deg_s2"),
        ("limit_deg = 12.0", "limit_deg = 12.0\nscale = [0.3]", "scale"),
        ("limit_deg = 12.0", "limit_deg = 12.0\nscale = [-0.3, 0.3]", "tilt_scale"),
        ("[workspace]", "[head]\noffset_m = [0.0, 0.0, 0.7]\n[workspace]", "offset_mm"),
        ("[workspace]", "[head]\noffset_mm = [0.0, 0.0, 70000.0]\n[workspace]", "head_offset"),
    ],
)
def test_bad_new_keys_are_refused(tmp_path, old: str, new: str, match: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(ConfigError, match=match):
        load_cueing(_variant(tmp_path, old, new))
