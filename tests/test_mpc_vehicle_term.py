"""The plans' strength term (``[mpc] w_vehicle``, issue 20 item 7) against independent oracles.

``w_vehicle`` prices the perceived error to the vehicle's *whole* motion beside ``w_error``'s
error to the tracked (shrunk) reference; the code folds both into one error to a blended
reference. Checked here: the folded stage cost equals the two terms computed apart (each with
the unblended model, the way the plans priced the reference before), up to a constant, for
any platform motion; the reference a plan tracks is the closed-form blend; and the term does
what it is for: against a sustained corner the plan renders more of the vehicle's force than
the same plan without it, and standing still costs the vehicle's whole perceived motion.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import load_cueing
from motioncue.cueing._mpc import build_model, reference
from motioncue.cueing._mpc_params import MpcParams
from motioncue.cueing._optimal import OptimalCueing

FS = 100.0
G = 9.80665
DOFS = (True, True, False, True, True, False)  # x, y, roll, pitch: the hexapod presets' dofs


def _stage_error_cost(mp: MpcParams, u: np.ndarray, d_model: np.ndarray) -> float:
    """Sum over the samples of the weighted perceived-error rows of the stage cost, the model
    of ``mp`` driven by the inputs ``u`` (N, 4) and the motion it is given ``d_model``."""
    m = build_model(DOFS, mp, FS)
    x = np.zeros(m.nx)
    total = 0.0
    for k in range(u.shape[0]):
        x = m.a @ x + m.bu @ u[k] + m.bd @ d_model[k]
        e = m.zx[0:6] @ x + m.zd[0:6] @ d_model[k]
        total += float(e @ e)
    return total


def _vehicle(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(n) / FS
    d = np.zeros((n, 6))
    d[:, 0] = 6.0 * np.sin(2 * np.pi * 0.4 * t) + rng.normal(scale=0.5, size=n)
    d[:, 1] = 9.0 * np.sin(2 * np.pi * 0.25 * t + 0.3) + rng.normal(scale=0.5, size=n)
    d[:, 3:6] = rng.normal(scale=0.05, size=(n, 3))
    return d


def test_folded_cost_is_the_two_error_terms_up_to_a_constant() -> None:
    n = 300
    d = _vehicle(n, 1)
    we = (1.0, 0.7, 0.3, 0.4, 0.5, 0.3)
    wv = (0.3, 1.9, 0.0, 0.0, 0.2, 0.0)
    base = MpcParams(
        w_error=we,
        ref_scale=(0.2, 0.4, 0.0, 0.0, 0.0, 0.0),
        ref_limit=(1.5, 2.0, 1e9, 1e9, 1e9, 1e9),
        ref_shape=3.0,
    )
    folded = dataclasses.replace(base, w_vehicle=wv)
    r_shrunk, _ = reference(d, base, FS)
    r_blend, _ = reference(d, folded, FS)
    # the second method: the unblended model priced once against the shrunk reference with
    # w_error and once against the vehicle itself with w_vehicle (all channels weighed apart)
    to_vehicle = MpcParams(w_error=tuple(max(w, 1e-300) for w in wv))  # identity reference

    def two_terms(u: np.ndarray) -> float:
        return _stage_error_cost(base, u, r_shrunk) + _stage_error_cost(to_vehicle, u, d)

    rng = np.random.default_rng(2)
    moves = [np.zeros((n, 4)), *(rng.normal(scale=s, size=(n, 4)) for s in (0.5, 2.0, 5.0))]
    got = np.array([_stage_error_cost(folded, u, r_blend) for u in moves])
    want = np.array([two_terms(u) for u in moves])
    # equal up to one constant (the part of the cost no motion of the platform changes)
    diff_got, diff_want = got[1:] - got[0], want[1:] - want[0]
    np.testing.assert_allclose(diff_got, diff_want, rtol=1e-9)
    assert np.ptp(diff_want) > 1e-3 * np.abs(diff_want).max()  # the moves do change the cost


def test_reference_is_the_closed_form_blend() -> None:
    d = _vehicle(200, 3)
    mp = MpcParams(
        w_error=(1.0, 2.0, 0.3, 1.0, 1.0, 1.0),
        w_vehicle=(1.0, 0.5, 0.0, 0.0, 0.0, 3.0),
        ref_scale=(0.1, 0.3, 1.0, 1.0, 1.0, 0.0),
        ref_limit=(1.0, 1.0, 1e9, 1e9, 1e9, 1e9),
    )
    r, _ = reference(d, mp, FS)
    shrunk = np.array(d, copy=True)
    for i, (k, lim) in enumerate(((0.1, 1.0), (0.3, 1.0))):
        shrunk[:, i] = lim * np.tanh(k * d[:, i] / lim)
    shrunk[:, 5] = 0.0
    beta = np.array([0.5, 0.2, 0.0, 0.0, 0.0, 0.75])  # wv / (we + wv)
    np.testing.assert_allclose(r, (1 - beta) * shrunk + beta * d, rtol=1e-12, atol=1e-12)
    # without the term the reference is the shrunk copy alone
    np.testing.assert_array_equal(
        reference(d, dataclasses.replace(mp, w_vehicle=(0.0,) * 6), FS)[0], shrunk
    )


@pytest.mark.parametrize("bad", [(-0.1, 0, 0, 0, 0, 0), (float("nan"),) * 6, (1.0,) * 5])
def test_bad_weight_is_refused(bad: tuple[float, ...]) -> None:
    with pytest.raises(ConfigError, match="w_vehicle"):
        MpcParams(w_vehicle=bad)


def test_term_pursues_strength_on_a_sustained_corner() -> None:
    # 1.2 g of cornering for 6 s, ramped in over 1 s: a plan tracking a faint copy renders
    # little of it; priced against the whole vehicle the same plan tilts further (within
    # the rig), so the rider feels more of the corner, with the right sign
    n = 800
    ramp = np.clip(np.arange(n) / FS, 0.0, 1.0)
    f = np.stack([np.zeros(n), 12.0 * ramp, np.full(n, G)], axis=1)
    w = np.zeros((n, 3))
    params = load_cueing("optimal-hexapod")
    assert params.mpc is not None
    faint = dataclasses.replace(
        params,
        mpc=dataclasses.replace(
            params.mpc, ref_scale=(0.05, 0.05, 0.0, 0.0, 0.0, 0.0), w_vehicle=(0.0,) * 6
        ),
    )
    strong = dataclasses.replace(
        faint, mpc=dataclasses.replace(faint.mpc, w_vehicle=(0.0, 1.0, 0.0, 0.0, 0.0, 0.0))
    )
    held = slice(300, 600)
    rolls = []
    for p in (faint, strong):
        poses = OptimalCueing(p, FS).run(f, w).poses
        rolls.append(float(np.median(poses[held, 3])))
    # fy > 0 is felt by rolling right-side up (+roll: s_y = g roll)
    assert rolls[0] > 0.0 and rolls[1] > 0.0
    assert G * np.sin(rolls[0]) < 0.05 * 12.0 * 1.5  # the faint plan: about its 5 % copy
    assert rolls[1] > 2.0 * rolls[0], rolls
