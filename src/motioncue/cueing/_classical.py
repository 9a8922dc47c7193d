"""The classical washout algorithm (Reid & Nahon), streaming and batch with equal numbers.

References
----------
* L. D. Reid, M. A. Nahon, "Flight simulation motion-base drive algorithms: Part 1 -
  Developing and testing the equations", UTIAS Report No. 296, University of Toronto, 1985.
* L. D. Reid, M. A. Nahon, "... Part 2 - Selecting the system parameters", UTIAS Report
  No. 307, 1986.
* M. A. Nahon, L. D. Reid, "Simulator motion-drive algorithms: a designer's perspective",
  Journal of Guidance, Control, and Dynamics 13(2), 1990, 356-362.

Signal flow (per sample; frames, signs and units of conventions.md)
-------------------------------------------------------------------
0. **Bad input.** A sample whose six values are not all finite, or whose specific-force
   deviation ``|f - [0, 0, g]|`` or angular velocity exceeds ``reject_*`` on any axis, is
   replaced by the last good sample (rest, ``f = [0, 0, g], w = 0``, before the first) and
   counted.
   With ``lead_s = (tau_x, tau_y)`` the held ``f_x, f_y`` fed to the tilt (step 2, with
   its own ``tilt_scale``) pass the phase lead ``(1 + tau s) / (1 + tau s / LEAD_GAIN)``
   (Tustin, prewarped at ``1/tau``), which offsets the tilt's lag.
1. **Scaling and smooth limiting.** ``f_s = [0, 0, g] + L_f(k_f * (f - [0, 0, g]))``,
   ``w_s = L_w(k_w * w)`` with the limiter ``L`` of :func:`~._filters.soft_limit`.
   With ``f_shape`` / ``w_shape`` set, the channel is compressed instead
   (:func:`~._filters.compress`): ``k x / (1 + |k x / L|^p)^(1/p)`` replaces ``L(k x)``,
   so small cues pass with the gain ``k`` and large ones bend smoothly below the limit.
2. **Tilt coordination.** ``f_t = f_s`` (x, y) or, when ``tilt_scale = (kt_x, kt_y)`` is set,
   ``f_t = [kt_x f_x, kt_y f_y]`` (its own gain, without the translational force limit:
   the tilt angle has its own limit). ``f_t,x`` and ``f_t,y`` pass the low-pass
   ``G_T(s) = wt^2 / (s^2 + 2 zt wt s + wt^2)``. The tilt that makes gravity supply that
   force in the platform frame (``R^T [0, 0, g]`` has x component ``-g sin(pitch)`` and y
   component ``g sin(roll) cos(pitch)``) is ``pitch* = -asin(f_x,lp / g)`` (forward
   acceleration -> nose up, negative pitch about the left-pointing y axis) and
   ``roll* = asin(f_y,lp / g)`` (rightward force -> left side down, rider pressed left).
   Each target is smoothly limited to ``tilt_limit`` and then rate limited:
   ``tilt[n] = tilt[n-1] + clip(target - tilt[n-1], -r/fs, r/fs)`` (the limit bounds the
   tilt; roll and pitch also carry the high-passed rotational cue of step 3).
   With ``tilt_forward_ratio = r`` (with ``tilt_scale``) the gain on a forward force
   (``f_x > 0``, throttle, nose up) is ``r kt_x`` and on a rearward one (braking, nose down)
   ``kt_x``, here and in the compressive tilt below: a smaller forward tilt leaves less to
   unwind when a stop follows the throttle.
   With ``tilt_shape = p`` (the compressive tilt) the force fed to the low-pass is
   ``f_t = compress(f, kt, L+, L-, p)`` with ``L = g sin(u * reach)`` in the direction the
   tilt goes (``u = tilt_reach_use``, ``reach`` the platform's own reach in pure tilt,
   ``tilt_reach_rad``): large sustained forces are compressed into the tilt this platform
   can give in that direction, and the angle is only clipped to ``u * reach`` (a no-op but
   for the low-pass's rounding) instead of the soft ``tilt_limit``. Roll and pitch together
   are kept inside the ellipse of the quadrant they are in,
   ``(roll / R)^2 + (pitch / P)^2 <= 1`` with ``R, P`` the limits in that direction: a
   target outside it is scaled back towards level along its own direction (a hexapod
   reaches about 0.9-1.1 times that ellipse along the diagonals, 12.4 deg of roll alone).
   With ``tilt_reach_exponent = q`` the region is the superellipse ``|roll / R|^q +
   |pitch / P|^q <= 1`` instead (``q = 2`` the ellipse; a smaller ``q`` is tighter along the
   diagonals, where a reach extended by the reach offset of step 4 is shortest).
   With ``tilt_fz_guard = (L, A, wz)`` the vehicle's ``f_z - g`` passes the low-pass
   ``wz^2 / (s^2 + 2 wz s + wz^2)``, ``d``; where ``d > A`` the roll's force ``f_t,y`` fed
   to ``G_T`` is clipped to ``+-sqrt(max(0, g^2 (1 - c^2) - f_t,x^2))`` (the pitch's kept),
   ``c = 1 - l / g``, ``l = L + (g - L) (1 - min(1, (d - A) / max(A, 0.05)))``: a settled
   tilt then has ``sin(roll)^2 + sin(pitch)^2 <= 1 - c^2`` unless the pitch alone exceeds
   it, so its fz loss ``g (1 - cos(roll) cos(pitch)) <= l`` (the held roll no longer lowers
   the felt ``f_z`` against a vehicle pressed into a dip).
   With ``tilt_adapt_peak_m_s2 = (c_x, c_y)`` the tilt's gain adapts to the drive: on each
   axis with ``c > 0`` the envelope ``e[n] = max(|f[n]|, d e[n-1])`` (``d = exp(-1 / (fs
   tau))``, ``tau = tilt_adapt_tau_s``, the held vehicle force, ``e =
   tilt_adapt_start_m_s2`` before the first sample) scales the force fed to the tilt by ``c
   / (kt e)`` where ``kt e > c`` (``kt`` that axis's ``tilt_scale``), before the lead's
   output meets the compression: the tilt's gain
   is ``min(kt, c / e)``, so the largest force of the last few ``tau`` reaches the
   compression at ``c``.
   With ``tilt_accel_limit_rad_s2 = a`` the tilt is also acceleration limited
   (:func:`rate_accel_limit_step`): with the per-sample step ``u[n] = tilt[n] - tilt[n-1]``,
   ``d = a / fs^2`` and ``e = target - tilt[n-1]``, the wanted step is
   ``sign(e) min(r/fs, |e|, d (sqrt(1/4 + 2|e|/d) - 1/2))`` (the last term is the largest
   step from which braking by ``d`` per sample stops at the target), and then
   ``u[n] = clip(wanted, u[n-1] - d, u[n-1] + d)``. So ``|u[n]| <= r/fs`` and
   ``|u[n] - u[n-1]| <= a/fs^2`` always: tilt rate at most ``r`` and tilt acceleration
   (backward difference) at most ``a``; a step in the target gives the time-optimal
   trapezoid (or triangle) under both limits, to within one sample (an overshoot below
   ``a/fs^2`` where braking would have to start between two samples).
   With ``tilt_rate_mix`` (rows ``(a_k, b_k)``) roll and pitch are also rate limited
   together (:func:`rate_mix_step`): the per-axis steps ``(u_r, u_p)`` above are scaled by
   one factor ``c = min(1, (r/fs) / max_k(a_k |u_r| + b_k |u_p|))``, which keeps the
   ratio of the two steps, and then (with the acceleration limit) clipped again to
   ``u[n-1] +- d`` per axis. So ``max_k(a_k |roll'| + b_k |pitch'|) <= r`` up to that clip (at most
   ``max_k(a_k + b_k) a / fs`` more, only while braking from a faster joint rate).
3. **Rotational channel.** Body rates are turned into Euler-angle rates
   ``e = T(beta) w_s`` (ZYX: ``roll' = p + tan(pitch)(q sin(roll) + r cos(roll))``,
   ``pitch' = q cos(roll) - r sin(roll)``, ``yaw' = (q sin(roll) + r cos(roll))/cos(pitch)``),
   then high-passed and integrated in one stable filter
   ``H_R(s)/s = s / (s^2 + 2 zr wr s + wr^2)`` (``H_R`` the second-order high-pass
   ``s^2/(s^2 + 2 zr wr s + wr^2)``): ``beta_hp = H_R/s * e``. The tilt is added:
   ``[roll, pitch, yaw] = [beta_hp,roll + tilt_roll, beta_hp,pitch + tilt_pitch, beta_hp,yaw]``.
   As in Reid & Nahon the high-pass comes after the (nonlinear) rate transformation, so
   every angular-velocity input washes out through a stable filter. ``T`` is evaluated at
   the attitude ``beta_pred = H_R/s * w_s + tilt`` (the small-angle prediction of the
   platform attitude) rather than at the previous output: this keeps the whole algorithm a
   feed-forward cascade (no feedback from output to input), which is what lets the batch
   run be vectorised with exactly the streaming numbers. The two differ only at second
   order in the high-passed angles.
4. **Translational channel.** The scaled force is taken to the inertial frame with the
   platform attitude and gravity removed, ``a = R(roll, pitch, yaw) f_s - [0, 0, g]``
   (``R = Rz Ry Rx``), then high-passed and integrated twice in one stable filter
   ``P(s) = H_T(s)/s^2`` with
   ``H_T(s) = s^2/(s^2 + 2 zeta wn s + wn^2) * s/(s + wb)``, i.e.
   ``P(s) = 1/(s^2 + 2 zeta wn s + wn^2) * s/(s + wb)``. With ``wb > 0`` a sustained
   acceleration returns the platform to neutral; with ``wb = 0``
   (``P = 1/(s^2 + 2 zeta wn s + wn^2)``) it leaves an offset ``a / wn^2``.

   **Additive tilt** (``tilt_additive``, with ``tilt_scale``). In the design above the
   scaled force ``f_s`` is the *whole* cue: where the tilt gives more than ``f_s`` (the tilt
   has its own gain ``tilt_scale``), the translation drives against the tilt's excess for
   as long as its high-pass lets it (tens of mm in a long corner, and an opposite cue on
   its way). With the additive tilt the tilt coordination's own gravity in the platform
   frame, ``g_t = R_t^T [0, 0, g] - [0, 0, g] = [-g sin(pitch_t), g sin(roll_t)
   cos(pitch_t), g (cos(roll_t) cos(pitch_t) - 1)]`` (``roll_t, pitch_t`` the rate-limited
   tilt of step 2), joins the target: ``a = R (f_s + g_t) - [0, 0, g]``. The translation
   then renders ``f_s`` (to first order ``a = f_s``, whatever the tilt) and the tilt adds
   its own cue: with ``f_s = 0`` and no rotational cue nothing reaches the translational
   filters (``R = R_t``). The gravity of the rotational channel's angles is still
   compensated as above.

   **Lag fill** (``tilt_lag_fill = k``, with the additive tilt). The rate (and
   acceleration) limit delays the tilt behind its target ``(roll*, pitch*)`` (step 2 before
   those limits). The translation's target then also carries ``k`` times the difference of
   the two tilts' gravity, ``a = R (f_s + g_t + k (g_t* - g_t)) - [0, 0, g]``, so that (to
   first order, within the translational high-pass) the rider feels ``f_s + g_t + k (g_t* -
   g_t)``: the tilt's force sooner at an onset, its late return countered. With ``f_s =
   0`` (``f_scale`` z too), no rotational cue and pure pitch it is exactly
   ``a_x = g (cos(pitch) (-(1-k) sin(pitch) - k sin(pitch*)) + sin(pitch) ((1-k) cos(pitch)
   + k cos(pitch*))) = -k g sin(pitch* - pitch)``.

   **Head offset.** With the rider's head at ``h = head_offset_m`` (platform frame, from the
   platform origin), a platform whose origin has specific force ``f_o`` (platform frame) and
   which turns with body angular velocity ``W`` and acceleration ``W'`` gives the head
   ``f_head = f_o + W' x h + W x (W x h)`` (tangential and centripetal terms; ``x`` the
   cross product). The cue wants ``f_head = f_s``, so the translational channel is fed
   ``a = R (f_s - W' x h - W x (W x h)) - [0, 0, g]`` instead. ``W`` and ``W'`` are those of
   this algorithm's own output attitude ``(roll, pitch, yaw)[n]``, by backward differences:
   ``e' = (beta[n] - beta[n-1]) fs``, ``W = [roll' - yaw' sin(pitch),
   pitch' cos(roll) + yaw' cos(pitch) sin(roll), -pitch' sin(roll) + yaw' cos(pitch)
   cos(roll)]`` at ``beta[n]``, ``W'[n] = (W[n] - W[n-1]) fs`` (zero before the first
   sample). Example: a head ``h_z`` above the origin and a small pitch ``theta`` (nose down
   positive) swing the head forward by ``h_z theta``: the term is ``W' x h = [h_z theta'',
   0, 0]``, so the platform origin is moved back by the high-passed ``h_z theta``,
   ``x = -h_z H_T(s) theta`` to first order. ``h = 0`` is the formula without these terms.
   **Reach offset** (``tilt_offset_m = C``). The origin also moves with the delivered tilt
   ``(roll_t, pitch_t)``: ``[x, y, z] += C [roll_t, pitch_t, roll_t^2, pitch_t^2, roll_t
   pitch_t]``, a static function of the tilt (so batch = streaming), added after the
   translational filters. It keeps the legs nearer the middle of their stroke as the platform
   tilts, which lets it tilt further than about its neutral position (``tilt_reach_rad`` is
   then the reach with the offset). Its own acceleration is felt (``C`` times the tilt's
   acceleration, to first order).
5. Components the machine cannot move (``dofs``) are zero, and are zero in ``R`` and ``T``.

Discretisation
--------------
Each continuous factor (one second-order or one first-order section) is discretised by
the bilinear (Tustin) transform prewarped at its own characteristic frequency (``wn`` of
a second-order factor, ``wb`` of the break) at the run's sample rate: ``s = K (z - 1) /
(z + 1)`` with ``K = w / tan(w / (2 fs))`` (:func:`scipy.signal.bilinear` with
``fs = K / 2``), so each factor's response is exact at its own ``w``. It is executed as a
second-order section in transposed direct form II (the recurrence of
:func:`scipy.signal.sosfilt`). Streaming runs that recurrence on plain floats; batch calls
``sosfilt``. A factor whose frequency is not below Nyquist is rejected at construction.
"""

from __future__ import annotations

import math
from collections.abc import Callable, MutableSequence, Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._filters import (
    Section,
    compress,
    compress_array,
    rate_limit_array,
    soft_limit,
    soft_limit_array,
    tustin_section,
)
from ._params import GRAVITY_M_S2, LEAD_GAIN, CueingParams

__all__ = [
    "ClassicalWashout",
    "WashoutResult",
    "WashoutState",
    "rate_accel_limit_step",
    "rate_mix_step",
]

_IDENTITY: Section = (1.0, 0.0, 0.0, 1.0, 0.0, 0.0)
_GUARD_MIN_RAMP_M_S2 = 0.05  # the fz guard's ramp is at least this wide (tilt_fz_guard)
_MIN_COS_PITCH = 1e-3

# Section order (each section owns two delay states in WashoutState.z):
# 0, 1: tilt low-pass x, y; 2, 3: rotational prediction roll, pitch (yaw does not enter T);
# 4-6: rotational high-pass+integrator roll, pitch, yaw; 7-12: translational x1, x2, y1, y2,
# z1, z2 (the second section of an axis is the identity when its wb is 0).
# 13, 14: phase lead on fx, fy (the identity without lead_s).
# 15: the low-pass of the vehicle's f_z - g for tilt_fz_guard (the identity without it).
_N_SECTIONS = 16


@dataclass(eq=False)
class WashoutState:
    """The changing state of one washout run (mutable; see :meth:`ClassicalWashout.step`).

    Attributes
    ----------
    z : list of 32 floats
        Delay states of the 16 second-order sections.
    tilt : list of 2 floats
        Rate-limited tilt ``[roll, pitch]`` (rad) of the last sample.
    hold : list of 6 floats
        Last good input ``[fx, fy, fz, wx, wy, wz]`` (used for bad samples).
    tilt_rate : list of 2 floats
        Tilt rate ``[roll, pitch]`` (rad/s) of the last sample (kept when the tilt is
        acceleration limited or has the joint rate limit ``tilt_rate_mix``).
    attitude : list of 3 floats
        Output ``[roll, pitch, yaw]`` (rad) of the last sample (kept with a head offset).
    omega : list of 3 floats
        Platform body angular velocity (rad/s) of the last sample (kept with a head offset).
    tilt_env : list of 2 floats
        Envelope ``[x, y]`` (m/s^2) of the vehicle's force peaks (kept with
        ``tilt_adapt_peak_m_s2``; :meth:`ClassicalWashout.initial_state` starts it at
        ``tilt_adapt_start_m_s2``).
    bad_samples : int
        Samples replaced by the last good one since the last reset.
    samples : int
        Samples processed since the last reset.
    """

    z: list[float] = field(default_factory=lambda: [0.0] * (2 * _N_SECTIONS))
    tilt: list[float] = field(default_factory=lambda: [0.0, 0.0])
    tilt_rate: list[float] = field(default_factory=lambda: [0.0, 0.0])
    attitude: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    omega: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    hold: list[float] = field(default_factory=lambda: [0.0, 0.0, GRAVITY_M_S2, 0.0, 0.0, 0.0])
    tilt_env: list[float] = field(default_factory=lambda: [0.0, 0.0])
    bad_samples: int = 0
    samples: int = 0


@dataclass(frozen=True, eq=False)
class WashoutResult:
    """Outcome of a batch run.

    Attributes
    ----------
    poses : (N, 6) array
        Platform pose ``[x, y, z, roll, pitch, yaw]`` (m, rad) per sample.
    bad_samples : int
        Input samples that were NaN/inf or spikes, replaced by the last good sample.
    bad_mask : (N,) bool array
        Which samples those were.
    tilt : (N, 2) array
        The rate-limited tilt-coordination angles ``[roll, pitch]`` (rad).
    f_used, w_used : (N, 3) arrays
        The input after bad samples were held (unscaled), for evaluation.
    fs_hz : float
        Sample rate.
    """

    poses: NDArray[np.float64]
    bad_samples: int
    bad_mask: NDArray[np.bool_]
    tilt: NDArray[np.float64]
    f_used: NDArray[np.float64]
    w_used: NDArray[np.float64]
    fs_hz: float


def _rate_accel_limit_array(
    target: NDArray[np.float64],
    step_max: float,
    accel_step: float,
    tilt: list[float],
    tilt_rate: list[float],
    k: int,
    fs: float,
) -> NDArray[np.float64]:
    """:func:`rate_accel_limit_step` over a signal (the loop on floats, so that it gives
    exactly the streaming numbers), continuing from and updating ``tilt[k]`` (rad) and
    ``tilt_rate[k]`` (rad/s)."""
    prev = tilt[k]
    rate = tilt_rate[k]
    out: list[float] = []
    append = out.append
    for x in target.tolist():
        u = rate_accel_limit_step(x, prev, rate / fs, step_max, accel_step)
        prev = prev + u
        rate = u * fs
        append(prev)
    tilt_rate[k] = rate
    return np.array(out, dtype=np.float64)


def _adapt_gain(
    f: NDArray[np.float64], c: float, kt: float, tau_s: float, fs: float, env: list[float], k: int
) -> NDArray[np.float64]:
    """The factor ``tilt_adapt_peak_m_s2`` puts on one axis's force fed to the tilt (step 2
    above): ``c / (kt e)`` where ``kt e > c``, else 1, with the envelope ``e`` of ``|f|``
    (the loop on floats, so that it gives exactly the streaming numbers), continuing from and
    updating ``env[k]`` (m/s^2). ``c = 0``: ones (the envelope still advances)."""
    decay = math.exp(-1.0 / (fs * tau_s))
    cur = env[k]
    e: list[float] = []
    append = e.append
    for v in np.abs(f).tolist():
        cur = cur * decay
        cur = v if v > cur else cur
        append(cur)
    env[k] = cur
    out = np.ones(len(e))
    if c > 0.0:
        ke = kt * np.array(e)
        over = ke > c
        out[over] = c / ke[over]
    return out


_StepFn = Callable[
    [WashoutState, Sequence[float], Sequence[float], MutableSequence[float] | None],
    MutableSequence[float],
]


def rate_accel_limit_step(
    target: float, prev: float, u_prev: float, step_max: float, accel_step: float
) -> float:
    """One sample of the rate- and acceleration-limited follower of the tilt (step 2 above).

    Parameters
    ----------
    target : float
        Where the output should go (rad).
    prev : float
        Output of the previous sample (rad).
    u_prev : float
        Previous per-sample step ``prev - prev_before`` (rad).
    step_max : float
        Largest step per sample, ``rate_limit / fs`` (rad), > 0.
    accel_step : float
        Largest change of the step per sample, ``accel_limit / fs^2`` (rad), > 0.

    Returns
    -------
    float
        This sample's step ``u`` (rad): the output is ``prev + u``; ``|u| <= step_max`` when
        ``|u_prev| <= step_max``, and ``|u - u_prev| <= accel_step``.
    """
    e = target - prev
    ae = -e if e < 0.0 else e
    u = step_max if step_max < ae else ae
    stop = accel_step * (math.sqrt(0.25 + 2.0 * ae / accel_step) - 0.5)
    if stop < u:
        u = stop
    if e < 0.0:
        u = -u
    lo = u_prev - accel_step
    hi = u_prev + accel_step
    if u < lo:
        u = lo
    elif u > hi:
        u = hi
    return u


def rate_mix_step(
    u_roll: float,
    u_pitch: float,
    prev_roll: float,
    prev_pitch: float,
    rows: Sequence[tuple[float, float]],
    step_max: float,
    accel_step: float,
) -> tuple[float, float]:
    """The joint rate limit of roll and pitch (``tilt_rate_mix``, step 2 above).

    Parameters
    ----------
    u_roll, u_pitch : float
        This sample's steps of each axis alone (rad), from its own rate (and acceleration)
        limit.
    prev_roll, prev_pitch : float
        The previous sample's steps (rad).
    rows : sequence of (a, b)
        Weights of ``|u_roll|`` and ``|u_pitch|``, each >= 0.
    step_max : float
        ``rate_limit / fs`` (rad), > 0.
    accel_step : float
        ``accel_limit / fs^2`` (rad); 0 without an acceleration limit.

    Returns
    -------
    (float, float)
        The steps ``c * (u_roll, u_pitch)`` with ``c = min(1, step_max / max_k(a_k |u_roll|
        + b_k |u_pitch|))``, then (``accel_step > 0``) each clipped to its previous step
        ``+- accel_step``.
    """
    ar = -u_roll if u_roll < 0.0 else u_roll
    ap = -u_pitch if u_pitch < 0.0 else u_pitch
    worst = 0.0
    for a, b in rows:
        v = a * ar + b * ap
        if v > worst:
            worst = v
    if worst <= step_max:
        return u_roll, u_pitch
    c = step_max / worst
    u_roll *= c
    u_pitch *= c
    if accel_step > 0.0:
        lo, hi = prev_roll - accel_step, prev_roll + accel_step
        u_roll = lo if u_roll < lo else (hi if u_roll > hi else u_roll)
        lo, hi = prev_pitch - accel_step, prev_pitch + accel_step
        u_pitch = lo if u_pitch < lo else (hi if u_pitch > hi else u_pitch)
    return u_roll, u_pitch


def _rate_mix_array(
    target_roll: NDArray[np.float64],
    target_pitch: NDArray[np.float64],
    rows: Sequence[tuple[float, float]],
    step_max: float,
    accel_step: float,
    tilt: list[float],
    tilt_rate: list[float],
    fs: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The rate (and acceleration) limit of each axis and :func:`rate_mix_step` over a
    signal (a loop on floats with the streaming numbers), continuing from and updating
    ``tilt`` (rad) and ``tilt_rate`` (rad/s)."""
    pr, pp = tilt[0], tilt[1]
    ur0, up0 = tilt_rate[0] / fs, tilt_rate[1] / fs
    out_r: list[float] = []
    out_p: list[float] = []
    for xr, xp in zip(target_roll.tolist(), target_pitch.tolist(), strict=True):
        ur, up = _axis_steps(xr, xp, pr, pp, ur0, up0, step_max, accel_step)
        ur, up = rate_mix_step(ur, up, ur0, up0, rows, step_max, accel_step)
        pr += ur
        pp += up
        ur0, up0 = ur, up
        out_r.append(pr)
        out_p.append(pp)
    tilt_rate[0], tilt_rate[1] = ur0 * fs, up0 * fs
    return np.array(out_r, dtype=np.float64), np.array(out_p, dtype=np.float64)


def _axis_steps(
    xr: float,
    xp: float,
    pr: float,
    pp: float,
    ur0: float,
    up0: float,
    step_max: float,
    accel_step: float,
) -> tuple[float, float]:
    """Each axis's own step towards its target (rate, and with ``accel_step > 0``
    acceleration, limited), before the joint limit."""
    if accel_step > 0.0:
        return (
            rate_accel_limit_step(xr, pr, ur0, step_max, accel_step),
            rate_accel_limit_step(xp, pp, up0, step_max, accel_step),
        )
    dr = xr - pr
    dp = xp - pp
    dr = step_max if dr > step_max else (-step_max if dr < -step_max else dr)
    dp = step_max if dp > step_max else (-step_max if dp < -step_max else dp)
    return dr, dp


def _sos(*sections: Section) -> NDArray[np.float64]:
    return np.array(sections, dtype=float)


@dataclass(frozen=True, eq=False)
class ClassicalWashout:
    """The classical washout of :class:`CueingParams` discretised at ``fs_hz``.

    Parameters
    ----------
    params : CueingParams
    fs_hz : float
        Sample rate of the run (> 0); every filter frequency must be below Nyquist.

    Notes
    -----
    Frozen: it holds only the discretised coefficients. The changing state lives in a
    :class:`WashoutState` from :meth:`initial_state`, passed explicitly to :meth:`step` and
    optionally to :meth:`run`; both give the same numbers (to rounding).
    """

    params: CueingParams
    fs_hz: float
    tilt_lp: Section = field(init=False)
    fz_lp: Section = field(init=False)
    lead: tuple[Section, Section] = field(init=False)
    rot: tuple[Section, Section, Section] = field(init=False)
    trans: tuple[tuple[Section, Section], ...] = field(init=False)
    _step_impl: _StepFn = field(init=False, repr=False)
    _sos: dict[int, NDArray[np.float64]] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        fs = self.fs_hz
        if isinstance(fs, bool) or not isinstance(fs, int | float) or not math.isfinite(fs):
            raise ConfigError(f"fs_hz = {fs!r} is invalid; allowed: a finite number > 0")
        if fs <= 0.0:
            raise ConfigError(f"fs_hz = {fs!r} is invalid; allowed: a finite number > 0")
        object.__setattr__(self, "fs_hz", float(fs))
        p = self.params
        wt, zt = p.tilt_wn_rad_s, p.tilt_zeta
        tilt_lp = tustin_section([wt * wt], [1.0, 2.0 * zt * wt, wt * wt], fs, wt)
        rot = tuple(
            tustin_section([1.0, 0.0], [1.0, 2.0 * z * w, w * w], fs, w)
            for w, z in zip(p.rot_wn_rad_s, p.rot_zeta, strict=True)
        )
        trans = []
        for w, z, wb in zip(p.trans_wn_rad_s, p.trans_zeta, p.trans_wb_rad_s, strict=True):
            if wb > 0.0:
                first = tustin_section([1.0, 0.0], [1.0, 2.0 * z * w, w * w], fs, w)
                second = tustin_section([1.0], [1.0, wb], fs, wb)
            else:
                first = tustin_section([1.0], [1.0, 2.0 * z * w, w * w], fs, w)
                second = _IDENTITY
            trans.append((first, second))
        leads: list[Section] = [_IDENTITY, _IDENTITY]
        if p.lead_s is not None:
            for i, tau in enumerate(p.lead_s):
                leads[i] = tustin_section([tau, 1.0], [tau / LEAD_GAIN, 1.0], fs, 1.0 / tau)
        object.__setattr__(self, "lead", (leads[0], leads[1]))
        object.__setattr__(self, "tilt_lp", tilt_lp)
        fz_lp = _IDENTITY
        if p.tilt_fz_guard is not None:
            wz = p.tilt_fz_guard[2]
            fz_lp = tustin_section([wz * wz], [1.0, 2.0 * wz, wz * wz], fs, wz)
        object.__setattr__(self, "fz_lp", fz_lp)
        object.__setattr__(self, "rot", (rot[0], rot[1], rot[2]))
        object.__setattr__(self, "trans", tuple(trans))
        object.__setattr__(self, "_step_impl", self._make_step())
        sos = {0: _sos(tilt_lp), 1: _sos(tilt_lp)}
        for k, sec in enumerate(rot):
            if k < 2:
                sos[2 + k] = _sos(sec)  # prediction (roll, pitch) at 2, 3
            sos[4 + k] = _sos(sec)  # high-pass + integrator at 4, 5, 6
        for k, secs in enumerate(trans):
            sos[7 + 2 * k] = _sos(*secs)
        sos[13] = _sos(leads[0])
        sos[14] = _sos(leads[1])
        sos[15] = _sos(fz_lp)
        object.__setattr__(self, "_sos", sos)

    # ------------------------------------------------------------------ continuous designs
    def continuous(self) -> dict[str, list[tuple[tuple[float, ...], tuple[float, ...]]]]:
        """The continuous transfer functions the sections were discretised from.

        Returns
        -------
        dict
            ``{"tilt": [(num, den)], "rot": [3 x (num, den)], "trans": [3 x (num, den)]}``,
            polynomials in ``s`` highest power first (``trans`` is the product ``P(s)``).
        """
        p = self.params
        wt, zt = p.tilt_wn_rad_s, p.tilt_zeta
        out: dict[str, list[tuple[tuple[float, ...], tuple[float, ...]]]] = {
            "tilt": [((wt * wt,), (1.0, 2.0 * zt * wt, wt * wt))],
            "rot": [
                ((1.0, 0.0), (1.0, 2.0 * z * w, w * w))
                for w, z in zip(p.rot_wn_rad_s, p.rot_zeta, strict=True)
            ],
            "trans": [],
        }
        for w, z, wb in zip(p.trans_wn_rad_s, p.trans_zeta, p.trans_wb_rad_s, strict=True):
            den2 = (1.0, 2.0 * z * w, w * w)
            if wb > 0.0:
                out["trans"].append(((1.0, 0.0), tuple(np.polymul(den2, [1.0, wb]).tolist())))
            else:
                out["trans"].append(((1.0,), den2))
        return out

    # ------------------------------------------------------------------ state
    def initial_state(self) -> WashoutState:
        """A fresh state: platform at neutral, vehicle at rest, no samples seen."""
        state = WashoutState()
        state.tilt_env[:] = self._env_start()
        return state

    def _env_start(self) -> list[float]:
        """The force envelope before the first sample (``tilt_adapt_start_m_s2``)."""
        e = self.params.tilt_adapt_start_m_s2 if self.params.tilt_adapt_peak_m_s2 else 0.0
        return [e, e]

    def reset(self, state: WashoutState) -> None:
        """Put ``state`` back to :meth:`initial_state` (in place, keeping its lists)."""
        z = state.z
        for i in range(len(z)):
            z[i] = 0.0
        state.tilt[:] = [0.0, 0.0]
        state.tilt_rate[:] = [0.0, 0.0]
        state.attitude[:] = [0.0, 0.0, 0.0]
        state.omega[:] = [0.0, 0.0, 0.0]
        state.hold[:] = [0.0, 0.0, GRAVITY_M_S2, 0.0, 0.0, 0.0]
        state.tilt_env[:] = self._env_start()
        state.bad_samples = 0
        state.samples = 0

    # ------------------------------------------------------------------ streaming
    def step(
        self,
        state: WashoutState,
        f: Sequence[float],
        w: Sequence[float],
        out: MutableSequence[float] | None = None,
    ) -> MutableSequence[float]:
        """Advance one sample: see :meth:`CueingAlgorithm.step` (``out`` written without
        allocation)."""
        return self._step_impl(state, f, w, out)

    def _make_step(self) -> _StepFn:
        p = self.params
        g = GRAVITY_M_S2
        fs = self.fs_hz
        rf, rw = p.reject_f_m_s2, p.reject_w_rad_s
        knee = p.soft_knee
        kfx, kfy, kfz = p.f_scale
        lfx, lfy, lfz = p.f_limit_m_s2
        afx, afy, afz = (knee * v for v in p.f_limit_m_s2)
        kwx, kwy, kwz = p.w_scale
        lwx, lwy, lwz = p.w_limit_rad_s
        awx, awy, awz = (knee * v for v in p.w_limit_rad_s)
        tl = p.tilt_limit_rad
        atl = knee * tl
        st = p.tilt_rate_limit_rad_s / fs
        accel = p.tilt_accel_limit_rad_s2
        sa = 0.0 if accel is None else accel / (fs * fs)
        ra_step = rate_accel_limit_step
        mix = p.tilt_rate_mix
        mix_step = rate_mix_step
        axis_steps = _axis_steps
        own_tilt = p.tilt_scale is not None
        ktx, kty = (1.0, 1.0) if p.tilt_scale is None else p.tilt_scale
        ktxf = ktx * p.tilt_forward_ratio  # the tilt's gain on a forward force
        fshape = p.f_shape is not None
        pfx, pfy, pfz = (1.0, 1.0, 1.0) if p.f_shape is None else p.f_shape
        wshape = p.w_shape is not None
        pwx, pwy, pwz = (1.0, 1.0, 1.0) if p.w_shape is None else p.w_shape
        cshape = p.tilt_shape is not None
        pt = 1.0 if p.tilt_shape is None else p.tilt_shape
        lxp, lxn, lyp, lyn = p.tilt_force_limits_m_s2
        rmin, rmax, pmin, pmax = p.tilt_limits_rad
        qe = p.tilt_reach_exponent
        guard = p.tilt_fz_guard is not None
        gz_above = 0.0 if p.tilt_fz_guard is None else p.tilt_fz_guard[1]
        gz_l = 0.0 if p.tilt_fz_guard is None else p.tilt_fz_guard[0]
        gz_width = max(gz_above, _GUARD_MIN_RAMP_M_S2)
        fz_lp = self.fz_lp
        comp = compress
        adapt = p.tilt_adapt_peak_m_s2 is not None
        cax, cay = (0.0, 0.0) if p.tilt_adapt_peak_m_s2 is None else p.tilt_adapt_peak_m_s2
        adapt_decay = math.exp(-1.0 / (fs * p.tilt_adapt_tau_s))
        has_lead = p.lead_s is not None
        ld0, ld1 = self.lead
        hx, hy, hz = p.head_offset_m
        head = hx != 0.0 or hy != 0.0 or hz != 0.0
        additive = p.tilt_additive
        lagk = p.tilt_lag_fill
        off = p.tilt_offset_m
        mx, my, mz, mr, mp, myaw = (1.0 if d else 0.0 for d in p.dofs)
        lb0, lb1, lb2, _, la1, la2 = self.tilt_lp
        r0, r1, r2 = self.rot
        t0a, t0b = self.trans[0]
        t1a, t1b = self.trans[1]
        t2a, t2b = self.trans[2]
        asin, sin, cos, sqrt = math.asin, math.sin, math.cos, math.sqrt
        soft = soft_limit
        mincos = _MIN_COS_PITCH

        def bq(c: Section, z: list[float], i: int, x: float) -> float:
            y = c[0] * x + z[i]
            z[i] = c[1] * x - c[4] * y + z[i + 1]
            z[i + 1] = c[2] * x - c[5] * y
            return y

        def step(
            state: WashoutState,
            f: Sequence[float],
            w: Sequence[float],
            out: MutableSequence[float] | None,
        ) -> MutableSequence[float]:
            fx, fy, fz = f[0], f[1], f[2]
            wx, wy, wz = w[0], w[1], w[2]
            h = state.hold
            state.samples += 1
            # NaN fails every comparison and inf fails <= bound: both land in the else.
            if (
                abs(fx) <= rf
                and abs(fy) <= rf
                and abs(fz - g) <= rf
                and abs(wx) <= rw
                and abs(wy) <= rw
                and abs(wz) <= rw
            ):
                h[0] = fx
                h[1] = fy
                h[2] = fz
                h[3] = wx
                h[4] = wy
                h[5] = wz
            else:
                state.bad_samples += 1
                fx, fy, fz, wx, wy, wz = h[0], h[1], h[2], h[3], h[4], h[5]
            flx = fx
            fly = fy
            if has_lead:  # 0b. phase lead on the tilt's fx, fy
                flx = bq(ld0, state.z, 26, fx)
                fly = bq(ld1, state.z, 28, fy)
            # 1. scaling and smooth limiting (or compression)
            if fshape:
                sx = comp(fx, kfx, lfx, lfx, pfx)
                sy = comp(fy, kfy, lfy, lfy, pfy)
                sz = comp(fz - g, kfz, lfz, lfz, pfz)
            else:
                sx = kfx * fx
                if sx > afx or sx < -afx:
                    sx = soft(sx, lfx, knee)
                sy = kfy * fy
                if sy > afy or sy < -afy:
                    sy = soft(sy, lfy, knee)
                sz = kfz * (fz - g)
                if sz > afz or sz < -afz:
                    sz = soft(sz, lfz, knee)
            fzs = g + sz
            if wshape:
                qx = comp(wx, kwx, lwx, lwx, pwx)
                qy = comp(wy, kwy, lwy, lwy, pwy)
                qz = comp(wz, kwz, lwz, lwz, pwz)
            else:
                qx = kwx * wx
                if qx > awx or qx < -awx:
                    qx = soft(qx, lwx, knee)
                qy = kwy * wy
                if qy > awy or qy < -awy:
                    qy = soft(qy, lwy, knee)
                qz = kwz * wz
                if qz > awz or qz < -awz:
                    qz = soft(qz, lwz, knee)
            z = state.z
            # 2. tilt coordination
            if adapt:  # the tilt's gain follows the drive's force peaks
                env = state.tilt_env
                ex = env[0] * adapt_decay
                ey = env[1] * adapt_decay
                ax_ = abs(fx)
                ay_ = abs(fy)
                ex = ax_ if ax_ > ex else ex
                ey = ay_ if ay_ > ey else ey
                env[0] = ex
                env[1] = ey
                if cax > 0.0 and ktx * ex > cax:
                    flx = flx * (cax / (ktx * ex))
                if cay > 0.0 and kty * ey > cay:
                    fly = fly * (cay / (kty * ey))
            if cshape:
                tix = comp(flx, ktxf if flx > 0.0 else ktx, lxp, lxn, pt)
                tiy = comp(fly, kty, lyp, lyn, pt)
            elif own_tilt:
                tix = (ktxf if flx > 0.0 else ktx) * flx
                tiy = kty * fly
            else:
                tix = sx
                tiy = sy
            if guard:  # the tilt's fz loss bounded while the vehicle's f_z is high
                dz = bq(fz_lp, z, 30, fz - g)
                if dz > gz_above:
                    ramp = (dz - gz_above) / gz_width
                    c = 1.0 - (gz_l if ramp >= 1.0 else gz_l + (g - gz_l) * (1.0 - ramp)) / g
                    room = g * g * (1.0 - c * c) - tix * tix  # the roll gives way
                    lim = sqrt(room) if room > 0.0 else 0.0
                    if tiy > lim:
                        tiy = lim
                    elif tiy < -lim:
                        tiy = -lim
            ylx = lb0 * tix + z[0]
            z[0] = lb1 * tix - la1 * ylx + z[1]
            z[1] = lb2 * tix - la2 * ylx
            yly = lb0 * tiy + z[2]
            z[2] = lb1 * tiy - la1 * yly + z[3]
            z[3] = lb2 * tiy - la2 * yly
            u = ylx / g
            u = 1.0 if u > 1.0 else (-1.0 if u < -1.0 else u)
            tp = -asin(u)
            u = yly / g
            u = 1.0 if u > 1.0 else (-1.0 if u < -1.0 else u)
            tr = asin(u)
            if cshape:
                tp = pmax if tp > pmax else (-pmin if tp < -pmin else tp)
                tr = rmax if tr > rmax else (-rmin if tr < -rmin else tr)
                er = tr / (rmax if tr > 0.0 else rmin)
                ep = tp / (pmax if tp > 0.0 else pmin)
                if qe == 2.0:
                    qq = er * er + ep * ep
                else:  # the superellipse |er|^q + |ep|^q <= 1
                    qq = abs(er) ** qe + abs(ep) ** qe
                if qq > 1.0:  # roll and pitch together: inside the quadrant's ellipse
                    sq = 1.0 / sqrt(qq) if qe == 2.0 else qq ** (-1.0 / qe)
                    tr = tr * sq
                    tp = tp * sq
            else:
                if tp > atl or tp < -atl:
                    tp = soft(tp, tl, knee)
                if tr > atl or tr < -atl:
                    tr = soft(tr, tl, knee)
            ttr = tr * mr  # the tilt's target (for the lag the translation fills)
            ttp = tp * mp
            tilt = state.tilt
            if mix is not None:
                trate = state.tilt_rate
                ur0 = trate[0] / fs
                up0 = trate[1] / fs
                ur, up = axis_steps(tr, tp, tilt[0], tilt[1], ur0, up0, st, sa)
                ur, up = mix_step(ur, up, ur0, up0, mix, st, sa)
                tr = tilt[0] + ur
                tp = tilt[1] + up
                trate[0] = ur * fs
                trate[1] = up * fs
            elif sa > 0.0:
                trate = state.tilt_rate
                prev = tilt[0]
                u = ra_step(tr, prev, trate[0] / fs, st, sa)
                tr = prev + u
                trate[0] = u * fs
                prev = tilt[1]
                u = ra_step(tp, prev, trate[1] / fs, st, sa)
                tp = prev + u
                trate[1] = u * fs
            else:
                prev = tilt[0]
                d = tr - prev
                if d > st:
                    tr = prev + st
                elif d < -st:
                    tr = prev - st
                prev = tilt[1]
                d = tp - prev
                if d > st:
                    tp = prev + st
                elif d < -st:
                    tp = prev - st
            tilt[0] = tr
            tilt[1] = tp
            tr *= mr
            tp *= mp
            # 3. rotational channel
            pr = mr * (bq(r0, z, 4, qx) + tr)
            pp = mp * (bq(r1, z, 6, qy) + tp)
            sphi = sin(pr)
            cphi = cos(pr)
            cth = cos(pp)
            if cth < mincos:
                cth = mincos
            tth = sin(pp) / cth
            qr = sphi * qy + cphi * qz
            e_roll = qx + tth * qr
            e_pitch = cphi * qy - sphi * qz
            e_yaw = qr / cth
            roll = mr * (bq(r0, z, 8, e_roll) + tr)
            pitch = mp * (bq(r1, z, 10, e_pitch) + tp)
            yaw = myaw * bq(r2, z, 12, e_yaw)
            # 4. translational channel: a = R f_s - [0, 0, g]
            sphi = sin(roll)
            cphi = cos(roll)
            sth = sin(pitch)
            cth = cos(pitch)
            sps = sin(yaw)
            cps = cos(yaw)
            hfx = sx
            hfy = sy
            hfz = fzs
            if additive:  # 4a. the tilt's own gravity joins the target
                ctp = cos(tp)
                hfx = sx - g * sin(tp)
                hfy = sy + g * sin(tr) * ctp
                hfz = fzs + g * (cos(tr) * ctp - 1.0)
                if lagk > 0.0:  # 4b. and a share of its lag behind its target
                    ctt = cos(ttp)
                    hfx = hfx - lagk * g * (sin(ttp) - sin(tp))
                    hfy = hfy + lagk * g * (sin(ttr) * ctt - sin(tr) * ctp)
                    hfz = hfz + lagk * g * (cos(ttr) * ctt - cos(tr) * ctp)
            if head:
                # f_o = f_s - W' x h - W x (W x h), W and W' by backward differences
                att = state.attitude
                om = state.omega
                dr = (roll - att[0]) * fs
                dp = (pitch - att[1]) * fs
                dyw = (yaw - att[2]) * fs
                att[0] = roll
                att[1] = pitch
                att[2] = yaw
                ycp = dyw * cth
                wx_ = dr - dyw * sth
                wy_ = dp * cphi + ycp * sphi
                wz_ = -dp * sphi + ycp * cphi
                ax_ = (wx_ - om[0]) * fs
                ay_ = (wy_ - om[1]) * fs
                az_ = (wz_ - om[2]) * fs
                om[0] = wx_
                om[1] = wy_
                om[2] = wz_
                cx = wy_ * hz - wz_ * hy
                cy = wz_ * hx - wx_ * hz
                cz = wx_ * hy - wy_ * hx
                hfx = hfx - ((ay_ * hz - az_ * hy) + (wy_ * cz - wz_ * cy))
                hfy = hfy - ((az_ * hx - ax_ * hz) + (wz_ * cx - wx_ * cz))
                hfz = hfz - ((ax_ * hy - ay_ * hx) + (wx_ * cy - wy_ * cx))
            # R = Rz Ry Rx: with Ry Rx f = [u, v, c], R f = [cps u - sps v, sps u + cps v, c]
            vv = sphi * hfy + cphi * hfz
            u = cth * hfx + sth * vv
            v = cphi * hfy - sphi * hfz
            ax = cps * u - sps * v
            ay = sps * u + cps * v
            az = -sth * hfx + cth * vv - g
            x = mx * bq(t0b, z, 16, bq(t0a, z, 14, ax))
            y = my * bq(t1b, z, 20, bq(t1a, z, 18, ay))
            zz = mz * bq(t2b, z, 24, bq(t2a, z, 22, az))
            if off is not None:  # 4c. the reach offset follows the delivered tilt
                b2, b3, b4 = tr * tr, tp * tp, tr * tp
                cx_, cy_, cz_ = off
                x += mx * (cx_[0] * tr + cx_[1] * tp + cx_[2] * b2 + cx_[3] * b3 + cx_[4] * b4)
                y += my * (cy_[0] * tr + cy_[1] * tp + cy_[2] * b2 + cy_[3] * b3 + cy_[4] * b4)
                zz += mz * (cz_[0] * tr + cz_[1] * tp + cz_[2] * b2 + cz_[3] * b3 + cz_[4] * b4)
            if out is None:
                return [x, y, zz, roll, pitch, yaw]
            out[0] = x
            out[1] = y
            out[2] = zz
            out[3] = roll
            out[4] = pitch
            out[5] = yaw
            return out

        return step

    # ------------------------------------------------------------------ batch
    def run(self, f: ArrayLike, w: ArrayLike, state: WashoutState | None = None) -> WashoutResult:
        """Run over a whole recording (vectorised; the same numbers as :meth:`step`).

        Parameters
        ----------
        f, w : (N, 3) array_like
            Specific force (m/s^2) and angular velocity (rad/s), body frame, at ``fs_hz``.
        state : WashoutState, optional
            Start from this state and leave it at the end state (to continue a stream);
            a fresh :meth:`initial_state` otherwise.

        Returns
        -------
        WashoutResult

        Notes
        -----
        The recording is processed in blocks of :attr:`BLOCK` samples, each continuing from
        the state the previous one left (so that the working arrays stay in cache).
        """
        f_arr = np.asarray(f, dtype=float)
        w_arr = np.asarray(w, dtype=float)
        if f_arr.ndim != 2 or f_arr.shape[1] != 3 or w_arr.shape != f_arr.shape:
            raise ConfigError(
                f"f and w must both have shape (N, 3); got {f_arr.shape} and {w_arr.shape}"
            )
        if state is None:
            state = self.initial_state()
        n = f_arr.shape[0]
        poses = np.empty((6, n))
        used = np.empty((6, n))
        tilt = np.empty((2, n))
        bad_mask = np.zeros(n, dtype=bool)
        n_bad = 0
        for lo in range(0, n, self.BLOCK):
            hi = min(n, lo + self.BLOCK)
            n_bad += self._run_block(
                f_arr[lo:hi],
                w_arr[lo:hi],
                state,
                poses[:, lo:hi],
                used[:, lo:hi],
                tilt[:, lo:hi],
                bad_mask[lo:hi],
            )
        return WashoutResult(
            poses=poses.T,
            bad_samples=n_bad,
            bad_mask=bad_mask,
            tilt=tilt.T,
            f_used=used[:3].T,
            w_used=used[3:].T,
            fs_hz=self.fs_hz,
        )

    BLOCK = 32768
    """Samples per block of :meth:`run`."""

    def _run_block(
        self,
        f_arr: NDArray[np.float64],
        w_arr: NDArray[np.float64],
        state: WashoutState,
        poses: NDArray[np.float64],
        used: NDArray[np.float64],
        tilt_out: NDArray[np.float64],
        bad_mask: NDArray[np.bool_],
    ) -> int:
        """One block of :meth:`run`: fills the (6, n), (6, n), (2, n), (n,) outputs in place,
        advances ``state`` and returns the number of bad samples."""
        from scipy.signal import sosfilt

        p = self.params
        g = GRAVITY_M_S2
        n = f_arr.shape[0]
        # 0. bad input: hold the last good sample (NaN fails every comparison, as in step)
        fdev = np.abs(f_arr - np.array([0.0, 0.0, g]))
        wdev = np.abs(w_arr)
        n_bad = 0
        if fdev.max(initial=0.0) <= p.reject_f_m_s2 and wdev.max(initial=0.0) <= p.reject_w_rad_s:
            used[:3] = f_arr.T
            used[3:] = w_arr.T
        else:
            good = (fdev <= p.reject_f_m_s2).all(axis=1) & (wdev <= p.reject_w_rad_s).all(axis=1)
            bad_mask[:] = ~good
            n_bad = int(bad_mask.sum())
            idx = np.where(good, np.arange(n), -1)
            np.maximum.accumulate(idx, out=idx)
            raw = np.concatenate([f_arr, w_arr], axis=1)
            held = np.where((idx >= 0)[:, None], raw[np.maximum(idx, 0)], np.array(state.hold))
            used[:] = held.T
        fx, fy, fz, wx, wy, wz = used
        z = np.array(state.z).reshape(_N_SECTIONS, 2)
        zf = z.copy()

        def filt(secs: Sequence[Section], x: NDArray[np.float64], k: int) -> NDArray[np.float64]:
            y, zout = sosfilt(self._sos[k], x, zi=z[k : k + len(secs)])
            zf[k : k + len(secs)] = zout
            return np.asarray(y)

        flx, fly = fx, fy
        if p.lead_s is not None:  # 0b. phase lead on the tilt's fx, fy
            flx = filt([self.lead[0]], fx, 13)
            fly = filt([self.lead[1]], fy, 14)
        # 1. scaling and smooth limiting
        knee = p.soft_knee
        if p.f_shape is None:
            sx = soft_limit_array(p.f_scale[0] * fx, p.f_limit_m_s2[0], knee)
            sy = soft_limit_array(p.f_scale[1] * fy, p.f_limit_m_s2[1], knee)
            sz = soft_limit_array(p.f_scale[2] * (fz - g), p.f_limit_m_s2[2], knee)
        else:
            k, lf, pf = p.f_scale, p.f_limit_m_s2, p.f_shape
            sx = compress_array(fx, k[0], lf[0], lf[0], pf[0])
            sy = compress_array(fy, k[1], lf[1], lf[1], pf[1])
            sz = compress_array(fz - g, k[2], lf[2], lf[2], pf[2])
        fzs = g + sz
        if p.w_shape is None:
            qx = soft_limit_array(p.w_scale[0] * wx, p.w_limit_rad_s[0], knee)
            qy = soft_limit_array(p.w_scale[1] * wy, p.w_limit_rad_s[1], knee)
            qz = soft_limit_array(p.w_scale[2] * wz, p.w_limit_rad_s[2], knee)
        else:
            k, lw, pw = p.w_scale, p.w_limit_rad_s, p.w_shape
            qx = compress_array(wx, k[0], lw[0], lw[0], pw[0])
            qy = compress_array(wy, k[1], lw[1], lw[1], pw[1])
            qz = compress_array(wz, k[2], lw[2], lw[2], pw[2])

        # 2. tilt coordination
        if p.tilt_adapt_peak_m_s2 is not None and p.tilt_scale is not None and n:
            flx = flx * _adapt_gain(fx, p.tilt_adapt_peak_m_s2[0], p.tilt_scale[0],
                                    p.tilt_adapt_tau_s, self.fs_hz, state.tilt_env, 0)  # fmt: skip
            fly = fly * _adapt_gain(fy, p.tilt_adapt_peak_m_s2[1], p.tilt_scale[1],
                                    p.tilt_adapt_tau_s, self.fs_hz, state.tilt_env, 1)  # fmt: skip
        fwd = p.tilt_forward_ratio
        if p.tilt_shape is not None and p.tilt_scale is not None:
            lxp, lxn, lyp, lyn = p.tilt_force_limits_m_s2
            ktx = p.tilt_scale[0]
            tix = compress_array(flx, ktx, lxp, lxn, p.tilt_shape)
            if fwd != 1.0:  # the forward force's own gain (the same operations as step)
                ahead = compress_array(flx, ktx * fwd, lxp, lxn, p.tilt_shape)
                tix = np.where(flx > 0.0, ahead, tix)
            tiy = compress_array(fly, p.tilt_scale[1], lyp, lyn, p.tilt_shape)
        elif p.tilt_scale is None:
            tix, tiy = sx, sy
        else:
            ktx = p.tilt_scale[0]
            tix = np.where(flx > 0.0, (ktx * fwd) * flx, ktx * flx) if fwd != 1.0 else ktx * flx
            tiy = p.tilt_scale[1] * fly
        if p.tilt_fz_guard is not None:  # the tilt's fz loss bounded while f_z is high
            gz_l, gz_above = p.tilt_fz_guard[0], p.tilt_fz_guard[1]
            width = max(gz_above, _GUARD_MIN_RAMP_M_S2)
            ramp = (filt([self.fz_lp], fz - g, 15) - gz_above) / width
            c = 1.0 - (gz_l + (g - gz_l) * (1.0 - np.clip(ramp, 0.0, 1.0))) / g
            room = g * g * (1.0 - c * c) - tix * tix  # the roll gives way
            lim = np.sqrt(np.maximum(room, 0.0))
            tiy = np.where(ramp > 0.0, np.clip(tiy, -lim, lim), tiy)
        ylx = filt([self.tilt_lp], tix, 0)
        yly = filt([self.tilt_lp], tiy, 1)
        tp = -np.arcsin(np.clip(ylx / g, -1.0, 1.0))
        tr = np.arcsin(np.clip(yly / g, -1.0, 1.0))
        if p.tilt_shape is not None:
            rmin, rmax, pmin, pmax = p.tilt_limits_rad
            tp = np.clip(tp, -pmin, pmax)
            tr = np.clip(tr, -rmin, rmax)
            er = tr / np.where(tr > 0.0, rmax, rmin)
            ep = tp / np.where(tp > 0.0, pmax, pmin)
            qe = p.tilt_reach_exponent
            if qe == 2.0:
                qq = er * er + ep * ep
                sq = np.where(qq > 1.0, 1.0 / np.sqrt(np.maximum(qq, 1.0)), 1.0)
            else:  # the superellipse |er|^q + |ep|^q <= 1
                qq = np.abs(er) ** qe + np.abs(ep) ** qe
                sq = np.where(qq > 1.0, np.maximum(qq, 1.0) ** (-1.0 / qe), 1.0)
            tr = np.where(qq > 1.0, tr * sq, tr)
            tp = np.where(qq > 1.0, tp * sq, tp)
        else:
            tp = soft_limit_array(tp, p.tilt_limit_rad, knee)
            tr = soft_limit_array(tr, p.tilt_limit_rad, knee)
        fs = self.fs_hz
        st = p.tilt_rate_limit_rad_s / fs
        ttr, ttp = tr, tp  # the tilt's target (for the lag the translation fills)
        if p.tilt_rate_mix is not None:
            sa = 0.0 if p.tilt_accel_limit_rad_s2 is None else p.tilt_accel_limit_rad_s2 / fs**2
            tr, tp = _rate_mix_array(
                tr, tp, p.tilt_rate_mix, st, sa, state.tilt, state.tilt_rate, fs
            )
        elif p.tilt_accel_limit_rad_s2 is None:
            tr = rate_limit_array(tr, st, state.tilt[0])
            tp = rate_limit_array(tp, st, state.tilt[1])
        else:
            sa = p.tilt_accel_limit_rad_s2 / (fs * fs)
            tr = _rate_accel_limit_array(tr, st, sa, state.tilt, state.tilt_rate, 0, fs)
            tp = _rate_accel_limit_array(tp, st, sa, state.tilt, state.tilt_rate, 1, fs)
        mx, my, mz, mr, mp, myaw = (1.0 if d else 0.0 for d in p.dofs)
        tilt_out[0] = tr
        tilt_out[1] = tp
        tr = tr * mr
        tp = tp * mp
        # 3. rotational channel
        pr = mr * (filt([self.rot[0]], qx, 2) + tr)
        pp = mp * (filt([self.rot[1]], qy, 3) + tp)
        sphi = np.sin(pr)
        cphi = np.cos(pr)
        cth = np.maximum(np.cos(pp), _MIN_COS_PITCH)
        tth = np.sin(pp) / cth
        qr = sphi * qy + cphi * qz
        roll = mr * (filt([self.rot[0]], qx + tth * qr, 4) + tr)
        pitch = mp * (filt([self.rot[1]], cphi * qy - sphi * qz, 5) + tp)
        yaw = myaw * filt([self.rot[2]], qr / cth, 6)
        # 4. translational channel
        sphi = np.sin(roll)
        cphi = np.cos(roll)
        sth = np.sin(pitch)
        cth = np.cos(pitch)
        sps = np.sin(yaw)
        cps = np.cos(yaw)
        hfx, hfy, hfz = sx, sy, fzs
        if p.tilt_additive:  # 4a. the tilt's own gravity joins the target (additive tilt)
            ctp = np.cos(tp)
            hfx = sx - g * np.sin(tp)
            hfy = sy + g * np.sin(tr) * ctp
            hfz = fzs + g * (np.cos(tr) * ctp - 1.0)
            lagk = p.tilt_lag_fill
            if lagk > 0.0:  # 4b. and a share of its lag behind its target
                ttr = ttr * mr
                ttp = ttp * mp
                ctt = np.cos(ttp)
                hfx = hfx - lagk * g * (np.sin(ttp) - np.sin(tp))
                hfy = hfy + lagk * g * (np.sin(ttr) * ctt - np.sin(tr) * ctp)
                hfz = hfz + lagk * g * (np.cos(ttr) * ctt - np.cos(tr) * ctp)
        hx, hy, hz = p.head_offset_m
        if (hx != 0.0 or hy != 0.0 or hz != 0.0) and n:
            # the same operations as step, on arrays (backward differences from the state)
            att = state.attitude
            dr = np.diff(roll, prepend=att[0]) * fs
            dp = np.diff(pitch, prepend=att[1]) * fs
            dyw = np.diff(yaw, prepend=att[2]) * fs
            ycp = dyw * cth
            wx_ = dr - dyw * sth
            wy_ = dp * cphi + ycp * sphi
            wz_ = -dp * sphi + ycp * cphi
            om = state.omega
            ax_ = np.diff(wx_, prepend=om[0]) * fs
            ay_ = np.diff(wy_, prepend=om[1]) * fs
            az_ = np.diff(wz_, prepend=om[2]) * fs
            cx = wy_ * hz - wz_ * hy
            cy = wz_ * hx - wx_ * hz
            cz = wx_ * hy - wy_ * hx
            hfx = hfx - ((ay_ * hz - az_ * hy) + (wy_ * cz - wz_ * cy))
            hfy = hfy - ((az_ * hx - ax_ * hz) + (wz_ * cx - wx_ * cz))
            hfz = hfz - ((ax_ * hy - ay_ * hx) + (wx_ * cy - wy_ * cx))
            state.attitude[:] = [float(roll[-1]), float(pitch[-1]), float(yaw[-1])]
            state.omega[:] = [float(wx_[-1]), float(wy_[-1]), float(wz_[-1])]
        vv = sphi * hfy + cphi * hfz
        u = cth * hfx + sth * vv
        v = cphi * hfy - sphi * hfz
        ax = cps * u - sps * v
        ay = sps * u + cps * v
        az = -sth * hfx + cth * vv - g
        poses[0] = mx * filt(self.trans[0], ax, 7)
        poses[1] = my * filt(self.trans[1], ay, 9)
        poses[2] = mz * filt(self.trans[2], az, 11)
        if p.tilt_offset_m is not None:  # 4c. the reach offset follows the delivered tilt
            basis = np.stack([tr, tp, tr * tr, tp * tp, tr * tp])
            for i, m in enumerate((mx, my, mz)):
                poses[i] += m * (np.asarray(p.tilt_offset_m[i]) @ basis)
        poses[3] = roll
        poses[4] = pitch
        poses[5] = yaw
        # leave the state where a stream would be
        if n:
            state.z[:] = zf.ravel().tolist()
            state.tilt[0] = float(tilt_out[0, -1])
            state.tilt[1] = float(tilt_out[1, -1])
            state.hold[:] = used[:, -1].tolist()
        state.bad_samples += n_bad
        state.samples += n
        return n_bad
