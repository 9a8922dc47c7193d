"""Rotation matrices of the pose convention R = Rz(yaw) Ry(pitch) Rx(roll), and derivatives.

Batch functions return the nine entries row-major in the last axis, shape ``(..., 9)``, so
that products with constant anchor sets become one matrix multiplication.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "euler_rate_matrix",
    "rot9",
    "rot9_derivatives",
    "rot_one",
    "rotation_matrix",
]


def rot9(angles: np.ndarray) -> np.ndarray:
    """Entries of R for angles ``(..., 3)`` = [roll, pitch, yaw] (rad); returns ``(..., 9)``."""
    cr, sr = np.cos(angles[..., 0]), np.sin(angles[..., 0])
    cp, sp = np.cos(angles[..., 1]), np.sin(angles[..., 1])
    cy, sy = np.cos(angles[..., 2]), np.sin(angles[..., 2])
    out = np.empty((*angles.shape[:-1], 9))
    spsr = sp * sr
    spcr = sp * cr
    out[..., 0] = cy * cp
    out[..., 1] = cy * spsr - sy * cr
    out[..., 2] = cy * spcr + sy * sr
    out[..., 3] = sy * cp
    out[..., 4] = sy * spsr + cy * cr
    out[..., 5] = sy * spcr - cy * sr
    out[..., 6] = -sp
    out[..., 7] = cp * sr
    out[..., 8] = cp * cr
    return out


def rotation_matrix(angles: np.ndarray) -> np.ndarray:
    """R for angles ``(..., 3)`` = [roll, pitch, yaw] (rad); returns ``(..., 3, 3)``."""
    angles = np.asarray(angles, dtype=float)
    return rot9(angles).reshape(*angles.shape[:-1], 3, 3)


def rot9_derivatives(angles: np.ndarray) -> np.ndarray:
    """dR/droll, dR/dpitch, dR/dyaw for angles ``(..., 3)``; returns ``(..., 3, 9)``."""
    cr, sr = np.cos(angles[..., 0]), np.sin(angles[..., 0])
    cp, sp = np.cos(angles[..., 1]), np.sin(angles[..., 1])
    cy, sy = np.cos(angles[..., 2]), np.sin(angles[..., 2])
    z = np.zeros_like(cr)
    d = np.empty((*angles.shape[:-1], 3, 9))
    # d/droll = Rz Ry dRx
    d[..., 0, 0] = z
    d[..., 0, 1] = cy * sp * cr + sy * sr
    d[..., 0, 2] = -cy * sp * sr + sy * cr
    d[..., 0, 3] = z
    d[..., 0, 4] = sy * sp * cr - cy * sr
    d[..., 0, 5] = -sy * sp * sr - cy * cr
    d[..., 0, 6] = z
    d[..., 0, 7] = cp * cr
    d[..., 0, 8] = -cp * sr
    # d/dpitch = Rz dRy Rx
    d[..., 1, 0] = -cy * sp
    d[..., 1, 1] = cy * cp * sr
    d[..., 1, 2] = cy * cp * cr
    d[..., 1, 3] = -sy * sp
    d[..., 1, 4] = sy * cp * sr
    d[..., 1, 5] = sy * cp * cr
    d[..., 1, 6] = -cp
    d[..., 1, 7] = -sp * sr
    d[..., 1, 8] = -sp * cr
    # d/dyaw = dRz Ry Rx
    d[..., 2, 0] = -sy * cp
    d[..., 2, 1] = -sy * sp * sr - cy * cr
    d[..., 2, 2] = -sy * sp * cr + cy * sr
    d[..., 2, 3] = cy * cp
    d[..., 2, 4] = cy * sp * sr - sy * cr
    d[..., 2, 5] = cy * sp * cr + sy * sr
    d[..., 2, 6] = z
    d[..., 2, 7] = z
    d[..., 2, 8] = z
    return d


def rot_one(roll: float, pitch: float, yaw: float) -> tuple[float, ...]:
    """The nine entries of R for one attitude, as plain floats (no numpy overhead)."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    spsr = sp * sr
    spcr = sp * cr
    return (
        cy * cp,
        cy * spsr - sy * cr,
        cy * spcr + sy * sr,
        sy * cp,
        sy * spsr + cy * cr,
        sy * spcr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )


def euler_rate_matrix(angles: np.ndarray) -> np.ndarray:
    """E with omega_world = E @ [roll_rate, pitch_rate, yaw_rate]; ``(..., 3)`` -> ``(..., 3, 3)``.

    For R = Rz(yaw) Ry(pitch) Rx(roll): omega = yaw_rate z + pitch_rate Rz y + roll_rate Rz Ry x.
    """
    angles = np.asarray(angles, dtype=float)
    cp, sp = np.cos(angles[..., 1]), np.sin(angles[..., 1])
    cy, sy = np.cos(angles[..., 2]), np.sin(angles[..., 2])
    e = np.zeros((*angles.shape[:-1], 3, 3))
    e[..., 0, 0] = cy * cp
    e[..., 1, 0] = sy * cp
    e[..., 2, 0] = -sp
    e[..., 0, 1] = -sy
    e[..., 1, 1] = cy
    e[..., 2, 2] = 1.0
    return e
