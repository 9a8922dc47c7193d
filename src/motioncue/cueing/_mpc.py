"""Model-predictive cueing (``algorithm = "mpc"``): a warm-started QP per sample.

Model (per sample ``dt = 1 / fs``; frames and signs of conventions.md)
---------------------------------------------------------------------
* **Platform**: a double integrator per moved degree of freedom, pose ``p`` (m, rad), rate
  ``v = p'`` and the input ``u = p''`` (m/s^2, rad/s^2), held over a sample (zero-order
  hold, discretised exactly with the matrix exponential).
* **What the rider gets** (linearised about neutral, with tilt coordination): specific-force
  deviation ``s_f = [u_x - g pitch, u_y + g roll, u_z]`` (``R^T [0, 0, g]`` has x component
  ``-g sin(pitch)`` and y component ``g sin(roll) cos(pitch)``) and angular velocity
  ``s_w = [roll', pitch', yaw']``.
* **Perceived error**: the model set's otolith (x, y, z) and canal (roll, pitch, yaw)
  transfer functions (:mod:`._vestibular`) in state-space form (:func:`scipy.signal.tf2ss`)
  driven by ``s - d``, where ``d = [f - [0, 0, g], w]`` is the vehicle's motion; their output
  ``e`` is the perceived error (linear models: ``H s - H d = H (s - d)``), counted in
  perception thresholds.
* **Vehicle prediction** over the horizon: ``d[k] = d[0] exp(-k dt / tau)``
  (``prediction_tau_s = tau``), or held (``tau = 0``).

Cost over the horizon ``k = 1..N`` (``N = horizon_s fs``), with the weights of
:class:`~._mpc_params.MpcParams`::

    sum_k |W_e e_k / thr|^2 + w_pose |p_k|^2 + w_vel |v_k|^2 + w_acc |u_{k-1}|^2
        + x_N' T x_N  [+ sum_k w_prior |p_k - p_c|^2]

(the last term only with ``w_prior``: ``p_c`` the classical fallback's pose at this sample,
held over the horizon; its quadratic part is folded into ``w_pose``, so ``T`` prices
``w_pose + w_prior`` about neutral, and its linear part is :func:`pose_sum`'s.)

``T = P - Q`` with ``P`` the solution of the discrete algebraic Riccati equation of the same
stage cost (``Q`` the state weight), so the finite-horizon cost equals the infinite-horizon one
when no constraint is active (and the first move then equals the LQ feedback ``-K x``: the test
checks it against :func:`scipy.linalg.solve_discrete_are`).

Constraints, at the end of each move block (the input is held within a block; ``blocks``
blocks whose lengths grow geometrically from one sample to cover the horizon):

* **actuator stroke**: the leg lengths linearised about the current pose ``p0`` each sample,
  ``q(p) ~ q(p0) + J(p0) (p - p0)`` (:meth:`Platform.inverse`, :meth:`Platform.jacobian`),
  within ``stroke_use`` of each leg's usable stroke about its centre;
* **actuator speed and acceleration**: ``|J v| <= rate_use v_max``,
  ``|J u| <= rate_use a_max`` (:class:`~motioncue.trajectory.ActuatorLimits` of the platform
  with the controller);
* **combined tilt** (with ``tilt_fz_use``, :func:`tilt_fz_bound`): ``|roll + pitch|,
  |roll - pitch| <= b`` and ``|roll|, |pitch| <= b / sqrt(2)`` (a regular octagon about the
  circle of radius ``b / sqrt(2)``, at most 8 % outside it), so that the vertical force the
  tilt takes away (``g (1 - cos)``, which the linear model does not see) stays below a share
  of the fz threshold in every direction (the diagonal rows alone let one axis reach
  ``b``: twice the loss);
* **tilt**: ``|roll'|, |pitch'| <=`` the ``[mpc]`` table's ``tilt_rate_limit_deg_s`` (default:
  the ``[tilt]`` table's) and, when the preset sets it, ``|roll''|, |pitch''| <=
  tilt_accel_limit_rad_s2``. These bound the *whole* roll and pitch rate (the MPC does not
  split tilt from rotation); the perceived rotation is priced by the canal models in the
  cost, so a bound above the 3-3.6 deg/s perception thresholds only lets the optimiser trade
  a perceptible rotation against a missing force where that lowers the error.

The condensed QP (inputs only; ``blocks x dofs`` unknowns) has a constant Hessian; its
gradient is linear in the state and the vehicle sample, its constraint matrix changes with the
Jacobian. It is solved densely by a casadi conic plugin (``solver``; default DAQP, a dual
active-set solver for small dense QPs, warm-started from the previous solution; see
``benchmarks/bench_mpc.py`` for the measured choice).

Fallback
--------
The classical washout of the same preset runs alongside every sample (it also replaces bad
input samples, exactly as in :mod:`._classical`). When a solve fails (infeasible, not
converged, a non-finite result) or, in :meth:`MpcCueing.step` only, takes longer than
``deadline_ms``, the platform model is instead driven towards the classical pose by a
critically damped tracker ``u = wn^2 (p_c - p) - 2 wn v`` (``wn = 4 rad/s``, ``u`` clipped to
what every actuator can follow). Pose and rate stay continuous (no jump); the next successful
solve starts from where the platform is. Failed and late solves are counted
(:meth:`MpcCueing.stats`). :meth:`MpcCueing.run` applies no deadline, so it gives the numbers
of :meth:`MpcCueing.step` whenever no streaming solve was late.
"""

from __future__ import annotations

import math
import time
from collections import deque
from collections.abc import Iterator, MutableSequence, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._classical import ClassicalWashout, WashoutState, _adapt_gain
from ._mpc_params import MpcParams
from ._params import GRAVITY_M_S2, CueingParams
from ._vestibular import DEFAULT_MODEL_SET, get_model_set

if TYPE_CHECKING:
    from ..kinematics import Platform
    from ._algorithm import Rig

__all__ = [
    "TILT_OCTAGON",
    "DaqpQp",
    "MpcCueing",
    "MpcResult",
    "MpcState",
    "PlanCueing",
    "QpData",
    "SoftGuardQp",
    "SoftRows",
    "accel_rows",
    "block_ends",
    "build_model",
    "fallback_accel",
    "guard_channels",
    "input_bounds",
    "input_responses",
    "octagon_bound",
    "plan_tilt_reach",
    "pose_sum",
    "reference",
    "resolve_reach",
    "sign_guard_bounds",
    "slack_hessian",
    "slack_terms",
    "tilt_axes",
    "tilt_fz_bound",
]

_FALLBACK_WN = 4.0


@dataclass(frozen=True, eq=False)
class LinearModel:
    """The discrete augmented model ``x+ = A x + Bu u + Bd d`` with cost matrices.

    Attributes
    ----------
    a : (nx, nx) array
    bu : (nx, nu) array
        Input: acceleration of each moved DOF (``active`` order).
    bd : (nx, 6) array
        Vehicle motion ``d = [f - [0, 0, g], w]``.
    zx : (18, nx) array
        Weighted cost output from the state: ``[W_e e / thr; sqrt(w_pose) p; sqrt(w_vel) v]``.
    zd : (18, 6) array
        Its direct part from ``d`` (the canals' feed-through).
    r : (nu, nu) array
        Input weight.
    active : tuple of int
        Moved pose components (indices into ``[x, y, z, roll, pitch, yaw]``).
    dt : float
        Sample period (s).
    ce, de : (6, nx), (6, 6) arrays
        Unweighted perceived error ``e = ce x + de d`` (m/s^2, rad/s), for constraints on it.
    thresholds : (6,) array
        The model set's perception thresholds (m/s^2 x3, rad/s x3).
    """

    a: NDArray[np.float64]
    bu: NDArray[np.float64]
    bd: NDArray[np.float64]
    zx: NDArray[np.float64]
    zd: NDArray[np.float64]
    r: NDArray[np.float64]
    active: tuple[int, ...]
    dt: float
    ce: NDArray[np.float64]
    de: NDArray[np.float64]
    thresholds: NDArray[np.float64]

    @property
    def nx(self) -> int:
        """State size."""
        return int(self.a.shape[0])

    @property
    def nu(self) -> int:
        """Input size (moved DOFs)."""
        return int(self.bu.shape[1])

    @property
    def q(self) -> NDArray[np.float64]:
        """Stage state weight ``zx' zx``."""
        return np.asarray(self.zx.T @ self.zx)


def build_model(
    dofs: Sequence[bool], mp: MpcParams, fs_hz: float, model_set: str = DEFAULT_MODEL_SET
) -> LinearModel:
    """The discrete augmented model (platform, rider's motion, vestibular error) at ``fs_hz``.

    State ``[p (6), v (6), otolith x, y, z states, canal roll, pitch, yaw states]``.
    """
    from scipy.linalg import expm
    from scipy.signal import tf2ss

    ms = get_model_set(model_set)
    active = tuple(i for i in range(6) if dofs[i])
    if not active:
        raise ConfigError("dofs moves nothing; an MPC needs at least one degree of freedom")
    nu = len(active)
    g = GRAVITY_M_S2
    # s = sx x + su u (specific-force deviation and angular velocity the platform gives)
    filters = [tf2ss(*m.transfer_function()) for m in ms.channel_models()]
    orders = [f[0].shape[0] for f in filters]
    nx = 12 + sum(orders)
    sx = np.zeros((6, nx))
    su = np.zeros((6, nu))
    sx[0, 4] = -g
    sx[1, 3] = g
    sx[3:6, 9:12] = np.eye(3)
    for j, i in enumerate(active):
        if i < 3:
            su[i, j] = 1.0
    ac = np.zeros((nx, nx))
    bu = np.zeros((nx, nu))
    bd = np.zeros((nx, 6))
    ce = np.zeros((6, nx))
    dd = np.zeros((6, 6))
    ac[0:6, 6:12] = np.eye(6)
    for j, i in enumerate(active):
        bu[6 + i, j] = 1.0
    at = 12
    for i, (fa, fb, fc, fdd) in enumerate(filters):
        n = orders[i]
        sl = slice(at, at + n)
        b = fb[:, 0]
        ac[sl, sl] = fa
        ac[sl, :] += np.outer(b, sx[i])
        bu[sl, :] += np.outer(b, su[i])
        bd[sl, i] = -b
        ce[i, sl] = fc[0]
        ce[i, :] += fdd[0, 0] * sx[i]
        if np.any(fdd[0, 0] * su[i]):
            raise ConfigError("vestibular model with feed-through from acceleration")
        dd[i, i] = -fdd[0, 0]
        at += n
    dt = 1.0 / fs_hz
    big = np.zeros((nx + nu + 6, nx + nu + 6))
    big[:nx, :nx] = ac
    big[:nx, nx : nx + nu] = bu
    big[:nx, nx + nu :] = bd
    e = expm(big * dt)
    # the error to the reference and to the vehicle's whole motion, as one error to the blend
    # that reference() returns (MpcParams.w_vehicle)
    we = np.sqrt(np.asarray(mp.w_error) + np.asarray(mp.w_vehicle)) / np.asarray(ms.thresholds)
    zx = np.zeros((18, nx))
    zd = np.zeros((18, 6))
    zx[0:6] = we[:, None] * ce
    zd[0:6] = we[:, None] * dd
    zx[6:12, 0:6] = np.diag(np.sqrt(mp.w_pose))
    zx[12:18, 6:12] = np.diag(np.sqrt(mp.w_vel))
    r = np.diag(np.asarray(mp.w_acc)[list(active)])
    a = e[:nx, :nx].copy()
    for i in range(6):  # a DOF the machine does not move stays at zero: no dynamics (and the
        if i not in active:  # Riccati equation then sees no uncontrollable integrator)
            a[i, :] = 0.0
            a[6 + i, :] = 0.0
    return LinearModel(
        a=a,
        bu=e[:nx, nx : nx + nu],
        bd=e[:nx, nx + nu :],
        zx=zx,
        zd=zd,
        r=r,
        active=active,
        dt=dt,
        ce=ce,
        de=dd,
        thresholds=np.asarray(ms.thresholds, dtype=float),
    )


def initial_ref_env(mp: MpcParams) -> list[float] | None:
    """The envelope of ``[mpc] ref_adapt_peak_m_s2`` before the first sample: ``[e_x, e_y]``
    at ``ref_adapt_start_m_s2`` (m/s^2), ``None`` when the gain is fixed."""
    if mp.ref_adapt_peak_m_s2 is None:
        return None
    return [mp.ref_adapt_start_m_s2, mp.ref_adapt_start_m_s2]


def reference(
    d: ArrayLike,
    mp: MpcParams,
    fs_hz: float,
    lp: NDArray[np.float64] | None = None,
    env: list[float] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The motion the plan tracks, sample by sample, and the low-pass state after it.

    Without a split (``mp.ref_split_hz = 0``) ``r = L tanh(k d / L)`` per channel
    (``k = mp.ref_scale``, ``L = mp.ref_limit``; a limit of ``1e9`` or more leaves ``k d``),
    or with ``mp.ref_shape = p > 0`` the compressive curve of the classical washout,
    ``r = compress(d, k, L+, L-, p) = k d / (1 + |k d / L|^p)^(1/p)``
    (:func:`~._filters.compress_array`; ``L+ = mp.ref_limit`` for ``d > 0``, ``L- =
    mp.ref_limit_neg`` for ``d < 0``, the same when that is ``None``).
    With a split, ``d`` is cut by a first-order low-pass ``lo`` at ``ref_split_hz`` (exact
    discretisation, ``lo_n = a lo_(n-1) + (1 - a) d_n``, ``a = exp(-2 pi f / fs)``) into
    ``lo`` and ``d - lo``: ``r = L tanh(k lo / L) + k_hf (d - lo)`` (``k_hf =
    mp.ref_scale_hf``): the slow part as a limited copy (tilt), the fast part as it comes
    (translation).

    With ``mp.ref_adapt_peak_m_s2 = (c_x, c_y)`` the gain ``k`` of fx and fy (of their
    slow part with a split) is ``min(k, c / e)`` sample by sample, ``e`` the causal envelope
    of the vehicle's ``|f|`` that the classical washout's adaptive tilt gain uses (the same
    code: ``_classical._adapt_gain``), continued from and written back to ``env``; the
    curve is the same, its input scaled (``compress(a d, k) = compress(d, a k)``).

    With ``mp.ref_small_gain = (b_x, b_y)`` the fx and fy copies get ``b K tanh(d / K)``
    more (``K = mp.ref_small_knee_m_s2``): small cues tracked with more gain.

    With ``mp.w_vehicle`` (``wv``; ``we = mp.w_error``) the result is the blend
    ``r' = r + wv / (we + wv) (d - r)`` per channel: the one target whose error, weighed by
    ``we + wv``, is the cost of both terms (:class:`~._mpc_params.MpcParams`).

    Parameters
    ----------
    d : (6,) or (N, 6) array
        Vehicle motion ``[f - [0, 0, g], w]`` (m/s^2, rad/s), one sample or a run of them.
    mp : MpcParams
    fs_hz : float
        Sample rate (Hz).
    lp : (6,) array, optional
        Low-pass state before ``d`` (default zeros: the vehicle at rest).
    env : list of 2 floats, optional
        With ``mp.ref_adapt_peak_m_s2``: the fx, fy envelope before ``d`` (m/s^2), updated in
        place to the envelope after it (default :func:`initial_ref_env`, not kept: a
        recording from its start). Ignored when the gain is fixed.

    Returns
    -------
    r : array shaped like ``d``
    lp : (6,) array
        The low-pass state after the last sample.
    """
    da = np.asarray(d, dtype=float)
    k = np.asarray(mp.ref_scale)
    lim = np.asarray(mp.ref_limit)
    soft = lim < 1e9
    state = np.zeros(6) if lp is None else np.asarray(lp, dtype=float)
    if mp.ref_split_hz > 0.0:
        from scipy.signal import lfilter

        a = math.exp(-2.0 * math.pi * mp.ref_split_hz / fs_hz)
        rows = da.reshape(-1, 6)
        lo, zf = lfilter([1.0 - a], [1.0, -a], rows, axis=0, zi=(a * state)[None, :])
        state = np.asarray(zf[0] / a if a > 0.0 else rows[-1], dtype=float)
        lo = lo.reshape(da.shape)
        fast = np.asarray(mp.ref_scale_hf) * (da - lo)
        slow = lo
    else:
        fast = np.zeros_like(da)
        slow = da
    peak = mp.ref_adapt_peak_m_s2
    if peak is not None:  # the gain adapts: the slow part scaled by min(1, c / (k e))
        ev = initial_ref_env(mp) if env is None else env
        assert ev is not None  # the gain adapts, so initial_ref_env gives an envelope
        slow = np.array(slow, dtype=float)
        rows = da.reshape(-1, 6)
        for j in (0, 1):
            fac = _adapt_gain(rows[:, j], peak[j], float(k[j]), mp.ref_adapt_tau_s, fs_hz, ev, j)
            slow[..., j] = slow[..., j] * fac.reshape(slow.shape[:-1])
    r = slow * k
    if mp.ref_shape > 0.0:
        from ._filters import compress_array

        neg = lim if mp.ref_limit_neg is None else np.asarray(mp.ref_limit_neg)
        for i in np.flatnonzero(soft | (neg < 1e9)):
            r[..., i] = compress_array(slow[..., i], k[i], lim[i], neg[i], mp.ref_shape)
    elif np.any(soft):
        r[..., soft] = lim[soft] * np.tanh(r[..., soft] / lim[soft])
    r = r + fast
    if any(mp.ref_small_gain):  # small fx, fy cues tracked with more gain, up to the knee
        knee = mp.ref_small_knee_m_s2
        r[..., :2] += np.asarray(mp.ref_small_gain) * knee * np.tanh(da[..., :2] / knee)
    wv = np.asarray(mp.w_vehicle)
    if np.any(wv > 0.0):
        beta = wv / np.maximum(np.asarray(mp.w_error) + wv, 1e-300)
        r = r + beta * (da - r)
    return np.asarray(r), state


def plan_tilt_reach(limits: RigLimits) -> tuple[float, float, float, float]:
    """The plan's own reach in pure tilt about neutral: ``(roll-, roll+, pitch-, pitch+)``.

    The largest angle (rad, magnitude, to 0.01 deg, at most 30 deg) such that every pure roll
    (or pitch) pose from neutral up to it in that direction keeps each leg (exact inverse
    kinematics) within the stroke the plan may use (``q_mid +- q_half``).

    Parameters
    ----------
    limits : RigLimits

    Returns
    -------
    tuple of 4 floats
    """
    angles = np.radians(np.arange(1, 3001) * 0.01)
    out = []
    for axis in (3, 4):
        for sign in (-1.0, 1.0):
            poses = np.zeros((angles.size, 6))
            poses[:, axis] = sign * angles
            q = np.asarray(limits.platform.inverse(poses), dtype=float)
            ok = np.all(np.abs(q - limits.q_mid) <= limits.q_half, axis=1)
            first_bad = int(np.argmin(ok)) if not ok.all() else angles.size
            out.append(float(angles[first_bad - 1]) if first_bad > 0 else 1e-4)
    return (out[0], out[1], out[2], out[3])


def resolve_reach(mp: MpcParams, limits: RigLimits) -> MpcParams:
    """``mp`` with its fx and fy reference limits set from the plan's tilt reach.

    With ``mp.ref_reach_use = u > 0``: ``L = g u reach`` in the direction each sign needs
    (the model's specific force is ``[u_x - g pitch, u_y + g roll]``, so ``fx > 0`` needs
    pitch down to ``-reach(pitch-)``, ``fx < 0`` pitch up, ``fy > 0`` roll up to
    ``reach(roll+)``, ``fy < 0`` roll down): ``ref_limit`` holds the positive limits and
    ``ref_limit_neg`` the negative ones. ``mp`` unchanged when ``u = 0``.
    """
    if mp.ref_reach_use <= 0.0:
        return mp
    rn, rp, pn, pp = plan_tilt_reach(limits)
    c = GRAVITY_M_S2 * mp.ref_reach_use
    pos = list(mp.ref_limit)
    neg = list(mp.ref_limit if mp.ref_limit_neg is None else mp.ref_limit_neg)
    pos[0], neg[0] = c * pn, c * pp
    pos[1], neg[1] = c * rp, c * rn
    return replace(
        mp,
        ref_limit=(pos[0], pos[1], pos[2], pos[3], pos[4], pos[5]),
        ref_limit_neg=(neg[0], neg[1], neg[2], neg[3], neg[4], neg[5]),
    )


def tilt_fz_bound(mp: MpcParams, thr_z_m_s2: float) -> float | None:
    """Bound ``b`` of the combined-tilt rows ``|roll + pitch|, |roll - pitch| <= b`` (rad).

    ``b = sqrt(2) acos(1 - u thr_z / g)`` (``u = mp.tilt_fz_use``): on the diagonal, where
    roll and pitch are equal, the combined tilt is then at most ``theta = acos(1 - u thr_z /
    g)``, whose loss of vertical force ``g (1 - cos theta)`` is ``u`` thresholds ``thr_z``
    (m/s^2); the plans also keep ``|roll|, |pitch| <= theta = b / sqrt(2)`` (the same loss
    on the axes). ``None`` when ``u = 0`` (no such rows).
    """
    if mp.tilt_fz_use <= 0.0:
        return None
    c = 1.0 - mp.tilt_fz_use * thr_z_m_s2 / GRAVITY_M_S2
    theta = math.acos(max(-1.0, min(1.0, c)))
    return math.sqrt(2.0) * theta


def block_ends(n_steps: int, blocks: int) -> NDArray[np.int64]:
    """Ends (in samples, increasing, last = ``n_steps``) of at most ``blocks`` move blocks whose
    lengths grow geometrically from one sample."""
    if blocks >= n_steps:
        return np.arange(1, n_steps + 1, dtype=np.int64)
    raw = np.geomspace(1.0, float(n_steps), blocks)
    ends = np.unique(np.round(raw).astype(np.int64))
    ends[-1] = n_steps
    return ends


def terminal_weight(m: LinearModel) -> NDArray[np.float64]:
    """``P - Q``: ``P`` of the discrete algebraic Riccati equation of the stage cost."""
    from scipy.linalg import solve_discrete_are

    q = m.q
    try:
        p = solve_discrete_are(m.a, m.bu, q + 1e-12 * np.eye(m.nx), m.r)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise ConfigError(
            f"MPC weights give no finite Riccati solution ({exc}); allowed: w_pose, w_vel "
            "and w_acc > 0 on every moved degree of freedom"
        ) from None
    t = p - q
    return np.asarray(0.5 * (t + t.T))


def input_responses(m: LinearModel, ends: NDArray[np.int64]) -> Iterator[NDArray[np.float64]]:
    """``G_k`` for ``k = 1..N`` (``N = ends[-1]``): the state at step ``k`` from the blocked
    inputs ``U`` (``nb nu``; block ``j`` holds its input over the steps up to ``ends[j]``),
    ``G_k = A G_(k-1) + B_u E_j`` from ``G_0 = 0``.

    Yields
    ------
    (nx, nb nu) array
        A new array each step (kept by the caller as it likes).
    """
    n = int(ends[-1])
    nu = m.nu
    blk = np.searchsorted(ends, np.arange(n), side="right")  # block of step k - 1
    gam = np.zeros((m.nx, len(ends) * nu))
    for k in range(1, n + 1):
        j = blk[k - 1]
        gam = m.a @ gam
        gam[:, j * nu : (j + 1) * nu] += m.bu
        yield gam


def pose_sum(m: LinearModel, ends: NDArray[np.int64]) -> NDArray[np.float64]:
    """``S = sum_k G_k'`` over the horizon's steps ``k = 1..N`` (``N = ends[-1]``), ``G_k``
    (6, ``nb nu``) the pose at step ``k`` from the blocked inputs (as in :func:`condense`).

    With it the cost ``sum_k |W^(1/2) (p_k - c)|^2`` (``W`` diagonal, ``c`` held) has the
    linear part ``-2 (S W c)' U`` in the inputs ``U`` (the ``w_prior`` term of
    :class:`MpcCueing`); its quadratic part is that of ``w_pose``.

    Returns
    -------
    (nb nu, 6) array
    """
    out = np.zeros((len(ends) * m.nu, 6))
    for gam in input_responses(m, ends):
        out += gam[:6].T
    return out


@dataclass(frozen=True, eq=False)
class Condensed:
    """The horizon's prediction condensed to the blocked inputs ``U`` (``nb * nu``).

    ``x_k = phi[k] x0 + gam[k] U + psi[k] d`` for ``k = 0..N`` (``d`` the current vehicle
    sample, propagated by the prediction), cost ``0.5 U' H U + (gx x0 + gd d)' U + const``.
    """

    ends: NDArray[np.int64]
    lengths: NDArray[np.int64]
    hess: NDArray[np.float64]
    gx: NDArray[np.float64]
    gd: NDArray[np.float64]
    gam_end: NDArray[np.float64]  # (nb, 12, nU): pose and rate at block ends
    phi_end: NDArray[np.float64]  # (nb, 12, nx)
    psi_end: NDArray[np.float64]  # (nb, 12, 6)
    ce_phi: NDArray[np.float64]  # (nb, 6, nx): perceived error (ce) of the free state
    ce_psi: NDArray[np.float64]  # (nb, 6, 6)
    ce_gam: NDArray[np.float64]  # (nb, 6, nU)


def condense(
    m: LinearModel, ends: NDArray[np.int64], decay: NDArray[np.float64], terminal: bool
) -> Condensed:
    """Build :class:`Condensed` for block ``ends`` and the prediction factors ``decay[k]``
    (``d_k = decay[k] d``, ``k = 0..N``)."""
    nb = len(ends)
    nu, nx = m.nu, m.nx
    n_u = nb * nu
    q = m.q
    zxd = m.zx.T @ m.zd  # (nx, 6)
    gam = np.zeros((nx, n_u))
    phi = np.eye(nx)
    psi = np.zeros((nx, 6))
    hess = np.zeros((n_u, n_u))
    gx = np.zeros((n_u, nx))
    gd = np.zeros((n_u, 6))
    gam_end = np.zeros((nb, 12, n_u))
    phi_end = np.zeros((nb, 12, nx))
    psi_end = np.zeros((nb, 12, 6))
    ce_phi = np.zeros((nb, 6, nx))
    ce_psi = np.zeros((nb, 6, 6))
    ce_gam = np.zeros((nb, 6, n_u))
    lengths = np.diff(np.concatenate([[0], ends]))
    b_at = 0
    for k, gam in enumerate(input_responses(m, ends), start=1):
        psi = m.a @ psi + m.bd * decay[k - 1]
        phi = m.a @ phi
        qg = q @ gam
        hess += gam.T @ qg
        gx += qg.T @ phi
        gd += qg.T @ psi + gam.T @ zxd * decay[k]
        if b_at < nb and k == ends[b_at]:
            gam_end[b_at] = gam[:12]
            phi_end[b_at] = phi[:12]
            psi_end[b_at] = psi[:12]
            ce_phi[b_at] = m.ce @ phi
            ce_psi[b_at] = m.ce @ psi + m.de * decay[k]
            ce_gam[b_at] = m.ce @ gam
            b_at += 1
    if terminal:
        t = terminal_weight(m)
        tg = t @ gam
        hess += gam.T @ tg
        gx += tg.T @ phi
        gd += tg.T @ psi
    for j in range(nb):
        sl = slice(j * nu, (j + 1) * nu)
        hess[sl, sl] += lengths[j] * m.r
    hess = 0.5 * (hess + hess.T)
    return Condensed(
        ends=ends,
        lengths=lengths,
        hess=2.0 * hess,
        gx=2.0 * gx,
        gd=2.0 * gd,
        gam_end=gam_end,
        phi_end=phi_end,
        psi_end=psi_end,
        ce_phi=ce_phi,
        ce_psi=ce_psi,
        ce_gam=ce_gam,
    )


@dataclass(frozen=True, eq=False)
class RigLimits:
    """Actuator-space limits the plan respects (already scaled by the ``*_use`` fractions).

    Attributes
    ----------
    platform : motioncue.kinematics.Platform
    q_mid, q_half : (n,) arrays
        Centre and usable half stroke of each actuator (m or rad).
    v_max, a_max : (n,) arrays
        Usable speed and acceleration (per second, per second^2).
    tilt_rate, tilt_accel : float
        Largest roll/pitch rate (rad/s) and acceleration (rad/s^2; inf = none).
    """

    platform: Platform
    q_mid: NDArray[np.float64]
    q_half: NDArray[np.float64]
    v_max: NDArray[np.float64]
    a_max: NDArray[np.float64]
    tilt_rate: float
    tilt_accel: float


def rig_limits(
    params: CueingParams, mp: MpcParams, fs_hz: float, rig: Rig | None = None
) -> RigLimits:
    """The plan's limits on ``rig`` (default: the platform and controller named by ``mp``)."""
    if rig is None:
        from ._algorithm import named_rig

        rig = named_rig(mp.platform, mp.controller, fs_hz)
    platform = rig.platform
    lim = rig.limits
    q_min = np.asarray(lim.q_min, dtype=float)
    q_max = np.asarray(lim.q_max, dtype=float)
    q0 = np.asarray(platform.inverse(np.zeros(6)), dtype=float)
    if np.any(q0 <= q_min) or np.any(q0 >= q_max):
        raise ConfigError(f"platform {mp.platform!r}: neutral pose outside the usable stroke")
    # symmetric about neutral: the plan's linearisation is about poses near neutral
    half = np.minimum(q0 - q_min, q_max - q0) * mp.stroke_use
    accel = params.tilt_accel_limit_rad_s2
    return RigLimits(
        platform=platform,
        q_mid=q0,
        q_half=half,
        v_max=np.asarray(lim.v_max, dtype=float) * mp.rate_use,
        a_max=np.asarray(lim.a_max, dtype=float) * mp.rate_use,
        tilt_rate=(
            params.tilt_rate_limit_rad_s
            if mp.tilt_rate_limit_rad_s is None
            else mp.tilt_rate_limit_rad_s
        ),
        tilt_accel=math.inf if accel is None else accel,
    )


def fallback_accel(
    m: LinearModel, lim: RigLimits, x: NDArray[np.float64], pose_c: Sequence[float]
) -> NDArray[np.float64]:
    """The fallback input: a critically damped tracker of the classical pose ``pose_c``,
    ``u = wn^2 (p_c - p) - 2 wn v`` per moved DOF, clipped to :func:`fallback_cap`."""
    wn = _FALLBACK_WN
    cap = fallback_cap(m, lim)
    u = np.empty(m.nu)
    for j, i in enumerate(m.active):
        a = wn * wn * (pose_c[i] - x[i]) - 2.0 * wn * x[6 + i]
        u[j] = min(max(a, -cap[j]), cap[j])
    return u


def fallback_cap(m: LinearModel, lim: RigLimits) -> NDArray[np.float64]:
    """Per moved DOF, an acceleration every actuator can follow when all DOFs use theirs at
    once (``min a_max / (nu max_l |J_lj|)`` at neutral; the tilt acceleration limit)."""
    jac = np.abs(np.asarray(lim.platform.jacobian(np.zeros(6)), dtype=float))[:, list(m.active)]
    share = float(lim.a_max.min()) / max(1, m.nu)
    cap = share / np.maximum(jac.max(axis=0), 1e-9)
    if math.isfinite(lim.tilt_accel):
        for j, i in enumerate(m.active):
            if i in (3, 4):
                cap[j] = min(cap[j], lim.tilt_accel)
    return np.asarray(cap)


@dataclass(frozen=True, eq=False)
class PlanCueing:
    """What the two plans of a preset's ``[mpc]`` table (:class:`MpcCueing`, live, and
    ``OptimalCueing``, ride files) are made of and read first.

    Parameters
    ----------
    params : CueingParams
        The preset; ``params.mpc`` (default :class:`MpcParams` when absent) is the plan's
        table, its classical tables the fallback washout.
    fs_hz : float
        Sample rate (Hz); validated (and stored as) the fallback washout's.
    rig : Rig, optional
        The rig whose limits the plan keeps (:func:`rig_limits`).

    Attributes
    ----------
    mpc : MpcParams
        The ``[mpc]`` table with the reference limits of :func:`resolve_reach`.
    classical : ClassicalWashout
        The fallback washout at ``fs_hz``.
    model : LinearModel
        The plan's error model (each plan builds its own).
    limits : RigLimits
        The limits of :func:`rig_limits` on ``rig``.
    """

    params: CueingParams
    fs_hz: float
    rig: Rig | None = None
    mpc: MpcParams = field(init=False)
    classical: ClassicalWashout = field(init=False)
    model: LinearModel = field(init=False)
    limits: RigLimits = field(init=False)

    def _set_up_plan(self) -> None:
        """Set ``fs_hz``, ``classical``, ``mpc`` and ``limits`` (see the class docstring);
        the first thing a plan's ``__post_init__`` does (``model`` is the plan's own)."""
        classical = ClassicalWashout(self.params, self.fs_hz)
        mp = self.params.mpc if self.params.mpc is not None else MpcParams()
        limits = rig_limits(self.params, mp, classical.fs_hz, self.rig)
        object.__setattr__(self, "fs_hz", classical.fs_hz)
        object.__setattr__(self, "classical", classical)
        object.__setattr__(self, "mpc", resolve_reach(mp, limits))
        object.__setattr__(self, "limits", limits)


def tilt_axes(dofs: Sequence[bool]) -> list[int]:
    """The moved tilt DOFs among roll (3) and pitch (4) of ``dofs`` (6 flags)."""
    return [i for i in (3, 4) if dofs[i]]


def guard_channels(mp: MpcParams) -> list[int]:
    """The channels (0-5: fx, fy, fz, roll, pitch, yaw rate) with a sign guard
    (``sign_guard > 0``)."""
    return [i for i in range(6) if mp.sign_guard[i] > 0.0]


def sign_guard_bounds(
    mp: MpcParams, vehicle: NDArray[np.float64], free: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Bounds ``(lo, hi)`` (flattened, in thresholds) of the sign-guard rows ``A_g u``: where
    the vehicle's perceived motion ``vehicle`` ``(nb, ng)`` (or its sign; 0: unguarded) is
    positive, the plan's perceived motion (``A_g u + free``, ``free`` ``(nb, ng)`` in
    thresholds) at least ``-sign_guard`` thresholds, where negative at most ``sign_guard``;
    ``ng`` the channels of :func:`guard_channels`."""
    g = np.asarray(mp.sign_guard)[guard_channels(mp)]
    lo = np.where(vehicle > 0, -g - free, -np.inf)
    hi = np.where(vehicle < 0, g - free, np.inf)
    return lo.reshape(-1), hi.reshape(-1)


TILT_OCTAGON = np.array([[1.0, 1.0], [1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])
TILT_OCTAGON.setflags(write=False)
"""The combined-tilt rows (4, 2) of ``(roll, pitch)``: ``roll + pitch``, ``roll - pitch``,
``roll``, ``pitch`` (with :func:`octagon_bound`, a regular octagon about the circle of radius
``bound / sqrt(2)``; see :func:`tilt_fz_bound`)."""


def octagon_bound(bound: float) -> NDArray[np.float64]:
    """Bounds (4,) of :data:`TILT_OCTAGON`'s rows for a combined tilt ``bound`` (rad)."""
    return np.array([bound, bound, bound / math.sqrt(2.0), bound / math.sqrt(2.0)])


def input_bounds(
    m: LinearModel, lim: RigLimits, n_u: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(lbx, ubx)`` ``(n_u,)`` of blocked inputs (``nu`` per block): the roll and pitch
    accelerations within ``lim.tilt_accel`` (rad/s^2), the others free."""
    lbx = np.full(n_u, -np.inf)
    ubx = np.full(n_u, np.inf)
    if math.isfinite(lim.tilt_accel):
        for j, i in enumerate(m.active):
            if i in (3, 4):
                lbx[j :: m.nu] = -lim.tilt_accel
                ubx[j :: m.nu] = lim.tilt_accel
    return lbx, ubx


def accel_rows(ja: NDArray[np.float64], nb: int) -> NDArray[np.float64]:
    """The legs' acceleration rows ``(nb nl, nb nu)`` of blocked inputs: block-diagonal,
    ``ja`` ``(nl, nu)`` (the Jacobian's columns of the moved DOFs) in every block."""
    nl, nu = ja.shape
    out = np.zeros((nb * nl, nb * nu))
    for b in range(nb):
        out[b * nl : (b + 1) * nl, b * nu : (b + 1) * nu] = ja
    return out


@dataclass(eq=False)
class MpcState:
    """The changing state of one MPC run (mutable).

    Attributes
    ----------
    x : (nx,) array
        Model state (pose, rate, vestibular error states).
    xv, xt : (nx,) arrays or None
        With a sign guard: the model driven by the tracked reference alone and by the
        vehicle's motion alone (platform at rest), for the perceived motions it compares.
    ref_lp : (6,) array or None
        Low-pass state of :func:`reference` (with ``ref_split_hz``).
    ref_env : list of 2 floats or None
        With ``ref_adapt_peak_m_s2``: the fx, fy force envelope of :func:`reference` after
        the last sample (:func:`initial_ref_env` in a fresh or reset state).
    zr : array or None
        With ``fz_guard``: the otolith model's z states driven by the rider's own specific
        force deviation ``g (cos roll cos pitch - 1)`` at the platform's pose (the loss of
        vertical force of the tilt, which the linear model does not see), up to the present
        pose.
    classical : WashoutState
        The fallback washout's state (also holds the last good input sample).
    warm_u, warm_lam_a, warm_lam_x : arrays or None
        The last solution, to warm-start the next solve.
    solves, failed, late : int
        Solves attempted, failed (infeasible or not converged), dropped as late, since the
        state was made (:meth:`MpcCueing.reset` keeps these diagnostics, so a live session's
        figures survive the bridge's resets while parked).
    solve_ms : deque of float
        Wall time of the last (at most 6000) solves (ms).
    """

    x: NDArray[np.float64]
    classical: WashoutState
    warm_u: NDArray[np.float64] | None = None
    warm_lam_a: NDArray[np.float64] | None = None
    warm_lam_x: NDArray[np.float64] | None = None
    solves: int = 0
    failed: int = 0
    late: int = 0
    solve_ms: deque[float] = field(default_factory=lambda: deque(maxlen=6000))
    last_ms: float = 0.0
    xv: NDArray[np.float64] | None = None
    xt: NDArray[np.float64] | None = None
    ref_lp: NDArray[np.float64] | None = None
    zr: NDArray[np.float64] | None = None
    ref_env: list[float] | None = None

    @property
    def bad_samples(self) -> int:
        """Input samples replaced (NaN, inf, spikes) since the last reset."""
        return self.classical.bad_samples

    @property
    def fallbacks(self) -> int:
        """Samples on which the fallback ran (failed + late)."""
        return self.failed + self.late


@dataclass(frozen=True, eq=False)
class MpcResult:
    """Outcome of :meth:`MpcCueing.run`.

    Attributes
    ----------
    poses : (N, 6) array
        Platform poses (m, rad).
    bad_samples : int
    bad_mask : (N,) bool array
    f_used, w_used : (N, 3) arrays
        The input after bad samples were held.
    fallbacks : int
        Samples on which the classical fallback ran.
    solve_ms : (N,) array
        Wall time of each solve (ms).
    fs_hz : float
    """

    poses: NDArray[np.float64]
    bad_samples: int
    bad_mask: NDArray[np.bool_]
    f_used: NDArray[np.float64]
    w_used: NDArray[np.float64]
    fallbacks: int
    solve_ms: NDArray[np.float64]
    fs_hz: float


def recording_arrays(f: ArrayLike, w: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``f`` (m/s^2) and ``w`` (rad/s) of a whole recording as float arrays of shape (N, 3),
    as :meth:`MpcCueing.run` and ``OptimalCueing.run`` take them.

    Raises
    ------
    ConfigError
        If they are not both of shape (N, 3).
    """
    fa = np.asarray(f, dtype=float)
    wa = np.asarray(w, dtype=float)
    if fa.ndim != 2 or fa.shape[1] != 3 or wa.shape != fa.shape:
        raise ConfigError(f"need f and w of shape (N, 3); got {fa.shape} and {wa.shape}")
    return fa, wa


@dataclass(frozen=True, eq=False)
class QpData:
    """The data of one dense QP ``min 0.5 u' H u + g' u  s.t.  lba <= A u <= uba,  lbx <= u <=
    ubx`` but its Hessian ``H``: the Hessian is constant per design and belongs to the solver
    (:class:`QpSolver`, :class:`DaqpQp`, :class:`SoftGuardQp`, ``WorkingSetQp``: built once
    for it), the rest changes from solve to solve. Shapes: ``n`` unknowns, ``r`` rows (``r``
    may be 0); the arrays are held, not copied. A bound may be infinite (no bound).

    Attributes
    ----------
    g : (n,) array
        Gradient.
    a : (r, n) array
        Row matrix.
    lba, uba : (r,) arrays
        Lower and upper bounds of ``A u``.
    lbx, ubx : (n,) arrays
        Lower and upper bounds of ``u``.
    """

    g: NDArray[np.float64]
    a: NDArray[np.float64]
    lba: NDArray[np.float64]
    uba: NDArray[np.float64]
    lbx: NDArray[np.float64]
    ubx: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class SoftRows:
    """Soft one-sided rows (the sign guard) of a :class:`QpData`'s unknowns ``u``, each with a
    slack ``s >= 0``: ``A_g u + s >= lo`` where ``lo`` is finite, else ``A_g u - s <= hi``
    (:class:`SoftGuardQp`); ``k`` rows, in the caller's units (thresholds for the guard).

    Attributes
    ----------
    a : (k, n) array
        Row matrix ``A_g``.
    lo, hi : (k,) arrays
        Lower and upper bounds (a row's unused side infinite).
    """

    a: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]


QpOutcome = tuple[bool, NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]
"""``(ok, u, lam_a, lam_x)`` of a solve: ``ok`` false when the solver failed or returned
non-finite numbers; the multipliers of the rows and of the variable bounds (casadi's sign
convention: positive at an upper bound, negative at a lower one)."""

Warm = tuple[NDArray[np.float64] | None, NDArray[np.float64] | None, NDArray[np.float64] | None]
"""``(u, lam_a, lam_x)`` of a previous solve of the same sizes (a warm start)."""


class QpSolver:
    """A dense QP (:class:`QpData` with the Hessian ``hess``) through a casadi conic plugin,
    built once for fixed sizes."""

    def __init__(self, plugin: str, hess: NDArray[np.float64], n_rows: int) -> None:
        import casadi

        self._ca = casadi
        n = hess.shape[0]
        opts: dict[str, Any] = {"error_on_fail": False}
        if plugin == "qpoases":
            opts.update({"printLevel": "none", "sparse": False, "hessian_type": "posdef"})
        elif plugin == "osqp":
            opts.update(
                {
                    "warm_start_primal": True,
                    "warm_start_dual": True,
                    "osqp": {
                        "verbose": False,
                        "eps_abs": 1e-6,
                        "eps_rel": 1e-6,
                        "max_iter": 20000,
                        "polish": True,
                    },
                }
            )
        elif plugin == "proxqp":
            opts.update({"proxqp": {"eps_abs": 1e-8}})
        self.h = casadi.DM(hess)
        self.n = n
        self.n_rows = n_rows
        self._solver = casadi.conic(
            "mpc_qp",
            plugin,
            {"h": casadi.Sparsity.dense(n, n), "a": casadi.Sparsity.dense(n_rows, n)},
            opts,
        )

    def solve(self, qp: QpData, warm: Warm | None = None) -> QpOutcome:
        """``(ok, u, lam_a, lam_x)`` (:data:`QpOutcome`) of ``qp``; ``warm``: a previous
        solve's ``(u, lam_a, lam_x)``."""
        args: dict[str, Any] = {
            "h": self.h,
            "g": qp.g,
            "a": self._ca.DM(qp.a),
            "lba": qp.lba,
            "uba": qp.uba,
            "lbx": qp.lbx,
            "ubx": qp.ubx,
        }
        if warm is not None and warm[0] is not None:
            args["x0"], args["lam_a0"], args["lam_x0"] = warm
        try:
            res = self._solver(**args)
            ok = bool(self._solver.stats().get("success", False))
        except RuntimeError:
            return False, np.zeros(self.n), np.zeros(self.n_rows), np.zeros(self.n)
        u = np.asarray(res["x"], dtype=float).reshape(-1)
        la = np.asarray(res["lam_a"], dtype=float).reshape(-1)
        lx = np.asarray(res["lam_x"], dtype=float).reshape(-1)
        ok = ok and bool(np.all(np.isfinite(u)))
        return ok, u, la, lx


DAQP_INFEASIBLE = -1
"""DAQP's exit flag for a problem whose constraints it proved infeasible (EXIT_INFEASIBLE)."""


class DaqpQp:
    """The problem of :class:`QpSolver` through DAQP's own interface (:func:`daqp.solve`),
    the ``mpc`` route for ``solver = "daqp"``.

    The same dual active-set solver as casadi's ``daqp`` plugin without casadi's per-call
    work (argument conversion and densifying: 0.9-2.0 ms of CPU a solve of ``mpc-hexapod``
    through casadi, against 0.03-0.3 ms here; ``benchmarks/bench_mpc.py``). Warm start: the
    previous solution's active set (``warm``'s multipliers; positive at an upper bound,
    negative at a lower one, casadi's convention) is the solver's starting working set, so a
    plan that keeps its active constraints converges in about one iteration; a warm start that
    does not fit (e.g. rows no longer independent: DAQP refuses it) is retried cold. Each
    solve has a fresh workspace (a reused :class:`daqp.Model` carries rounding from one solve
    to the next), so the result depends only on the arguments and streaming, batch and reset
    runs give the same numbers.

    Attributes
    ----------
    infeasible : bool
        The last :meth:`solve` failed because DAQP proved its rows infeasible (exit flag
        :data:`DAQP_INFEASIBLE` on every start tried), not for another reason (cycling, an
        iteration limit, a refused start).
    """

    def __init__(self, hess: NDArray[np.float64], n_rows: int) -> None:
        self.h = np.ascontiguousarray(hess, dtype=float)
        self.n = int(hess.shape[0])
        self.n_rows = n_rows
        self.infeasible = False

    def solve(self, qp: QpData, warm: Warm | None = None) -> QpOutcome:
        """``(ok, u, lam_a, lam_x)`` as :meth:`QpSolver.solve`; ``warm`` is ``(u, lam_a,
        lam_x)`` of a previous solve of the same sizes (only its multipliers are used)."""
        import daqp

        n = self.n
        bu = np.concatenate([qp.ubx, qp.uba])
        bl = np.concatenate([qp.lbx, qp.lba])
        sense = np.zeros(n + self.n_rows, dtype=np.int32)
        if warm is not None and warm[1] is not None and warm[2] is not None:
            lam = np.concatenate([warm[2], warm[1]])
            if lam.shape == sense.shape:
                sense[lam > 0.0] = 1  # active at its upper bound
                sense[lam < 0.0] = 3  # active at its lower bound
        fail = (False, np.zeros(n), np.zeros(self.n_rows), np.zeros(n))
        self.infeasible = True  # until a start ends otherwise
        gv = np.ascontiguousarray(qp.g, dtype=float)
        am = np.ascontiguousarray(qp.a, dtype=float)
        for start in (sense, None) if np.any(sense) else (sense,):
            if start is None:  # a warm start that does not fit this problem: once cold
                start = np.zeros_like(sense)
            try:
                x, _, flag, info = daqp.solve(self.h, gv, am, bu, bl, start)
            except (RuntimeError, ValueError):
                self.infeasible = False
                continue
            self.infeasible &= int(flag) == DAQP_INFEASIBLE
            z = np.array(x, dtype=float).reshape(-1)
            if int(flag) == 1 and z.shape == (n,) and np.all(np.isfinite(z)):
                lam_all = np.array(info["lam"], dtype=float).reshape(-1)
                return True, z, lam_all[n:], lam_all[:n]
        return fail


def qp_solver(plugin: str, hess: NDArray[np.float64], n_rows: int) -> QpSolver | DaqpQp:
    """The ``mpc`` route to ``plugin``: :class:`DaqpQp` for ``"daqp"``, otherwise casadi's
    plugin (:class:`QpSolver`)."""
    if plugin == "daqp":
        return DaqpQp(hess, n_rows)
    return QpSolver(plugin, hess, n_rows)


def slack_hessian(hess: NDArray[np.float64], weight: float, k: int) -> NDArray[np.float64]:
    """The Hessian ``(n + k, n + k)`` of inputs and ``k`` slacks priced ``weight (s + s^2 /
    2)``: ``hess`` ``(n, n)``, then ``weight`` on the slacks' diagonal."""
    n = hess.shape[0]
    h = np.zeros((n + k, n + k))
    h[:n, :n] = hess
    h[n:, n:] = weight * np.eye(k)
    return h


def slack_terms(
    g: NDArray[np.float64],
    lbx: NDArray[np.float64],
    ubx: NDArray[np.float64],
    weight: float,
    k: int,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The gradient and variable bounds of inputs and ``k`` slacks (``s >= 0``, priced
    ``weight`` each): ``[g, weight]``, ``[lbx, 0]``, ``[ubx, inf]``."""
    return (
        np.concatenate([g, np.full(k, weight)]),
        np.concatenate([lbx, np.zeros(k)]),
        np.concatenate([ubx, np.full(k, np.inf)]),
    )


class SoftGuardQp:
    """:class:`QpSolver` plus soft one-sided rows (the sign guard, :class:`SoftRows`), each
    with a slack ``s >= 0`` priced ``weight (s + s^2 / 2)``::

        min 0.5 u' H u + g' u + weight sum(s + s^2 / 2)
        s.t. lba <= A u <= uba,  lbx <= u <= ubx,
             A_g u + s >= lo_g (rows with a finite lower bound),  A_g u - s <= hi_g (others)

    The rows are scaled by the caller so that a slack of 1 is one perception threshold; with
    the linear price the guard is met exactly whenever it can be, and otherwise violated as
    little as the price allows (no infeasible solve, no switching between two QPs).
    """

    def __init__(
        self,
        plugin: str,
        hess: NDArray[np.float64],
        n_rows: int,
        n_guard: int,
        weight: float,
        direct: bool = False,
    ) -> None:
        n = hess.shape[0]
        h = slack_hessian(hess, weight, n_guard)
        self.n = n
        self.n_rows = n_rows
        self.n_guard = n_guard
        self.weight = weight
        self._qp: QpSolver | DaqpQp = (
            qp_solver(plugin, h, n_rows + n_guard)
            if direct
            else QpSolver(plugin, h, n_rows + n_guard)
        )

    def solve(self, qp: QpData, guard: SoftRows) -> QpOutcome:
        """``(ok, u, lam_a, lam_x)`` of the inputs ``u`` (slacks dropped) of ``qp`` with the
        soft rows ``guard``."""
        ok, x, la, lx = self.solve_full(qp, guard)
        return ok, x[: self.n], la[: self.n_rows], lx[: self.n]

    def solve_full(self, qp: QpData, guard: SoftRows, warm: Warm | None = None) -> QpOutcome:
        """``(ok, z, lam_a, lam_x)`` of the whole problem: ``z = [u, s]`` (inputs, slacks),
        ``lam_a`` of ``[A; guard rows]``, ``lam_x`` of ``z``'s bounds; ``warm`` is such a
        triple of a previous solve (a warm start through the guard: the slacks' and the guard
        rows' multipliers are part of the active set it passes on)."""
        ng = self.n_guard
        sigma = np.where(np.isfinite(guard.lo), 1.0, -1.0)
        a_aug = np.zeros((self.n_rows + ng, self.n + ng))
        a_aug[: self.n_rows, : self.n] = qp.a
        a_aug[self.n_rows :, : self.n] = guard.a
        a_aug[self.n_rows :, self.n :] = np.diag(sigma)
        g_s, lbx_s, ubx_s = slack_terms(qp.g, qp.lbx, qp.ubx, self.weight, ng)
        lba_s, uba_s = np.concatenate([qp.lba, guard.lo]), np.concatenate([qp.uba, guard.hi])
        return self._qp.solve(QpData(g_s, a_aug, lba_s, uba_s, lbx_s, ubx_s), warm)


def _lin_at(
    limits: RigLimits, pose: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Leg positions and Jacobian ``(n, 6)`` at ``pose``."""
    plat = limits.platform
    q = np.asarray(plat.inverse(pose), dtype=float)
    jac = np.asarray(plat.jacobian(pose), dtype=float)
    return q, jac


@dataclass(frozen=True, eq=False)
class _FzParts:
    """Constant pieces of :meth:`MpcCueing.fz_guard_rows` (``nb`` block ends, ``nU``
    inputs, ``nx`` states, ``nz`` otolith z states)."""

    sl: NDArray[np.int64]  # (nz,): the otolith z states in the model's state
    az: NDArray[np.float64]  # (nz, nz)
    bz: NDArray[np.float64]  # (nz,): from the rider's specific force deviation s_z
    cz: NDArray[np.float64]  # (nz,)
    dz: float
    zmat: NDArray[np.float64]  # (nb, nz): perceived fz at the block ends from z_1
    hsum: NDArray[np.float64]  # (nb,): from a constant s_z of 1 over the horizon
    g_tilt: NDArray[np.float64]  # (nb, 2, nU): from roll, pitch of each step, by the inputs
    p_tilt: NDArray[np.float64]  # (nb, 2, nx): the same from the free state x0


@dataclass(frozen=True, eq=False)
class _QpParts:
    """Constant pieces of :meth:`MpcCueing.qp_matrices` and :meth:`MpcCueing.guard_rows`
    (``nb`` block ends, ``nU`` inputs, ``nx`` states, ``ng`` guarded channels)."""

    g_xd: NDArray[np.float64]  # (nU, nx + 6): gradient from [x0, d]
    free_xd: NDArray[np.float64]  # (nb, 12, nx + 6): free pose and rate at block ends
    gp: NDArray[np.float64]  # (nb, 6, nU): pose at block ends from the inputs
    gv: NDArray[np.float64]  # (nb, 6, nU): rate at block ends from the inputs
    fixed_rows: NDArray[np.float64]  # (r, nU): tilt-rate and octagon rows (constant)
    fixed_sel: tuple[NDArray[np.float64], ...]  # (w, 12) per kind: their free part
    leg_bound: tuple[NDArray[np.float64], NDArray[np.float64]]  # (nb nl,) stroke, speed
    fixed_bound: NDArray[np.float64]  # (r,): their symmetric bound
    acc_bound: NDArray[np.float64]  # (nb nl,): leg acceleration bound
    eye_nb: NDArray[np.float64]
    lbx: NDArray[np.float64]
    ubx: NDArray[np.float64]
    n_legs: int
    guard_a: NDArray[np.float64]  # (nb ng, nU): guard rows, in thresholds
    guard_phi: NDArray[np.float64]  # (nb, ng, nx)
    guard_psi: NDArray[np.float64]  # (nb, ng, 6)


@dataclass(frozen=True, eq=False)
class MpcCueing(PlanCueing):
    """Model-predictive cueing of a preset with an ``[mpc]`` table, at ``fs_hz``.

    Parameters
    ----------
    params : CueingParams
        Its classical tables set the fallback washout and the tilt limits; ``params.mpc``
        (default :class:`MpcParams` when absent) the MPC.
    fs_hz : float
        Sample rate (Hz).
    """

    cond: Condensed = field(init=False)
    _qp: QpSolver | DaqpQp = field(init=False, repr=False)
    _qp_guard: SoftGuardQp | None = field(init=False, repr=False)
    _prior_g: NDArray[np.float64] | None = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self._set_up_plan()
        fs = self.fs_hz
        mp = self.mpc
        prior = np.asarray(mp.w_prior)
        if np.any(prior > 0.0):  # w_pose |p|^2 + wc |p - c|^2: the quadratic part of both
            wp = [float(v) for v in np.asarray(mp.w_pose) + prior]
            both = replace(mp, w_pose=(wp[0], wp[1], wp[2], wp[3], wp[4], wp[5]))
            model = build_model(self.params.dofs, both, fs)
        else:
            model = build_model(self.params.dofs, mp, fs)
        n = max(1, round(mp.horizon_s * fs))
        ends = block_ends(n, mp.blocks)
        k = np.arange(n + 1)
        decay = (
            np.exp(-k / (mp.prediction_tau_s * fs)) if mp.prediction_tau_s > 0 else np.ones(n + 1)
        )
        cond = condense(model, ends, decay, terminal=True)
        object.__setattr__(self, "model", model)
        object.__setattr__(self, "cond", cond)
        object.__setattr__(
            self, "_prior_g", -2.0 * pose_sum(model, ends) * prior if np.any(prior > 0.0) else None
        )
        object.__setattr__(self, "_qp", qp_solver(mp.solver, cond.hess, self.n_rows))
        guard = self._guard_channels()
        n_soft = len(guard) + int(self._fz_guarded())
        object.__setattr__(
            self,
            "_qp_guard",
            SoftGuardQp(
                mp.solver,
                cond.hess,
                self.n_rows,
                len(ends) * n_soft,
                mp.sign_guard_weight,
                direct=True,
            )
            if n_soft
            else None,
        )

    # ------------------------------------------------------------------ sizes
    @property
    def n_rows(self) -> int:
        """Constraint rows of the QP (stroke, speed, acceleration of each leg per block, the
        tilt rate, and the combined tilt with ``tilt_fz_use``)."""
        nl = len(self.limits.q_mid)
        per_block = 3 * nl + len(self._tilt_axes()) + 4 * self._combined_tilt()
        return len(self.cond.ends) * (per_block + len(self._trans_boxed()))

    def _combined_tilt(self) -> bool:
        """Whether the QP has the combined-tilt rows (``tilt_fz_use`` with roll and pitch)."""
        return len(self._tilt_axes()) == 2 and self.mpc.tilt_fz_use > 0.0

    def _trans_boxed(self) -> list[int]:
        """Moved translations with a ``trans_limit_m`` below ``1e9`` (their pose rows)."""
        return [i for i in (0, 1, 2) if self.params.dofs[i] and self.mpc.trans_limit_m[i] < 1e9]

    def _guard_channels(self) -> list[int]:
        return guard_channels(self.mpc)

    def _fz_guarded(self) -> bool:
        """Whether the QP has ``fz_guard``'s rows (roll or pitch moved)."""
        return self.mpc.fz_guard > 0.0 and bool(self._tilt_axes())

    def _fz_parts(self) -> _FzParts:
        """Constant pieces of :meth:`fz_guard_rows` (built once, on first use): the
        otolith z model driven by the rider's specific force deviation, and its response at
        the block ends to the roll and pitch of every step of the horizon."""
        fp: _FzParts | None = self.__dict__.get("_fzp")
        if fp is not None:
            return fp
        m = self.model
        c = self.cond
        # the otolith z block of the error model (z is not moved by an fz_guard plan's
        # inputs' coupling: sx has no tilt term in fz), driven by s_z instead of -d_z
        from scipy.signal import tf2ss

        orders = [
            tf2ss(*vm.transfer_function())[0].shape[0]
            for vm in get_model_set(DEFAULT_MODEL_SET).channel_models()
        ]
        at = 12 + orders[0] + orders[1]
        sl = np.arange(at, at + orders[2])
        az = m.a[np.ix_(sl, sl)]
        bz = -m.bd[sl, 2]
        cz = m.ce[2, sl]
        dz = -float(m.de[2, 2])
        n = int(c.ends[-1])
        h = np.zeros(n + 1)  # p_n = cz az^(n-1) z_1 + sum_k h[n - k] s_k
        h[0] = dz
        powb = bz.copy()
        for j in range(1, n + 1):
            h[j] = float(cz @ powb)
            powb = az @ powb
        nb = len(c.ends)
        hmat = np.zeros((nb, n))  # (nb, steps 1..n)
        zmat = np.zeros((nb, len(sl)))
        powc = cz.copy()
        k_of = {int(e): b for b, e in enumerate(c.ends)}
        for j in range(1, n + 1):  # cz az^(j-1)
            if j in k_of:
                zmat[k_of[j]] = powc
            powc = powc @ az
        for b, e in enumerate(c.ends):
            e = int(e)
            hmat[b, :e] = h[e - np.arange(1, e + 1)]
        # roll and pitch of each step from x0 and the blocked inputs (as condense builds them)
        phi = np.eye(m.nx)
        g_tilt = np.zeros((n, 2, nb * m.nu))
        p_tilt = np.zeros((n, 2, m.nx))
        for k, gam in enumerate(input_responses(m, c.ends), start=1):
            phi = m.a @ phi
            g_tilt[k - 1] = gam[3:5]
            p_tilt[k - 1] = phi[3:5]
        fp = _FzParts(
            sl=sl,
            az=az,
            bz=bz,
            cz=cz,
            dz=dz,
            zmat=zmat,
            hsum=hmat.sum(axis=1),
            g_tilt=np.einsum("bk,kiu->biu", hmat, g_tilt),
            p_tilt=np.einsum("bk,kix->bix", hmat, p_tilt),
        )
        self.__dict__["_fzp"] = fp
        return fp

    def fz_guard_rows(
        self, state: MpcState, d_vehicle: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``fz_guard``'s rows ``(A, lo, hi)`` of this sample's QP, in thresholds of fz: at
        each block end where the vehicle's perceived fz (predicted from ``d_vehicle`` as the
        sign guard predicts it) is above ``fz_guard_from`` thresholds, the rider's perceived
        fz at least ``-fz_guard`` thresholds. The rider's specific force deviation from the tilt,
        ``g (cos roll cos pitch - 1)``, is linearised about the present roll and pitch (held
        over the horizon) and passed through the otolith model from its present state
        (``state.zr``); ``hi`` is ``inf`` (one-sided rows)."""
        fp = self._fz_parts()
        m = self.model
        c = self.cond
        g = GRAVITY_M_S2
        thr = float(m.thresholds[2])
        x0 = state.x
        r0, p0 = float(x0[3]), float(x0[4])
        loss0 = g * (1.0 - math.cos(r0) * math.cos(p0))
        a_r = g * math.sin(r0) * math.cos(p0) * float(self.params.dofs[3])
        a_p = g * math.cos(r0) * math.sin(p0) * float(self.params.dofs[4])
        a_p *= self.mpc.fz_guard_pitch
        const = loss0 - a_r * r0 - a_p * p0  # s = -(const + a_r roll + a_p pitch)
        zr = state.zr if state.zr is not None else np.zeros(len(fp.sl))
        free_tilt = fp.p_tilt @ x0  # (nb, 2)
        free = fp.zmat @ zr - const * fp.hsum - a_r * free_tilt[:, 0] - a_p * free_tilt[:, 1]
        a_rows = -(a_r * fp.g_tilt[:, 0, :] + a_p * fp.g_tilt[:, 1, :]) / thr
        xt = state.xt if state.xt is not None else np.zeros(m.nx)
        pv = -(c.ce_phi[:, 2, :] @ xt + c.ce_psi[:, 2, :] @ d_vehicle)
        lo = np.where(pv > self.mpc.fz_guard_from * thr, -self.mpc.fz_guard - free / thr, -np.inf)
        return a_rows, lo, np.full(lo.shape, np.inf)

    def guard_rows(
        self, state: MpcState, d_vehicle: NDArray[np.float64]
    ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """Sign-guard rows ``(A, lo, hi)`` of this sample's QP: at each block end, the plan's
        perceived motion on a guarded channel must not oppose the vehicle's perceived motion
        (both predicted over the horizon, the vehicle's held or decaying from ``d_vehicle``)
        by more than ``sign_guard`` thresholds; rows and bounds in thresholds)."""
        pre = self._parts()
        m = self.model
        xv = state.xv if state.xv is not None else np.zeros(m.nx)
        xt = state.xt if state.xt is not None else np.zeros(m.nx)
        # perceived simulator motion = ce (x - xv) (the reference's part cancels)
        free = pre.guard_phi @ (state.x - xv)  # (nb, ng)
        pv = -(pre.guard_phi @ xt + pre.guard_psi @ d_vehicle)
        lo, hi = sign_guard_bounds(self.mpc, pv, free / m.thresholds[self._guard_channels()])
        return pre.guard_a, lo, hi

    def _tilt_axes(self) -> list[int]:
        return tilt_axes(self.params.dofs)

    # ------------------------------------------------------------------ state
    def initial_state(self) -> MpcState:
        """A fresh state: platform at neutral and at rest, vehicle at rest."""
        return MpcState(
            x=np.zeros(self.model.nx),
            classical=self.classical.initial_state(),
            xv=np.zeros(self.model.nx),
            xt=np.zeros(self.model.nx),
            ref_env=initial_ref_env(self.mpc),
        )

    def reset(self, state: MpcState) -> None:
        """Put ``state`` back to :meth:`initial_state` (in place); the solve statistics are
        kept (diagnostics of the session, not part of the algorithm's state)."""
        state.x[:] = 0.0
        state.xv = np.zeros(self.model.nx)
        state.xt = np.zeros(self.model.nx)
        state.ref_lp = None
        state.ref_env = initial_ref_env(self.mpc)
        state.zr = None
        self.classical.reset(state.classical)
        state.warm_u = state.warm_lam_a = state.warm_lam_x = None

    def stats(self, state: MpcState) -> dict[str, float]:
        """Solve statistics of ``state``: ``solves``, ``failed``, ``late``, ``fallbacks``
        (counts since the state was made) and ``p50_ms``, ``p99_ms``, ``max_ms`` of the solve
        time over the last (at most 6000) solves; the bridge prints them."""
        t = np.array(state.solve_ms, dtype=float)
        out: dict[str, float] = {
            "solves": float(state.solves),
            "failed": float(state.failed),
            "late": float(state.late),
            "fallbacks": float(state.fallbacks),
        }
        for name, qv in (("p50_ms", 50.0), ("p99_ms", 99.0)):
            out[name] = float(np.percentile(t, qv)) if t.size else 0.0
        out["max_ms"] = float(t.max()) if t.size else 0.0
        return out

    # ------------------------------------------------------------------ the QP
    def _parts(self) -> _QpParts:
        """The constant pieces of every sample's QP (built once, on first use)."""
        pre: _QpParts | None = self.__dict__.get("_pre")
        if pre is not None:
            return pre
        c = self.cond
        m = self.model
        lim = self.limits
        nb = len(c.ends)
        nu = m.nu
        n_u = nb * nu
        gp = c.gam_end[:, 0:6, :]
        gv = c.gam_end[:, 6:12, :]
        fixed_rows: list[NDArray[np.float64]] = []
        fixed_sel: list[NDArray[np.float64]] = []  # each kind's part of the free pose, rate
        fixed_bound: list[NDArray[np.float64]] = []
        tilt = self._tilt_axes()
        eye12 = np.eye(12)
        if tilt:
            fixed_rows.append(gv[:, tilt, :].reshape(-1, n_u))
            fixed_sel.append(eye12[[6 + i for i in tilt]])
            fixed_bound.append(np.full(nb * len(tilt), lim.tilt_rate))
        if self._combined_tilt():
            bound = tilt_fz_bound(self.mpc, float(m.thresholds[2]))
            assert bound is not None
            fixed_rows.append(
                np.einsum("ck,bku->bcu", TILT_OCTAGON, gp[:, 3:5, :]).reshape(-1, n_u)
            )
            sel = np.zeros((4, 12))
            sel[:, 3:5] = TILT_OCTAGON
            fixed_sel.append(sel)
            fixed_bound.append(np.tile(octagon_bound(bound), nb))
        boxed = self._trans_boxed()
        if boxed:
            fixed_rows.append(gp[:, boxed, :].reshape(-1, n_u))
            fixed_sel.append(eye12[boxed])
            fixed_bound.append(np.tile(np.asarray(self.mpc.trans_limit_m)[boxed], nb))
        lbx, ubx = input_bounds(m, lim, n_u)
        lbx.flags.writeable = ubx.flags.writeable = False  # every sample's QP holds them
        nl = lim.q_mid.shape[0]
        guard = self._guard_channels()
        thr = m.thresholds[guard]
        pre = _QpParts(
            g_xd=np.hstack([c.gx, c.gd]),
            free_xd=np.concatenate([c.phi_end, c.psi_end], axis=2),
            gp=np.ascontiguousarray(gp),
            gv=np.ascontiguousarray(gv),
            fixed_rows=(np.concatenate(fixed_rows, axis=0) if fixed_rows else np.zeros((0, n_u))),
            fixed_sel=tuple(fixed_sel),
            leg_bound=(np.tile(lim.q_half, nb), np.tile(lim.v_max, nb)),
            fixed_bound=(np.concatenate(fixed_bound) if fixed_bound else np.zeros(0)),
            acc_bound=np.tile(lim.a_max, nb),
            eye_nb=np.eye(nb),
            lbx=lbx,
            ubx=ubx,
            n_legs=nl,
            guard_a=(c.ce_gam[:, guard] / thr[None, :, None]).reshape(-1, n_u),
            guard_phi=np.ascontiguousarray(c.ce_phi[:, guard]),
            guard_psi=np.ascontiguousarray(c.ce_psi[:, guard]),
        )
        self.__dict__["_pre"] = pre
        return pre

    def qp_matrices(
        self,
        x0: NDArray[np.float64],
        d: NDArray[np.float64],
        pose_c: Sequence[float] | None = None,
    ) -> QpData:
        """This sample's QP (the Hessian is ``cond.hess``), from state ``x0`` ``(nx,)`` and
        the vehicle's motion ``d`` ``(6,)``; with ``pose_c`` (the classical fallback's pose,
        m and rad) and ``w_prior``, the gradient has the prior's linear part too.

        Rows, each kind block-major (block end ``b`` outer): leg strokes, leg speeds, leg
        accelerations, the roll/pitch rates, the combined-tilt octagon, the translation box
        (``trans_limit_m``). ``lbx``, ``ubx`` are the design's own arrays (read-only)."""
        pre = self._parts()
        lim = self.limits
        m = self.model
        xd = np.concatenate([x0, d])
        g = pre.g_xd @ xd
        if self._prior_g is not None and pose_c is not None:
            g = g + self._prior_g @ np.asarray(pose_c, dtype=float)
        pose0 = x0[:6]
        q0, jac = _lin_at(lim, pose0)
        free = pre.free_xd @ xd  # (nb, 12)
        a_pos = np.matmul(jac, pre.gp).reshape(-1, pre.g_xd.shape[0])  # (nb nl, nU)
        a_vel = np.matmul(jac, pre.gv).reshape(-1, pre.g_xd.shape[0])
        a_acc = accel_rows(jac[:, list(m.active)], pre.eye_nb.shape[0])
        base = q0 - jac @ pose0 - lim.q_mid  # leg offset from centre at p = 0
        pos_free = (free[:, 0:6] @ jac.T + base).reshape(-1)  # (nb nl,)
        vel_free = (free[:, 6:12] @ jac.T).reshape(-1)
        # the tilt-rate and octagon rows' free part, block-major like their rows
        ff = [(free @ sel.T).reshape(-1) for sel in pre.fixed_sel]
        a_mat = np.concatenate([a_pos, a_vel, a_acc, pre.fixed_rows], axis=0)
        q_half, v_max = pre.leg_bound
        lba = np.concatenate(
            [
                -q_half - pos_free,
                -v_max - vel_free,
                -pre.acc_bound,
                -pre.fixed_bound - np.concatenate([np.zeros(0), *ff]),
            ]
        )
        uba = np.concatenate(
            [
                q_half - pos_free,
                v_max - vel_free,
                pre.acc_bound,
                pre.fixed_bound - np.concatenate([np.zeros(0), *ff]),
            ]
        )
        return QpData(g, a_mat, lba, uba, pre.lbx, pre.ubx)

    def _solve(
        self,
        state: MpcState,
        d: NDArray[np.float64],
        deadline_s: float | None,
        d_vehicle: NDArray[np.float64] | None = None,
        pose_c: Sequence[float] | None = None,
    ) -> NDArray[np.float64] | None:
        t0 = time.perf_counter()
        qp = self.qp_matrices(state.x, d, pose_c)
        warm = (state.warm_u, state.warm_lam_a, state.warm_lam_x)
        if self._qp_guard is not None and d_vehicle is not None:
            ga, glo, ghi = self.guard_rows(state, d_vehicle)
            if self._fz_guarded():
                fa, flo, fhi = self.fz_guard_rows(state, d_vehicle)
                ga = np.concatenate([ga, fa])
                glo = np.concatenate([glo, flo])
                ghi = np.concatenate([ghi, fhi])
            ok, u, la, lx = self._qp_guard.solve_full(qp, SoftRows(ga, glo, ghi), warm)
        else:
            ok, u, la, lx = self._qp.solve(qp, warm)
        elapsed = time.perf_counter() - t0
        state.solves += 1
        state.last_ms = elapsed * 1e3
        state.solve_ms.append(state.last_ms)
        if not ok:
            state.failed += 1
            state.warm_u = state.warm_lam_a = state.warm_lam_x = None
            return None
        state.warm_u, state.warm_lam_a, state.warm_lam_x = u, la, lx
        if deadline_s is not None and elapsed > deadline_s:
            state.late += 1
            return None
        return u[: self.model.nu]

    def _fallback(self, state: MpcState, pose_c: Sequence[float]) -> NDArray[np.float64]:
        return fallback_accel(self.model, self.limits, state.x, pose_c)

    def _advance(
        self, state: MpcState, f: Sequence[float], w: Sequence[float], deadline_s: float | None
    ) -> NDArray[np.float64]:
        pose_c = self.classical.step(state.classical, f, w)
        h = state.classical.hold
        dv = np.array([h[0], h[1], h[2] - GRAVITY_M_S2, h[3], h[4], h[5]])
        d, state.ref_lp = reference(dv, self.mpc, self.fs_hz, state.ref_lp, state.ref_env)
        u = self._solve(state, d, deadline_s, dv, pose_c)
        if u is None:
            u = self._fallback(state, pose_c)
        m = self.model
        state.x = m.a @ state.x + m.bu @ u + m.bd @ d
        if self._qp_guard is not None:
            if state.xv is None or state.xt is None:
                state.xv, state.xt = np.zeros(m.nx), np.zeros(m.nx)
            state.xv = m.a @ state.xv + m.bd @ d
            state.xt = m.a @ state.xt + m.bd @ dv
        if self._fz_guarded():
            fp = self._fz_parts()
            if state.zr is None:
                state.zr = np.zeros(len(fp.sl))
            sz = GRAVITY_M_S2 * (math.cos(state.x[3]) * math.cos(state.x[4]) - 1.0)
            state.zr = fp.az @ state.zr + fp.bz * sz
        return state.x[:6]

    # ------------------------------------------------------------------ streaming / batch
    def step(
        self,
        state: MpcState,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        """Advance one sample: see :meth:`CueingAlgorithm.step` (one solve; see the module
        docstring for the deadline)."""
        pose = self._advance(state, f, w, self.mpc.deadline_ms * 1e-3)
        vals = [float(v) for v in pose]
        if out is None:
            return vals
        out[:] = vals
        return out

    def run(self, f: ArrayLike, w: ArrayLike, state: MpcState | None = None) -> MpcResult:
        """A whole recording ``f``, ``w`` (N, 3) at ``fs_hz`` (no deadline; otherwise the
        numbers of :meth:`step`)."""
        fa, wa = recording_arrays(f, w)
        st = self.initial_state() if state is None else state
        n = fa.shape[0]
        poses = np.zeros((n, 6))
        bad = np.zeros(n, dtype=bool)
        f_used = np.zeros((n, 3))
        w_used = np.zeros((n, 3))
        times = np.zeros(n)
        fb_start = st.fallbacks
        bad_start = st.bad_samples
        for k in range(n):
            before = st.bad_samples
            poses[k] = self._advance(st, fa[k].tolist(), wa[k].tolist(), None)
            times[k] = st.last_ms
            bad[k] = st.bad_samples != before
            hold = st.classical.hold
            f_used[k] = hold[0:3]
            w_used[k] = hold[3:6]
        return MpcResult(
            poses=poses,
            bad_samples=st.bad_samples - bad_start,
            bad_mask=bad,
            f_used=f_used,
            w_used=w_used,
            fallbacks=st.fallbacks - fb_start,
            solve_ms=times,
            fs_hz=self.fs_hz,
        )
