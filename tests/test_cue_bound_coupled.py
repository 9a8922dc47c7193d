"""The bound with translation and tilt coupled through the legs (RigReach.coupling).

Closed form: the support function in the direction of one sample's force, where the cut
corner of the (p, tau) square binds. Brute force: on a four-sample problem every motion of
a grid within the boxes *and* the half-planes stays within the coupled bounds, an independent
dense LP (the half-planes written out by the test) finds the coupled gain bound, and the
coupled bounds are never looser than the boxes' and tighter where the cut binds. The coupled
reach of the bundled hexapod contains random reachable poses and admissible rates (also
poses combining DOFs beyond the single-DOF box) and cuts the box's corners.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import linprog

from motioncue import ConfigError
from motioncue.cueing import ReachPolygon, RigReach, cue_bound, get_model_set
from motioncue.cueing._bound import _Channel, _second_difference, _support

G = 9.80665
MS = get_model_set("telban-cardullo-2005")
THR = np.asarray(MS.thresholds)
P, T = 0.2, 0.1  # stroke (m) and tilt term


def _cut(offset: float = 1.0, rate: float = 1e3) -> ReachPolygon:
    """The square |p| <= P, |tau| <= T with the corner (-P, +T) cut: -p/P + tau/T <= offset
    (the rates left free)."""
    normals = np.array([[-1.0 / P, 1.0 / T]])
    return ReachPolygon(normals, np.array([offset]), np.array([[1.0, 0.0]]), np.array([rate]))


def test_one_sample_support_closed_form() -> None:
    """max s_1 = (p0 - 2 p1 + p2) fs^2 + g tau_1 over three samples (rates and acceleration
    free): p0 = p2 = P and at sample 1 the best vertex of the cut square, (-P, 0) or (0, T):
    ``2 fs^2 P + max(2 fs^2 P, g T)``; without the cut ``4 fs^2 P + g T``."""
    fs = math.sqrt(G * T / (2.0 * P))  # 2 fs^2 P = g T: both vertices tie
    d2 = _second_difference(3, fs)
    base = _Channel(P, 1e3, 1e6, T, 1e3, fs, MS.otolith[0])
    c = np.array([0.0, 1.0, 0.0])
    two = 2.0 * fs * fs * P
    assert _support(base, c, d2) == pytest.approx(2.0 * two + G * T, rel=1e-9)
    cut = replace(base, poly=_cut())
    assert _support(cut, c, d2) == pytest.approx(two + max(two, G * T), rel=1e-9)
    # a cut that does not reach the square changes nothing
    assert _support(replace(base, poly=_cut(offset=2.5)), c, d2) == pytest.approx(
        2.0 * two + G * T, rel=1e-9
    )


def _tiny() -> tuple[np.ndarray, float, RigReach, RigReach]:
    n, fs = 4, 2.0
    f = np.zeros((n, 3))
    f[:, 0] = [3.0, -2.0, 4.0, 1.0]
    f[:, 1] = [-2.5, 1.8, -3.0, 2.2]
    f[:, 2] = G
    boxes = RigReach((P, P), (0.4, 0.4), (1.0, 1.0), (math.asin(T),) * 2, (0.2, 0.2))
    # the corner (+p, +tau) cut on both channels, and the rates' corner (+pdot, +taudot)
    poly = ReachPolygon(
        np.array([[1.0 / P, 1.0 / T]]), np.array([1.0]),
        np.array([[1.0 / 0.4, 1.0 / 0.2]]), np.array([1.2]),
    )  # fmt: skip
    return f, fs, boxes, replace(boxes, coupling=(poly, poly))


def _in_poly(p: np.ndarray, tau: np.ndarray, fs: float) -> np.ndarray:
    """Which rows (motions) of the grid the tiny problem's half-planes admit."""
    ok = (p / P + tau / T <= 1.0 + 1e-12).all(axis=1)
    return ok & (
        np.diff(p, axis=1) * fs / 0.4 + np.diff(tau, axis=1) * fs / 0.2 <= 1.2 + 1e-12
    ).all(axis=1)


def test_tiny_problem_coupled_against_brute_force_and_a_dense_lp() -> None:
    f, fs, boxes, coupled = _tiny()
    n = f.shape[0]
    b0 = cue_bound(f, fs, boxes, corr_min=(0.9, 0.9))
    b1 = cue_bound(f, fs, coupled, corr_min=(0.9, 0.9))
    assert b1.solver["coupling"] != "none" and b0.solver["coupling"] == "none"
    d2 = np.asarray(_second_difference(n, fs).todense())
    vals_p = np.linspace(-P, P, 5)
    vals_t = np.linspace(-T, T, 5)
    grid = np.array(list(itertools.product(range(5), repeat=2 * n)))  # 5^8 motions
    p, tau = vals_p[grid[:, :n]], vals_t[grid[:, n:]]
    ok = (np.abs(np.diff(p, axis=1)) * fs <= 0.4 + 1e-12).all(axis=1)
    ok &= (np.abs(p @ d2.T) <= 1.0 + 1e-12).all(axis=1)
    ok &= (np.abs(np.diff(tau, axis=1)) * fs <= 0.2 + 1e-12).all(axis=1)
    inside = ok & _in_poly(p, tau, fs)
    assert inside.sum() > 1000 and (ok & ~inside).sum() > 1000  # the cut removes motions
    s = p[inside] @ d2.T + G * tau[inside]
    for i in range(2):
        h = np.array([MS.otolith[i].apply(e, fs) for e in np.eye(n)]).T
        v = h @ f[:, i]
        y = s @ h.T
        err = np.sqrt(np.mean((y - v) ** 2, axis=1))
        gain = (y @ v) / (v @ v)
        rev = ((np.abs(v) > THR[i]) & (np.abs(y) > THR[i]) & (y * v < 0)).any(axis=1)
        assert b1.error_rms[i] <= err.min() + 1e-9
        assert b1.gain_max_any[i] >= gain.max() - 1e-9
        assert b1.gain_max[i] >= gain[~rev].max() - 1e-9
        yc, vc = y - y.mean(axis=1, keepdims=True), v - v.mean()
        corr = (yc @ vc) / np.maximum(np.linalg.norm(yc, axis=1) * np.linalg.norm(vc), 1e-300)
        share = np.sqrt(np.sum(y * y, axis=1) / (v @ v))
        assert b1.share_max_at_corr[i] >= share[corr >= 0.9].max() - 1e-9
        # coupled never looser than the boxes alone
        assert b1.error_rms[i] >= b0.error_rms[i] - 1e-9
        assert b1.gain_max_any[i] <= b0.gain_max_any[i] + 1e-9
        assert b1.share_max_at_corr[i] <= b0.share_max_at_corr[i] * (1 + 1e-6)
        # the dense LP written here: max <H s, v> over (p, tau) in the boxes and half-planes
        sm = np.hstack([d2, G * np.eye(n)])
        d1 = np.diff(np.eye(n), axis=0) * fs
        z = np.zeros((n - 1, n))
        a = np.vstack([
            np.hstack([d1, z]), -np.hstack([d1, z]), np.hstack([z, d1]), -np.hstack([z, d1]),
            np.hstack([d2, 0 * d2]), -np.hstack([d2, 0 * d2]),
            np.hstack([np.eye(n) / P, np.eye(n) / T]),
            np.hstack([d1 / 0.4, d1 / 0.2]),
        ])  # fmt: skip
        hi = np.concatenate([np.full(2 * (n - 1), 0.4), np.full(2 * (n - 1), 0.2),
                             np.full(2 * n, 1.0), np.ones(n), np.full(n - 1, 1.2)])  # fmt: skip
        lp = linprog(-(sm.T @ (h.T @ v)), A_ub=a, b_ub=hi,
                     bounds=[(-P, P)] * n + [(-T, T)] * n, method="highs")  # fmt: skip
        assert lp.status == 0
        assert b1.gain_max_any[i] == pytest.approx(-lp.fun / (v @ v), rel=1e-7)
    # the cut binds on this drive: strictly tighter on at least one channel
    assert np.any(b1.gain_max_any < b0.gain_max_any * (1 - 1e-3))


def test_reach_polygon_refuses_bad_input() -> None:
    with pytest.raises(ConfigError, match="offsets"):
        ReachPolygon(np.ones((1, 2)), np.array([0.0]), np.ones((1, 2)), np.array([1.0]))
    with pytest.raises(ConfigError, match="shapes"):
        ReachPolygon(np.ones((2, 2)), np.array([1.0]), np.ones((1, 2)), np.array([1.0]))
    with pytest.raises(ConfigError, match="coupling"):
        RigReach((0.1, 0.1), (0.1, 0.1), (1, 1), (0.1, 0.1), (1, 1), coupling=(1, 2))  # type: ignore[arg-type]


@pytest.fixture(scope="module")
def hexapod():  # type: ignore[no-untyped-def]
    from motioncue.analysis import rig_reach
    from motioncue.analysis._reach_coupling import reach_coupling
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.trajectory import ActuatorLimits

    pl = load_platform("stewart6-linear")
    lim = ActuatorLimits.from_platform(pl, load_controller("mbox6"), rate_hz=100.0)
    old = rig_reach(pl, lim)
    return pl, lim, old, reach_coupling(pl, lim, old)


def test_hexapod_coupled_reach_contains_reachable_poses_and_rates(hexapod) -> None:  # type: ignore[no-untyped-def]
    from motioncue.kinematics import dof_ranges
    from motioncue.trajectory import reachable

    pl, lim, old, new = hexapod
    rng = np.random.default_rng(123)  # not the seed the polygons were searched with
    box = dof_ranges(pl)
    span = np.maximum(np.abs(box.lower), np.abs(box.upper)) * 1.4  # beyond the single-DOF box
    cand = rng.uniform(-1, 1, (150000, 6)) * span * np.asarray(pl.dof_mask)
    poses = cand[reachable(pl, cand, limits=lim)]
    assert len(poses) > 200
    # combining DOFs goes beyond rig_reach's boxes: the widened boxes cover it
    assert (
        np.abs(poses[:, 0]).max() > old.stroke_m[0] or np.abs(poses[:, 4]).max() > old.tilt_rad[0]
    )
    taus = (-np.sin(poses[:, 4]), np.cos(poses[:, 4]) * np.sin(poses[:, 3]))
    v_lim = np.asarray(lim.v_max)
    jac = np.asarray(pl.jacobian(poses[:60]))
    for ch in range(2):
        poly = new.coupling[ch]
        pt = np.stack([poses[:, ch], taus[ch]], axis=1)
        assert np.all(pt @ poly.normals.T <= poly.offsets)
        assert np.all(np.abs(pt[:, 0]) <= new.stroke_m[ch])
        assert np.all(np.abs(pt[:, 1]) <= math.sin(new.tilt_rad[ch]))
        # rates: random pose rates scaled to the actuator speed limits
        for j in range(60):
            qd = rng.normal(size=(20, 6)) * np.asarray(pl.dof_mask)
            k = np.max(np.abs(qd @ jac[j].T) / v_lim, axis=1)
            qd = qd / k[:, None]
            r, pi = poses[j, 3], poses[j, 4]
            td = -np.cos(pi) * qd[:, 4] if ch == 0 else (
                np.cos(pi) * np.cos(r) * qd[:, 3] - np.sin(pi) * np.sin(r) * qd[:, 4])  # fmt: skip
            rt = np.stack([qd[:, ch], td], axis=1)
            assert np.all(rt @ poly.rate_normals.T <= poly.rate_offsets)
        # and the polygon cuts the box's corners: some diagonal offset is below the corner's
        corner = np.abs(poly.normals) @ np.array([new.stroke_m[ch], math.sin(new.tilt_rad[ch])])
        assert np.any(poly.offsets < 0.9 * corner)
