"""Kinematics: closed-form IK against independent oracles, FK round trips, Jacobian, checks."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import motioncue
from motioncue import ConfigError
from motioncue._config import config_dir
from motioncue.kinematics import (
    CheckResult,
    FKResult,
    Platform,
    Seat2Yaw,
    Seat3,
    Stewart6Linear,
    Stewart6Rotary,
    load_platform,
)

BUNDLED = ("stewart6-linear", "stewart6-rotary", "seat3", "seat2-yaw")


def _rot(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """R = Rz Ry Rx from elementary rotations (independent of the module's closed form)."""
    cx, sx = math.cos(roll), math.sin(roll)
    cy, sy = math.cos(pitch), math.sin(pitch)
    cz, sz = math.cos(yaw), math.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _random_reachable(p: Platform, n: int, seed: int) -> np.ndarray:
    """Random poses over the supported DOFs that pass check(), ``(n, 6)``."""
    rng = np.random.default_rng(seed)
    scale = np.array([0.12, 0.12, 0.08, 0.3, 0.3, 0.5]) * p.dof_mask
    out: list[np.ndarray] = []
    while sum(len(o) for o in out) < n:
        cand = rng.uniform(-1, 1, (4 * n, 6)) * scale
        out.append(cand[p.check(cand).ok])
    return np.concatenate(out)[:n]


@pytest.fixture(scope="module", params=BUNDLED)
def platform(request: pytest.FixtureRequest) -> Platform:
    return load_platform(request.param)


def _config(name: str) -> dict:
    with open(config_dir("platforms") / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


# --- loading and the public surface -------------------------------------------------------


def test_load_by_name_and_path_and_package_reexport() -> None:
    a = motioncue.load_platform("stewart6-linear")
    b = load_platform(config_dir("platforms") / "stewart6-linear.toml")
    assert isinstance(a, Stewart6Linear)
    assert np.array_equal(a.inverse(np.full(6, 0.01)), b.inverse(np.full(6, 0.01)))
    assert isinstance(load_platform("stewart6-rotary"), Stewart6Rotary)
    assert isinstance(load_platform("seat3"), Seat3)
    assert isinstance(load_platform("seat2-yaw"), Seat2Yaw)


def test_unknown_platform_name_lists_bundled() -> None:
    with pytest.raises(ConfigError, match="stewart6-linear"):
        load_platform("no-such-rig")


def test_attributes_have_contract_shapes(platform: Platform) -> None:
    n = platform.n_actuators
    assert len(platform.actuator_names) == n == len(platform.actuator_kinds)
    assert platform.dof_mask.shape == (6,) and platform.dof_mask.dtype == bool
    assert int(platform.dof_mask.sum()) == n
    for arr in (platform.q_neutral, platform.q_min, platform.q_max, platform.q_park):
        assert arr.shape == (n,)
    assert np.all(platform.q_neutral == 0.0)
    assert np.all(platform.q_min < 0.0) and np.all(platform.q_max > 0.0)
    assert np.all(platform.q_park >= platform.q_min) and np.all(platform.q_park <= platform.q_max)
    assert platform.pose_park.shape == (6,)
    # the park pose really gives the park actuator positions
    assert np.allclose(platform.inverse(platform.pose_park), platform.q_park, atol=1e-10)
    with pytest.raises(AttributeError):
        platform.name = "x"  # type: ignore[misc]
    with pytest.raises(ValueError):
        platform.q_min[0] = 1.0


def test_neutral_pose_gives_zero_and_inverse_shapes(platform: Platform) -> None:
    n = platform.n_actuators
    assert np.allclose(platform.inverse(np.zeros(6)), 0.0, atol=1e-12)
    assert platform.inverse(np.zeros((4, 5, 6))).shape == (4, 5, n)
    assert platform.jacobian(np.zeros((3, 6))).shape == (3, n, 6)
    res = platform.check(np.zeros((2, 6)))
    assert isinstance(res, CheckResult)
    assert res.q.shape == (2, n) and res.ok.shape == (2,) and res.unsupported.shape == (2, 6)
    assert res.ok.all()


def test_single_pose_path_matches_batch_path(platform: Platform) -> None:
    poses = _random_reachable(platform, 200, seed=1)
    batch = platform.inverse(poses)
    for pose, q in zip(poses, batch, strict=True):
        assert np.allclose(platform.inverse(pose), q, atol=1e-13, rtol=0)
        assert np.allclose(platform.inverse(list(pose)), q, atol=1e-13, rtol=0)


# --- independent oracles ------------------------------------------------------------------


def test_linear_neutral_lengths_from_config_by_hand() -> None:
    """Leg length at neutral computed from the config's numbers with plain trigonometry."""
    cfg = _config("stewart6-linear")
    g = cfg["geometry"]
    p = load_platform("stewart6-linear")
    for i in range(6):
        centre = 120.0 * (i // 2)
        side = -1.0 if i % 2 == 0 else 1.0
        ab = math.radians(centre + side * g["base_pair_angle_deg"])
        ap = math.radians(centre + side * g["platform_pair_angle_deg"])
        dx = g["platform_radius_mm"] * math.cos(ap) - g["base_radius_mm"] * math.cos(ab)
        dy = g["platform_radius_mm"] * math.sin(ap) - g["base_radius_mm"] * math.sin(ab)
        length_mm = math.sqrt(dx * dx + dy * dy + g["neutral_height_mm"] ** 2)
        assert p.neutral_absolute[i] == pytest.approx(length_mm * 1e-3, abs=1e-12)
        # the config comment promises mid-stroke at neutral
        s = cfg["stroke"]
        assert length_mm == pytest.approx(s["retracted_length_mm"] + s["stroke_mm"] / 2, abs=0.01)
    # pulses at neutral: (neutral length - retracted - lift) * pulses per metre
    d = cfg["drive"]
    expect = round(
        (555.0 - cfg["stroke"]["retracted_length_mm"] - d["home_lift_mm"])
        * d["pulses_per_rev"]
        / d["lead_mm"]
    )
    assert np.all(p.drives.to_pulses(p.q_neutral) == expect)


def test_seat_neutral_matches_config_heights() -> None:
    for name in ("seat3", "seat2-yaw"):
        cfg = _config(name)
        p = load_platform(name)
        mid = cfg["stroke"]["retracted_length_mm"] + cfg["stroke"]["stroke_mm"] / 2
        legs = p.n_actuators - (1 if name == "seat2-yaw" else 0)
        assert np.allclose(p.neutral_absolute[:legs], mid * 1e-3, atol=1e-12)


def test_known_answer_simple_geometry() -> None:
    """Anchors on two circles (base radius 1 m at c +- 10 deg, platform radius 0.5 m at
    c +- 50 deg, c = 0/120/240 deg), neutral height 1 m. By the law of cosines the horizontal
    leg span is d^2 = 1 + 0.25 - 2 * 0.5 * cos(angle between anchors), so:
    heave dz: L = sqrt(d^2 + (1 + dz)^2); yaw psi: angle 40 deg + psi for odd legs and
    40 deg - psi for even ones (they turn the other way round)."""
    base, plat = [], []
    for c in (0.0, 120.0, 240.0):
        for side in (-1.0, 1.0):
            a, b = math.radians(c + side * 10.0), math.radians(c + side * 50.0)
            base.append([math.cos(a), math.sin(a), 0.0])
            plat.append([0.5 * math.cos(b), 0.5 * math.sin(b), 0.0])
    p = Stewart6Linear(np.array(base), np.array(plat), 1.0, (1.1, 1.6))
    d2 = 1.25 - math.cos(math.radians(40.0))
    length0 = math.sqrt(d2 + 1.0)
    assert np.allclose(p.neutral_absolute, length0, atol=1e-15)
    q = p.inverse([0, 0, 0.25, 0, 0, 0])
    assert np.allclose(q + length0, math.sqrt(d2 + 1.25**2), atol=1e-15)
    psi = math.radians(15.0)
    q = p.inverse([0, 0, 0, 0, 0, psi])
    odd = math.sqrt(1.25 - math.cos(math.radians(40.0) + psi) + 1.0)
    even = math.sqrt(1.25 - math.cos(math.radians(40.0) - psi) + 1.0)
    assert np.allclose(q + length0, [even, odd] * 3, atol=1e-15)
    # sideways 0.1 m: leg 0 base at -10 deg, platform at -50 deg, both shifted by hand
    q = p.inverse([0, 0.1, 0, 0, 0, 0])
    dx = 0.5 * math.cos(math.radians(-50)) - math.cos(math.radians(-10))
    dy = 0.5 * math.sin(math.radians(-50)) + 0.1 - math.sin(math.radians(-10))
    assert q[0] + length0 == pytest.approx(math.sqrt(dx * dx + dy * dy + 1.0), abs=1e-15)


@pytest.mark.parametrize("name", ["stewart6-linear", "seat3", "seat2-yaw"])
def test_inverse_against_elementary_rotations(name: str) -> None:
    """Linear legs: |t + R p - b| with R built from elementary matrices."""
    platform = load_platform(name)
    legs = platform.legs
    poses = _random_reachable(platform, 100, seed=2)
    q = platform.inverse(poses)
    for pose, qi in zip(poses, q, strict=True):
        pm = pose * platform.dof_mask
        roll, pitch = pm[3], pm[4]
        yaw = 0.0 if platform.has_yaw_axis else pm[5]
        r = _rot(roll, pitch, yaw)
        t = pm[:3] + np.array([0, 0, legs.height])
        lengths = np.linalg.norm(t + legs.plat @ r.T - legs.base, axis=1)
        assert np.allclose(qi[: legs.n] + platform.neutral_absolute[: legs.n], lengths, atol=1e-13)
        if platform.has_yaw_axis:
            assert qi[-1] == pm[5]


def test_rotary_rod_length_oracle() -> None:
    """The crank angle found puts the crank tip exactly one rod length from the rod end."""
    p = load_platform("stewart6-rotary")
    legs = p.legs
    poses = _random_reachable(p, 300, seed=3)
    q = p.inverse(poses)
    for pose, qi in zip(poses, q, strict=True):
        r = _rot(*pose[3:])
        anchor = pose[:3] + np.array([0, 0, legs.height]) + legs.plat @ r.T
        theta = qi + p.neutral_absolute
        tip = legs.base + legs.crank[:, None] * (
            np.cos(theta)[:, None] * legs.e1 + np.sin(theta)[:, None] * legs.e2
        )
        assert np.allclose(np.linalg.norm(anchor - tip, axis=1), legs.rod, atol=1e-12)
        # the crank tip turns in the plane perpendicular to the crank axis
        assert np.allclose(np.einsum("ij,ij->i", tip - legs.base, legs.axes), 0.0, atol=1e-15)


# --- round trips and derivatives ----------------------------------------------------------


def test_fk_of_ik_round_trip_bundled(platform: Platform) -> None:
    poses = _random_reachable(platform, 2000, seed=4)
    q = platform.inverse(poses)
    worst = 0.0
    for pose, qi in zip(poses, q, strict=True):
        fk = platform.forward(qi)
        assert isinstance(fk, FKResult)
        assert fk.converged, (pose, fk)
        worst = max(worst, float(np.max(np.abs(fk.pose - pose * platform.dof_mask))))
    assert worst < 1e-9


def _random_user_hexapod(rng: np.random.Generator) -> Stewart6Linear:
    """A random, irregular but well-conditioned hexapod in SI."""
    while True:
        rb, rp = rng.uniform(0.3, 1.0), rng.uniform(0.2, 0.8)
        hb, hp = rng.uniform(5, 25), rng.uniform(35, 55)
        jitter = rng.normal(0, 2.0, (2, 6))
        base, plat = [], []
        for i in range(6):
            c = 120.0 * (i // 2)
            s = -1 if i % 2 == 0 else 1
            a = math.radians(c + s * hb + jitter[0, i])
            b = math.radians(c + s * hp + jitter[1, i])
            base.append([rb * math.cos(a), rb * math.sin(a), rng.normal(0, 0.01)])
            plat.append([rp * math.cos(b), rp * math.sin(b), rng.normal(0, 0.01)])
        height = rng.uniform(0.4, 1.2)
        base_a, plat_a = np.array(base), np.array(plat)
        length0 = np.linalg.norm(plat_a + np.array([0, 0, height]) - base_a, axis=1)
        stroke = np.stack([length0 - 0.1, length0 + 0.1], axis=1)
        p = Stewart6Linear(base_a, plat_a, height, stroke)
        if np.linalg.cond(p.jacobian(np.zeros(6))) < 50:
            return p


def test_fk_of_ik_round_trip_user_geometries() -> None:
    rng = np.random.default_rng(5)
    worst = 0.0
    for _ in range(10):
        p = _random_user_hexapod(rng)
        poses = rng.uniform(-1, 1, (200, 6)) * np.array([0.05, 0.05, 0.05, 0.1, 0.1, 0.1])
        for pose, qi in zip(poses, p.inverse(poses), strict=True):
            fk = p.forward(qi)
            assert fk.converged
            worst = max(worst, float(np.max(np.abs(fk.pose - pose))))
    assert worst < 1e-9


def test_jacobian_against_finite_differences(platform: Platform) -> None:
    poses = _random_reachable(platform, 50, seed=6)
    jac = platform.jacobian(poses)
    # fourth-order central difference: truncation ~h^4 f^(5) (large near a crank's dead
    # centre), rounding ~1e-16/h; both stay below 1e-8 here
    h = 1e-5
    for k in range(6):
        e = np.zeros(6)
        e[k] = h
        f = platform.inverse
        fd = (8 * (f(poses + e) - f(poses - e)) - (f(poses + 2 * e) - f(poses - 2 * e))) / (12 * h)
        assert np.allclose(jac[:, :, k], fd, atol=2e-8, rtol=1e-8), k


def test_blocked_batches_match_single_block(platform: Platform) -> None:
    """Batches longer than one internal block give the same numbers as short ones."""
    poses = np.random.default_rng(15).uniform(-0.02, 0.02, (20000, 6))
    q = platform.inverse(poses)
    jac = platform.jacobian(poses)
    res = platform.check(poses)
    for lo, hi in ((0, 100), (8100, 8300), (19900, 20000)):
        assert np.allclose(platform.inverse(poses[lo:hi]), q[lo:hi], rtol=0, atol=1e-15)
        assert np.allclose(platform.jacobian(poses[lo:hi]), jac[lo:hi], rtol=0, atol=1e-15)
        assert np.array_equal(platform.check(poses[lo:hi]).ok, res.ok[lo:hi])


def test_forward_with_guess_and_reports_iterations(platform: Platform) -> None:
    pose = _random_reachable(platform, 1, seed=7)[0]
    q = platform.inverse(pose)
    cold = platform.forward(q)
    warm = platform.forward(q, guess=pose)
    assert warm.converged and warm.iterations <= 1 < cold.iterations + 1
    assert warm.residual <= 1e-12


def test_forward_reports_failure_without_raising() -> None:
    p = load_platform("stewart6-linear")
    # legs shorter than zero (1 m below their 0.555 m neutral length): no pose can match;
    # must come back unconverged with a finite pose
    fk = p.forward(np.full(6, -1.0), max_iter=20)
    assert not fk.converged
    assert fk.iterations <= 20
    assert np.all(np.isfinite(fk.pose))


def test_mirror_symmetric_geometry_gives_mirror_lengths() -> None:
    """The bundled hexapods are symmetric about the x-z plane: mirroring a pose (y, roll, yaw
    change sign) permutes the legs 0<->1, 2<->5, 3<->4."""
    perm = [1, 0, 5, 4, 3, 2]
    for name in ("stewart6-linear", "stewart6-rotary"):
        p = load_platform(name)
        poses = _random_reachable(p, 300, seed=8)
        mirrored = poses * np.array([1, -1, 1, -1, 1, -1])
        assert np.allclose(p.inverse(mirrored), p.inverse(poses)[:, perm], atol=1e-12)
    s = load_platform("seat3")
    poses = _random_reachable(s, 300, seed=9)
    mirrored = poses * np.array([1, -1, 1, -1, 1, -1])
    assert np.allclose(s.inverse(mirrored), s.inverse(poses)[:, [1, 0, 2]], atol=1e-12)


# --- checks and bad input -----------------------------------------------------------------


def test_check_stroke_overshoot_is_signed_amount() -> None:
    p = load_platform("stewart6-linear")
    up = np.array([0, 0, 0.2, 0, 0, 0])
    res = p.check(up)
    assert not res.ok and not res.in_stroke.any()
    assert np.allclose(res.overshoot, res.q - p.q_max)
    assert np.all(res.overshoot > 0)
    down = p.check(-up)
    assert np.all(down.overshoot < 0) and np.allclose(down.overshoot, down.q - p.q_min)
    inside = p.check(np.array([0, 0, 0.01, 0, 0, 0]))
    assert inside.ok and np.all(inside.overshoot == 0)


def test_rotary_unreachable_reported_not_nan() -> None:
    p = load_platform("stewart6-rotary")
    far = np.array([0.0, 0.0, 0.5, 0.0, 0.0, 0.0])  # rods cannot reach this high
    q = p.inverse(far)
    assert np.all(np.isfinite(q))
    res = p.check(far)
    assert not res.reachable.any() and not res.ok
    # closest approach: the crank points straight at the rod end (tip up as far as it goes)
    legs = p.legs
    theta = q + p.neutral_absolute
    anchor = far[:3] + np.array([0, 0, legs.height]) + legs.plat
    d = anchor - legs.base
    tip_dir = np.cos(theta)[:, None] * legs.e1 + np.sin(theta)[:, None] * legs.e2
    in_plane = d - np.einsum("ij,ij->i", d, legs.axes)[:, None] * legs.axes
    in_plane /= np.linalg.norm(in_plane, axis=1)[:, None]
    assert np.allclose(tip_dir, in_plane, atol=1e-12)
    mixed = p.check(np.stack([far, np.zeros(6)]))
    assert list(mixed.ok) == [False, True]


def test_unsupported_dofs_held_and_reported() -> None:
    s = load_platform("seat3")
    pose = np.array([0.05, -0.02, 0.01, 0.02, 0.03, 0.1])
    assert np.array_equal(s.inverse(pose), s.inverse(pose * s.dof_mask))
    res = s.check(pose)
    assert list(res.unsupported) == [True, True, False, False, False, True]
    assert not s.check(pose * s.dof_mask).unsupported.any()
    y = load_platform("seat2-yaw")
    assert list(y.check(pose).unsupported) == [True, True, True, False, False, False]
    assert y.inverse(pose)[2] == pytest.approx(0.1)
    # the legs ignore the yaw (the turntable carries them)
    assert np.allclose(y.inverse(pose)[:2], y.inverse(pose * [0, 0, 0, 1, 1, 0])[:2])


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nonfinite_poses_rejected_with_clear_error(platform: Platform, bad: float) -> None:
    pose = np.zeros(6)
    pose[4] = bad
    for call in (platform.inverse, platform.check, platform.jacobian):
        with pytest.raises(ConfigError, match=r"poses\[4\]"):
            call(pose)
    batch = np.zeros((3, 6))
    batch[2, 1] = bad
    with pytest.raises(ConfigError, match=r"poses\[2, 1\]"):
        platform.inverse(batch)
    with pytest.raises(ConfigError, match=r"q\[0\]"):
        platform.forward(np.r_[bad, np.zeros(platform.n_actuators - 1)])


def test_wrong_shapes_rejected(platform: Platform) -> None:
    with pytest.raises(ConfigError, match="shape"):
        platform.inverse(np.zeros(5))
    with pytest.raises(ConfigError, match="shape"):
        platform.forward(np.zeros(platform.n_actuators + 1))


def _random_user_rotary(rng: np.random.Generator) -> Stewart6Rotary:
    """A random crank-and-rod hexapod built directly in SI, cranks near horizontal at neutral."""
    while True:
        rb, rp = rng.uniform(0.2, 0.5), rng.uniform(0.15, 0.45)
        hb, hp = rng.uniform(5, 20), rng.uniform(35, 55)
        crank, rod = rng.uniform(0.06, 0.15), rng.uniform(0.25, 0.6)
        base, plat, zero = [], [], []
        for i in range(6):
            c = 120.0 * (i // 2)
            s = -1.0 if i % 2 == 0 else 1.0
            a, b = math.radians(c + s * hb), math.radians(c + s * hp)
            base.append([rb * math.cos(a), rb * math.sin(a), 0.0])
            plat.append([rp * math.cos(b), rp * math.sin(b), 0.0])
            zero.append([-s * math.sin(a), s * math.cos(a), 0.0])
        base_a, plat_a, zero_a = np.array(base), np.array(plat), np.array(zero)
        tip = base_a[0] + crank * zero_a[0]
        span = float(np.linalg.norm(plat_a[0, :2] - tip[:2]))
        if span >= rod:
            continue
        height = math.sqrt(rod**2 - span**2)  # crank horizontal at neutral
        axes = np.cross(zero_a, [0.0, 0.0, 1.0])
        p = Stewart6Rotary(
            base_a, axes, zero_a, crank, rod, plat_a, height, (-math.radians(60), math.radians(60))
        )
        if np.linalg.cond(p.jacobian(np.zeros(6))) < 50:
            return p


def test_fk_of_ik_round_trip_user_rotary_geometries() -> None:
    rng = np.random.default_rng(11)
    worst = 0.0
    count = 0
    for _ in range(8):
        p = _random_user_rotary(rng)
        assert np.allclose(p.neutral_absolute, 0.0, atol=1e-9)
        poses = _random_reachable(p, 150, seed=int(rng.integers(1 << 30)))
        for pose, qi in zip(poses, p.inverse(poses), strict=True):
            fk = p.forward(qi)
            assert fk.converged
            worst = max(worst, float(np.max(np.abs(fk.pose - pose))))
            count += 1
    assert count == 1200 and worst < 1e-9


def test_seat_constructors_in_si_match_configs() -> None:
    cfg = _config("seat3")
    g = cfg["geometry"]
    loaded = load_platform("seat3")
    built = Seat3(
        np.array(g["base_anchors_mm"]) * 1e-3,
        np.array(g["platform_anchors_mm"]) * 1e-3,
        g["neutral_height_mm"] * 1e-3,
        (loaded.q_min[0] + 0.37, loaded.q_max[0] + 0.37),
    )
    poses = _random_reachable(loaded, 100, seed=12)
    assert np.allclose(built.inverse(poses), loaded.inverse(poses), atol=1e-15)
    assert np.allclose(built.q_min, loaded.q_min) and np.allclose(built.q_max, loaded.q_max)
    cfg = _config("seat2-yaw")
    g = cfg["geometry"]
    loaded2 = load_platform("seat2-yaw")
    built2 = Seat2Yaw(
        np.array(g["base_anchors_mm"]) * 1e-3,
        np.array(g["platform_anchors_mm"]) * 1e-3,
        g["neutral_height_mm"] * 1e-3,
        (0.313, 0.407),
        (-math.pi, math.pi),
    )
    poses = _random_reachable(loaded2, 100, seed=13)
    assert np.allclose(built2.inverse(poses), loaded2.inverse(poses), atol=1e-15)
    with pytest.raises(ConfigError, match="yaw_range"):
        Seat2Yaw(np.zeros((2, 3)), np.zeros((2, 3)), 0.3, (0.2, 0.4), (0.1, 1.0))


def test_seat2_yaw_mirror() -> None:
    p = load_platform("seat2-yaw")
    poses = _random_reachable(p, 200, seed=14)
    mirrored = poses * np.array([1, -1, 1, -1, 1, -1])
    q, qm = p.inverse(poses), p.inverse(mirrored)
    assert np.allclose(qm[:, [1, 0]], q[:, :2], atol=1e-12)
    assert np.allclose(qm[:, 2], -q[:, 2])


def test_si_constructor_rejects_bad_geometry() -> None:
    good = load_platform("stewart6-linear")
    with pytest.raises(ConfigError, match="base_anchors"):
        Stewart6Linear(np.zeros((5, 3)), good.legs.plat, 0.45, (0.485, 0.625))
    with pytest.raises(ConfigError, match="neutral_height"):
        Stewart6Linear(good.legs.base, good.legs.plat, math.nan, (0.485, 0.625))
    with pytest.raises(ConfigError, match="stroke"):
        Stewart6Linear(good.legs.base, good.legs.plat, 0.45, (0.625, 0.485))
    # six vertical legs cannot hold x, y or yaw
    ring = np.array([[math.cos(a), math.sin(a), 0.0] for a in np.radians(np.arange(0, 360, 60))])
    with pytest.raises(ConfigError, match="singular at the neutral pose"):
        Stewart6Linear(ring, ring, 1.0, (0.9, 1.1))
    # neutral outside the stroke
    with pytest.raises(ConfigError, match="neutral"):
        Stewart6Linear(good.legs.base, good.legs.plat, 0.45, (0.6, 0.7))


@settings(max_examples=200)
@given(
    name=st.sampled_from(BUNDLED),
    pose=st.lists(st.floats(-10.0, 10.0, allow_nan=False), min_size=6, max_size=6),
)
def test_any_finite_pose_gives_finite_positions(name: str, pose: list[float]) -> None:
    """Wild but finite requests never produce NaN: positions stay finite, check() says why."""
    p = load_platform(name)
    q = p.inverse(np.array(pose))
    assert np.all(np.isfinite(q))
    res = p.check(np.array([pose]))
    assert np.all(np.isfinite(res.q)) and np.all(np.isfinite(res.overshoot))
    assert np.array_equal(res.q[0], q) or np.allclose(res.q[0], q, atol=1e-12)
    assert res.ok[0] == bool(np.all(res.in_stroke[0] & res.reachable[0]))
