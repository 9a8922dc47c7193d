"""Parameters of the optimisation-based cueing algorithms (the ``[mpc]`` table of a preset).

Kept apart from :mod:`._params` so that the classical parameters stay as they are: a preset
with ``algorithm = "mpc"`` or ``"optimal"`` carries every classical table (the classical
washout is the MPC's fallback) plus one ``[mpc]`` table, read by :func:`read_mpc_table`::

    [mpc]
    platform = "stewart6-linear"       # bundled name or TOML path: actuator-space limits
    controller = "mbox6"               # bundled name or TOML path: its speed/accel limits
    horizon_s = 1.2                    # prediction horizon (>= 1 s for real time at 100 Hz)
    blocks = 12                        # move blocks (input held within a block)
    w_error = [1.0, 1.0, 0.3, 1.0, 1.0, 0.3]   # perceived error, per threshold^2
    w_pose = [30.0, 30.0, 30.0, 10.0, 10.0, 10.0]  # pose washout, per (m or rad)^2
    w_vel = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]         # per (m/s or rad/s)^2
    w_acc = [0.01, 0.01, 0.01, 0.1, 0.1, 0.1]      # per (m/s^2 or rad/s^2)^2
    w_vehicle = [0.5, 0.5, 0.0, 0.0, 0.0, 0.0]     # optional: perceived error to the
                                       #   vehicle's whole motion (not the reference), per
                                       #   threshold^2 (strength: standing still costs it all)
    prediction_tau_s = 0.0             # vehicle prediction: 0 = held, > 0 = decays with tau
    ref_scale = [1.0, 1.0, 1.0, 1.0, 1.0, 1.0]    # the plan tracks ref_scale * vehicle motion
    ref_limit_m_s2 = [4.0, 4.0, 2.0]   # optional: soft limits of that copy (fx, fy, fz)
    ref_limit_deg_s = [5.0, 5.0, 5.0]  # optional: and of its wx, wy, wz
    ref_shape = 2.0                    # optional: the compressive curve of the classical
                                       #   washout instead of tanh (exponent p >= 1)
    ref_reach_use = 0.8                # optional: fx, fy limits from this share of the
                                       #   plan's own tilt reach, per direction
    ref_adapt_peak_m_s2 = [2.0, 0.0]   # optional: the fx, fy gain adapts to the drive,
                                       #   min(ref_scale, c / e), e the envelope of the
                                       #   vehicle's force peaks (0: that axis fixed)
    ref_adapt_tau_s = 18.0             # optional: the envelope's decay time (s)
    ref_adapt_start_m_s2 = 22.0        # optional: the envelope before the first sample
    ref_small_gain = [0.5, 0.0]        # optional: small fx, fy cues tracked with this much
    ref_small_knee_m_s2 = 0.5          #   more gain, up to about this size (see below)
    ref_split_hz = 0.5                 # optional: only the part below this is scaled and
    ref_scale_hf = [1.0, 1.0, 0.0, 0.0, 0.0, 0.0]  # limited; the part above times this
    sign_guard = [0.7, 0.7, 0.0, 0.0, 0.0, 0.0]  # wrong-sign perceived motion at most this
                                       #   x threshold (0: no such constraint)
    sign_guard_weight = 1e4            # price of one threshold over it (a soft constraint)
    stroke_use = 0.9                   # fraction of each actuator's stroke the plan may use
    rate_use = 0.9                     # fraction of its speed and acceleration limits
    tilt_fz_use = 1.0                  # optional: roll and pitch together at most the tilt
                                       #   that costs this many fz thresholds (0: none)
    tilt_fz_use_against = 0.4          # optional, optimal only: the same where the vehicle's
                                       #   perceived fz is above its threshold (0: none)
    fz_guard = 0.7                     # optional, mpc only: the rider's perceived fz (the
                                       #   tilt's loss) at most this x threshold against the
                                       #   vehicle's (0: no such rows)
    fz_guard_from = 1.0                # optional: where the vehicle's perceived fz is above
                                       #   this x threshold (-100: everywhere)
    fz_guard_pitch = 1.0               # optional: share of the pitch's loss the rows see
    trans_limit_m = [0.06, 0.06, 1e9]  # optional, mpc only: |x|, |y|, |z| of the plan at most
                                       #   this (m; 1e9 = none), so that the legs keep stroke
                                       #   for the tilt
    tilt_rate_limit_deg_s = 8.0        # optional: the plan's roll/pitch rate limit
                                       #   (default: the [tilt] table's, which the fallback
                                       #   washout keeps)
    solver = "daqp"                    # QP solver (a casadi conic plugin)
    deadline_ms = 6.0                  # streaming: a slower solve is dropped (fallback)
    window_s = 4.0                     # optimal only: window length
    stride_s = 2.0                     # optimal only: kept part of each window
    block_samples = 5                  # optimal only: input held for this many samples
    sign_guard_every = 1               # optional, optimal only: the sign guard (fz excepted)
                                       #   also every this many samples within a block
                                       #   (0: at the block ends only)

All weights are dimensionless multipliers of the units given; the perceived error is
measured in perception thresholds, like :func:`~._vestibular.perceived_motion_error`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .._errors import ConfigError

if TYPE_CHECKING:
    from .._config import ConfigReader

__all__ = ["MPC_SOLVERS", "MpcParams", "read_mpc_table"]

Vec6 = tuple[float, float, float, float, float, float]

MPC_SOLVERS: tuple[str, ...] = ("daqp", "qpoases", "osqp", "proxqp")
"""QP solvers (casadi conic plugins) the MPC accepts; ``daqp`` is the measured default."""


def _vec6(name: str, v: Iterable[float], lo: float, hi: float) -> Vec6:
    t = tuple(float(x) for x in v)
    if len(t) != 6 or not all(math.isfinite(x) and lo <= x <= hi for x in t):
        raise ConfigError(
            f"MpcParams.{name} = {v!r} is invalid; allowed: 6 numbers in [{lo}, {hi}]"
        )
    return (t[0], t[1], t[2], t[3], t[4], t[5])


@dataclass(frozen=True)
class MpcParams:
    """Settings of :class:`~._mpc.MpcCueing` and :class:`~._optimal.OptimalCueing` (SI).

    Attributes
    ----------
    platform, controller : str
        Platform and controller (bundled names or TOML paths) whose actuator limits
        constrain the plan (stroke, speed, acceleration).
    horizon_s : float
        Prediction horizon (s), in [0.1, 10].
    blocks : int
        Number of move blocks over the horizon (the input is held within a block; block
        lengths grow geometrically from one sample), in [1, 200].
    w_error : 6 floats
        Weight of the perceived error ``fx, fy, fz, wx, wy, wz`` (per threshold^2).
    w_pose, w_vel, w_acc : 6 floats
        Weights of the platform pose (per m^2, rad^2), its rate and its acceleration.
    w_vehicle : 6 floats
        Weight of the perceived error to the vehicle's *whole* motion ``H (s - d)`` (per
        threshold^2; default 0: none), beside ``w_error``'s error to the tracked reference
        ``H (s - r)``. Its target is what the vehicle gives, not a shrunk copy, so standing
        still costs the vehicle's whole perceived motion: the term pursues strength. Per
        channel the two terms are one error to a blend (exactly, the models being linear and
        one per channel): ``we |H (s - r)|^2 + wv |H (s - d)|^2 = (we + wv) |H (s - r')|^2 +
        const`` with ``r' = r + wv / (we + wv) (d - r)``; :func:`~._mpc.reference` returns
        ``r'`` and :func:`~._mpc.build_model` weighs it by ``we + wv``.
    w_jerk : 6 floats
        ``optimal`` only. 0 (default): none. Otherwise the price of each change of the input
        (the acceleration, m/s^2 or rad/s^2, held within a block) from one block to the next
        and from the last block applied before a window to its first: ``w_jerk |u_b -
        u_{b-1}|^2`` per degree of freedom (per (m/s^2)^2, (rad/s^2)^2). The otoliths'
        lead turns each step of a translation's acceleration into a brief felt pulse of its
        own; without this price a plan may use them (a jolt the vehicle did not have).
    w_prior : 6 floats
        ``mpc`` only. 0 (default): none. Otherwise ``wc`` (each in [0, 1e9], per pose
        component ``x, y, z`` in m, ``roll, pitch, yaw`` in rad) prices the plan's distance to
        the pose of the preset's classical washout (the fallback, which runs on every sample)
        at this sample, held over the horizon: ``wc |p_k - p_c|^2`` at every step ``k`` of it
        (the terminal weight prices ``w_pose + wc`` about neutral). The plan then starts from
        what the classical washout does (its compressed target, its tilt within the reach
        in each direction, its rate limit from the leg speeds, its translation filling the
        tilt's lag) and departs from it where the perceived error pays for it.
    prediction_tau_s : float
        Vehicle motion over the horizon: 0 holds the last sample, ``tau > 0`` lets it decay
        as ``exp(-t / tau)`` (s).
    ref_scale : 6 floats
        The motion the plan tracks is ``r = L tanh(k d / L)`` per channel (``k = ref_scale``,
        ``L = ref_limit``; ``d = [f - [0, 0, g], w]``): a scaled, soft-limited copy of the
        vehicle's motion the platform can follow, so its shape survives (chasing the full
        motion saturates the platform and distorts it). Each ``k`` in [0, 1]; the cue quality
        is still judged against the unscaled vehicle.
    ref_limit : 6 floats
        ``L`` (m/s^2 for ``fx, fy, fz``, rad/s for ``wx, wy, wz``; the TOML keys are
        ``ref_limit_m_s2`` and ``ref_limit_deg_s``), > 0; ``1e9`` (the default) means none.
    ref_shape : float
        0 (default): the soft limit ``L tanh(k d / L)``. Otherwise the exponent ``p`` in
        [1, 50] of the compressive curve the classical washout uses
        (:func:`~._filters.compress`): ``r = k d / (1 + |k d / L|^p)^(1/p)`` on every channel
        with a limit, so small cues are tracked nearly whole (slope ``k``) and large ones are
        compressed into ``L``.
    ref_reach_use : float
        0 (default): ``ref_limit`` as given. In (0, 1]: the fx and fy limits are set by the
        algorithm from the plan's own tilt reach (:func:`~._mpc.plan_tilt_reach`, each
        direction apart): ``L = g u reach`` (``u = ref_reach_use``; the force of that tilt in
        the plan's linear model), so the sustained part of the tracked motion asks for at
        most that share of the tilt this platform reaches in the direction it needs.
    ref_limit_neg : 6 floats or None
        Limits for negative values (``None``: ``ref_limit``, symmetric); set by the algorithm
        from ``ref_reach_use`` (no TOML key).
    ref_split_hz : float
        0 (default): no split. Otherwise the vehicle's motion is split by a first-order
        low-pass at this frequency (Hz), in [0, 50]; ``ref_scale`` and ``ref_limit`` apply to
        the slow part only and ``ref_scale_hf`` (6 floats in [0, 1]) to the fast part (see
        :func:`~._mpc.reference`).
    ref_scale_hf : 6 floats
    ref_adapt_peak_m_s2 : 2 floats or None
        ``None`` (default): the gain of the tracked fx and fy is ``ref_scale``, fixed.
        ``(c_x, c_y)``, each in [0, 50] m/s^2: the gain adapts to the drive as the classical
        washout's tilt gain does (``tilt_adapt_peak_m_s2``, the same envelope and code): on
        each axis with ``c > 0`` the envelope ``e[n] = max(|f[n]|, e[n-1] exp(-1 / (fs
        tau)))`` of the vehicle's force (``tau = ref_adapt_tau_s``, ``e =
        ref_adapt_start_m_s2`` before the first sample) sets the gain of that channel's
        copy (of its slow part with ``ref_split_hz``) to ``min(k, c / e)`` (``k`` its
        ``ref_scale``): the largest force of the last few ``tau`` is tracked as ``c``, so a
        car whose stops are 1 g gets about three times the gain of one whose stops are
        3 g. Causal for both plans (the envelope sees the past only; ``mpc`` keeps it in its
        state, ``MpcState.ref_env``, and a reset starts it again), so ``optimal`` tracks
        the reference the streaming plan would.
    ref_adapt_tau_s : float
        The envelope's decay time (s), in [0.1, 3600]; default 30.
    ref_adapt_start_m_s2 : float
        The envelope before the first sample (m/s^2), in [0, 100]; default g. Starting high
        keeps a hard car's first stop from being tracked at a gentle car's gain.
    ref_small_gain : 2 floats
        ``(b_x, b_y)``, each in [0, 1] (default 0: none): the tracked fx and fy get
        ``b K tanh(d / K)`` more (``K = ref_small_knee_m_s2``, ``d`` the vehicle's force on
        the channel), added to the copy above before the blend with ``w_vehicle``. A cue
        well below ``K`` is tracked with the gain ``b`` more (a car's light braking and
        coasting, which an adaptive gain set by 4 g stops leaves below the rider's
        threshold); a large one gets at most ``b K`` more, so the stops, which carry the
        variance, keep their proportion.
    ref_small_knee_m_s2 : float
        ``K`` (m/s^2), in [0.001, 20]; default 0.5.
    sign_guard : 6 floats
        Where ``g_i > 0``, the plan's
        perceived motion on channel ``i`` may oppose the vehicle's perceived motion by at most
        ``g_i`` perception thresholds (a false cue is one that exceeds a threshold with the
        wrong sign), checked at every block end against the vehicle's motion as the plan
        knows it (``optimal``: the recording; ``mpc``: its prediction). A soft constraint
        (:class:`~._mpc.SoftGuardQp`). Each in [0, 10]; 0 = no such constraint. ``optimal``
        with roll and pitch moved guards fz with the change of vertical force that tilt and
        translation bring (second order, not in the linear model), linearised about its first
        plan, at the sample of each block where the rider's fz is lowest while the vehicle's
        is positive (:mod:`._optimal`).
    sign_guard_weight : float
        Price of violating the sign guard by one threshold, in (0, 1e9].
    stroke_use, rate_use : float
        Fraction (0, 1] of the stroke and of the speed/acceleration limits the plan may use
        (the rest absorbs the linearisation of the leg lengths).
    tilt_fz_use : float
        0 (default): roll and pitch are limited one by one (stroke, rate). Otherwise ``u`` in
        (0, 5]: the *combined* tilt is held below ``theta = acos(1 - u thr_z / g)``, the tilt
        whose loss of vertical force ``g (1 - cos theta)`` is ``u`` perception thresholds of
        fz (``thr_z`` of the model set). The plan's linear model does not see that loss; a
        rider does: braking in a corner with roll and pitch both near their reach felt as a
        drop (fz reversals against the vehicle's downforce). Linear rows at every block end,
        ``|roll + pitch|, |roll - pitch| <= sqrt(2) theta`` (an octagon with the roll and
        pitch limits, exact on the diagonals).
    tilt_fz_use_against : float
        ``optimal`` only. 0 (default): ``tilt_fz_use`` everywhere. Otherwise ``u'`` in
        (0, 5]: at the block ends where the vehicle's perceived fz (known from the recording)
        is above its threshold, the combined tilt is held to the ``tilt_fz_use = u'`` octagon
        (where it is tighter): there a tilt's loss of vertical force would be felt against
        the vehicle (an fz reversal, as with downforce in a fast corner), elsewhere it agrees
        with the vehicle or is below a threshold.
    trans_limit_m : 3 floats
        ``mpc`` only: the plan's ``|x|, |y|, |z|`` at every block end at most these (m; hard
        rows of the QP, exact: the platform model is linear in the pose), each in (0, 1e9];
        ``1e9`` (the default) means none. A plan that renders corner entries by translation
        carries the platform to the legs' stroke, where the tilt it then needs for the
        sustained part has no stroke left (the legs at their limit, the linearised stroke
        rows force a jump of the other translation: spikes of fx); a box keeps a share of
        each leg's stroke for the tilt.
    fz_guard : float
        ``mpc`` only. 0 (default): none. Otherwise ``g`` in (0, 10]: at each block end where
        the vehicle's perceived fz (its prediction, as the sign guard's) is above its
        threshold, the rider's perceived fz may be below ``-g`` thresholds only at the sign
        guard's price (``sign_guard_weight``; a soft row): an fz reversal. The rider's fz is
        what the tilt takes away, ``g (cos roll cos pitch - 1)`` (not in the linear model),
        linearised about the present roll and pitch and passed through the otolith model
        from its present state, so the overshoot of the model's lead at a quick tilt is seen.
    fz_guard_from : float
        The rows of ``fz_guard`` hold at the block ends where the vehicle's predicted
        perceived fz is above this many thresholds (default 1: where a drop would be a
        reversal), in [-100, 100]; at -100 everywhere.
    fz_guard_pitch : float
        Share in [0, 1] of the pitch's future loss of vertical force the rows of ``fz_guard``
        see (default 1: all; 0: the roll's alone, so short stops keep their pitch; the
        rider's present fz state, ``MpcState.zr``, always has both).
    tilt_rate_limit_rad_s : float or None
        Largest roll and pitch rate of the plan (rad/s); ``None``: the preset's
        ``tilt_rate_limit_rad_s`` (the classical fallback always keeps that one).
    solver : str
        QP solver, one of :data:`MPC_SOLVERS`.
    deadline_ms : float
        Streaming only: a solve slower than this is dropped and counted as late (the
        fallback runs instead); batch runs have no deadline.
    window_s, stride_s : float
        ``optimal``: length of each window (s) and the part of it that is kept (s),
        ``stride_s < window_s``.
    block_samples : int
        ``optimal``: samples per move block.
    sign_guard_every : int
        ``optimal``: the sign guard's rows (every guarded channel but fz) also at every
        ``sign_guard_every``-th sample within each block, not only at the block ends (0: at
        the block ends only; a perceived motion judged sample by sample, against a vehicle
        whose sign can change within a block).
    """

    platform: str = "stewart6-linear"
    controller: str = "mbox6"
    horizon_s: float = 1.2
    blocks: int = 12
    w_error: Vec6 = (1.0, 1.0, 0.3, 1.0, 1.0, 0.3)
    w_pose: Vec6 = (30.0, 30.0, 30.0, 10.0, 10.0, 10.0)
    w_vel: Vec6 = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0)
    w_acc: Vec6 = (0.01, 0.01, 0.01, 0.1, 0.1, 0.1)
    w_vehicle: Vec6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    w_prior: Vec6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    w_jerk: Vec6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    prediction_tau_s: float = 0.0
    ref_scale: Vec6 = (1.0, 1.0, 1.0, 1.0, 1.0, 1.0)
    ref_limit: Vec6 = (1e9, 1e9, 1e9, 1e9, 1e9, 1e9)
    ref_split_hz: float = 0.0
    ref_scale_hf: Vec6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    ref_shape: float = 0.0
    ref_reach_use: float = 0.0
    ref_limit_neg: Vec6 | None = None
    ref_adapt_peak_m_s2: tuple[float, float] | None = None
    ref_adapt_tau_s: float = 30.0
    ref_adapt_start_m_s2: float = 9.80665
    ref_small_gain: tuple[float, float] = (0.0, 0.0)
    ref_small_knee_m_s2: float = 0.5
    sign_guard: Vec6 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    sign_guard_weight: float = 1e4
    stroke_use: float = 0.9
    rate_use: float = 0.9
    tilt_rate_limit_rad_s: float | None = None
    tilt_fz_use: float = 0.0
    tilt_fz_use_against: float = 0.0
    trans_limit_m: tuple[float, float, float] = (1e9, 1e9, 1e9)
    fz_guard: float = 0.0
    fz_guard_from: float = 1.0
    fz_guard_pitch: float = 1.0
    solver: str = "daqp"
    deadline_ms: float = 6.0
    window_s: float = 4.0
    stride_s: float = 2.0
    block_samples: int = 5
    sign_guard_every: int = 0

    def __post_init__(self) -> None:
        for name in ("w_error", "w_pose", "w_vel", "w_acc", "w_vehicle", "w_prior", "w_jerk"):
            object.__setattr__(self, name, _vec6(name, getattr(self, name), 0.0, 1e9))
        object.__setattr__(self, "ref_scale", _vec6("ref_scale", self.ref_scale, 0.0, 1.0))
        object.__setattr__(self, "ref_limit", _vec6("ref_limit", self.ref_limit, 1e-6, 1e9))
        object.__setattr__(self, "ref_scale_hf", _vec6("ref_scale_hf", self.ref_scale_hf, 0.0, 1.0))
        if self.ref_limit_neg is not None:
            object.__setattr__(
                self, "ref_limit_neg", _vec6("ref_limit_neg", self.ref_limit_neg, 1e-6, 1e9)
            )
        peak = self.ref_adapt_peak_m_s2
        if peak is not None:
            pk = tuple(peak)
            if len(pk) != 2 or not all(
                not isinstance(v, bool) and isinstance(v, int | float) and 0.0 <= v <= 50.0
                for v in pk
            ):
                raise ConfigError(
                    f"MpcParams.ref_adapt_peak_m_s2 = {peak!r} is invalid; allowed: two numbers "
                    "(x, y) in [0, 50]"
                )
            object.__setattr__(self, "ref_adapt_peak_m_s2", (float(pk[0]), float(pk[1])))
        sg = tuple(self.ref_small_gain) if isinstance(self.ref_small_gain, Iterable) else ()
        if len(sg) != 2 or not all(
            not isinstance(v, bool) and isinstance(v, int | float) and 0.0 <= v <= 1.0 for v in sg
        ):
            raise ConfigError(
                f"MpcParams.ref_small_gain = {self.ref_small_gain!r} is invalid; allowed: two "
                "numbers (x, y) in [0, 1]"
            )
        object.__setattr__(self, "ref_small_gain", (float(sg[0]), float(sg[1])))
        rs = self.ref_shape
        if (
            isinstance(rs, bool)
            or not isinstance(rs, int | float)
            or not (rs == 0.0 or 1.0 <= rs <= 50.0)
        ):
            raise ConfigError(f"MpcParams.ref_shape = {rs!r} is invalid; allowed: 0 or [1, 50]")
        tl = tuple(float(x) for x in self.trans_limit_m)
        if len(tl) != 3 or not all(math.isfinite(x) and 0.0 < x <= 1e9 for x in tl):
            raise ConfigError(
                f"MpcParams.trans_limit_m = {self.trans_limit_m!r} is invalid; allowed: 3 "
                "numbers in (0, 1e9]"
            )
        object.__setattr__(self, "trans_limit_m", (tl[0], tl[1], tl[2]))
        object.__setattr__(self, "sign_guard", _vec6("sign_guard", self.sign_guard, 0.0, 10.0))
        if not any(self.w_error):
            raise ConfigError(f"MpcParams.w_error = {self.w_error!r} is invalid; not all zero")
        checks = (
            ("horizon_s", self.horizon_s, 0.1, 10.0),
            ("prediction_tau_s", self.prediction_tau_s, 0.0, 1e6),
            ("stroke_use", self.stroke_use, 1e-3, 1.0),
            ("rate_use", self.rate_use, 1e-3, 1.0),
            ("deadline_ms", self.deadline_ms, 0.1, 1e6),
            ("sign_guard_weight", self.sign_guard_weight, 1e-9, 1e9),
            ("ref_split_hz", self.ref_split_hz, 0.0, 50.0),
            ("ref_reach_use", self.ref_reach_use, 0.0, 1.0),
            ("ref_adapt_tau_s", self.ref_adapt_tau_s, 0.1, 3600.0),
            ("ref_adapt_start_m_s2", self.ref_adapt_start_m_s2, 0.0, 100.0),
            ("ref_small_knee_m_s2", self.ref_small_knee_m_s2, 1e-3, 20.0),
            ("tilt_fz_use", self.tilt_fz_use, 0.0, 5.0),
            ("tilt_fz_use_against", self.tilt_fz_use_against, 0.0, 5.0),
            ("fz_guard", self.fz_guard, 0.0, 10.0),
            ("fz_guard_from", self.fz_guard_from, -100.0, 100.0),
            ("fz_guard_pitch", self.fz_guard_pitch, 0.0, 1.0),
            ("window_s", self.window_s, 0.2, 600.0),
            ("stride_s", self.stride_s, 0.1, 600.0),
        )
        for name, v, lo, hi in checks:
            if isinstance(v, bool) or not isinstance(v, int | float) or not lo <= v <= hi:
                raise ConfigError(f"MpcParams.{name} = {v!r} is invalid; allowed: [{lo}, {hi}]")
        tr = self.tilt_rate_limit_rad_s
        if tr is not None and (
            isinstance(tr, bool) or not isinstance(tr, int | float) or not 0.0 < tr <= 100.0
        ):
            raise ConfigError(
                f"MpcParams.tilt_rate_limit_rad_s = {tr!r} is invalid; allowed: (0, 100] or None"
            )
        if self.stride_s >= self.window_s:
            raise ConfigError(
                f"MpcParams.stride_s = {self.stride_s!r} is invalid; allowed: below "
                f"window_s = {self.window_s!r}"
            )
        for name, iv, ilo, ihi in (
            ("blocks", self.blocks, 1, 200),
            ("block_samples", self.block_samples, 1, 100),
            ("sign_guard_every", self.sign_guard_every, 0, 100),
        ):
            if isinstance(iv, bool) or not isinstance(iv, int) or not ilo <= iv <= ihi:
                raise ConfigError(f"MpcParams.{name} = {iv!r} is invalid; allowed: [{ilo}, {ihi}]")
        if self.solver not in MPC_SOLVERS:
            raise ConfigError(
                f"MpcParams.solver = {self.solver!r} is invalid; allowed: {', '.join(MPC_SOLVERS)}"
            )
        for name in ("platform", "controller"):
            if not isinstance(getattr(self, name), str) or not getattr(self, name):
                raise ConfigError(f"MpcParams.{name} = {getattr(self, name)!r}; a name or path")


def read_mpc_table(table: ConfigReader) -> MpcParams:
    """:class:`MpcParams` from the preset's ``[mpc]`` table (a ``ConfigReader``); unknown keys
    are rejected, missing ones take the defaults of :class:`MpcParams`."""
    d = MpcParams()
    vals: dict[str, Any] = {}  # MpcParams' keyword arguments by name, of several types
    for name in ("platform", "controller"):
        vals[name] = table.string(name, getattr(d, name))
    vals["solver"] = table.string("solver", d.solver, choices=MPC_SOLVERS)
    for name in ("w_error", "w_pose", "w_vel", "w_acc", "w_vehicle", "w_prior", "w_jerk"):
        vals[name] = table.vector(name, 6, list(getattr(d, name)))
    for name in (
        "horizon_s",
        "prediction_tau_s",
        "stroke_use",
        "rate_use",
        "deadline_ms",
        "sign_guard_weight",
        "ref_split_hz",
        "ref_shape",
        "ref_reach_use",
        "ref_adapt_tau_s",
        "ref_adapt_start_m_s2",
        "ref_small_knee_m_s2",
        "tilt_fz_use",
        "tilt_fz_use_against",
        "fz_guard",
        "fz_guard_from",
        "fz_guard_pitch",
        "window_s",
        "stride_s",
    ):
        vals[name] = table.number(name, getattr(d, name))
    for name in ("blocks", "block_samples", "sign_guard_every"):
        vals[name] = table.integer(name, getattr(d, name))
    lim = list(d.ref_limit)
    if table.has("ref_limit_m_s2"):
        lim[0:3] = table.vector("ref_limit_m_s2", 3)
    if table.has("ref_limit_deg_s"):
        lim[3:6] = [
            1e9 if v >= 1e9 else math.radians(v) for v in table.vector("ref_limit_deg_s", 3)
        ]
    vals["ref_limit"] = tuple(lim)
    vals["ref_scale"] = table.vector("ref_scale", 6, list(d.ref_scale))
    vals["ref_scale_hf"] = table.vector("ref_scale_hf", 6, list(d.ref_scale_hf))
    vals["sign_guard"] = table.vector("sign_guard", 6, list(d.sign_guard))
    if table.has("ref_adapt_peak_m_s2"):
        vals["ref_adapt_peak_m_s2"] = tuple(table.vector("ref_adapt_peak_m_s2", 2))
    vals["ref_small_gain"] = tuple(table.vector("ref_small_gain", 2, list(d.ref_small_gain)))
    vals["trans_limit_m"] = tuple(table.vector("trans_limit_m", 3, list(d.trans_limit_m)))
    if table.has("tilt_rate_limit_deg_s"):
        deg = table.number("tilt_rate_limit_deg_s", lo=0.0, hi=5000.0, lo_open=True)
        vals["tilt_rate_limit_rad_s"] = math.radians(deg)
    table.finish()
    return MpcParams(**vals)
