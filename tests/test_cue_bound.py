"""The physical bound (motioncue.cueing.cue_bound) against brute force and random motions.

On a four-sample problem the admissible platform motions of the relaxation are enumerated on
a grid: the error bound is at most the grid's least error and the gain bounds at least the
grid's largest gains; an independent solver (scipy trust-constr on the dense problem, and a
dense LP) finds the same optimum as the bound. On an excerpt of the bundled lap, random
admissible motions never beat the bound, whether the problem is solved at the full rate or
its certificate comes from a decimated one.
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import LinearConstraint, linprog, minimize

from motioncue import ConfigError
from motioncue.cueing import RigReach, cue_bound, get_model_set
from motioncue.telemetry._recording import read_recording_csv, resample

G = 9.80665
MS = get_model_set("telban-cardullo-2005")
THR = np.asarray(MS.thresholds)
TINY = RigReach(
    stroke_m=(0.2, 0.2),
    speed_m_s=(0.2, 0.2),
    accel_m_s2=(1.0, 1.0),
    tilt_rad=(math.asin(0.1), math.asin(0.1)),
    tilt_rate_rad_s=(0.2, 0.2),
)


def _h(n: int, fs: float, axis: int = 0) -> np.ndarray:
    """The otolith as an (n, n) matrix: column j is the response to a unit pulse at j."""
    return np.array([MS.otolith[axis].apply(e, fs) for e in np.eye(n)]).T


def _d2(n: int, fs: float) -> np.ndarray:
    """Central second difference as simulator_motion: the pose held before the first sample,
    continued at its last velocity after the last (``p[N] = 2 p[N-1] - p[N-2]``, so the last
    row is zero)."""
    d = np.zeros((n, n))
    for k in range(n - 1):
        d[k, max(k - 1, 0)] += 1.0
        d[k, k + 1] += 1.0
        d[k, k] -= 2.0
    return d * fs * fs


def _tiny_problem() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    n, fs = 4, 2.0
    f = np.zeros((n, 3))
    f[:, 0] = [3.0, -2.0, 4.0, 1.0]
    f[:, 1] = [0.5, 0.8, -0.3, 0.2]
    f[:, 2] = G
    return f, _h(n, fs), _d2(n, fs), MS.otolith[0].apply(f[:, 0], fs), fs


def _grid_motions(fs: float, d2: np.ndarray) -> np.ndarray:
    """Every (p, tau) on a 5-point grid per sample admissible in TINY: s = d2 p + g tau."""
    p_vals = np.linspace(-0.2, 0.2, 5)
    t_vals = np.linspace(-0.1, 0.1, 5)
    p = np.array(list(itertools.product(p_vals, repeat=4)))
    tau = np.array(list(itertools.product(t_vals, repeat=4)))
    ok_p = (np.abs(np.diff(p, axis=1)) <= 0.2 / fs + 1e-12).all(axis=1)
    ok_p &= (np.abs(p @ d2.T) <= 1.0 + 1e-12).all(axis=1)
    ok_t = (np.abs(np.diff(tau, axis=1)) <= 0.2 / fs + 1e-12).all(axis=1)
    sp, st = p[ok_p] @ d2.T, G * tau[ok_t]
    return (sp[:, None, :] + st[None, :, :]).reshape(-1, 4)


def test_tiny_problem_against_brute_force_and_a_second_solver() -> None:
    f, h, d2, v, fs = _tiny_problem()
    b = cue_bound(f, fs, TINY)
    s = _grid_motions(fs, d2)
    y = s @ h.T
    err = np.sqrt(np.mean((y - v) ** 2, axis=1))
    assert len(s) > 1000
    assert b.error_rms[0] <= err.min() + 1e-9  # a lower bound of every admissible motion
    gain = (y @ v) / (v @ v)
    reversal = ((np.abs(v) > THR[0]) & (np.abs(y) > THR[0]) & (y * v < 0)).any(axis=1)
    assert b.gain_max_any[0] >= gain.max() - 1e-9
    assert b.gain_max[0] >= gain[~reversal].max() - 1e-9
    assert b.gain_max[0] <= b.gain_max_any[0] + 1e-12
    # the optimum of the relaxation by an independent dense solver
    n = 4
    sm = np.hstack([d2, G * np.eye(n)])
    d1 = np.diff(np.eye(n), axis=0)
    z = np.zeros((n - 1, n))
    a = np.vstack([np.hstack([d1, z]), np.hstack([z, d1]), np.hstack([d2, np.zeros((n, n))])])
    hi = np.concatenate([np.full(2 * (n - 1), 0.2 / fs), np.full(n, 1.0)])
    box = [(-0.2, 0.2)] * n + [(-0.1, 0.1)] * n

    def obj(x: np.ndarray) -> float:
        r = h @ (sm @ x) - v
        return float(r @ r)

    def grad(x: np.ndarray) -> np.ndarray:
        return 2.0 * sm.T @ (h.T @ (h @ (sm @ x) - v))

    res = minimize(obj, np.zeros(2 * n), jac=grad, method="trust-constr", bounds=box,
                   constraints=[LinearConstraint(a, -hi, hi)],
                   options={"gtol": 1e-12, "xtol": 1e-14, "maxiter": 5000})  # fmt: skip
    # the interior point stops a hair inside the boxes (4e-9 above the optimum when it lies on
    # a vertex, as with the end continued at its velocity); an active-set polish from there
    # lands on it
    pol = minimize(obj, res.x, jac=grad, method="SLSQP", bounds=box,
                   constraints=[LinearConstraint(a, -hi, hi)],
                   options={"ftol": 1e-15, "maxiter": 1000})  # fmt: skip
    assert np.all(np.abs(a @ pol.x) <= hi + 1e-9)
    assert all(lo - 1e-9 <= x <= up + 1e-9 for x, (lo, up) in zip(pol.x, box, strict=True))
    best = math.sqrt(min(res.fun, pol.fun) / n)
    assert b.error_rms[0] == pytest.approx(best, rel=1e-4)
    assert err.min() >= best - 1e-9
    lp = linprog(-(sm.T @ (h.T @ v)), A_ub=np.vstack([a, -a]), b_ub=np.concatenate([hi, hi]),
                 bounds=box, method="highs")  # fmt: skip
    assert b.gain_max_any[0] == pytest.approx(-lp.fun / (v @ v), rel=1e-7)


@pytest.fixture(scope="module")
def lap() -> np.ndarray:
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"
    return np.asarray(resample(read_recording_csv(path), 100.0).f, dtype=float)


HEX = RigReach(
    stroke_m=(0.13, 0.115),
    speed_m_s=(0.54, 0.55),
    accel_m_s2=(21.4, 22.0),
    tilt_rad=(0.24, 0.23),
    tilt_rate_rad_s=(0.99, 0.90),
)


def _random_motion(rng: np.random.Generator, n: int, fs: float, i: int, d: np.ndarray):
    """A random admissible (p, tau) of HEX on channel i, scaled into every box."""
    t = np.arange(n) / fs
    p = sum(rng.normal() * np.sin(2 * np.pi * rng.uniform(0.05, 3) * t + rng.uniform(0, 6))
            for _ in range(4))  # fmt: skip
    if rng.uniform() < 0.5:  # half of them follow the vehicle's force by tilt
        tau = np.clip(d / G, -1, 1) + 0.2 * rng.normal() * np.sin(rng.uniform(0.1, 2) * t)
    else:
        tau = sum(rng.normal() * np.sin(2 * np.pi * rng.uniform(0.01, 1) * t) for _ in range(3))
    dd = _d2_apply(p, fs)
    kp = min(HEX.stroke_m[i] / np.abs(p).max(), HEX.speed_m_s[i] / fs / np.abs(np.diff(p)).max(),
             HEX.accel_m_s2[i] / np.abs(dd).max())  # fmt: skip
    kt = min(math.sin(HEX.tilt_rad[i]) / np.abs(tau).max(),
             HEX.tilt_rate_rad_s[i] / fs / np.abs(np.diff(tau)).max())  # fmt: skip
    return kp * p, kt * tau


def _d2_apply(p: np.ndarray, fs: float) -> np.ndarray:
    """As simulator_motion: held before the first sample, the last velocity continued."""
    pad = np.concatenate([p[:1], p, 2 * p[-1:] - p[-2:-1]])
    return (pad[2:] - 2 * pad[1:-1] + pad[:-2]) * fs * fs


# full rate; certificates from fs / 2 (600 samples solved as 300: the path a drive longer than
# primal_samples takes, at a quarter of the CPU of the 1500 samples it was tried on before)
@pytest.mark.parametrize("primal_samples", [1000, 300])
def test_random_motions_never_beat_the_bound(lap: np.ndarray, primal_samples: int) -> None:
    fs = 100.0
    n = 600
    f = lap[1000 : 1000 + n]
    # (the share bound: test_cue_bound_corr.py)
    b = cue_bound(f, fs, HEX, corr_min=None, primal_samples=primal_samples)
    assert b.solver["decimation"] == ("1" if primal_samples >= n else "2")
    rng = np.random.default_rng(7)
    for i in range(2):
        v = MS.otolith[i].apply(f[:, i], fs)
        assert b.vehicle_rms[i] == pytest.approx(math.sqrt(np.mean(v**2)), rel=1e-12)
        assert 0.0 < b.error_rms[i] < b.vehicle_rms[i]
        assert 0.0 < b.gain_max[i] <= b.gain_max_any[i] < 1.0
        for _ in range(12):
            p, tau = _random_motion(rng, n, fs, i, f[:, i])
            y = MS.otolith[i].apply(_d2_apply(p, fs) + G * tau, fs)
            assert math.sqrt(np.mean((y - v) ** 2)) >= b.error_rms[i]
            gain = float(y @ v / (v @ v))
            assert gain <= b.gain_max_any[i]
            if not np.any((np.abs(v) > THR[i]) & (np.abs(y) > THR[i]) & (y * v < 0)):
                assert gain <= b.gain_max[i]


def test_bad_input_is_refused() -> None:
    with pytest.raises(ConfigError, match="f_vehicle"):
        cue_bound(np.zeros((2, 3)), 100.0, HEX)
    with pytest.raises(ConfigError, match="sample rate"):
        cue_bound(np.zeros((10, 3)), 0.0, HEX)
    with pytest.raises(ConfigError, match="rig reach"):
        RigReach((0.1, -1.0), (0.1, 0.1), (1, 1), (0.1, 0.1), (1, 1))


def test_no_preset_beats_the_bound_through_compare(lap: np.ndarray) -> None:
    """The presets' delivered motion (exact kinematics, the chain's limits) against the bound
    of the relaxation (first order in the angles): never below the error bound, never above
    the gain bounds."""
    from motioncue.analysis._compare import compare_cueing
    from motioncue.cueing import load_cueing
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.telemetry._recording import Recording
    from motioncue.trajectory import ActuatorLimits

    platform = load_platform("stewart6-linear")
    limits = ActuatorLimits.from_platform(platform, load_controller("mbox6"), rate_hz=100.0)
    # 3 s of the lap and no extra cut of the share bound (one cone programme per channel, a
    # valid bound; the cuts are test_cue_bound_corr's): 8 s with cuts took three times the CPU
    # of 4 s, and 4 s 1.4 times that of these 3 s (10.9 against 7.3 s), which hold the presets
    # as close to the bound: least RMS error 1.095x the error bound (4 s: 1.086x), and the gain
    # without a reversal checked on three channels up to 0.71 of the gain bound (4 s: one,
    # 0.06 of it)
    n = 300
    rec = Recording(np.arange(n) / 100.0, lap[2000 : 2000 + n], np.zeros((n, 3)))
    presets = [(p, load_cueing(p)) for p in ("racing-hexapod", "optimal-hexapod", "racing")]
    res = compare_cueing([("lap", rec)], presets, platform, limits, bound=True, bound_corr_cuts=0)
    assert res.reach is not None and res.reach.coupling is not None
    assert res.reach is not None and "Physical bound" in res.summary()
    import json

    js = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert js["bounds"]["lap"]["gain_max"]["fy"] == pytest.approx(res.runs[0].bound.gain_max[1])
    for row, run in zip(res.rows(), res.runs, strict=True):
        assert run.bound is not None
        for i, a in enumerate(("fx", "fy")):
            assert row[f"rms_{a}_m_s2"] >= row[f"bound_error_{a}_m_s2"]
            assert row[f"gain_{a}"] <= run.bound.gain_max_any[i]
            if row[f"reversal_s_{a}"] == 0.0:
                assert row[f"gain_{a}"] <= row[f"bound_gain_{a}"]
            assert row[f"share_of_bound_pct_{a}"] == pytest.approx(
                100 * row[f"share_{a}"] / row[f"bound_gain_{a}"]
            )
            # the share bound at the correlation (test_cue_bound_corr.py checks its value)
            assert row[f"bound_share_corr_{a}"] == run.bound.share_max_at_corr[i]
            assert row[f"share_of_corr_bound_pct_{a}"] == pytest.approx(
                100 * row[f"share_{a}"] / row[f"bound_share_corr_{a}"]
            )
            if row[f"corr_{a}"] >= run.bound.corr_min[i]:
                assert row[f"share_{a}"] <= row[f"bound_share_corr_{a}"]
    assert js["bounds"]["lap"]["share_max_at_corr"]["fx"] == pytest.approx(
        res.runs[0].bound.share_max_at_corr[0]
    )
    assert "share <= fx" in res.summary() and "@corr fx" in res.table()


def test_an_lp_stopped_on_numerical_difficulties_is_solved_by_the_next_method() -> None:
    """HiGHS's default choice stopped with status 4 ("HiGHS Status 0: Not Set") on the gain LP
    of flowing-formula's samples 5000-5200 (the hexapod's reach, 100 Hz) and ``cue_bound``
    raised; the LP has a solution (status 0 with HiGHS's interior-point method), so the bound
    is computed, and each value is the one of a solve that never failed."""
    fs = 100.0
    path = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "flowing-formula.csv"
    f = resample(read_recording_csv(path), fs).f[5000:5200]
    b = cue_bound(f, fs, HEX, corr_min=None)  # raised ConfigError before
    assert np.all(np.isfinite(b.gain_max)) and np.all(b.gain_max <= b.gain_max_any)
    assert np.all(b.error_rms < b.vehicle_rms)


def test_each_lp_method_is_tried_while_one_stops_on_numerical_difficulties(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The retry itself, on the tiny problem: the first method made to report status 4 on
    every call, the bound equals the one of an untouched solve (to the LP's tolerance)."""
    import scipy.optimize

    f, *_, fs = _tiny_problem()
    ref = cue_bound(f, fs, TINY, corr_min=None)
    real, calls = scipy.optimize.linprog, []

    def first_method_fails(*args: object, **kw: object) -> object:
        calls.append(kw["method"])
        res = real(*args, **kw)
        if kw["method"] == "highs":
            res.status, res.message = 4, "(HiGHS Status 0: Not Set)"
        return res

    monkeypatch.setattr(scipy.optimize, "linprog", first_method_fails)
    got = cue_bound(f, fs, TINY, corr_min=None)
    assert "highs-ipm" in calls and "highs-ds" not in calls
    np.testing.assert_allclose(got.gain_max, ref.gain_max, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(got.error_rms, ref.error_rms, rtol=1e-6, atol=1e-9)
