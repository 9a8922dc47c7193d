"""Model-predictive and optimal cueing: independent checks of the QP, limits, bad input."""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import load_cueing, make_cueing
from motioncue.cueing._mpc import DaqpQp, MpcCueing, QpSolver, block_ends, condense
from motioncue.cueing._mpc_params import MpcParams
from motioncue.cueing._optimal import OptimalCueing
from motioncue.kinematics import load_platform
from motioncue.output._controllers import load_controller
from motioncue.trajectory import ActuatorLimits

G = 9.80665
FS = 100.0
REC = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "chicane-gt.csv"


def _drive(start: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    a = np.loadtxt(REC, delimiter=",", skiprows=1, max_rows=start + n)[start:]
    return a[:, 1:4].copy(), a[:, 4:7].copy()


def _with(params, **kw):  # type: ignore[no-untyped-def]
    return dataclasses.replace(params, mpc=dataclasses.replace(params.mpc, **kw))


@pytest.fixture(scope="module")
def hexapod() -> MpcCueing:
    design = make_cueing(_with(load_cueing("mpc-hexapod"), deadline_ms=1e6), FS)
    assert isinstance(design, MpcCueing)
    return design


@pytest.fixture(scope="module")
def unblocked() -> MpcCueing:
    """A short horizon without move blocking (every sample its own input)."""
    return MpcCueing(_with(load_cueing("mpc-hexapod"), horizon_s=0.2, blocks=200), FS)


def test_unconstrained_first_move_is_the_lq_feedback_of_scipys_riccati(
    unblocked: MpcCueing,
) -> None:
    from scipy.linalg import solve_discrete_are

    m = unblocked.model
    p = solve_discrete_are(m.a, m.bu, m.q + 1e-12 * np.eye(m.nx), m.r)
    k_lq = np.linalg.solve(m.r + m.bu.T @ p @ m.bu, m.bu.T @ p @ m.a)
    rng = np.random.default_rng(1)
    for _ in range(5):
        state = unblocked.initial_state()
        state.x = rng.normal(scale=1e-4, size=m.nx)
        qp = unblocked.qp_matrices(state.x, np.zeros(6))
        a_mat, lba, uba = qp.a, qp.lba, qp.uba
        ok, u, _, _ = unblocked._qp.solve(qp)
        assert ok
        assert np.all(a_mat @ u < uba - 1e-9) and np.all(a_mat @ u > lba + 1e-9)  # inactive
        np.testing.assert_allclose(u[: m.nu], -k_lq @ state.x, rtol=1e-6, atol=1e-9)


def test_finite_horizon_without_terminal_cost_matches_a_riccati_recursion(
    unblocked: MpcCueing,
) -> None:
    m = unblocked.model
    n = 20
    cond = condense(m, block_ends(n, n), np.ones(n + 1), terminal=False)
    # backward recursion: V_N = x'Qx, V_k = x'Qx + min_u u'Ru + V_{k+1}, V_0 without Q
    p = m.q.copy()
    for _ in range(n - 1):
        bp = m.bu.T @ p
        p = m.q + m.a.T @ p @ m.a - (bp @ m.a).T @ np.linalg.solve(m.r + bp @ m.bu, bp @ m.a)
    k0 = np.linalg.solve(m.r + m.bu.T @ p @ m.bu, m.bu.T @ p @ m.a)
    x0 = np.random.default_rng(2).normal(size=m.nx)
    u = np.linalg.solve(cond.hess, -(cond.gx @ x0))
    np.testing.assert_allclose(u[: m.nu], -k0 @ x0, rtol=1e-6, atol=1e-9)


def test_kkt_residuals_and_feasibility_on_random_active_problems(hexapod: MpcCueing) -> None:
    rng = np.random.default_rng(3)
    h = hexapod.cond.hess
    active_seen = 0
    for _ in range(30):
        x0 = np.zeros(hexapod.model.nx)
        x0[:6] = rng.uniform(-1, 1, 6) * np.array([0.02, 0.02, 0.01, 0.03, 0.03, 0.03])
        x0[6:12] = rng.uniform(-1, 1, 6) * 0.02
        d = rng.normal(scale=[8, 8, 3, 0.5, 0.5, 0.5])
        qp = hexapod.qp_matrices(x0, d)
        g, a_mat, lba, uba = qp.g, qp.a, qp.lba, qp.uba
        ok, u, la, lx = hexapod._qp.solve(qp)
        assert ok
        au = a_mat @ u
        tol = 1e-7 * (1 + np.abs(uba))
        assert np.all(au <= uba + tol) and np.all(au >= lba - tol)
        stat = h @ u + g + a_mat.T @ la + lx
        assert np.linalg.norm(stat) <= 1e-6 * (1 + np.linalg.norm(g))
        # complementarity: a multiplier only on a constraint at its bound, with the right sign
        at_hi = np.abs(au - uba) <= 1e-6 * (1 + np.abs(uba))
        at_lo = np.abs(au - lba) <= 1e-6 * (1 + np.abs(lba))
        big = np.abs(la) > 1e-8 * (1 + np.abs(la).max())
        assert np.all(at_hi[big & (la > 0)]) and np.all(at_lo[big & (la < 0)])
        active_seen += int(big.sum())
    assert active_seen > 0  # the random problems did reach the limits


def test_daqp_route_matches_casadis_solver_and_any_warm_start_gives_the_optimum(
    hexapod: MpcCueing,
) -> None:
    """The plan's own DAQP route (:class:`DaqpQp`) against casadi's qpOASES plugin (a second,
    primal active-set method) on random active problems; warm starts from the true active
    set, from the previous problem's, from the true one at the wrong bounds and from every
    row at once (more rows than unknowns: DAQP refuses it, the solve is retried cold) change
    the work, not the answer."""
    rng = np.random.default_rng(4)
    h = hexapod.cond.hess
    direct = DaqpQp(h, hexapod.n_rows)
    oracle = QpSolver("qpoases", h, hexapod.n_rows)
    prev = None
    active_seen = 0
    for _ in range(12):
        x0 = np.zeros(hexapod.model.nx)
        x0[:6] = rng.uniform(-1, 1, 6) * np.array([0.02, 0.02, 0.0, 0.03, 0.03, 0.0])
        x0[6:12] = rng.uniform(-1, 1, 6) * 0.02
        d = rng.normal(scale=[8, 8, 3, 0.5, 0.5, 0.5])
        qp = hexapod.qp_matrices(x0, d)
        ok_o, u_o, _, _ = oracle.solve(qp)
        ok, u, la, lx = direct.solve(qp)
        assert ok and ok_o
        scale = 1.0 + np.abs(u_o).max()
        np.testing.assert_allclose(u, u_o, rtol=0, atol=1e-6 * scale)
        active_seen += int(np.count_nonzero(la))
        flipped = (u, -la, -lx)  # the true active set, each row at its other bound
        every = (u, -np.where(la == 0, 1.0, la), -np.where(lx == 0, 1.0, lx))  # refused: cold
        for warm in ((u, la, lx), prev, flipped, every):
            ok_w, u_w, _, _ = direct.solve(qp, warm=warm)
            assert ok_w
            np.testing.assert_allclose(u_w, u_o, rtol=0, atol=1e-6 * scale)
        prev = (u, la, lx)
    assert active_seen > 0  # the problems did reach the limits


def test_the_guarded_plan_warm_starts_through_its_sign_guard() -> None:
    """With a sign guard the solve's warm start is the whole problem's (inputs and slacks):
    a warm-started run gives the cold run's plan."""
    params = _with(load_cueing("mpc-hexapod"), sign_guard=(0.7, 0.7, 0.0, 0.0, 0.0, 0.0))
    design = MpcCueing(_with(params, deadline_ms=1e6), FS)
    assert design._qp_guard is not None
    inner = design._qp_guard._qp
    real = inner.solve
    seen: list[int] = []

    def spy(qp, warm=None):  # type: ignore[no-untyped-def]
        seen.append(0 if warm is None or warm[1] is None else len(warm[1]))
        return real(qp, warm)

    inner.solve = spy  # type: ignore[method-assign]
    f, w = _drive(600, 120)
    warm_poses = design.run(f, w).poses
    n_rows = design.n_rows + design._qp_guard.n_guard
    assert seen[0] == 0 and all(k == n_rows for k in seen[1:])  # guard rows' multipliers too

    def cold(qp, warm=None):  # type: ignore[no-untyped-def]
        return real(qp)

    inner.solve = cold  # type: ignore[method-assign]
    cold_poses = design.run(f, w).poses
    np.testing.assert_allclose(warm_poses, cold_poses, rtol=0, atol=1e-6)
    assert np.abs(cold_poses).max() > 1e-3


def test_every_frame_is_within_the_actuator_limits(hexapod: MpcCueing) -> None:
    f, w = _drive(300, 900)
    f[100:160] *= 3.0  # a harsher excerpt than the drive itself
    res = hexapod.run(f, w)
    plat = load_platform("stewart6-linear")
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox6"), rate_hz=FS)
    q = plat.inverse(res.poses)
    assert np.all(q <= lim.q_max) and np.all(q >= lim.q_min)
    v = np.abs(np.diff(q, axis=0)) * FS
    a = np.abs(np.diff(q, 2, axis=0)) * FS * FS
    assert np.all(v <= lim.v_max * 1.0001) and np.all(a <= lim.a_max * 1.0001)
    rates = np.abs(np.diff(res.poses[:, 3:5], axis=0)) * FS
    assert rates.max() <= hexapod.limits.tilt_rate * (1 + 1e-6)
    assert res.fallbacks == 0 and np.abs(q).max() > 0.5 * hexapod.limits.q_half.max()


def test_streaming_equals_batch(hexapod: MpcCueing) -> None:
    f, w = _drive(400, 300)
    batch = hexapod.run(f, w).poses
    state = hexapod.initial_state()
    out = [0.0] * 6
    stream = np.array([list(hexapod.step(state, fk, wk, out)) for fk, wk in zip(f, w, strict=True)])
    np.testing.assert_array_equal(stream, batch)
    assert hexapod.stats(state)["solves"] == 300 and hexapod.stats(state)["p99_ms"] > 0


def test_nan_inf_and_spikes_are_held_and_never_reach_the_pose(hexapod: MpcCueing) -> None:
    f, w = _drive(500, 200)
    clean_f, clean_w = f.copy(), w.copy()
    bad = [20, 21, 80, 150]
    f[20] = np.nan
    w[21] = [np.inf, 0, 0]
    f[80] = [1e6, 0, G]
    w[150] = [0, -1e9, 0]
    for k in bad:  # the held value: the last good sample
        clean_f[k], clean_w[k] = clean_f[k - 1], clean_w[k - 1]
    res = hexapod.run(f, w)
    ref = hexapod.run(clean_f, clean_w)
    assert res.bad_samples == 4 and np.flatnonzero(res.bad_mask).tolist() == bad
    assert np.all(np.isfinite(res.poses))
    np.testing.assert_array_equal(res.poses, ref.poses)


def test_failed_solves_fall_back_smoothly_and_are_counted(
    hexapod: MpcCueing, monkeypatch: pytest.MonkeyPatch
) -> None:
    f, w = _drive(300, 400)
    # the solver the plan uses (with a sign guard, the one inside its soft-guard QP)
    qp = hexapod._qp if hexapod._qp_guard is None else hexapod._qp_guard._qp
    real = qp.solve
    calls = {"n": 0}

    def flaky(*args, **kw):  # type: ignore[no-untyped-def]
        calls["n"] += 1
        ok, u, la, lx = real(*args, **kw)
        return (ok and not 100 <= calls["n"] < 250), u, la, lx

    monkeypatch.setattr(qp, "solve", flaky)
    res = hexapod.run(f, w)
    assert res.fallbacks == 150
    assert np.all(np.isfinite(res.poses))
    # no jump: into and out of the fallback every leg stays within its speed and acceleration
    plat = hexapod.limits.platform
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox6"), rate_hz=FS)
    q = plat.inverse(res.poses)
    assert np.all(np.abs(np.diff(q, axis=0)) * FS <= lim.v_max * 1.0001)
    assert np.all(np.abs(np.diff(q, 2, axis=0)) * FS * FS <= lim.a_max * 1.0001)
    # and the fallback did steer towards the classical washout's pose
    classical = hexapod.classical.run(f, w).poses
    gap = np.abs(res.poses - classical).max(axis=1)
    assert gap[240] < gap[100]


def test_a_late_streaming_solve_is_counted_and_falls_back() -> None:
    design = make_cueing(_with(load_cueing("mpc-hexapod"), deadline_ms=0.1), FS)
    state = design.initial_state()
    f, w = _drive(300, 20)
    for fk, wk in zip(f, w, strict=True):
        pose = design.step(state, fk, wk)
        assert all(math.isfinite(v) for v in pose)
    st = design.stats(state)  # type: ignore[attr-defined]
    assert st["late"] >= 15 and st["fallbacks"] == st["late"] + st["failed"]


def test_mpc_table_is_validated_with_the_value_and_the_range(tmp_path: Path) -> None:
    src = (
        Path(__file__).resolve().parents[1] / "configs" / "cueing" / "mpc-hexapod.toml"
    ).read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(src.replace("horizon_s = 1.2", "horizon_s = -1.0"))
    with pytest.raises(ConfigError, match=r"horizon_s = -1.0 is invalid"):
        load_cueing(bad)
    bad.write_text(src.replace('solver = "daqp"', 'solver = "magic"'))
    with pytest.raises(ConfigError, match="magic"):
        load_cueing(bad)
    bad.write_text(src.replace("[mpc]", "[mpc]\nwhat = 1"))
    with pytest.raises(ConfigError, match="what"):
        load_cueing(bad)
    with pytest.raises(ConfigError, match="stride_s"):
        MpcParams(window_s=2.0, stride_s=3.0)
    with pytest.raises(ConfigError, match=r"tilt_rate_limit_rad_s = -1.0 is invalid"):
        MpcParams(tilt_rate_limit_rad_s=-1.0)
    line = next(ln for ln in src.splitlines() if ln.startswith("tilt_rate_limit_deg_s = "))
    bad.write_text(src.replace(line, "tilt_rate_limit_deg_s = 0"))
    with pytest.raises(ConfigError, match="tilt_rate_limit_deg_s = 0"):
        load_cueing(bad)


def test_optimal_is_offline_and_within_the_limits() -> None:
    params = _with(load_cueing("optimal-hexapod"), window_s=1.0, stride_s=0.5, block_samples=10)
    design = make_cueing(params, FS)
    assert isinstance(design, OptimalCueing)
    with pytest.raises(ConfigError, match="whole recording"):
        design.step(design.initial_state(), (0.0, 0.0, G), (0.0, 0.0, 0.0))
    f, w = _drive(300, 400)
    f[50] = np.nan
    res = design.run(f, w)
    assert res.bad_samples == 1 and np.all(np.isfinite(res.poses))
    plat = load_platform("stewart6-linear")
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox6"), rate_hz=FS)
    q = plat.inverse(res.poses)
    assert np.all(q <= lim.q_max) and np.all(q >= lim.q_min)
    assert np.abs(res.poses).max() > 1e-3


def test_the_bridge_runs_mpc_live_within_the_limits_and_reports_its_solves() -> None:
    from motioncue.pipeline._bridge import Bridge, BridgeConfig
    from motioncue.pipeline._verify import check_frames
    from test_bridge import GATE, FakeSource, ListTransport, _decode_frames

    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, rate_hz=FS)
    src, tr = FakeSource(), ListTransport()
    bridge = Bridge(
        platform, ctrl, load_cueing("mpc-hexapod"), src, tr, lim, BridgeConfig(FS, GATE)
    )
    f, w = _drive(300, 200)
    f[50] = np.nan
    with bridge:
        for k, (fk, wk) in enumerate(zip(f, w, strict=True)):
            src.put(tuple(fk.tolist()), tuple(wk.tolist()))
            time.sleep(1 / FS)
            # the bad sample stays the latest until the bridge has taken it: on a busy machine
            # the loop may miss frames, and the next sample would replace it unseen (a bound
            # for a bridge that never takes it, not a timing)
            end = time.monotonic() + 30.0
            while k == 50 and bridge.stats.cueing_bad_samples < 1 and time.monotonic() < end:
                time.sleep(0.001)
        during = bridge.stats
    final = bridge.stats
    assert during.state == "live" and final.error is None
    assert final.cueing["solves"] > 50 and final.cueing["p99_ms"] > 0.0
    assert "solve p99" in final.status_line() and final.cueing_bad_samples >= 1
    t, p = _decode_frames(tr.sent)
    chk = check_frames(t, p, lim.to_pulses_table(platform), start_at_rest=True)
    assert chk.ok, chk.summary()


@pytest.mark.parametrize("preset", ["mpc-seat3", "optimal-seat3"])
def test_seat3_presets_move_only_heave_roll_pitch_within_its_limits(preset: str) -> None:
    design = make_cueing(load_cueing(preset), FS)
    f, w = _drive(300, 600)
    poses = np.asarray(design.run(f, w).poses)
    assert np.all(poses[:, [0, 1, 5]] == 0.0) and np.abs(poses[:, 3:5]).max() > 1e-3
    plat = load_platform("seat3")
    lim = ActuatorLimits.from_platform(plat, load_controller("mbox3"), rate_hz=FS)
    q = plat.inverse(poses)
    assert np.all(q <= lim.q_max) and np.all(q >= lim.q_min)
    assert np.all(np.abs(np.diff(q, axis=0)) * FS <= lim.v_max * 1.0001)


def test_the_bridge_refuses_the_offline_optimal_algorithm_by_name() -> None:
    from motioncue.pipeline._bridge import Bridge, BridgeConfig
    from test_bridge import FakeSource, ListTransport

    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, rate_hz=FS)
    with pytest.raises(ConfigError, match="'optimal' needs the whole recording"):
        Bridge(
            platform,
            ctrl,
            load_cueing("optimal-hexapod"),
            FakeSource(),
            ListTransport(),
            lim,
            BridgeConfig(FS),
        )


def test_frames_on_arrival_refuse_mpc_and_the_cli_picks_fixed_frames_for_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """On arrival the cueing steps every millisecond: fine for the classical washout, not
    for a QP per step. The bridge refuses the pairing; ``--frames auto`` avoids it."""
    from motioncue.cli import main
    from motioncue.pipeline._bridge import Bridge, BridgeConfig
    from test_bridge import FakeSource, ListTransport

    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, rate_hz=FS)
    cfg = BridgeConfig(FS, frame_clock="arrival")
    with pytest.raises(ConfigError, match="'mpc' is meant for the frame rate"):
        Bridge(platform, ctrl, load_cueing("mpc-hexapod"), FakeSource(), ListTransport(), lim, cfg)
    from test_bridge_replay import write_f1_recording

    rec = tmp_path / "short.mctr"
    write_f1_recording(rec, 0.5)
    rc = main(["bridge", "--source", f"replay:{rec}?speed=1", "--platform", "stewart6-linear",
               "--controller", "mbox6", "--preset", "mpc-hexapod", "--target",
               f"file:{tmp_path / 'frames.bin'}", "--duration", "3"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 0, err
    assert "frames fixed" in err  # auto chose fixed frames for the MPC
