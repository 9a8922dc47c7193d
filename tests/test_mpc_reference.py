"""The tracked reference, the soft sign guard and their settings (issue 12's quality work)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import evaluate_cueing, load_cueing, make_cueing
from motioncue.cueing._mpc import MpcCueing, QpData, SoftGuardQp, SoftRows, reference
from motioncue.cueing._mpc_params import MpcParams
from motioncue.cueing._optimal import OptimalCueing

FS = 100.0
ROOT = Path(__file__).resolve().parents[1]
REC = ROOT / "configs" / "recordings" / "chicane-gt.csv"


def _drive(start: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    a = np.loadtxt(REC, delimiter=",", skiprows=1, max_rows=start + n)[start:]
    return a[:, 1:4].copy(), a[:, 4:7].copy()


def _with(params, **kw):  # type: ignore[no-untyped-def]
    return dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, **kw))


# ---------------------------------------------------------------------- reference
def test_reference_is_the_scaled_soft_limited_copy_and_identity_by_default() -> None:
    d = np.random.default_rng(1).normal(scale=6.0, size=(400, 6))
    same, _ = reference(d, MpcParams(), FS)
    np.testing.assert_array_equal(same, d)
    mp = MpcParams(
        ref_scale=(0.3, 0.5, 0.0, 1.0, 0.2, 0.0), ref_limit=(1.5, 2.0, 1e9, 0.1, 1e9, 1e9)
    )
    r, _ = reference(d, mp, FS)
    k = np.array(mp.ref_scale)
    lim = np.array(mp.ref_limit)
    for i in range(6):  # closed form, channel by channel
        want = k[i] * d[:, i] if lim[i] >= 1e9 else lim[i] * np.tanh(k[i] * d[:, i] / lim[i])
        np.testing.assert_allclose(r[:, i], want, rtol=1e-14, atol=1e-14)
    assert np.all(np.abs(r[:, 0]) < 1.5) and np.all(np.sign(r[:, 0]) == np.sign(d[:, 0]))


def test_compressive_reference_is_the_classical_curve_with_a_limit_per_sign() -> None:
    d = np.random.default_rng(3).normal(scale=8.0, size=(500, 6))
    mp = MpcParams(
        ref_scale=(0.4, 0.2, 0.0, 1.0, 1.0, 1.0),
        ref_limit=(1.7, 2.0, 1e9, 1e9, 1e9, 1e9),
        ref_limit_neg=(1.2, 2.5, 1e9, 1e9, 1e9, 1e9),
        ref_shape=3.0,
    )
    r, _ = reference(d, mp, FS)
    for i, (k, lp, ln) in enumerate(((0.4, 1.7, 1.2), (0.2, 2.0, 2.5))):
        y = k * d[:, i]  # the curve written out: k d / (1 + |k d / L|^p)^(1/p)
        lim = np.where(y > 0, lp, ln)
        want = y / (1.0 + np.abs(y / lim) ** 3.0) ** (1.0 / 3.0)
        np.testing.assert_allclose(r[:, i], want, rtol=1e-13, atol=1e-13)
        assert np.all(r[d[:, i] > 0, i] < lp) and np.all(r[d[:, i] < 0, i] > -ln)
        assert np.all(np.diff(r[np.argsort(d[:, i]), i]) >= 0.0)  # monotonic, sign kept
    small = reference(np.full((1, 6), 1e-3), mp, FS)[0][0]
    assert small[0] == pytest.approx(0.4e-3, rel=1e-9)  # small cues pass with the gain k
    np.testing.assert_array_equal(r[:, 3:], d[:, 3:])  # no limit: k d
    np.testing.assert_array_equal(r[:, 2], 0.0)


def test_small_cue_gain_adds_its_closed_form_before_the_vehicle_blend() -> None:
    d = np.random.default_rng(5).normal(scale=2.0, size=(600, 6))
    base = MpcParams(
        ref_scale=(0.1, 0.2, 0.0, 0.0, 0.0, 0.0),
        ref_limit=(1.5, 2.0, 1e9, 1e9, 1e9, 1e9),
        ref_shape=3.0,
        w_error=(8.0, 1.0, 0.3, 1.0, 1.0, 0.3),
    )
    mp = dataclasses.replace(base, ref_small_gain=(0.3, 0.5), ref_small_knee_m_s2=0.4)
    r0, _ = reference(d, base, FS)
    r1, _ = reference(d, mp, FS)
    for j, b in ((0, 0.3), (1, 0.5)):  # b K tanh(d / K), written out
        np.testing.assert_allclose(
            r1[:, j] - r0[:, j], b * 0.4 * np.tanh(d[:, j] / 0.4), rtol=1e-12, atol=1e-14
        )
    np.testing.assert_array_equal(r1[:, 2:], r0[:, 2:])
    # at most b K more on any cue; near zero the slope is the copy's plus b (finite difference)
    assert np.all(np.abs(r1[:, 0] - r0[:, 0]) <= 0.3 * 0.4 + 1e-15)
    h = 1e-6
    tiny = np.zeros((2, 6))
    tiny[1, 0] = h
    slope = (reference(tiny, mp, FS)[0][1, 0] - reference(tiny, mp, FS)[0][0, 0]) / h
    assert slope == pytest.approx(0.1 + 0.3, rel=1e-6)
    # with w_vehicle the boosted copy is blended with the whole vehicle: r' = r + beta (d - r)
    wv = (0.7, 0.0, 0.0, 0.0, 0.0, 0.0)
    rb, _ = reference(d, dataclasses.replace(mp, w_vehicle=wv), FS)
    beta = 0.7 / (8.0 + 0.7)
    np.testing.assert_allclose(rb[:, 0], r1[:, 0] + beta * (d[:, 0] - r1[:, 0]), rtol=1e-12)


def test_reach_limits_are_the_tilt_the_plan_can_hold_in_each_direction() -> None:
    from motioncue.cueing._mpc import plan_tilt_reach, resolve_reach, rig_limits

    params = load_cueing("optimal-hexapod")
    mp = dataclasses.replace(params.mpc, ref_shape=2.0, ref_reach_use=0.6)
    lim = rig_limits(params, mp, FS)
    reach = plan_tilt_reach(lim)
    for j, (axis, sign) in enumerate(((3, -1.0), (3, 1.0), (4, -1.0), (4, 1.0))):
        for angle, inside in ((reach[j], True), (reach[j] + math.radians(0.02), False)):
            pose = np.zeros(6)
            pose[axis] = sign * angle
            q = np.asarray(lim.platform.inverse(pose))
            assert bool(np.all(np.abs(q - lim.q_mid) <= lim.q_half)) is inside
    assert all(math.radians(5.0) < a < math.radians(20.0) for a in reach)
    got = resolve_reach(mp, lim)
    g = 9.80665
    rn, rp, pn, pp = reach
    # the plan's force of a tilt: fx = -g pitch, fy = +g roll (its linear model)
    assert got.ref_limit[:2] == pytest.approx((0.6 * g * pn, 0.6 * g * rp), rel=1e-12)
    assert got.ref_limit_neg is not None
    assert got.ref_limit_neg[:2] == pytest.approx((0.6 * g * pp, 0.6 * g * rn), rel=1e-12)
    assert got.ref_limit[2:] == mp.ref_limit[2:]
    assert resolve_reach(dataclasses.replace(mp, ref_reach_use=0.0), lim) == dataclasses.replace(
        mp, ref_reach_use=0.0
    )
    design = make_cueing(params, FS)
    assert isinstance(design, OptimalCueing) and design.mpc == resolve_reach(params.mpc, lim)


def test_split_reference_matches_an_explicit_recursion_and_streams_like_the_batch() -> None:
    rng = np.random.default_rng(2)
    d = rng.normal(scale=4.0, size=(600, 6)) + np.linspace(0, 8, 600)[:, None]
    mp = MpcParams(
        ref_scale=(0.3,) * 6, ref_limit=(1.5,) * 6, ref_split_hz=0.5, ref_scale_hf=(0.8,) * 6
    )
    batch, lp_end = reference(d, mp, FS)
    a = math.exp(-2.0 * math.pi * 0.5 / FS)
    lo = np.zeros(6)
    want = np.empty_like(d)
    for n in range(d.shape[0]):  # the documented recursion, written out
        lo = a * lo + (1.0 - a) * d[n]
        want[n] = 1.5 * np.tanh(0.3 * lo / 1.5) + 0.8 * (d[n] - lo)
    np.testing.assert_allclose(batch, want, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(lp_end, lo, rtol=1e-12)
    lp = None
    stream = np.empty_like(d)
    for n in range(d.shape[0]):
        stream[n], lp = reference(d[n], mp, FS, lp)
    np.testing.assert_allclose(stream, batch, rtol=1e-12, atol=1e-12)


# ---------------------------------------------------------------------- soft guard QP
def _soft_objective(hess, g, w, a_g, lo_g, hi_g):  # type: ignore[no-untyped-def]
    """The soft problem with the slacks eliminated: each row's violation, priced."""

    def f(u: np.ndarray) -> float:
        au = a_g @ u
        viol = np.where(np.isfinite(lo_g), np.maximum(lo_g - au, 0.0), 0.0)
        viol += np.where(np.isfinite(hi_g), np.maximum(au - hi_g, 0.0), 0.0)
        return float(0.5 * u @ hess @ u + g @ u + w * np.sum(viol + 0.5 * viol * viol))

    return f


@pytest.mark.parametrize("seed", range(6))
def test_soft_guard_qp_matches_a_general_minimiser_of_the_priced_problem(seed: int) -> None:
    from scipy.optimize import Bounds, LinearConstraint, minimize

    rng = np.random.default_rng(seed)
    n, n_rows, n_guard, w = 4, 3, 5, 7.0
    m = rng.normal(size=(n, n))
    hess = m @ m.T + n * np.eye(n)
    g = rng.normal(size=n) * 3
    a = rng.normal(size=(n_rows, n))
    lba, uba = -np.full(n_rows, 2.0), np.full(n_rows, 2.0)
    lbx, ubx = -np.full(n, 3.0), np.full(n, 3.0)
    a_g = rng.normal(size=(n_guard, n))
    side = rng.integers(0, 3, n_guard)  # 0: lower bound, 1: upper, 2: none
    val = rng.normal(size=n_guard) * 2
    lo_g = np.where(side == 0, val, -np.inf)
    hi_g = np.where(side == 1, val, np.inf)
    qp = SoftGuardQp("daqp", hess, n_rows, n_guard, w)
    ok, u, _, _ = qp.solve(QpData(g, a, lba, uba, lbx, ubx), SoftRows(a_g, lo_g, hi_g))
    assert ok
    # the same problem with explicit slacks, smooth, by scipy's SLSQP (a second method)
    lower = np.isfinite(lo_g)
    upper = np.isfinite(hi_g)

    def obj(z: np.ndarray) -> float:
        x, sl = z[:n], z[n:]
        return float(0.5 * x @ hess @ x + g @ x + w * np.sum(sl + 0.5 * sl * sl))

    eye = np.eye(n_guard)
    rows = [
        LinearConstraint(np.hstack([a, np.zeros((n_rows, n_guard))]), lba, uba),
        LinearConstraint(np.hstack([a_g, eye])[lower], lo_g[lower], np.inf),
        LinearConstraint(np.hstack([a_g, -eye])[upper], -np.inf, hi_g[upper]),
    ]
    ref = minimize(
        obj,
        np.zeros(n + n_guard),
        jac=lambda z: np.concatenate([hess @ z[:n] + g, w * (1.0 + z[n:])]),
        hess=lambda z: np.block(
            [[hess, np.zeros((n, n_guard))], [np.zeros((n_guard, n)), w * eye]]
        ),
        method="trust-constr",
        bounds=Bounds(
            np.concatenate([lbx, np.zeros(n_guard)]),
            np.concatenate([ubx, np.full(n_guard, np.inf)]),
        ),
        constraints=[r for r in rows if r.A.shape[0]],
        options={"gtol": 1e-11, "xtol": 1e-13, "maxiter": 5000},
    )
    assert ref.success
    f = _soft_objective(hess, g, w, a_g, lo_g, hi_g)
    assert f(u) <= ref.fun + 1e-7 * (1 + abs(ref.fun))
    np.testing.assert_allclose(u, ref.x[:n], atol=1e-5)
    au = a @ u
    assert np.all(au <= uba + 1e-7) and np.all(au >= lba - 1e-7)


def test_a_feasible_guard_is_met_exactly() -> None:
    hess = np.diag([1.0, 2.0])
    g = np.array([-4.0, 1.0])  # unconstrained optimum u = (4, -0.5)
    qp = SoftGuardQp("daqp", hess, 0, 1, 1e4)
    big = np.full(2, 1e3)
    ok, u, _, _ = qp.solve(
        QpData(g, np.zeros((0, 2)), np.zeros(0), np.zeros(0), -big, big),
        SoftRows(np.array([[1.0, 0.0]]), np.array([-np.inf]), np.array([1.0])),
    )
    assert ok
    np.testing.assert_allclose(u, [1.0, -0.5], atol=1e-6)  # u0 <= 1 active, u1 free


# ---------------------------------------------------------------------- in the algorithms
def test_the_optimal_sign_guard_cuts_wrong_sign_cues_on_a_drive() -> None:
    f, w = _drive(0, 3000)
    base = _with(  # the hand-set plan before tuning: without a guard it cues against the car
        load_cueing("optimal-hexapod"),
        sign_guard=(0.0,) * 6,
        window_s=3.0,
        stride_s=2.0,
        ref_scale=(0.3, 0.3, 0.0, 0.0, 0.0, 0.0),
        ref_limit=(1.5, 1.5, 1e9, 1e9, 1e9, 1e9),
        tilt_rate_limit_rad_s=math.radians(2.5),
        w_error=(1.0, 1.0, 0.3, 3.0, 3.0, 0.3),
        w_pose=(30.0, 30.0, 30.0, 10.0, 10.0, 10.0),
        w_acc=(0.01, 0.01, 0.01, 10.0, 10.0, 10.0),
        ref_shape=0.0,
        ref_reach_use=0.0,
        w_vehicle=(0.0,) * 6,  # (the tuned preset's pull to the whole vehicle is not hand-set)
    )
    guarded = _with(base, sign_guard=(0.7, 0.7, 0.0, 0.0, 0.0, 0.0))
    times = []
    for params in (base, guarded):
        design = make_cueing(params, FS)
        assert isinstance(design, OptimalCueing)
        res = design.run(f, w)
        assert res.fallbacks == 0
        ev = evaluate_cueing(res.f_used, res.w_used, res.poses, FS)
        times.append(float(ev.false_cue_time_s[0] + ev.false_cue_time_s[1]))
    assert times[0] > 2.0  # without the guard the plan does cue against the vehicle ...
    assert times[1] <= 0.25 * times[0]  # ... and the guard removes most of it


def test_mpc_with_guard_and_split_streams_like_the_batch_and_resets() -> None:
    params = _with(
        load_cueing("mpc-hexapod"),
        ref_scale=(0.3, 0.3, 0.0, 0.0, 0.0, 0.0),
        ref_split_hz=0.5,
        ref_scale_hf=(1.0, 1.0, 0.0, 0.0, 0.0, 0.0),
        sign_guard=(0.7, 0.7, 0.0, 0.7, 0.7, 0.0),
        deadline_ms=1e6,
    )
    design = MpcCueing(params, FS)
    f, w = _drive(900, 150)
    batch = design.run(f, w).poses
    state = design.initial_state()
    stream = np.array([design.step(state, fk, wk) for fk, wk in zip(f, w, strict=True)])
    np.testing.assert_array_equal(stream, batch)
    assert np.abs(batch).max() > 1e-4 and np.all(np.isfinite(batch))
    design.reset(state)
    again = np.array([design.step(state, fk, wk) for fk, wk in zip(f, w, strict=True)])
    np.testing.assert_array_equal(again, batch)


# ---------------------------------------------------------------------- settings
def test_new_mpc_settings_are_validated_and_read_in_their_units(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"ref_scale = .* allowed: 6 numbers in \[0.0, 1.0\]"):
        MpcParams(ref_scale=(1.5, 0, 0, 0, 0, 0))
    with pytest.raises(ConfigError, match="sign_guard"):
        MpcParams(sign_guard=(-1.0, 0, 0, 0, 0, 0))
    with pytest.raises(
        ConfigError, match=r"ref_split_hz = 80.0 is invalid; allowed: \[0.0, 50.0\]"
    ):
        MpcParams(ref_split_hz=80.0)
    with pytest.raises(ConfigError, match="sign_guard_weight"):
        MpcParams(sign_guard_weight=0.0)
    with pytest.raises(ConfigError, match=r"ref_shape = 0.5 is invalid; allowed: 0 or \[1, 50\]"):
        MpcParams(ref_shape=0.5)
    with pytest.raises(ConfigError, match=r"ref_reach_use = 1.5 is invalid; allowed: \[0.0, 1.0\]"):
        MpcParams(ref_reach_use=1.5)
    for bad_gain in ((1.5, 0.0), (0.1,), (-0.1, 0.0), (math.nan, 0.0), 0.3, "ab"):
        with pytest.raises(ConfigError, match=r"ref_small_gain = .* allowed: two numbers"):
            MpcParams(ref_small_gain=bad_gain)  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match=r"ref_small_knee_m_s2 = 0.0 is invalid; allowed"):
        MpcParams(ref_small_knee_m_s2=0.0)
    src = (ROOT / "configs" / "cueing" / "optimal-hexapod.toml").read_text()
    import tomllib

    table = tomllib.loads(src)["mpc"]  # the file as a plain TOML reader sees it
    p = load_cueing("optimal-hexapod").mpc
    assert p is not None and p.ref_scale == tuple(table["ref_scale"])
    assert p.ref_limit[:3] == tuple(table["ref_limit_m_s2"])
    assert p.tilt_rate_limit_rad_s == pytest.approx(math.radians(table["tilt_rate_limit_deg_s"]))
    good = tmp_path / "deg.toml"
    lines = [ln for ln in src.splitlines() if not ln.startswith("ref_limit_deg_s")]
    good.write_text("\n".join(lines).replace("[mpc]", "[mpc]\nref_limit_deg_s = [6.0, 6.0, 1e12]"))
    q = load_cueing(good).mpc
    assert q is not None
    assert q.ref_limit[3] == pytest.approx(math.radians(6.0)) and q.ref_limit[5] == 1e9
    bad = tmp_path / "bad.toml"
    bad.write_text(src.replace("ref_limit_m_s2 = [", "ref_limit_m_s2 = [1.0, 2.0] # ["))
    assert bad.read_text() != src
    with pytest.raises(ConfigError, match="ref_limit_m_s2"):
        load_cueing(bad)


# ---------------------------------------------------------------------- tune and write
@pytest.mark.parametrize(
    "preset", ["mpc-hexapod", "optimal-hexapod", "optimal-seat3", "optimal-hexapod-auto"]
)
def test_a_plan_preset_written_by_tune_reads_back_the_same(preset: str, tmp_path: Path) -> None:
    from motioncue.cueing._tune import params_from_vector, preset_toml, vector_from_params

    base = load_cueing(preset)
    out = tmp_path / f"{preset}.toml"
    out.write_text(preset_toml(base, ["round trip"]))
    back = load_cueing(out)
    assert back.algorithm == base.algorithm and back.dofs == base.dofs
    assert back.mpc == base.mpc
    assert dataclasses.replace(back, name=base.name) == base
    moved = params_from_vector(base, vector_from_params(base) + 0.1)
    assert moved.mpc is not None and base.mpc is not None
    if base.mpc.ref_shape > 0.0:  # the strength table: gains per axis, reach share, exponent
        for got, was, hi in (
            (moved.mpc.ref_scale[0], base.mpc.ref_scale[0], 1.0),
            (moved.mpc.ref_scale[1], base.mpc.ref_scale[1], 1.0),
            (moved.mpc.ref_reach_use, base.mpc.ref_reach_use, 1.0),
            (moved.mpc.ref_shape, base.mpc.ref_shape, 8.0),
        ):
            assert got == pytest.approx(min(hi, was * math.exp(0.1)), rel=1e-9)
        assert moved.mpc.ref_limit == base.mpc.ref_limit
    else:
        assert moved.mpc.ref_limit[0] == pytest.approx(
            min(10.0, math.exp(math.log(min(max(base.mpc.ref_limit[0], 0.3), 10.0)) + 0.1))
        )
    assert moved.mpc.w_pose[2:] == base.mpc.w_pose[2:] and moved.f_scale == base.f_scale


def test_tune_drives_an_optimal_preset_and_never_returns_a_worse_one(tmp_path: Path) -> None:
    import contextlib
    import io

    from motioncue.cli import main
    from motioncue.telemetry import sample_drives
    from motioncue.telemetry._recording import Recording, read_recording_csv, write_recording_csv

    src = next(p for p in sample_drives("tuning", kind="car") if p.stem == "flowing-road")
    rec = read_recording_csv(src)
    a, b = 1700, 2100  # 4 s: the braking into a long corner (cues on fx and fy)
    part = tmp_path / "flowing-road-4s.csv"
    write_recording_csv(part, Recording(rec.t_s[a:b] - rec.t_s[a], rec.f[a:b], rec.w[a:b]))
    out = tmp_path / "tuned-optimal.toml"
    # one population about the base (the base itself its first member, as in every tune run):
    # 18 candidates of the plan's nine parameters, no generation after it
    args = [
        "tune", "--input", str(part), "--platform", "stewart6-linear", "--controller", "mbox6",
        "--preset", "optimal-hexapod", "--out", str(out), "--seed", "1", "--generations", "0",
        "--init-spread", "0.3", "--popsize", "2", "--workers", "1", "--json",
        "--objective", "strength",
    ]  # fmt: skip
    stdout, stderr = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
        status = main(args)
    assert status == 0, stderr.getvalue()
    import json

    report = json.loads(stdout.getvalue())
    before, after = report["before"], report["after"]
    # the base meets the default targets on this excerpt, so the result is at least as strong
    for m in (before, after):
        assert m["cue_metrics"]["false_any"] <= 0.15 and m["cue_metrics"]["reversals_any"] <= 0.02
    assert after["strength"] >= before["strength"] - 1e-9
    tuned = load_cueing(out)
    base = load_cueing("optimal-hexapod")
    assert tuned.algorithm == "optimal" and tuned.mpc is not None and base.mpc is not None
    assert tuned.f_scale == base.f_scale and tuned.mpc.sign_guard[:3] == base.mpc.sign_guard[:3]
    assert tuned.mpc.ref_shape >= 1.0 and 0.0 < tuned.mpc.ref_reach_use <= 1.0
