"""The optimal plan's sign guard within its input blocks (``sign_guard_every``).

The rider's perceived motion is judged sample by sample, and a car's perceived roll rate can
change sign every few samples (a formula car's roll is small, its perceived rate mostly road
texture). With ``sign_guard_every = k`` the guard's rows (every guarded channel but fz) are
also set every ``k``-th sample within each block, not only at the block ends. Oracles: a
forward simulation of the plan's model sample by sample (for the condensed rows), the
evaluation's own vestibular filter of the poses (for the false cues).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import evaluate_cueing, load_cueing
from motioncue.cueing._mpc_params import MpcParams
from motioncue.cueing._optimal import OptimalCueing

FS = 100.0
ROOT = Path(__file__).resolve().parents[1]


def _with(params, **kw):  # type: ignore[no-untyped-def]
    return dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, **kw))


@pytest.mark.parametrize("bad", [-1, 101, 1.5, True, "1"])
def test_sign_guard_every_is_validated(bad: object) -> None:
    with pytest.raises(ConfigError, match=r"sign_guard_every = .* allowed: \[0, 100\]"):
        MpcParams(sign_guard_every=bad)  # type: ignore[arg-type]


def test_the_preset_reads_it_and_a_bad_one_is_refused(tmp_path: Path) -> None:
    mp = load_cueing("optimal-hexapod").mpc
    assert mp is not None and mp.sign_guard_every == 1
    src = (ROOT / "configs" / "cueing" / "optimal-hexapod.toml").read_text()
    assert "\nsign_guard_every = 1\n" in src
    for text, want in (("0", 0), ("3", 3)):
        good = tmp_path / f"every{want}.toml"
        good.write_text(src.replace("\nsign_guard_every = 1\n", f"\nsign_guard_every = {text}\n"))
        got = load_cueing(good).mpc
        assert got is not None and got.sign_guard_every == want
    bad = tmp_path / "bad.toml"
    bad.write_text(src.replace("\nsign_guard_every = 1\n", "\nsign_guard_every = -2\n"))
    with pytest.raises(ConfigError, match="sign_guard_every"):
        load_cueing(bad)


@pytest.mark.parametrize("every", [1, 2])
def test_the_inner_rows_are_the_perceived_motion_of_a_forward_simulation(every: int) -> None:
    params = _with(
        load_cueing("optimal-hexapod"),
        window_s=1.0,
        stride_s=0.5,
        block_samples=5,
        sign_guard_every=every,
    )
    design = OptimalCueing(params, FS)
    m = design.model
    n, bs = design.n_window, design.mpc.block_samples
    nb = n // bs
    inner = design._inner_samples()
    offs = [o for o in range(1, bs) if o % every == 0]
    assert inner.tolist() == [j * bs + o for j in range(nb) for o in offs]
    gi = design._inner_channels()
    assert 2 not in gi and set(gi) == {0, 1, 3, 4}
    rng = np.random.default_rng(3)
    x0 = rng.normal(scale=0.02, size=m.nx)
    d = rng.normal(scale=0.5, size=(n + 1, 6))
    u = rng.normal(scale=0.5, size=nb * m.nu)
    win = design._window_qp(x0, d)
    xv = np.zeros((n + 1, m.nx))  # a vehicle-only state of its own
    xv[0] = rng.normal(scale=0.02, size=m.nx)
    for k in range(1, n + 1):
        xv[k] = m.a @ xv[k - 1] + m.bd @ d[k - 1]
    sign = np.ones((n + 1, 6))  # every row bounded from below: lo = -g - free
    lo, hi = design._guard_bounds(win.xf, xv, sign)
    assert np.all(np.isinf(hi))
    ng = len(design._guard_channels())
    n_end = nb * ng
    g = np.asarray(design.mpc.sign_guard)[gi]
    free_in = (-np.asarray(lo[n_end:]).reshape(-1, len(gi)) - g).reshape(-1)
    got = design._a_guard[n_end:] @ u + free_in  # the rows' perceived motion (thresholds)
    # the oracle: the model stepped sample by sample with the blocked input
    x = x0.copy()
    want = np.zeros((n + 1, len(gi)))
    for k in range(1, n + 1):
        j = (k - 1) // bs
        x = m.a @ x + m.bu @ u[j * m.nu : (j + 1) * m.nu] + m.bd @ d[k - 1]
        want[k] = (m.ce[gi] @ (x - xv[k])) / m.thresholds[gi]
    np.testing.assert_allclose(got, want[inner].reshape(-1), rtol=1e-9, atol=1e-9)
    # the block ends' rows are unchanged
    assert design._a_guard.shape[0] == n_end + inner.size * len(gi)
    base = OptimalCueing(_with(params, sign_guard_every=0), FS)
    np.testing.assert_allclose(design._a_guard[:n_end], base._a_guard, rtol=0, atol=0)
    assert base._inner_samples().size == 0


def test_the_inner_guard_cuts_false_roll_cues_on_a_formula_drive() -> None:
    rec = ROOT / "configs" / "recordings" / "street-formula.csv"  # a tuning drive
    a = np.loadtxt(rec, delimiter=",", skiprows=1, max_rows=4000)[2500:4000]
    f, w = a[:, 1:4].copy(), a[:, 4:7].copy()
    base = load_cueing("optimal-hexapod")
    false_s, share = [], []
    for every in (0, 1):
        res = OptimalCueing(_with(base, sign_guard_every=every), FS).run(f, w)
        assert res.fallbacks == 0
        ev = evaluate_cueing(res.f_used, res.w_used, res.poses, FS)
        false_s.append(float(ev.false_cue_time_s[3] + ev.false_cue_time_s[4]))
        pv, ps = np.asarray(ev.perceived_vehicle), np.asarray(ev.perceived_sim)
        share.append(float(np.sqrt(np.mean(ps[:, 1] ** 2) / np.mean(pv[:, 1] ** 2))))
    # measured (15 s): 2.31 s of false roll and pitch cues at the block ends only, 0.82 s at
    # every sample; fy share 0.159 and 0.155
    assert false_s[0] > 1.0  # block ends only: the tilt's rate felt against the car's
    assert false_s[1] <= 0.5 * false_s[0]
    assert share[1] >= 0.9 * share[0]  # at (nearly) the same lateral strength


def test_the_working_set_gives_the_whole_qps_plan_with_the_inner_rows() -> None:
    rec = ROOT / "configs" / "recordings" / "street-formula.csv"  # a tuning drive
    a = np.loadtxt(rec, delimiter=",", skiprows=1, max_rows=2800)[2500:2800]
    f, w = a[:, 1:4].copy(), a[:, 4:7].copy()
    params = _with(load_cueing("optimal-hexapod"), window_s=1.0, stride_s=0.5)
    assert params.mpc is not None and params.mpc.sign_guard_every == 1
    fast = OptimalCueing(params, FS)
    whole = OptimalCueing(params, FS)
    object.__setattr__(whole, "_ws", None)  # every row and guard slack in every solve
    got, want = fast.run(f, w), whole.run(f, w)
    assert got.fallbacks == want.fallbacks == 0 and got.windows == want.windows >= 5
    assert np.ptp(want.poses[:, 3]) > np.radians(5.0)  # the excerpt moves the plan (roll)
    # the same optimum to DAQP's primal tolerance, carried by the state (as in
    # tests/test_optimal_working_set.py)
    np.testing.assert_allclose(got.poses, want.poses, rtol=0, atol=1e-5)  # m, rad
