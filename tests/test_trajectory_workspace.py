"""Workspace limiting: reachable results, direction kept, reachable poses untouched."""

from __future__ import annotations

import numpy as np
import pytest

import motioncue
from motioncue.trajectory import ActuatorLimits, limit_pose

SIGMA = np.array([0.1, 0.1, 0.05, 0.3, 0.3, 0.5])


@pytest.fixture(scope="module", params=["stewart6-linear", "stewart6-rotary", "seat3"])
def platform(request):
    return motioncue.load_platform(request.param)


def test_batch_results_are_reachable_keep_direction_and_are_maximal(platform):
    rng = np.random.default_rng(0)
    req = rng.normal(0.0, SIGMA, (400, 6))
    res = limit_pose(platform, req)
    mask = platform.dof_mask
    req_m = np.where(mask, req, 0.0)
    assert np.all(platform.check(res.pose).ok)
    # direction kept: the result is scale * (request without unsupported components)
    np.testing.assert_allclose(res.pose, res.scale[:, None] * req_m, atol=1e-15)
    assert np.all((res.scale >= 0) & (res.scale <= 1))
    np.testing.assert_array_equal(res.dropped, (req != 0) & ~mask)
    np.testing.assert_allclose(res.amount, req - res.pose, atol=1e-15)
    clamped = res.status == "clamped"
    assert clamped.any() and (~clamped).any()
    # maximal to the documented resolution: a little further out is infeasible (oracle:
    # the platform's own check on scaled poses)
    s_more = np.minimum(res.scale[clamped] + 16.0**-3 * 1.01, 1.0)
    further = s_more[:, None] * req_m[clamped]
    assert not np.any(platform.check(further).ok)


def test_reachable_poses_are_untouched(platform):
    rng = np.random.default_rng(1)
    req = np.where(platform.dof_mask, rng.normal(0.0, SIGMA * 0.05, (200, 6)), 0.0)
    assert np.all(platform.check(req).ok)
    res = limit_pose(platform, req)
    assert np.array_equal(res.pose, req)
    assert np.all(res.status == "ok") and np.all(res.scale == 1.0)


def test_single_pose_and_invalid_pose():
    p = motioncue.load_platform("stewart6-linear")
    res = limit_pose(p, [0.3, 0, 0.1, 0, 0, 0.5])
    assert res.status == "clamped" and 0 < res.scale < 1
    assert p.check(res.pose).ok
    bad = limit_pose(p, [np.nan, 0, 0, 0, 0, 0])
    assert bad.status == "invalid"
    np.testing.assert_array_equal(bad.pose, np.zeros(6))


def test_narrower_limits_are_respected():
    p = motioncue.load_platform("stewart6-linear")
    lim = ActuatorLimits(p.q_min * 0.5, p.q_max * 0.5, np.ones(6), np.ones(6))
    res = limit_pose(p, [0.0, 0.0, 0.06, 0.0, 0.0, 0.0], limits=lim)
    assert res.status == "clamped"
    assert np.all(lim.contains(p.inverse(res.pose)))


def test_single_pose_fast_path_agrees_with_the_batch_path():
    p = motioncue.load_platform("stewart6-linear")
    rng = np.random.default_rng(5)
    req = rng.normal(0.0, SIGMA * 0.3, (300, 6))
    batch = limit_pose(p, req)
    singles = [limit_pose(p, x) for x in req]
    assert {r.status for r in singles} == {"ok", "clamped"}
    for r, s_b, st_b, x in zip(singles, batch.scale, batch.status, req, strict=True):
        assert r.status == st_b
        assert p.check(r.pose).ok
        np.testing.assert_allclose(r.pose, r.scale * x, atol=1e-15)
        # same boundary to the batch grid's resolution (17**-3 per bracket)
        assert abs(r.scale - s_b) <= 17.0**-3 + 1e-9
        if r.status == "ok":
            assert np.array_equal(r.pose, x)


@pytest.mark.parametrize(
    "pose",
    [
        [1e308, 1e308, 0, 0, 0, 0],
        [1e200, 0, 0, 0, 0, 0],
        [0, -1e300, 1e300, 0, 0, 0],
        [0, 0, 0, 1e308, -1e308, 0],
    ],
)
def test_absurd_finite_poses_are_clamped_not_a_crash(pose):
    """Finite but absurd poses (a float's square overflows) are bad input: clamped towards
    neutral with finite actuator positions, single pose and batch alike, never an exception
    (the single-pose path raised OverflowError from ``** 2`` on plain floats)."""
    p = motioncue.kinematics.load_platform("stewart6-linear")
    one = limit_pose(p, np.array(pose, dtype=float))
    with np.errstate(over="ignore", invalid="ignore"):
        batch = limit_pose(p, np.array([pose, pose], dtype=float))
    assert one.status == "clamped" and list(batch.status) == ["clamped", "clamped"]
    for r in (one.pose, *batch.pose):
        assert np.all(np.isfinite(r)) and np.all(np.abs(r[:3]) < 0.5)
    assert np.all(np.isfinite(one.q)) and np.all(np.isfinite(batch.q))
    assert limit_pose(p, one.pose).status == "ok"
