"""The bound without false rotation cues (cue_bound(..., forbid_false_rotation=True)).

The canal rows are checked against a dense LP written out by the test (the canal as a
matrix of pulse responses, the no-spurious / no-reversal rows as plain inequalities), on a
support function and on the gain bounds of a tiny drive; against the closed form of a tilt
built as fast as the canal allows (the perceived rate held at the threshold from rest: the
tilt after T seconds is ``thr`` times the step response of ``1 / (s H_canal(s))``); and the
smaller set's figures are never looser than the whole rig's, while a motion of the smaller
set built by the test (a slowly ramped tilt checked through the canal) never beats them.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import linprog

from motioncue import ConfigError
from motioncue.cueing import RigReach, cue_bound, get_model_set
from motioncue.cueing._bound import _Channel, _Rotation, _second_difference, _support
from test_cue_bound_corr import _d2, _h

G = 9.80665
MS = get_model_set("telban-cardullo-2005")
THR = np.asarray(MS.thresholds)


def _d1(n: int) -> np.ndarray:
    return np.eye(n)[1:] - np.eye(n)[:-1]


def _rot_ineq(
    n: int, fs: float, sign: float, omega: np.ndarray, axis: int, rule: str = "spurious"
) -> tuple:
    """The test's own no-false-rotation rows on tau: ``R tau <= hi`` and ``-R tau <= -lo``
    where finite (R: the canal matrix times the rate, from the neutral pose before the first
    sample). ``rule="false"``: only the rows against a cue beyond the threshold with the sign
    opposite to the vehicle's (whatever the vehicle's size)."""
    canal = MS.canal[axis]
    thr = THR[3 + axis]
    rate = np.vstack([np.eye(n)[:1], _d1(n)]) * fs * sign
    r = _h(n, fs, canal) @ rate
    v = canal.apply(omega, fs)
    rows, rhs = [], []
    for k in range(n):
        if rule == "false":
            if v[k] > 0.0:  # the vehicle's rate positive: the platform's not below -thr
                rows.append(-r[k])
                rhs.append(thr)
            elif v[k] < 0.0:
                rows.append(r[k])
                rhs.append(thr)
            continue
        if v[k] >= -thr:  # not below -thr: the platform's perceived rate >= -thr
            rows.append(-r[k])
            rhs.append(thr)
        if v[k] <= thr:
            rows.append(r[k])
            rhs.append(thr)
    return np.array(rows), np.array(rhs)


def _dense_support(
    c: np.ndarray, fs: float, box: tuple[float, ...], rot: tuple | None, h_rows: tuple | None = None
) -> float:
    """max c' (D2 p + g tau) over the boxes (and the rotation rows, and rows on y = H s)."""
    stroke, speed, accel, tilt, rate = box
    n = c.shape[0]
    d1, d2 = _d1(n), _d2(n, fs)
    z1 = np.zeros((n - 1, n))
    z2 = np.zeros((n, n))
    a = [np.hstack([d1, z1]), np.hstack([-d1, z1]), np.hstack([z1, d1]), np.hstack([z1, -d1]),
         np.hstack([d2, z2]), np.hstack([-d2, z2])]  # fmt: skip
    b = [np.full(2 * (n - 1), speed / fs), np.full(2 * (n - 1), rate / fs), np.full(2 * n, accel)]
    if rot is not None:
        a.append(np.hstack([np.zeros((rot[0].shape[0], n)), rot[0]]))
        b.append(rot[1])
    if h_rows is not None:  # rows on H s = H (D2 p + g tau)
        a.append(h_rows[0] @ np.hstack([d2, G * np.eye(n)]))
        b.append(h_rows[1])
    res = linprog(-np.concatenate([d2.T @ c, G * c]), A_ub=np.vstack(a), b_ub=np.concatenate(b),
                  bounds=[(-stroke, stroke)] * n + [(-tilt, tilt)] * n, method="highs")  # fmt: skip
    assert res.status == 0
    return float(-res.fun)


N, FS = 12, 5.0
BOX = (0.2, 0.3, 2.0, 0.15, 0.4)  # stroke, speed, accel, tau, tau rate
REACH = RigReach((BOX[0],) * 2, (BOX[1],) * 2, (BOX[2],) * 2, (math.asin(BOX[3]),) * 2,
                 (BOX[4],) * 2)  # fmt: skip


def _omega() -> np.ndarray:
    """Vehicle rates (rad/s) whose perception is below, above and under -thr in turn."""
    w = np.zeros(N)
    w[2:5] = 0.3
    w[7:10] = -0.3
    return w


def test_support_matches_a_dense_lp() -> None:
    rng = np.random.default_rng(3)
    d2 = _second_difference(N, FS)
    omega = _omega()
    v = MS.canal[1].apply(omega, FS)
    assert v.max() > THR[4] and v.min() < -THR[4] and np.any(np.abs(v) < THR[4])
    for i, (axis, sign) in enumerate(((1, -1.0), (0, 1.0))):
        rot = _Rotation(canal=MS.canal[axis], sign=sign, omega=omega, thr=float(THR[3 + axis]))
        base = _Channel(BOX[0], BOX[1], BOX[2], BOX[3], BOX[4], FS, MS.otolith[i])
        ch = _Channel(BOX[0], BOX[1], BOX[2], BOX[3], BOX[4], FS, MS.otolith[i], rot=rot)
        ineq = _rot_ineq(N, FS, sign, omega, axis)
        tighter = 0
        for _ in range(4):
            c = rng.normal(size=N)
            got = _support(ch, c, d2)
            want = _dense_support(c, FS, BOX, ineq)
            assert got == pytest.approx(want, rel=1e-6, abs=1e-9)
            whole = _support(base, c, d2)
            assert got <= whole * (1.0 + 1e-9) + 1e-12
            tighter += got < whole * (1.0 - 1e-3)
        assert tighter >= 1  # the rows bind somewhere


def test_the_false_rule_matches_a_dense_lp_between_the_smaller_set_and_the_rig() -> None:
    # rotation_rule="false": only the rows against a false cue (the sign opposite to the
    # vehicle's beyond the threshold, whatever the vehicle's size), so S' within S'' within S
    rng = np.random.default_rng(7)
    d2 = _second_difference(N, FS)
    omega = _omega()
    for i, (axis, sign) in enumerate(((1, -1.0), (0, 1.0))):
        canal, thr = MS.canal[axis], float(THR[3 + axis])
        base = _Channel(*BOX, FS, MS.otolith[i])
        strict = _Channel(*BOX, FS, MS.otolith[i], rot=_Rotation(canal, sign, omega, thr))
        loose = _Channel(*BOX, FS, MS.otolith[i], rot=_Rotation(canal, sign, omega, thr, "false"))
        ineq = _rot_ineq(N, FS, sign, omega, axis, rule="false")
        looser = 0
        for _ in range(6):
            c = rng.normal(size=N)
            got = _support(loose, c, d2)
            assert got == pytest.approx(_dense_support(c, FS, BOX, ineq), rel=1e-6, abs=1e-9)
            small, whole = _support(strict, c, d2), _support(base, c, d2)
            assert small <= got * (1.0 + 1e-9) + 1e-12 <= whole * (1.0 + 2e-9) + 2e-12
            looser += got > small * (1.0 + 1e-3)
        assert looser >= 1  # the spurious cues with the vehicle's sign are allowed somewhere


def _drive() -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(N) / FS
    f = np.zeros((N, 3))
    f[:, 0] = 2.0 * np.sin(1.3 * t) + 1.0
    f[:, 1] = -1.5 * np.cos(0.9 * t)
    f[:, 2] = G
    w = np.zeros((N, 3))
    w[:, 1] = _omega()
    w[:, 0] = -_omega()[::-1]
    return f, w


def test_gain_bounds_match_dense_lps_and_never_exceed_the_whole_rig() -> None:
    f, w = _drive()
    free = cue_bound(f, FS, REACH, corr_min=None)
    b = cue_bound(f, FS, REACH, corr_min=None, w_vehicle=w, forbid_false_rotation=True)
    assert b.rotation_cues == "forbidden" and free.rotation_cues == "allowed"
    for i, (axis, sign) in enumerate(((1, -1.0), (0, 1.0))):
        h = _h(N, FS, MS.otolith[i])
        v = h @ f[:, i]
        vv = float(v @ v)
        ineq = _rot_ineq(N, FS, sign, w[:, axis], axis)
        assert b.gain_max_any[i] == pytest.approx(
            _dense_support(h.T @ v, FS, BOX, ineq) / vv, rel=1e-6
        )
        thr = THR[i]
        rows = [-h[k] for k in range(N) if v[k] > thr] + [h[k] for k in range(N) if v[k] < -thr]
        no_rev = (np.array(rows), np.full(len(rows), thr)) if rows else None
        assert b.gain_max[i] == pytest.approx(
            _dense_support(h.T @ v, FS, BOX, ineq, no_rev) / vv, rel=1e-5
        )
        assert b.gain_max[i] <= free.gain_max[i] * (1.0 + 1e-7)


def test_the_false_rule_gain_bounds_match_dense_lps_and_are_refused_when_unknown() -> None:
    f, w = _drive()
    strict = cue_bound(f, FS, REACH, corr_min=None, w_vehicle=w, forbid_false_rotation=True)
    b = cue_bound(
        f, FS, REACH, corr_min=None, w_vehicle=w, forbid_false_rotation=True, rotation_rule="false"
    )
    free = cue_bound(f, FS, REACH, corr_min=None)
    assert b.rotation_cues == "no-false" and b.to_dict()["rotation_cues"] == "no-false"
    for i, (axis, sign) in enumerate(((1, -1.0), (0, 1.0))):
        h = _h(N, FS, MS.otolith[i])
        v = h @ f[:, i]
        ineq = _rot_ineq(N, FS, sign, w[:, axis], axis, rule="false")
        assert b.gain_max_any[i] == pytest.approx(
            _dense_support(h.T @ v, FS, BOX, ineq) / float(v @ v), rel=1e-6
        )
        assert strict.gain_max[i] <= b.gain_max[i] * (1.0 + 1e-7)
        assert b.gain_max[i] <= free.gain_max[i] * (1.0 + 1e-7)
        assert b.error_rms[i] <= strict.error_rms[i] * (1.0 + 1e-7) + 1e-12
    with pytest.raises(ConfigError, match="rotation_rule 'reversed' is invalid; allowed"):
        cue_bound(f, FS, REACH, w_vehicle=w, forbid_false_rotation=True, rotation_rule="reversed")


def test_canal_limited_tilt_closed_form() -> None:
    """A sustained step: with the vehicle not rotating, the tilt can only build as fast as
    the canal allows. Holding the perceived rate at the threshold from rest is optimal when
    ``1 / (s H(s))``'s impulse response is >= 0 (checked), so the largest tilt term after
    ``T`` s is ``thr`` times the step response of ``1 / (s H(s))`` at ``T`` (continuous; the
    bilinear discretisation at 200 Hz is within 2 %)."""
    from scipy.signal import lti

    fs, t_end = 200.0, 1.5
    n = int(t_end * fs) + 1
    canal = MS.canal[1]
    thr = float(THR[4])
    num, den = canal.transfer_function()
    # 1 / (s H): the perceived rate to the tilt. num ends in s^2 (two zeros at 0): cancel them,
    # 1 / (s H) = den / (num / s^2 * s^3)
    num_red = np.trim_zeros(num, "b")
    inv = lti(den, np.polymul(num_red, [1.0, 0.0, 0.0, 0.0]))
    t = np.linspace(0.0, t_end, 3001)
    _, imp = inv.impulse(T=t[1:])
    assert imp.min() >= 0.0
    _, step = inv.step(T=t)
    ramp = thr * float(step[-1])  # the largest tau (= sin tilt, to first order) at t_end
    assert 0.005 < ramp < 0.5  # far below the tilt box and the rate box below
    rot = _Rotation(canal=canal, sign=-1.0, omega=np.zeros(n), thr=thr)
    ch = _Channel(0.0, 0.0, 0.0, 0.5, 10.0, fs, MS.otolith[0], rot=rot)
    c = np.zeros(n)
    c[-1] = 1.0
    got = _support(ch, c, _second_difference(n, fs)) / G
    assert got == pytest.approx(ramp, rel=0.02)
    # the whole rig reaches the tilt box (0.5) well before: the canal is what binds
    free = _Channel(0.0, 0.0, 0.0, 0.5, 10.0, fs, MS.otolith[0])
    assert _support(free, c, _second_difference(n, fs)) / G == pytest.approx(0.5, rel=1e-9)


def test_a_motion_without_false_rotation_never_beats_the_bound() -> None:
    """A slow tilt copy of the drive's fx (checked through the canal by the test: no spurious,
    no reversed rotation cue) and a small translation: its gain and share at its correlation
    stay below the bound's."""
    n, fs = 100, 10.0
    t = np.arange(n) / fs
    f = np.zeros((n, 3))
    f[:, 0] = 3.0 * np.sin(0.4 * t) + 2.0 * np.sin(2.1 * t)
    f[:, 2] = G
    w = np.zeros((n, 3))
    reach = RigReach((0.1, 0.1), (0.3, 0.3), (3.0, 3.0), (0.25, 0.25), (1.0, 1.0))
    b = cue_bound(
        f, fs, reach, w_vehicle=w, forbid_false_rotation=True, corr_min=(0.5, 0.5), corr_cuts=1
    )
    free = cue_bound(f, fs, reach, corr_min=(0.5, 0.5), corr_cuts=1)
    assert b.share_max_at_corr[0] <= free.share_max_at_corr[0] * (1.0 + 1e-6)
    assert b.share_at_corr_primal[0] <= b.share_max_at_corr[0] * (1.0 + 1e-6)
    h = _h(n, fs, MS.otolith[0])
    v = h @ f[:, 0]
    canal = MS.canal[1]
    tau = np.convolve(f[:, 0] / G, np.ones(10) / 10, mode="same")
    p = 0.02 * np.sin(2.1 * t) * (1 - np.cos(2 * np.pi * t / t[-1]))
    for scale in (1.0, 0.5, 0.2, 0.1, 0.05, 0.02):
        ts = scale * tau
        r = canal.apply(-np.diff(ts, prepend=0.0) * fs, fs)  # from the neutral pose
        if np.abs(r).max() <= THR[4] and np.abs(ts).max() <= math.sin(0.25):
            break
    else:
        pytest.fail("no scale of the tilt copy is free of rotation cues")
    assert np.abs(np.diff(ts)).max() * fs <= 1.0
    assert np.abs(p).max() <= 0.1 and np.abs(np.diff(p)).max() * fs <= 0.3
    assert np.abs(_d2(n, fs) @ p).max() <= 3.0
    y = h @ (_d2(n, fs) @ p + G * ts)
    gain = float(y @ v) / float(v @ v)
    share = math.sqrt(float(y @ y) / float(v @ v))
    corr = float(np.corrcoef(y, v)[0, 1])
    assert gain <= b.gain_max_any[0] * (1.0 + 1e-7)
    assert corr >= 0.5
    assert share <= b.share_max_at_corr[0] * (1.0 + 1e-7)


def test_forbidding_needs_the_vehicle_rates() -> None:
    f, w = _drive()
    with pytest.raises(ConfigError, match="w_vehicle"):
        cue_bound(f, FS, REACH, forbid_false_rotation=True)
    with pytest.raises(ConfigError, match="w_vehicle"):
        cue_bound(f, FS, REACH, w_vehicle=w[:-1], forbid_false_rotation=True)
    with pytest.raises(ConfigError, match="w_vehicle"):
        cue_bound(f, FS, REACH, w_vehicle=np.full_like(w, np.nan), forbid_false_rotation=True)


def test_no_preset_without_false_rotation_cues_beats_it() -> None:
    """Presets delivered on 3 s of the lap (exact kinematics, the chain's limits, the
    vehicle's own rotation) that give no spurious and no reversed cue on the tilt axis (pitch
    ``q`` for fx, roll ``p`` for fy) never beat the bound without false rotation cues. The
    bundled presets all give some there (racing-hexapod, optimal-hexapod, racing-hexapod-firm
    and mpc-hexapod: 0.6-1.8 s of spurious pitch cues), so the default preset is run without
    tilt and with a tilt slower than the canal's threshold."""
    from dataclasses import replace
    from pathlib import Path

    from motioncue.analysis import compare_cueing, rig_reach
    from motioncue.cueing import load_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.telemetry._recording import Recording, read_recording_csv, resample
    from motioncue.trajectory import ActuatorLimits, pulse_rounding_limits

    path = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"
    lap = resample(read_recording_csv(path), 100.0)
    # 3 s: the two bounds take two thirds of the CPU of 4 s (2.1 against 3.1-3.7 s), and the
    # presets come closer to them: four channels checked (4 s: three), the largest gain 0.12
    # of the bound (4 s: 0.02), and the gain bound without reversals reached (slow tilt, fy;
    # on 4 s no checked channel was free of reversals)
    n = 300
    f = np.asarray(lap.f, dtype=float)[2000 : 2000 + n]
    w = np.asarray(lap.w, dtype=float)[2000 : 2000 + n]
    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=100.0)
    lims = pulse_rounding_limits(limits, platform, 0.01)
    reach = rig_reach(platform, lims)  # the boxes alone: a larger set, still a valid bound
    b = cue_bound(f, 100.0, reach, w_vehicle=w, forbid_false_rotation=True, corr_min=None)
    free = cue_bound(f, 100.0, reach, corr_min=None)
    base = load_cueing("racing-hexapod")
    deg = math.pi / 180.0
    presets = [
        ("no tilt", replace(base, dofs=(True, True, True, False, False, True))),
        ("slow tilt", replace(base, tilt_rate_limit_rad_s=1.5 * deg, tilt_wn_rad_s=1.0,
                              w_scale=(0.0, 0.0, base.w_scale[2]))),
    ]  # fmt: skip
    res = compare_cueing(
        [("lap", Recording(np.arange(n) / 100.0, f, w))], presets, platform, limits
    )
    checked = 0
    for row in res.rows():
        for i, (a, r) in enumerate((("fx", "q"), ("fy", "p"))):
            assert b.gain_max_any[i] <= free.gain_max_any[i] * (1.0 + 1e-7)
            assert b.gain_max[i] <= free.gain_max[i] * (1.0 + 1e-7)
            if row[f"spurious_s_{r}"] > 0.0 or row[f"reversal_s_{r}"] > 0.0:
                continue
            checked += 1
            assert row[f"gain_{a}"] <= b.gain_max_any[i]
            if row[f"reversal_s_{a}"] == 0.0:
                assert row[f"gain_{a}"] <= b.gain_max[i]
    assert checked >= 3  # no tilt: both channels; slow tilt: fx at least


def test_an_lp_failing_with_the_rows_falls_back_to_the_larger_set(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """HiGHS stopped on one support LP with the canal rows (status 4 with every method, the
    whole lap): the support of the larger set (without the rows) is an upper bound on the
    smaller set's, so the certificates stay valid; the fallback is counted."""
    from types import SimpleNamespace

    import motioncue.cueing._bound as bound

    real = bound._linprog

    def failing(c: np.ndarray, **kw: object) -> object:
        rates = {float(THR[3]), float(THR[4])}  # the canal rows' variables are bounded so
        if any(isinstance(bd, tuple) and bd[1] in rates for bd in kw.get("bounds", ())):  # type: ignore[attr-defined]
            return SimpleNamespace(status=4, message="HiGHS Status 4: Solve error")
        return real(c, **kw)

    f, w = _drive()
    free = cue_bound(f, FS, REACH, corr_min=None)
    monkeypatch.setattr(bound, "_linprog", failing)
    b = cue_bound(f, FS, REACH, corr_min=None, w_vehicle=w, forbid_false_rotation=True)
    assert int(b.solver["rotation_fallbacks"]) >= 3
    np.testing.assert_allclose(b.gain_max_any, free.gain_max_any, rtol=1e-9)
    np.testing.assert_allclose(b.gain_max, free.gain_max, rtol=1e-9)
