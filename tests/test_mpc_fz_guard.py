"""The MPC's fz guard (``[mpc] fz_guard``, issue 20): the rider's perceived vertical force.

A tilt takes ``g (1 - cos roll cos pitch)`` off the rider's vertical force, which the plan's
linear model does not see; through the otolith model's lead a quick tilt is felt as up to
about twice that drop for seconds. Against a vehicle whose perceived fz is above its
threshold (downforce, a compression) that drop is an fz reversal. ``fz_guard = g`` keeps the
rider's perceived fz, linearised about the present tilt, at least ``-g`` thresholds there.
The oracle is the model set's own filter (:meth:`VestibularModelSet.filter`, the evaluation's
path) on the rider's exact specific force at the plan's poses.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import CueingParams, get_model_set, load_cueing
from motioncue.cueing._mpc import MpcCueing
from motioncue.cueing._mpc_params import MpcParams

FS = 100.0
G = 9.80665
MS = get_model_set("telban-cardullo-2005")
THR_Z = float(MS.thresholds[2])


def _rider_fz(poses: np.ndarray) -> np.ndarray:
    """The rider's perceived fz (m/s^2) from rest, through the model set's filter, of the
    specific force deviation the poses' tilt gives (R^T [0, 0, g], z component, less g)."""
    s = np.zeros((poses.shape[0], 6))
    s[:, 2] = G * (np.cos(poses[:, 3]) * np.cos(poses[:, 4]) - 1.0)
    return np.asarray(MS.filter(s, FS))[:, 2]


def _preset(fz_guard: float) -> CueingParams:
    params = load_cueing("mpc-hexapod")
    assert params.mpc is not None
    mp = dataclasses.replace(params.mpc, fz_guard=fz_guard, tilt_fz_use=0.0)
    return dataclasses.replace(params, mpc=mp)


def _downforce_corner(n: int) -> tuple[np.ndarray, np.ndarray]:
    """2.5 g of cornering and 0.3 g of extra vertical force (downforce), ramped in over 0.3 s."""
    ramp = np.clip(np.arange(n) / (0.3 * FS), 0.0, 1.0)
    f = np.stack([np.zeros(n), 25.0 * ramp, G + 3.0 * ramp], axis=1)
    return f, np.zeros((n, 3))


def test_rows_predict_the_riders_perceived_fz() -> None:
    """The rows' linear prediction at the block ends matches the model set's filter on the
    exact specific force of the poses the inputs give (to the linearisation's second order)."""
    mc = MpcCueing(_preset(0.7), FS)
    st = mc.initial_state()
    f, w = _downforce_corner(150)
    hist: list[list[float]] = []
    for k in range(150):
        hist.append(list(mc.step(st, f[k].tolist(), w[k].tolist())))
    roll0 = st.x[3]
    assert math.degrees(roll0) > 5.0  # tilted into the corner
    dv = np.array([0.0, 25.0, 3.0, 0.0, 0.0, 0.0])
    a, lo, hi = mc.fz_guard_rows(st, dv)
    assert np.all(np.isfinite(lo)) and np.all(hi == np.inf)  # the vehicle's fz is above
    rng = np.random.default_rng(3)
    m, c = mc.model, mc.cond
    n, nu = int(c.ends[-1]), m.nu
    blk = np.searchsorted(c.ends, np.arange(n), side="right")
    for scale in (0.0, 0.3):
        u = np.asarray(rng.normal(size=a.shape[1])) * scale
        pred = THR_Z * (a @ u - lo - 0.7)  # lo = -g - free / thr
        x = np.array(st.x, dtype=float)
        poses = list(hist)
        for k in range(n):
            j = blk[k]
            x = m.a @ x + m.bu @ u[j * nu : (j + 1) * nu]
            poses.append(x[:6].tolist())
        felt = _rider_fz(np.asarray(poses))
        at = np.asarray([len(hist) - 1 + int(e) for e in c.ends])
        pz = np.asarray(poses)
        dev = (pz[:, 3] - roll0) ** 2 + (pz[:, 4] - st.x[4]) ** 2
        worst = np.maximum.accumulate(dev)[at]  # the largest up to each block end
        # second order: the tangent's error is at most g dev / 2 at each step, felt up to
        # twice (the lead); the filters' discretisations differ by a small share
        tol = 2.0 * G * worst / 2.0 + 0.03 * np.abs(felt[at]) + 2e-3
        assert np.all(np.abs(pred - felt[at]) <= tol), (pred, felt[at], tol)
        assert np.max(np.abs(felt[at])) > 0.1  # a felt drop, not a trivial match


def test_guard_keeps_the_drop_from_reversing_the_vehicles_fz() -> None:
    """In a sustained downforce corner the plan without the guard tilts far enough for the
    rider to feel a drop beyond the fz threshold (an fz reversal); with ``fz_guard = 0.7``
    the felt drop stays near 0.7 thresholds, and the roll still renders the corner."""
    f, w = _downforce_corner(400)
    felt = {}
    roll = {}
    for g in (0.0, 0.7):
        mc = MpcCueing(_preset(g), FS)
        res = mc.run(f, w)
        assert res.fallbacks == 0
        felt[g] = _rider_fz(res.poses)
        roll[g] = np.degrees(res.poses[:, 3])
    assert felt[0.0].min() < -1.2 * THR_Z
    assert felt[0.7].min() > -0.85 * THR_Z
    assert roll[0.7][-100:].mean() > 6.0
    assert roll[0.7][-100:].mean() < roll[0.0][-100:].mean()


def test_no_rows_without_a_tilt_or_with_the_default() -> None:
    """The default (0) adds no rows; with the vehicle's fz below ``fz_guard_from`` no row
    binds; at rest the rows are zero."""
    mc = MpcCueing(_preset(0.0), FS)
    assert not mc._fz_guarded()
    mg = MpcCueing(_preset(0.7), FS)
    st = mg.initial_state()
    a, lo, _ = mg.fz_guard_rows(st, np.zeros(6))
    assert np.all(a == 0.0) and np.all(lo == -np.inf)
    a, lo, _ = mg.fz_guard_rows(st, np.array([0.0, 0.0, 3.0, 0.0, 0.0, 0.0]))
    assert np.all(a == 0.0) and np.allclose(lo[np.isfinite(lo)], -0.7)


@pytest.mark.parametrize(
    ("field", "value"), [("fz_guard", -0.1), ("fz_guard", 11.0), ("fz_guard_from", 101.0)]
)
def test_bad_values_are_rejected(field: str, value: float) -> None:
    with pytest.raises(ConfigError, match=field):
        if field == "fz_guard":
            MpcParams(fz_guard=value)
        else:
            MpcParams(fz_guard_from=value)


def test_pitch_share_scales_the_pitchs_part_of_the_rows() -> None:
    """``fz_guard_pitch = w`` scales the pitch's part of the rows (the linearisation's pitch
    slope): rows(w) = rows(0) + w (rows(1) - rows(0)); rows(0) has no pitch slope, so at a pose
    with no pitch every share gives the same rows."""
    rows = {}
    for share in (0.0, 0.5, 1.0):
        params = _preset(0.7)
        assert params.mpc is not None
        mp = dataclasses.replace(params.mpc, fz_guard_pitch=share)
        mc = MpcCueing(dataclasses.replace(params, mpc=mp), FS)
        st = mc.initial_state()
        st.x[3], st.x[4] = math.radians(8.0), math.radians(-6.0)  # rolled and pitched
        dv = np.array([0.0, 0.0, 3.0, 0.0, 0.0, 0.0])
        rows[share] = mc.fz_guard_rows(st, dv)[:2]
        st.x[4] = 0.0
        flat = mc.fz_guard_rows(st, dv)[:2]
        if share == 0.0:
            flat0 = flat
        for got, ref in zip(flat, flat0, strict=True):
            assert np.allclose(got, ref, rtol=1e-12, atol=1e-12)
    for i in range(2):
        mid = rows[0.0][i] + 0.5 * (rows[1.0][i] - rows[0.0][i])
        assert np.allclose(rows[0.5][i], mid, rtol=1e-9, atol=1e-12)
    assert not np.allclose(rows[1.0][0], rows[0.0][0])  # the pitch's slope is there
    # at rest the plan's free pose is the present one, where the tangent is exact whatever
    # its slope: the rows' bounds do not depend on the share
    assert np.allclose(rows[1.0][1], rows[0.0][1], rtol=1e-12, atol=1e-12)
