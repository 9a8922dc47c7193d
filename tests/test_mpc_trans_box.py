"""The MPC's translation box (``[mpc] trans_limit_m``): its QP rows against an independent
integrator of the platform, and the plan's poses within it."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from motioncue._errors import ConfigError
from motioncue.cueing import load_cueing
from motioncue.cueing._mpc import MpcCueing
from motioncue.cueing._mpc_params import MpcParams

FS = 100.0
ROOT = Path(__file__).resolve().parents[1]
BOX_M = 0.03


def _design(**kw: object) -> MpcCueing:
    p = load_cueing("mpc-hexapod")
    assert p.mpc is not None
    return MpcCueing(dataclasses.replace(p, mpc=dataclasses.replace(p.mpc, **kw)), FS)


@pytest.fixture(scope="module")
def boxed() -> MpcCueing:
    return _design(trans_limit_m=(BOX_M, BOX_M, 1e9), deadline_ms=1e6)


def test_box_rows_predict_the_pose_of_a_plain_double_integrator(boxed: MpcCueing) -> None:
    """The box rows at each block end against the pose of the platform stepped sample by
    sample (exact zero-order hold of a double integrator, the blocked input held)."""
    m = boxed.model
    ends = boxed.cond.ends
    nb, nu = len(ends), m.nu
    active = list(m.active)
    boxed_dofs = [i for i in (0, 1) if i in active]  # x, y: the table's finite limits
    assert boxed_dofs == [0, 1]
    rng = np.random.default_rng(4)
    dt = 1.0 / FS
    for _ in range(5):
        x0 = np.zeros(m.nx)
        x0[:6] = rng.uniform(-0.02, 0.02, 6)
        x0[6:12] = rng.uniform(-0.1, 0.1, 6)
        d = rng.normal(scale=[5, 5, 1, 0.2, 0.2, 0.2])
        u_blocks = rng.normal(scale=2.0, size=(nb, nu))
        qp = boxed.qp_matrices(x0, d)
        a_mat, lba, uba = qp.a, qp.lba, qp.uba
        rows = a_mat[-nb * 2 :]
        lo, hi = lba[-nb * 2 :], uba[-nb * 2 :]
        # the rows are L - free <= ... : the predicted pose is rows @ U + (hi - L) offset
        pred = (rows @ u_blocks.reshape(-1) + (BOX_M - hi)).reshape(nb, 2)
        np.testing.assert_allclose(lo, -2 * BOX_M + hi, rtol=0, atol=1e-12)
        p = x0[:6].copy()
        v = x0[6:12].copy()
        got = []
        k = 0
        for b, end in enumerate(ends):
            acc = np.zeros(6)
            acc[active] = u_blocks[b]
            while k < end:
                p = p + v * dt + 0.5 * acc * dt * dt
                v = v + acc * dt
                k += 1
            got.append(p[boxed_dofs].copy())
        np.testing.assert_allclose(pred, np.array(got), rtol=1e-9, atol=1e-12)


def _corners() -> tuple[np.ndarray, np.ndarray]:
    """Left and right sustained corners (fy +-15 m/s^2 for 3 s each) with braking."""
    n = 900
    f = np.zeros((n, 3))
    f[:, 2] = 9.80665
    f[100:400, 1] = 15.0
    f[450:750, 1] = -15.0
    f[80:140, 0] = -20.0
    f[430:480, 0] = -20.0
    return f, np.zeros((n, 3))


def test_the_plan_stays_in_the_box_that_it_would_leave_without_it(boxed: MpcCueing) -> None:
    f, w = _corners()
    free = _design(deadline_ms=1e6).run(f, w)
    assert np.abs(free.poses[:, 1]).max() > 1.5 * BOX_M  # without the box it goes further
    res = boxed.run(f, w)
    assert res.fallbacks == 0  # every solve met the box (no infeasible QP)
    assert np.abs(res.poses[:, 0:2]).max() <= BOX_M + 1e-6  # 1 um: the QP solver's tolerance
    assert np.all(np.isfinite(res.poses))


@pytest.mark.parametrize("bad", [(0.0, 0.1, 1e9), (0.1, float("nan"), 1e9), (0.1, 0.1)])
def test_trans_limit_is_validated_with_the_value_and_the_range(bad: tuple[float, ...]) -> None:
    with pytest.raises(ConfigError, match=r"trans_limit_m = .* allowed: 3 numbers in \(0, 1e9\]"):
        MpcParams(trans_limit_m=bad)


def test_the_preset_table_reads_trans_limit_m_and_refuses_a_bad_one(tmp_path: Path) -> None:
    src = (ROOT / "configs" / "cueing" / "mpc-hexapod.toml").read_text()
    path = tmp_path / "boxed.toml"
    path.write_text(src.replace("\n[mpc]\n", "\n[mpc]\ntrans_limit_m = [0.05, 0.04, 1e9]\n"))
    mp = load_cueing(path).mpc
    assert mp is not None and mp.trans_limit_m == (0.05, 0.04, 1e9)
    path.write_text(src.replace("\n[mpc]\n", "\n[mpc]\ntrans_limit_m = [0.05, -0.04, 1e9]\n"))
    with pytest.raises(ConfigError, match="trans_limit_m"):
        load_cueing(path)
