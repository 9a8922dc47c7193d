"""Actuator forces for a payload moving along a pose trajectory (Pinocchio rigid-body dynamics).

The payload (seat, rider, frame: mass, centre of mass and inertia in the platform frame) sits on
a free-flyer joint whose configuration is the platform pose. Pinocchio's recursive Newton-Euler
algorithm gives the wrench the platform must apply to it (gravity included). By virtual work,
actuator forces ``f`` and the generalised force ``tau`` conjugate to the pose vector satisfy
``J^T f = tau`` with ``J = dq/dpose``, so ``f = J^-T tau`` on the pose components the machine
produces (the others are held by its guide).

Pinocchio is imported inside the function so that ``import motioncue`` stays light.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from .._errors import ConfigError
from .._frozen import set_fields
from ._platform import Platform
from ._rotation import euler_rate_matrix, rotation_matrix

__all__ = ["STANDARD_GRAVITY", "ForceResult", "Payload", "actuator_forces", "pose_wrench"]

STANDARD_GRAVITY = 9.80665  # m/s^2


@dataclass(frozen=True)
class Payload:
    """A rigid payload carried by the platform.

    Parameters
    ----------
    mass_kg
        Mass (kg), > 0.
    com_m
        ``(3,)`` centre of mass in the platform frame (m).
    inertia_kgm2
        ``(3, 3)`` inertia about the centre of mass, platform axes (kg m^2); symmetric,
        positive semi-definite. Default: a point mass.
    """

    mass_kg: float
    com_m: npt.ArrayLike = (0.0, 0.0, 0.0)
    inertia_kgm2: npt.ArrayLike = field(default_factory=lambda: np.zeros((3, 3)))

    def __post_init__(self) -> None:
        m = float(self.mass_kg)
        if not math.isfinite(m) or m <= 0:
            raise ConfigError(f"mass_kg = {self.mass_kg!r} is invalid; allowed: finite > 0")
        com = np.asarray(self.com_m, dtype=float)
        if com.shape != (3,) or not np.isfinite(com).all():
            raise ConfigError(f"com_m = {self.com_m!r} is invalid; allowed: 3 finite numbers (m)")
        inertia = np.asarray(self.inertia_kgm2, dtype=float)
        if (
            inertia.shape != (3, 3)
            or not np.isfinite(inertia).all()
            or not np.allclose(inertia, inertia.T, atol=1e-12)
            or np.linalg.eigvalsh(inertia).min() < -1e-12
        ):
            raise ConfigError(
                f"inertia_kgm2 = {self.inertia_kgm2!r} is invalid; allowed: a symmetric "
                "positive semi-definite 3x3 matrix (kg m^2)"
            )
        set_fields(self, mass_kg=m, com_m=com, inertia_kgm2=inertia)


@dataclass(frozen=True)
class ForceResult:
    """Actuator forces along a trajectory.

    Attributes
    ----------
    t_s
        ``(N,)`` sample times (s).
    forces
        ``(N, n)`` actuator forces: N along linear legs (positive pushes, i.e. extends),
        N m about crank axes / the yaw axis (positive turns toward positive ``q``).
    peak
        ``(n,)`` largest magnitude per actuator over the trajectory.
    peak_index
        ``(n,)`` sample index of each peak.
    wrench
        ``(N, 6)`` wrench the platform applies to the payload, base axes, moment about the
        platform frame origin: ``[Fx, Fy, Fz, Mx, My, Mz]`` (N, N m).
    condition
        ``(N,)`` condition number of the leg Jacobian on the produced DOFs (large: near a
        singular pose, forces unreliable).
    speed
        ``(N, n)`` actuator speeds ``J @ pose_rate`` (m/s or rad/s).
    motor_torque_nm
        ``(N, n)`` motor torque through an ideal (lossless) screw or gearbox:
        ``force * travel_per_rev / (2 pi)``. Divide by the transmission efficiency.
    motor_rpm
        ``(N, n)`` motor speed (rev/min), signed like ``speed``.
    """

    t_s: NDArray[np.float64]
    forces: NDArray[np.float64]
    peak: NDArray[np.float64]
    peak_index: NDArray[np.intp]
    wrench: NDArray[np.float64]
    condition: NDArray[np.float64]
    speed: NDArray[np.float64]
    motor_torque_nm: NDArray[np.float64]
    motor_rpm: NDArray[np.float64]

    @property
    def peak_motor_torque_nm(self) -> NDArray[np.float64]:
        """``(n,)`` largest motor torque magnitude per actuator (ideal transmission)."""
        return np.asarray(np.max(np.abs(self.motor_torque_nm), axis=0), dtype=float)

    @property
    def peak_motor_rpm(self) -> NDArray[np.float64]:
        """``(n,)`` largest motor speed magnitude per actuator (rev/min)."""
        return np.asarray(np.max(np.abs(self.motor_rpm), axis=0), dtype=float)


def _derivative(t: NDArray[np.float64], y: NDArray[np.float64]) -> NDArray[np.float64]:
    if len(t) < 3:
        return np.zeros_like(y)
    return np.gradient(y, t, axis=0, edge_order=2)


def _euler_rate_derivative(
    angles: NDArray[np.float64], rates: NDArray[np.float64]
) -> NDArray[np.float64]:
    """Time derivative of :func:`euler_rate_matrix`, ``(N, 3, 3)``."""
    cp, sp = np.cos(angles[:, 1]), np.sin(angles[:, 1])
    cy, sy = np.cos(angles[:, 2]), np.sin(angles[:, 2])
    dp, dy = rates[:, 1], rates[:, 2]
    out = np.zeros((len(angles), 3, 3))
    out[:, 0, 0] = -sy * dy * cp - cy * sp * dp
    out[:, 1, 0] = cy * dy * cp - sy * sp * dp
    out[:, 2, 0] = -cp * dp
    out[:, 0, 1] = -cy * dy
    out[:, 1, 1] = -sy * dy
    return out


def pose_wrench(
    poses: NDArray[np.float64],
    velocities: NDArray[np.float64],
    accelerations: NDArray[np.float64],
    payload: Payload,
    gravity_mps2: float = STANDARD_GRAVITY,
) -> NDArray[np.float64]:
    """Wrench ``(N, 6)`` the platform applies to the payload (base axes, moment about the
    platform origin), from Pinocchio's RNEA, given pose-vector rates and accelerations."""
    import pinocchio as pin

    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    model.appendBodyToJoint(
        joint,
        pin.Inertia(payload.mass_kg, np.asarray(payload.com_m), np.asarray(payload.inertia_kgm2)),
        pin.SE3.Identity(),
    )
    model.gravity = pin.Motion(np.array([0.0, 0.0, -gravity_mps2, 0.0, 0.0, 0.0]))
    data = model.createData()

    angles = poses[:, 3:6]
    rot = rotation_matrix(angles)
    e = euler_rate_matrix(angles)
    omega = np.einsum("nij,nj->ni", e, velocities[:, 3:6])
    omega_dot = np.einsum("nij,nj->ni", e, accelerations[:, 3:6]) + np.einsum(
        "nij,nj->ni", _euler_rate_derivative(angles, velocities[:, 3:6]), velocities[:, 3:6]
    )
    out = np.empty((len(poses), 6))
    for k in range(len(poses)):
        r_t = rot[k].T
        v_b = r_t @ velocities[k, 0:3]
        w_b = r_t @ omega[k]
        # free-flyer tangent: [R^T p_dot, R^T omega]; its time derivative:
        a_lin = r_t @ accelerations[k, 0:3] - np.cross(w_b, v_b)
        a_ang = r_t @ omega_dot[k]
        quat = pin.Quaternion(rot[k]).coeffs()  # x, y, z, w
        q = np.concatenate([poses[k, 0:3], quat])
        tau = pin.rnea(model, data, q, np.concatenate([v_b, w_b]), np.concatenate([a_lin, a_ang]))
        out[k, 0:3] = rot[k] @ tau[0:3]
        out[k, 3:6] = rot[k] @ tau[3:6]
    return out


def actuator_forces(
    platform: Platform,
    poses: npt.ArrayLike,
    t_s: npt.ArrayLike,
    payload: Payload,
    *,
    velocities: npt.ArrayLike | None = None,
    accelerations: npt.ArrayLike | None = None,
    gravity_mps2: float = STANDARD_GRAVITY,
) -> ForceResult:
    """Actuator forces needed to move ``payload`` along a pose trajectory.

    Parameters
    ----------
    platform
        The machine.
    poses
        ``(N, 6)`` poses (m, rad); components the machine cannot produce are held at zero.
    t_s
        ``(N,)`` strictly increasing times (s).
    payload
        Mass, centre of mass and inertia in the platform frame.
    velocities, accelerations
        ``(N, 6)`` pose-vector rates; estimated from ``poses`` by second-order finite
        differences when not given (a single pose: at rest).
    gravity_mps2
        Gravity magnitude (m/s^2), acting along -z of the base frame.

    Returns
    -------
    ForceResult
        Forces ``(N, n)``, peak per actuator ``(n,)`` for motor sizing.
    """
    arr = np.asarray(poses, dtype=float)
    if arr.ndim == 1:
        arr = arr[None]
    if arr.ndim != 2 or arr.shape[1] != 6:
        raise ConfigError(f"poses has shape {arr.shape}; expected (N, 6)")
    if not np.isfinite(arr).all():
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise ConfigError(f"poses{bad.tolist()} is not finite; allowed: finite numbers")
    t = np.atleast_1d(np.asarray(t_s, dtype=float))
    if t.shape != (len(arr),) or not np.isfinite(t).all() or np.any(np.diff(t) <= 0):
        raise ConfigError(f"t_s must be {len(arr)} finite, strictly increasing times (s)")
    mask = platform.dof_mask.astype(float)
    arr = arr * mask
    vel = _derivative(t, arr) if velocities is None else np.asarray(velocities, dtype=float) * mask
    acc = _derivative(t, vel) if accelerations is None else np.asarray(accelerations, float) * mask
    for name, x in (("velocities", vel), ("accelerations", acc)):
        if x.shape != arr.shape or not np.isfinite(x).all():
            raise ConfigError(f"{name} must be finite with shape {arr.shape}")
    wrench = pose_wrench(arr, vel, acc, payload, gravity_mps2)
    e = euler_rate_matrix(arr[:, 3:6])
    tau = np.concatenate([wrench[:, 0:3], np.einsum("nji,nj->ni", e, wrench[:, 3:6])], axis=1)
    idx = np.flatnonzero(platform.dof_mask)
    jac = platform.jacobian(arr)[:, :, idx]  # (N, n, k), n >= k
    jt = np.transpose(jac, (0, 2, 1))
    if jac.shape[1] == jac.shape[2]:
        forces = np.linalg.solve(jt, tau[:, idx, None])[..., 0]
    else:
        # more actuators than degrees of freedom (a corner rig's four legs for three): the
        # load shares are statically indeterminate; the smallest forces (least-norm, the
        # share of equally stiff legs on a stiff frame) are reported. Spare axes carry none.
        forces = np.einsum("nij,nj->ni", np.linalg.pinv(jt), tau[:, idx])
    condition = np.linalg.cond(jac)
    peak_index = np.argmax(np.abs(forces), axis=0)
    peak = np.abs(forces[peak_index, np.arange(forces.shape[1])])
    speed = np.einsum("nik,nk->ni", jac, vel[:, idx])
    travel = platform.drives.units_per_rev
    return ForceResult(
        t_s=t,
        forces=forces,
        peak=peak,
        peak_index=peak_index,
        wrench=wrench,
        condition=condition,
        speed=speed,
        motor_torque_nm=forces * travel / (2.0 * math.pi),
        motor_rpm=speed / travel * 60.0,
    )
