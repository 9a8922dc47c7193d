"""Actuator forces (Pinocchio RNEA through the leg Jacobian) against independent statics and
Newton-Euler written out by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.kinematics import (
    STANDARD_GRAVITY,
    Payload,
    actuator_forces,
    load_platform,
    pose_wrench,
)

G = STANDARD_GRAVITY
PAYLOAD = Payload(
    mass_kg=140.0,
    com_m=(0.08, -0.03, 0.35),
    inertia_kgm2=np.array([[14.0, 0.4, -1.1], [0.4, 16.0, 0.2], [-1.1, 0.2, 9.0]]),
)


def _rot(roll: float, pitch: float, yaw: float) -> np.ndarray:
    cx, sx = math.cos(roll), math.sin(roll)
    cy, sy = math.cos(pitch), math.sin(pitch)
    cz, sz = math.cos(yaw), math.sin(yaw)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    rz = np.array([[cz, -sz, 0], [sz, cz, 0], [0, 0, 1]])
    return rz @ ry @ rx


def _static_load(pose: np.ndarray, payload: Payload) -> tuple[np.ndarray, np.ndarray]:
    """Force and moment about the platform origin that hold the payload against gravity."""
    r = _rot(*pose[3:])
    weight_support = np.array([0.0, 0.0, payload.mass_kg * G])
    return weight_support, np.cross(r @ payload.com_m, weight_support)


def test_linear_hexapod_statics_level_at_rest() -> None:
    p = load_platform("stewart6-linear")
    res = actuator_forces(p, np.zeros((1, 6)), [0.0], PAYLOAD)
    f = res.forces[0]
    legs = p.legs
    anchors = legs.plat + np.array([0, 0, legs.height])  # base frame, neutral pose
    units = (anchors - legs.base) / np.linalg.norm(anchors - legs.base, axis=1)[:, None]
    # vertical components of the leg forces carry the payload weight
    assert np.sum(f * units[:, 2]) == pytest.approx(PAYLOAD.mass_kg * G, rel=1e-12)
    # independent 6x6 static equilibrium: sum f_i u_i = F, sum (p_i x f_i u_i) = M
    a = np.vstack([units.T, np.cross(legs.plat, units).T])
    force, moment = _static_load(np.zeros(6), PAYLOAD)
    f_hand = np.linalg.solve(a, np.concatenate([force, moment]))
    assert np.allclose(f, f_hand, rtol=1e-10, atol=1e-9)
    assert np.all(f > 0)  # a payload on top compresses every leg
    assert np.allclose(res.peak, np.abs(f))


def test_linear_hexapod_statics_tilted_and_shifted() -> None:
    p = load_platform("stewart6-linear")
    pose = np.array([0.03, -0.02, 0.01, 0.06, -0.05, 0.1])
    f = actuator_forces(p, pose[None], [0.0], PAYLOAD).forces[0]
    legs = p.legs
    r = _rot(*pose[3:])
    anchors = pose[:3] + np.array([0, 0, legs.height]) + legs.plat @ r.T
    units = (anchors - legs.base) / np.linalg.norm(anchors - legs.base, axis=1)[:, None]
    arms = anchors - (pose[:3] + np.array([0, 0, legs.height]))
    a = np.vstack([units.T, np.cross(arms, units).T])
    force, moment = _static_load(pose, PAYLOAD)
    assert np.allclose(a @ f, np.concatenate([force, moment]), rtol=1e-10, atol=1e-8)
    assert np.sum(f * units[:, 2]) == pytest.approx(PAYLOAD.mass_kg * G, rel=1e-10)


def test_rotary_hexapod_statics_rod_forces_to_crank_torques() -> None:
    """Rods are two-force members: solve their tensions from the platform's equilibrium,
    then each motor holds the torque of its rod force about the crank axis."""
    p = load_platform("stewart6-rotary")
    pose = np.array([0.01, 0.02, -0.01, 0.03, 0.02, -0.05])
    torque = actuator_forces(p, pose[None], [0.0], PAYLOAD).forces[0]
    legs = p.legs
    r = _rot(*pose[3:])
    origin = pose[:3] + np.array([0, 0, legs.height])
    anchors = origin + legs.plat @ r.T
    theta = p.inverse(pose) + p.neutral_absolute
    crank = legs.crank[:, None] * (
        np.cos(theta)[:, None] * legs.e1 + np.sin(theta)[:, None] * legs.e2
    )
    tips = legs.base + crank
    u = (anchors - tips) / np.linalg.norm(anchors - tips, axis=1)[:, None]
    a = np.vstack([u.T, np.cross(anchors - origin, u).T])
    force, moment = _static_load(pose, PAYLOAD)
    rod = np.linalg.solve(a, np.concatenate([force, moment]))  # push of each rod on platform
    # the rod pushes the crank tip with -rod*u; the motor balances that torque
    motor = np.einsum("ij,ij->i", np.cross(crank, rod[:, None] * u), legs.axes)
    assert np.allclose(torque, motor, rtol=1e-9, atol=1e-8)


def test_seat3_statics() -> None:
    p = load_platform("seat3")
    payload = Payload(95.0, (0.05, 0.04, 0.4))
    f = actuator_forces(p, np.zeros((1, 6)), [0.0], payload).forces[0]
    legs = p.legs  # vertical legs at neutral
    weight = payload.mass_kg * G
    assert f.sum() == pytest.approx(weight, rel=1e-12)
    # moments about the centre joint: sum f_i y_i = W y_c, sum f_i x_i = W x_c
    assert np.dot(f, legs.plat[:, 1]) == pytest.approx(weight * 0.04, rel=1e-10)
    assert np.dot(f, legs.plat[:, 0]) == pytest.approx(weight * 0.05, rel=1e-10)


def test_seat2_yaw_statics_joint_takes_weight_legs_take_moment() -> None:
    p = load_platform("seat2-yaw")
    payload = Payload(95.0, (-0.05, 0.02, 0.45))
    f = actuator_forces(p, np.zeros((1, 6)), [0.0], payload).forces[0]
    weight = payload.mass_kg * G
    x, y = p.legs.plat[:, 0], p.legs.plat[:, 1]
    # legs vertical at neutral: their moments about the joint balance the weight's
    assert np.dot(f[:2], y) == pytest.approx(weight * 0.02, rel=1e-10)
    assert np.dot(f[:2], x) == pytest.approx(weight * -0.05, rel=1e-10)
    assert f[2] == pytest.approx(0.0, abs=1e-9)  # no yaw torque at rest


def _trajectory(t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    amp = np.array([0.03, 0.02, 0.025, 0.05, 0.04, 0.08])
    w = np.array([2.1, 1.7, 3.0, 2.5, 1.3, 1.9])
    phase = np.array([0.1, 0.7, 1.3, 0.4, 2.0, 0.9])
    arg = t[:, None] * w + phase
    return amp * np.sin(arg), amp * w * np.cos(arg), -amp * w * w * np.sin(arg)


def test_wrench_against_hand_newton_euler() -> None:
    """F = m (a_com + g z); M_origin = c_w x F + I_w alpha + omega x I_w omega, with omega and
    alpha from the Euler-angle rates by numerical differentiation of R (no E matrix)."""
    t = np.linspace(0, 2, 9)
    poses, vel, acc = _trajectory(t)
    wrench = pose_wrench(poses, vel, acc, PAYLOAD)
    h = 1e-4
    for k, tk in enumerate(t):

        def rot_at(s: float) -> np.ndarray:
            return _rot(*_trajectory(np.array([s]))[0][0, 3:])

        r = rot_at(tk)
        r_dot = (rot_at(tk + h) - rot_at(tk - h)) / (2 * h)
        r_ddot = (rot_at(tk + h) - 2 * r + rot_at(tk - h)) / (h * h)
        w_hat = r_dot @ r.T
        omega = np.array([w_hat[2, 1], w_hat[0, 2], w_hat[1, 0]])
        # alpha_hat = R'' R^T + R' R'^T  (derivative of R' R^T)
        a_hat = r_ddot @ r.T + r_dot @ r_dot.T
        alpha = np.array([a_hat[2, 1], a_hat[0, 2], a_hat[1, 0]])
        c_w = r @ PAYLOAD.com_m
        a_com = acc[k, :3] + np.cross(alpha, c_w) + np.cross(omega, np.cross(omega, c_w))
        force = PAYLOAD.mass_kg * (a_com + np.array([0, 0, G]))
        i_w = r @ PAYLOAD.inertia_kgm2 @ r.T
        moment = np.cross(c_w, force) + i_w @ alpha + np.cross(omega, i_w @ omega)
        assert np.allclose(wrench[k, :3], force, rtol=1e-6, atol=1e-5)
        assert np.allclose(wrench[k, 3:], moment, rtol=1e-6, atol=1e-5)


def test_vertical_acceleration_scales_leg_load() -> None:
    p = load_platform("stewart6-linear")
    pose = np.zeros((1, 6))
    rest = actuator_forces(p, pose, [0.0], PAYLOAD).forces[0]
    up = actuator_forces(
        p,
        pose,
        [0.0],
        PAYLOAD,
        velocities=np.zeros((1, 6)),
        accelerations=np.array([[0, 0, 0.5 * G, 0, 0, 0]]),
    ).forces[0]
    assert np.allclose(up, 1.5 * rest, rtol=1e-12)


def test_finite_difference_rates_match_analytic() -> None:
    p = load_platform("stewart6-linear")
    t = np.linspace(0, 2, 2001)
    poses, vel, acc = _trajectory(t)
    est = actuator_forces(p, poses, t, PAYLOAD)
    exact = actuator_forces(p, poses, t, PAYLOAD, velocities=vel, accelerations=acc)
    inner = slice(5, -5)
    assert np.allclose(est.forces[inner], exact.forces[inner], rtol=0, atol=0.05)
    assert est.forces.shape == (len(t), 6)
    assert np.array_equal(exact.peak, np.abs(exact.forces[exact.peak_index, np.arange(6)]))
    assert np.all(exact.peak >= np.abs(exact.forces).max(axis=0) - 1e-12)
    assert np.all(exact.condition < 100)


def test_bad_inputs_rejected() -> None:
    p = load_platform("seat3")
    with pytest.raises(ConfigError, match="mass_kg"):
        Payload(0.0)
    with pytest.raises(ConfigError, match="inertia_kgm2"):
        Payload(10.0, inertia_kgm2=np.diag([1.0, -1.0, 1.0]))
    with pytest.raises(ConfigError, match="com_m"):
        Payload(10.0, com_m=(0, 0))
    with pytest.raises(ConfigError, match="t_s"):
        actuator_forces(p, np.zeros((3, 6)), [0.0, 0.0, 1.0], PAYLOAD)
    bad = np.zeros((2, 6))
    bad[1, 3] = math.nan
    with pytest.raises(ConfigError, match="poses"):
        actuator_forces(p, bad, [0.0, 1.0], PAYLOAD)


def test_motor_torque_and_speed_for_sizing() -> None:
    """Ideal screw: torque = F * lead / (2 pi); speed = dq/dt, checked by differencing IK."""
    p = load_platform("stewart6-linear")
    t = np.linspace(0, 2, 4001)
    poses, vel, acc = _trajectory(t)
    res = actuator_forces(p, poses, t, PAYLOAD, velocities=vel, accelerations=acc)
    assert np.allclose(res.motor_torque_nm, res.forces * 0.005 / (2 * math.pi), rtol=1e-12)
    q = p.inverse(poses)
    q_dot = np.gradient(q, t, axis=0)
    assert np.allclose(res.speed[5:-5], q_dot[5:-5], atol=1e-6)
    assert np.allclose(res.motor_rpm, res.speed / 0.005 * 60.0, rtol=1e-12)
    assert np.allclose(res.peak_motor_rpm, np.abs(res.motor_rpm).max(axis=0))
    assert np.allclose(res.peak_motor_torque_nm, np.abs(res.motor_torque_nm).max(axis=0))
    # rotary: crank torque / gear ratio, rpm = crank speed * gear ratio
    r = load_platform("stewart6-rotary")
    rr = actuator_forces(r, poses * 0.5, t, PAYLOAD)
    assert np.allclose(rr.motor_torque_nm, rr.forces / 50.0, rtol=1e-12)
    assert np.allclose(rr.motor_rpm, rr.speed * 50.0 / (2 * math.pi) * 60.0, rtol=1e-12)
