"""Leg sets: the closed-form maps from platform anchor positions to actuator positions.

Every leg joins a base-fixed point ``b_i`` to a platform anchor ``p_i`` (platform frame).
With the pose ``[x, y, z, roll, pitch, yaw]`` the anchor is, in the base frame,
``P_i = [x, y, z + h] + R p_i`` where ``h`` is the neutral height of the platform frame above
the base frame. All anchors of a set are computed by one matrix product: the features
``[R (9 entries), x, y, z, 1]`` times a constant ``(13, 3 n)`` matrix give ``D_i = P_i - b_i``.

A linear leg's position is ``|D_i| - L0_i`` (m). A crank leg (rotary actuator: crank of
length ``r`` turning about an axis through ``b_i``, rod of length ``l`` to ``p_i``) solves
``A cos(theta) + B sin(theta) = C`` for the crank angle in closed form; its position is the
angle from its neutral value (rad).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

__all__ = ["CrankLegs", "LegSet", "LinearLegs"]


def _anchor_matrix(
    base: NDArray[np.float64], plat: NDArray[np.float64], height: float
) -> NDArray[np.float64]:
    n = base.shape[0]
    m = np.zeros((13, 3 * n))
    for i in range(n):
        for j in range(3):
            for k in range(3):
                m[3 * j + k, 3 * i + j] = plat[i, k]
            m[9 + j, 3 * i + j] = 1.0
            m[12, 3 * i + j] = -base[i, j] + (height if j == 2 else 0.0)
    return m


def _wrap(angle: NDArray[np.float64]) -> NDArray[np.float64]:
    """Angles wrapped to [-pi, pi)."""
    return np.remainder(angle + math.pi, 2.0 * math.pi) - math.pi


class LegSet:
    """Common part: anchors and the matrix product giving ``D = P - b``."""

    kind = ""

    def __init__(self, base: NDArray[np.float64], plat: NDArray[np.float64], height: float) -> None:
        self.base = np.array(base, dtype=float)
        self.plat = np.array(plat, dtype=float)
        self.height = float(height)
        self.n = self.base.shape[0]
        self.matrix = _anchor_matrix(self.base, self.plat, self.height)
        self.rot_part = np.ascontiguousarray(self.matrix[:9])
        # Plain-float copies for the one-pose path.
        shifted = self.base - np.array([0.0, 0.0, self.height])
        self._one = [(*self.plat[i].tolist(), *shifted[i].tolist()) for i in range(self.n)]

    def vectors(self, features: NDArray[np.float64]) -> NDArray[np.float64]:
        """``D = P - b`` for features ``(N, 13)``; returns ``(N, n, 3)``."""
        return (features @ self.matrix).reshape(-1, self.n, 3)

    def vectors_one(
        self, r: tuple[float, ...], t: tuple[float, float, float]
    ) -> list[tuple[float, float, float]]:
        x, y, z = t
        out = []
        for px, py, pz, bx, by, bz in self._one:
            out.append(
                (
                    x + r[0] * px + r[1] * py + r[2] * pz - bx,
                    y + r[3] * px + r[4] * py + r[5] * pz - by,
                    z + r[6] * px + r[7] * py + r[8] * pz - bz,
                )
            )
        return out

    def anchor_derivatives(self, drot: NDArray[np.float64]) -> NDArray[np.float64]:
        """``dP_i/dangle_k = dR_k p_i`` for ``drot (N, 3, 9)``; returns ``(N, 3, n, 3)``."""
        return (drot @ self.rot_part).reshape(drot.shape[0], 3, self.n, 3)

    def jacobian_one(
        self,
        d: list[tuple[float, float, float]],
        q: list[float],
        t: tuple[float, float, float],
        angles: tuple[float, float, float],
    ) -> list[list[float]]:
        """Rows ``dq_i/dpose`` (6 floats each) for one pose, without numpy.

        With ``g = dq_i/dP_i`` and ``r = R p_i``, the Euler-angle columns are
        ``g . (e_k x r) = e_k . (r x g)`` where ``e_k`` are the columns of the Euler-rate
        matrix E (world axes of the roll, pitch and yaw rotations).
        """
        _, pitch, yaw = angles
        cp, sp = math.cos(pitch), math.sin(pitch)
        cy, sy = math.cos(yaw), math.sin(yaw)
        e0x, e0y, e0z = cy * cp, sy * cp, -sp
        x, y, z = t
        rows = []
        for (dx, dy, dz), (_, _, _, bx, by, bz), (gx, gy, gz) in zip(
            d, self._one, self.gradient_one(d, q), strict=True
        ):
            rx, ry, rz = dx - x + bx, dy - y + by, dz - z + bz
            mx = ry * gz - rz * gy
            my = rz * gx - rx * gz
            mz = rx * gy - ry * gx
            rows.append([gx, gy, gz, mx * e0x + my * e0y + mz * e0z, -mx * sy + my * cy, mz])
        return rows

    def joints(self, q: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """How a drawing shows the legs: the joint between each leg's ends, as an offset
        ``(N, n, 3)`` from its base end (m), for leg positions ``q (N, n)``; None for a
        straight leg drawn from base end to platform anchor (the default)."""
        return None

    # Implemented by the subclasses.
    def gradient_one(
        self, d: list[tuple[float, float, float]], q: list[float]
    ) -> list[tuple[float, float, float]]:
        raise NotImplementedError

    def q(self, d: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        raise NotImplementedError

    def q_one(self, d: list[tuple[float, float, float]]) -> list[float]:
        raise NotImplementedError

    def q_one_checked(self, d: list[tuple[float, float, float]]) -> tuple[list[float], bool]:
        """Positions and whether every leg is reachable, for one pose."""
        return self.q_one(d), True

    def gradient(self, d: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        """``dq_i / dP_i``, ``(N, n, 3)``."""
        raise NotImplementedError


class LinearLegs(LegSet):
    """Straight legs whose length changes: electric cylinders between two spherical joints."""

    kind = "linear"

    def __init__(self, base: NDArray[np.float64], plat: NDArray[np.float64], height: float) -> None:
        super().__init__(base, plat, height)
        d0 = self.plat + np.array([0.0, 0.0, self.height]) - self.base
        self.length0 = np.sqrt(np.einsum("ij,ij->i", d0, d0))
        self._matrix_t = np.ascontiguousarray(self.matrix.T)
        self._l0 = self.length0.tolist()

    def q_pose_one(self, r: tuple[float, ...], x: float, y: float, z: float) -> list[float]:
        """Positions for one pose from R's entries and the translation (fused, no numpy)."""
        r0, r1, r2, r3, r4, r5, r6, r7, r8 = r
        sqrt = math.sqrt
        out = []
        for (px, py, pz, bx, by, bz), l0 in zip(self._one, self._l0, strict=True):
            dx = x + r0 * px + r1 * py + r2 * pz - bx
            dy = y + r3 * px + r4 * py + r5 * pz - by
            dz = z + r6 * px + r7 * py + r8 * pz - bz
            # products, not ``** 2``: a float power raises OverflowError where a product
            # gives inf, as the array path does (an absurd pose is then out of stroke)
            out.append(sqrt(dx * dx + dy * dy + dz * dz) - l0)
        return out

    def q_from_features_t(self, feat_t: NDArray[np.float64]) -> NDArray[np.float64]:
        """Positions ``(n, N)`` from transposed features ``(13, N)`` (the fast batch path)."""
        d = self._matrix_t @ feat_t
        d *= d
        d3 = d.reshape(self.n, 3, -1)
        out = d3[:, 0] + d3[:, 1]
        out += d3[:, 2]
        np.sqrt(out, out=out)
        out -= self.length0[:, None]
        return out

    def lengths(self, d: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(np.sqrt(np.einsum("...ij,...ij->...i", d, d)), dtype=float)

    def q(self, d: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        q = self.lengths(d)
        q -= self.length0
        return q, np.ones(q.shape, dtype=bool)

    def q_one(self, d: list[tuple[float, float, float]]) -> list[float]:
        return [
            math.sqrt(dx * dx + dy * dy + dz * dz) - l0
            for (dx, dy, dz), l0 in zip(d, self._l0, strict=True)
        ]

    def gradient(self, d: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.asarray(d / (q + self.length0)[..., None], dtype=float)

    def gradient_one(
        self, d: list[tuple[float, float, float]], q: list[float]
    ) -> list[tuple[float, float, float]]:
        out = []
        for (dx, dy, dz), qi, l0 in zip(d, q, self._l0, strict=True):
            inv = 1.0 / (qi + l0)
            out.append((dx * inv, dy * inv, dz * inv))
        return out


class CrankLegs(LegSet):
    """Crank-and-rod legs: a motor turns a crank about a fixed axis; a rod joins crank tip
    and platform anchor with spherical joints.

    ``zero_dirs`` (e1) is the crank direction at angle 0 and ``axes`` the crank axis; the
    crank direction at angle ``theta`` is ``cos(theta) e1 + sin(theta) (axis x e1)``.
    """

    kind = "rotary"

    def __init__(
        self,
        base: NDArray[np.float64],
        plat: NDArray[np.float64],
        height: float,
        axes: NDArray[np.float64],
        zero_dirs: NDArray[np.float64],
        crank: NDArray[np.float64],
        rod: NDArray[np.float64],
    ) -> None:
        super().__init__(base, plat, height)
        self.axes = np.array(axes, dtype=float)
        self.e1 = np.array(zero_dirs, dtype=float)
        self.e2 = np.cross(self.axes, self.e1)
        self.crank = np.array(crank, dtype=float)
        self.rod = np.array(rod, dtype=float)
        self.branch = np.ones(self.n)
        self.theta0 = np.zeros(self.n)
        # Neutral crank angle: of the two assembly branches, the one nearer angle 0.
        d0 = (self.plat + np.array([0.0, 0.0, self.height]) - self.base)[None]
        up = _wrap(self._theta_branch(d0, 1.0)[0])
        down = _wrap(self._theta_branch(d0, -1.0)[0])
        self.branch = np.where(np.abs(up) <= np.abs(down), 1.0, -1.0)
        theta, ok = self._theta(d0)
        self.reachable0 = ok[0]
        self.theta0 = _wrap(theta[0])
        self._one_c = list(
            zip(
                self.e1.tolist(),
                self.e2.tolist(),
                self.crank.tolist(),
                self.rod.tolist(),
                self.branch.tolist(),
                self.theta0.tolist(),
                strict=True,
            )
        )

    def _abc(
        self, d: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        a = np.einsum("...ij,ij->...i", d, self.e1)
        b = np.einsum("...ij,ij->...i", d, self.e2)
        c = (np.einsum("...ij,...ij->...i", d, d) + self.crank**2 - self.rod**2) / (
            2.0 * self.crank
        )
        return a, b, c

    def _theta_branch(self, d: NDArray[np.float64], sign: float) -> NDArray[np.float64]:
        a, b, c = self._abc(d)
        rho = np.hypot(a, b)
        ratio = np.clip(np.divide(c, rho, out=np.full_like(c, 2.0), where=rho > 0), -1.0, 1.0)
        return np.asarray(np.arctan2(b, a) + sign * np.arccos(ratio), dtype=float)

    def _theta(self, d: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        a, b, c = self._abc(d)
        rho = np.hypot(a, b)
        ratio = np.divide(c, rho, out=np.full_like(c, 2.0), where=rho > 0)
        reachable = np.abs(ratio) <= 1.0
        theta = np.arctan2(b, a) + self.branch * np.arccos(np.clip(ratio, -1.0, 1.0))
        return theta, reachable

    def q(self, d: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        theta, reachable = self._theta(d)
        return _wrap(theta - self.theta0), reachable

    def q_one(self, d: list[tuple[float, float, float]]) -> list[float]:
        return self.q_one_checked(d)[0]

    def q_one_checked(self, d: list[tuple[float, float, float]]) -> tuple[list[float], bool]:
        out = []
        reachable = True
        for (dx, dy, dz), (e1, e2, r, rod, s, t0) in zip(d, self._one_c, strict=True):
            a = dx * e1[0] + dy * e1[1] + dz * e1[2]
            b = dx * e2[0] + dy * e2[1] + dz * e2[2]
            c = (dx * dx + dy * dy + dz * dz + r * r - rod * rod) / (2.0 * r)
            rho = math.hypot(a, b)
            ratio = c / rho if rho > 0 else 2.0
            if not -1.0 <= ratio <= 1.0:
                reachable = False
                ratio = min(1.0, max(-1.0, ratio))
            theta = math.atan2(b, a) + s * math.acos(ratio)
            out.append((theta - t0 + math.pi) % (2.0 * math.pi) - math.pi)
        return out, reachable

    def gradient_one(
        self, d: list[tuple[float, float, float]], q: list[float]
    ) -> list[tuple[float, float, float]]:
        g = self.gradient(np.asarray(d, dtype=float)[None], np.asarray(q)[None])[0]
        return [tuple(row) for row in g.tolist()]

    def crank_vectors(
        self, q: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Crank tip offset ``c`` and its angle derivative ``dc/dtheta``, ``(N, n, 3)`` each."""
        theta = (q + self.theta0)[..., None]
        cos, sin = np.cos(theta), np.sin(theta)
        r = self.crank[:, None]
        c = r * (cos * self.e1 + sin * self.e2)
        dc = r * (-sin * self.e1 + cos * self.e2)
        return c, dc

    def joints(self, q: NDArray[np.float64]) -> NDArray[np.float64]:
        """The crank tips, ``(N, n, 3)`` offsets from the crank pivots (m): a crank leg is
        drawn pivot -> crank tip -> platform anchor."""
        return self.crank_vectors(q)[0]

    def gradient(self, d: NDArray[np.float64], q: NDArray[np.float64]) -> NDArray[np.float64]:
        c, dc = self.crank_vectors(q)
        w = d - c
        denom = np.einsum("...ij,...ij->...i", w, dc)
        tiny = 1e-12 * self.crank * self.rod
        denom = np.where(np.abs(denom) < tiny, np.copysign(tiny, denom), denom)
        return np.asarray(w / denom[..., None], dtype=float)
