"""Cueing parameters: one frozen dataclass, loaded from ``configs/cueing/*.toml``.

Human units live only in the TOML keys (``limit_deg_s``, ``half_range_mm``); the loader
converts them once to SI, so every field of :class:`CueingParams` is in metres, radians,
seconds, m/s^2 and rad/s.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

from .._config import ConfigReader, find_config, load_toml
from .._errors import ConfigError
from ._mpc_params import MpcParams

__all__ = [
    "DOF_NAMES",
    "GRAVITY_M_S2",
    "INTENSITY_KEYS",
    "LEAD_GAIN",
    "CueingParams",
    "load_cueing",
]

LEAD_GAIN = 5.0
"""High-frequency gain of the phase lead ``(1 + tau s) / (1 + tau s / LEAD_GAIN)``."""

GRAVITY_M_S2 = 9.80665
"""Standard gravity (the ``g`` of ``f = a - g`` in conventions.md)."""

DOF_NAMES: tuple[str, ...] = ("x", "y", "z", "roll", "pitch", "yaw")

_D2R = math.pi / 180.0

INTENSITY_KEYS: tuple[str, ...] = (
    "f_scale_x",
    "f_scale_y",
    "f_limit_xy_m_s2",
    "f_shape_xy",
    "f_scale_z",
    "trans_wn_xy_rad_s",
    "trans_wb_xy_rad_s",
    "tilt_scale_x",
    "tilt_scale_y",
    "tilt_shape",
    "tilt_reach_use",
    "tilt_wn_rad_s",
    "tilt_rate_limit_deg_s",
    "tilt_accel_limit_deg_s2",
    "w_scale_rp",
    "rot_wn_rp_rad_s",
    "w_scale_yaw",
    "rot_wn_yaw_rad_s",
    "trans_wn_z_rad_s",
    "lead_x_s",
    "lead_y_s",
)
"""Keys of a classical preset's ``[intensity] gentle`` table: the parameters the tuner sets
on a preset with the compressive tilt (:data:`motioncue.cueing._tune.STRENGTH_TUNED_PARAMETERS`),
in their units, at the gentle (0 %) end of the preset's intensity range."""


def intensity_keys(algorithm: str) -> tuple[str, ...]:
    """The keys of an ``[intensity] gentle`` table for a preset of ``algorithm``: those its
    registered tuning plan declares (:class:`motioncue.cueing.TunePlan` ``intensity_keys``).

    Raises
    ------
    ConfigError
        An algorithm that is not registered, or that declares no intensity range.
    """
    from ._algorithm import cueing_entry

    plan = cueing_entry(algorithm).tune
    keys = () if plan is None else tuple(plan.intensity_keys)
    if not keys:
        raise ConfigError(
            f"cueing algorithm {algorithm!r} has no intensity range: an [intensity] table "
            "is not allowed in its presets"
        )
    return keys


Vec3 = tuple[float, float, float]


def _vec3(values: tuple[float, ...]) -> Vec3:
    return (values[0], values[1], values[2])


def _check(name: str, values: tuple[float, ...], lo: float, lo_open: bool, hi: float) -> None:
    for v in values:
        bad = (v <= lo if lo_open else v < lo) or v > hi or not math.isfinite(v)
        if bad:
            left = "(" if lo_open else "["
            raise ConfigError(
                f"CueingParams.{name} = {values!r} is invalid; each in {left}{lo}, {hi}]"
            )


@dataclass(frozen=True)
class CueingParams:
    """Every tunable of the classical washout, in SI units.

    Per-axis tuples are ordered x, y, z (forces, translations) or roll, pitch, yaw
    (rates, rotations), in the body/platform frame of conventions.md.

    Attributes
    ----------
    name : str
        Preset name (the TOML file's stem) or a user label.
    algorithm : str
        Name of the cueing algorithm in the registry (:func:`motioncue.cueing.make_cueing`)
        that runs these parameters (``"classical"``: :class:`~motioncue.cueing.ClassicalWashout`).
    dofs : tuple of 6 bool
        Which pose components ``[x, y, z, roll, pitch, yaw]`` the machine moves; the others
        are held at zero (a 3-DOF seat: ``z, roll, pitch``).
    f_scale, w_scale : 3-tuples
        Gain on the specific-force deviation from rest ``f - [0, 0, g]`` and on the angular
        velocity.
    f_limit_m_s2, w_limit_rad_s : 3-tuples
        Smooth limit applied after scaling (the output never exceeds it).
    soft_knee : float
        Fraction of the limit up to which the limiter is the identity; above it the signal
        bends smoothly (C1, tanh) towards the limit. ``1.0`` is a hard clip.
    trans_wn_rad_s, trans_zeta : 3-tuples
        Natural frequency and damping of the translational second-order high-pass
        ``s^2 / (s^2 + 2 zeta wn s + wn^2)``.
    trans_wb_rad_s : 3-tuple
        Third-order break ``s / (s + wb)``; ``0`` leaves the high-pass second order, in which
        case a sustained acceleration leaves a displacement offset ``a / wn^2``.
    tilt_wn_rad_s, tilt_zeta : float
        Tilt-coordination low-pass ``wn^2 / (s^2 + 2 zeta wn s + wn^2)`` on ``f_x, f_y``.
    tilt_rate_limit_rad_s : float
        Largest tilt angular rate (per axis).
    tilt_limit_rad : float
        Largest tilt angle (smooth limit, same knee as the input limiter).
    tilt_scale : 2-tuple or None
        Gain on ``f_x, f_y`` feeding the tilt coordination, separate from the translational
        ``f_scale`` (and not bounded by ``f_limit_m_s2``: the tilt has its own
        ``tilt_limit_rad``). ``None`` (the default) feeds the tilt the translational channel's
        scaled and limited force, as before this key existed.
    f_shape, w_shape : 3-tuples or None
        Compressive scaling (:func:`~._filters.compress`) of the force and angular-velocity
        channels: with ``p = f_shape[i]`` the scaled force is ``k x / (1 + |k x / L|^p)^(1/p)``
        (``k = f_scale[i]``, ``L = f_limit_m_s2[i]``): small cues pass with gain ``k``, large
        ones are compressed smoothly below ``L``, with no linear stretch and no knee.
        ``None`` (the default): the knee-and-tanh limiter of ``soft_knee``, as before these
        keys existed.
    lead_s : 2-tuple or None
        Phase lead on the longitudinal and lateral force (x, y) fed to the tilt (with
        ``tilt_scale``; the translational channel is not led): ``(1 + tau s) / (1 + tau s /
        LEAD_GAIN)``
        with ``tau = lead_s[i]`` (s) and :data:`LEAD_GAIN` the lead's high-frequency gain.
        It offsets the lag of the tilt (its low-pass and rate limit), so that the cue turns
        with the vehicle instead of after it (fewer reversals in quick direction changes).
        ``None`` (the default): no lead.
    tilt_shape : float or None
        Compressive scaling of the tilt channel (needs ``tilt_scale`` and ``tilt_reach_rad``):
        the force fed to the tilt is ``compress(f, k_t, L+, L-, tilt_shape)`` with the limits
        ``L = g sin(tilt_reach_use * reach)`` of the platform's reach in that direction, so
        that the sustained force is compressed into the tilt the platform can give; the tilt
        angle is then clipped to ``tilt_reach_use * reach`` (instead of the soft
        ``tilt_limit_rad``, which is not used). ``None`` (the default): the old tilt.
    tilt_reach_rad : 4-tuple or None
        The platform's reach in pure tilt about neutral, magnitudes (rad):
        ``(roll-, roll+, pitch-, pitch+)`` (from the platform's workspace, e.g.
        :func:`motioncue.cueing.tilt_reach`).
    tilt_reach_use : float
        Share of ``tilt_reach_rad`` the tilt may use, in (0, 1] (the rest is left to the
        translational and rotational cues).
    tilt_additive : bool
        With ``True`` the tilt coordination's own specific force (gravity in the tilted
        platform frame) is added to the translational channel's target, so the translation
        renders its own scaled force on top of the tilt instead of the difference between
        that force and the tilt's (the classical complementary design, in which the
        translation drives against a tilt stronger than its target). Needs ``tilt_scale``
        (the tilt's own gain). ``False`` (the default): the classical design.
    tilt_accel_limit_rad_s2 : float or None
        Largest tilt angular acceleration (per axis, rad/s^2), on top of
        ``tilt_rate_limit_rad_s``; ``None`` (the default): rate limit only.
    tilt_lag_fill : float
        With the additive tilt: the share ``k`` in [0, 1] of the tilt's lag that the
        translational channel renders. The tilt's rate (and acceleration) limit delays it
        behind its target (the low-passed, clipped tilt before those limits); the
        translation's target gains ``k`` times the difference between the gravity of that
        target tilt and of the delivered one, so that the rider feels the tilt's force
        sooner (a surge onset while the tilt catches up; and the tilt's late return is
        countered). 0 (the default): the translation renders only its own force.
    tilt_forward_ratio : float
        The tilt's gain on forward specific force (``f_x > 0``: throttle, nose up) as a share
        of its gain on rearward force (``tilt_scale[0]``, braking, nose down), in (0, 4]
        (needs ``tilt_scale``). A race car's stops are several times its throttle; with a
        smaller forward gain the throttle's nose-up tilt is smaller, so the tilt has less
        to unwind when a stop starts (at the tilt's rate limit, while it still tilts the
        wrong way the rider feels the throttle during the braking: a reversal). Measured
        (``tools/fx_phase_costs.py``, the firm default with the tilt's x gain 0.1 on
        chicane-gt): fx reversals in a stop's first 0.5 s 1.49 -> 0.14 % of the time and
        in the 0.8 s after it 1.05 -> 0.03 % with ``r = 0.5``. With
        ``tilt_shape`` the forward force is ``compress(f_x, r k, L+, L-, p)``, without it
        ``r k f_x``. 1 (the default): the same gain both ways, as before this key existed.
    tilt_rate_mix : tuple of (a, b) pairs or None
        Joint rate limit of the tilt (roll and pitch together): for every row,
        ``a |roll rate| + b |pitch rate| <= tilt_rate_limit_rad_s`` (on top of each axis
        alone). For a hexapod the rows are the legs' speeds per unit roll and pitch rate
        (one row per leg pair, scaled so that the largest value is 1): pure roll or pure
        pitch may then turn at about the rate limit while both together, which add up in
        some legs, turn slower, instead of one box limit for both that is either too slow
        alone or too fast together. 1 to 12 rows of two numbers in [0, 10], not both 0.
        ``None`` (the default): each axis alone.
    tilt_offset_m : 3 tuples of 5 floats, or None
        The reach offset: the platform's origin moves with the delivered tilt
        ``(roll, pitch)`` (rad) by ``x, y, z = C @ [roll, pitch, roll^2, pitch^2, roll
        pitch]`` (m per rad, m per rad^2; rows x, y, z) on top of the translational cue, so
        that the legs stay centred in their stroke as the platform tilts and it can tilt
        further than about its neutral position (``tilt_reach_rad`` is then the reach with
        this offset). Every value in [-10, 10]. ``None`` (the default): no offset.
    tilt_reach_exponent : float
        Shape of the compressive tilt's region of roll and pitch together: the superellipse
        ``|roll / R|^q + |pitch / P|^q <= 1`` (``R, P`` the limits in that quadrant) with
        ``q`` in [1, 8]; 2 (the default) is the ellipse.
    tilt_fz_guard : 3-tuple or None
        ``(loss_m_s2, above_m_s2, wn_rad_s)``: a tilt lowers the specific force the rider
        feels along the platform's z axis by ``g (1 - cos(roll) cos(pitch))`` (0.20 m/s^2 at
        11.6 deg of roll), the opposite of a vehicle's rising ``f_z`` in a dip or compression
        taken in a corner: a z reversal for as long as the roll is held. Where the vehicle's
        ``f_z - g``, low-passed by ``wn^2 / (s^2 + 2 wn s + wn^2)`` (so that bumps do not
        switch it), exceeds ``above_m_s2``, the roll gives way: the force the roll is made
        of (``f_t,y`` of step 2 of :mod:`._classical`, before the tilt's low-pass) is clipped
        to ``+-sqrt(max(0, g^2 (1 - c^2) - f_t,x^2))``, ``c = 1 - l / g``, and the pitch's
        ``f_t,x`` is kept. A settled tilt then has ``sin(roll)^2 + sin(pitch)^2 <= 1 - c^2``
        (the low-pass's step response does not overshoot), so ``g (1 - cos(roll)
        cos(pitch)) <= l``, with equality in pure roll, unless the pitch alone loses more
        (then the roll is 0). The allowed loss ``l`` falls linearly from ``g`` (no cut) where
        the low-passed ``f_z - g`` is ``above_m_s2`` to ``loss_m_s2`` where it is ``2
        above_m_s2`` (at least 0.05 m/s^2 further) and stays there above; the tilt's
        low-pass and rate limits smooth the cut. ``loss_m_s2`` in (0, 9.8], ``above_m_s2``
        in [0, 100], ``wn_rad_s`` in (0, 100] (below Nyquist of the run). ``None`` (the
        default): no guard.
    tilt_adapt_peak_m_s2 : 2-tuple or None
        ``(c_x, c_y)``: the tilt's gain adapts to the drive. On each axis an envelope follows
        the peaks of the vehicle's specific force (held input, before any lead),
        ``e[n] = max(|f[n]|, e[n-1] exp(-1 / (fs tau)))`` (``tau = tilt_adapt_tau_s``; 0
        before the first sample), and the tilt's gain ``tilt_scale`` on that axis becomes
        ``min(kt, c / e)``: the largest force of the last few ``tau`` is brought to at most
        ``c`` before the tilt's compression. A car whose stops are 1 g gets a larger tilt gain
        than one whose stops are 3 g, so each uses the tilt the rig has (the fixed gain of a
        preset is set by its hardest drive); within a drive the gain changes as slowly as the
        envelope decays. ``c`` in [0, 50] (0: that axis keeps its fixed gain). Needs
        ``tilt_scale``. ``None`` (the default): fixed gains.
    tilt_adapt_tau_s : float
        Decay time constant of that envelope (s), in [0.1, 3600]; 30 (the default).
    tilt_adapt_start_m_s2 : float
        The envelope before the first sample (m/s^2, both axes), in [0, 100]: the drive's
        peaks the gain assumes until it has seen them (0 starts at the fixed gain, so a
        drive's first hard stop would be rendered at the gain of a gentle one); 9.81 (1 g,
        the default).
    head_offset_m : 3-tuple
        The rider's head (the vestibular system) relative to the platform origin, platform
        frame ``[x fwd, y left, z up]`` (m). The translational channel removes the specific
        force the platform's own rotation causes there (see :mod:`._classical`);
        ``(0, 0, 0)`` (the default) cues at the origin.
    rot_wn_rad_s, rot_zeta : 3-tuples
        Rotational second-order high-pass on the Euler-angle rates.
    reject_f_m_s2, reject_w_rad_s : float
        Input samples whose specific-force deviation or angular velocity exceeds these (any
        axis) are spikes: held at the last good sample and counted, like NaN and inf.
    workspace : 6-tuple
        Half range of each DOF about neutral (m, rad), for the workspace-use metric.
    mpc : MpcParams or None
        Settings of the optimisation-based algorithms (``"mpc"``, ``"optimal"``), from the
        optional ``[mpc]`` table; ``None`` when the preset has none.
    tables : mapping of str to object
        The other algorithms' own tables, by name, as their registered readers return them
        (:class:`motioncue.cueing.ParameterTable`).
    intensity_gentle : tuple of floats or None
        The gentle (0 %) end of the preset's tuned intensity range: one value per key of
        its algorithm (:func:`intensity_keys`: :data:`INTENSITY_KEYS` for the classical
        washout, the terms of the plan's cost that ask for strength for ``mpc`` and
        ``optimal``; their units), from
        the optional ``[intensity]`` table; the
        preset's own tables are the strong (100 %) end. ``None``: the preset has no range
        (see :func:`motioncue.cueing.at_intensity`).
    """

    name: str = "default"
    algorithm: str = "classical"
    dofs: tuple[bool, bool, bool, bool, bool, bool] = (True, True, True, True, True, True)
    f_scale: Vec3 = (0.5, 0.5, 0.3)
    f_limit_m_s2: Vec3 = (6.0, 6.0, 4.0)
    w_scale: Vec3 = (0.5, 0.5, 0.5)
    w_limit_rad_s: Vec3 = (0.5, 0.5, 0.5)
    soft_knee: float = 0.7
    trans_wn_rad_s: Vec3 = (4.0, 4.0, 6.0)
    trans_zeta: Vec3 = (1.0, 1.0, 1.0)
    trans_wb_rad_s: Vec3 = (0.5, 0.5, 0.5)
    tilt_wn_rad_s: float = 5.0
    tilt_zeta: float = 1.0
    tilt_rate_limit_rad_s: float = 3.0 * _D2R
    tilt_limit_rad: float = 12.0 * _D2R
    tilt_scale: tuple[float, float] | None = None
    tilt_accel_limit_rad_s2: float | None = None
    f_shape: Vec3 | None = None
    w_shape: Vec3 | None = None
    lead_s: tuple[float, float] | None = None
    tilt_shape: float | None = None
    tilt_reach_rad: tuple[float, float, float, float] | None = None
    tilt_reach_use: float = 1.0
    tilt_additive: bool = False
    tilt_rate_mix: tuple[tuple[float, float], ...] | None = None
    tilt_lag_fill: float = 0.0
    tilt_forward_ratio: float = 1.0
    tilt_offset_m: tuple[tuple[float, ...], ...] | None = None
    tilt_reach_exponent: float = 2.0
    tilt_fz_guard: tuple[float, float, float] | None = None
    tilt_adapt_peak_m_s2: tuple[float, float] | None = None
    tilt_adapt_tau_s: float = 30.0
    tilt_adapt_start_m_s2: float = 9.80665
    head_offset_m: Vec3 = (0.0, 0.0, 0.0)
    rot_wn_rad_s: Vec3 = (1.0, 1.0, 0.5)
    rot_zeta: Vec3 = (1.0, 1.0, 1.0)
    reject_f_m_s2: float = 100.0
    reject_w_rad_s: float = 20.0
    workspace: tuple[float, float, float, float, float, float] = (
        0.1,
        0.1,
        0.1,
        15.0 * _D2R,
        15.0 * _D2R,
        20.0 * _D2R,
    )
    mpc: MpcParams | None = None
    intensity_gentle: tuple[float, ...] | None = None
    tables: Mapping[str, object] = field(default_factory=dict, hash=False)

    @property
    def tilt_limits_rad(self) -> tuple[float, float, float, float]:
        """Clip of the compressed tilt, ``(roll-, roll+, pitch-, pitch+)`` magnitudes (rad):
        ``tilt_reach_use * tilt_reach_rad`` (``tilt_limit_rad`` each without a reach)."""
        if self.tilt_reach_rad is None:
            return (self.tilt_limit_rad,) * 4
        u = self.tilt_reach_use
        r = self.tilt_reach_rad
        return (u * r[0], u * r[1], u * r[2], u * r[3])

    @property
    def tilt_force_limits_m_s2(self) -> tuple[float, float, float, float]:
        """Limits of the compressed tilt force ``(fx+, fx-, fy+, fy-)`` (m/s^2, magnitudes):
        ``g sin`` of the tilt limit in the direction that force needs (forward force: nose
        up, pitch-; rightward force: roll+)."""
        rn, rp, pn, pp = self.tilt_limits_rad
        g = GRAVITY_M_S2
        return (g * math.sin(pn), g * math.sin(pp), g * math.sin(rp), g * math.sin(rn))

    def __post_init__(self) -> None:
        if not isinstance(self.algorithm, str) or not self.algorithm:
            raise ConfigError(
                f"CueingParams.algorithm = {self.algorithm!r} is invalid; a registered name"
            )
        if self.tilt_scale is not None:
            if len(self.tilt_scale) != 2:
                raise ConfigError(
                    f"CueingParams.tilt_scale = {self.tilt_scale!r} is invalid; 2 numbers"
                )
            _check("tilt_scale", self.tilt_scale, 0.0, False, 100.0)
        if self.tilt_accel_limit_rad_s2 is not None:
            _check("tilt_accel_limit_rad_s2", (self.tilt_accel_limit_rad_s2,), 0.0, True, 1e6)
        for name in ("f_shape", "w_shape"):
            shape = getattr(self, name)
            if shape is not None:
                if len(shape) != 3:
                    raise ConfigError(f"CueingParams.{name} = {shape!r} is invalid; 3 numbers")
                _check(name, shape, 1.0, False, 50.0)
        _check("tilt_reach_use", (self.tilt_reach_use,), 0.0, True, 1.0)
        if self.lead_s is not None:
            if len(self.lead_s) != 2:
                raise ConfigError(f"CueingParams.lead_s = {self.lead_s!r} is invalid; 2 numbers")
            _check("lead_s", self.lead_s, 0.0, True, 10.0)
        if self.tilt_reach_rad is not None:
            if len(self.tilt_reach_rad) != 4:
                raise ConfigError(
                    f"CueingParams.tilt_reach_rad = {self.tilt_reach_rad!r} is invalid; 4 "
                    "numbers (roll-, roll+, pitch-, pitch+)"
                )
            _check("tilt_reach_rad", self.tilt_reach_rad, 0.0, True, math.radians(60.0))
        if self.tilt_shape is not None:
            _check("tilt_shape", (self.tilt_shape,), 1.0, False, 50.0)
            if self.tilt_reach_rad is None or self.tilt_scale is None:
                raise ConfigError(
                    f"CueingParams.tilt_shape = {self.tilt_shape!r} needs tilt_scale and "
                    "tilt_reach_rad (the platform's reach)"
                )
        if self.tilt_rate_mix is not None:
            rows = self.tilt_rate_mix
            if not 1 <= len(rows) <= 12 or any(len(r) != 2 for r in rows):
                raise ConfigError(
                    f"CueingParams.tilt_rate_mix = {rows!r} is invalid; allowed: 1 to 12 "
                    "rows of two numbers (roll, pitch weights)"
                )
            for row in rows:
                _check("tilt_rate_mix", row, 0.0, False, 10.0)
                if row[0] + row[1] <= 0.0:
                    raise ConfigError(
                        f"CueingParams.tilt_rate_mix row {row!r} is invalid; allowed: not both 0"
                    )
        _check("tilt_lag_fill", (self.tilt_lag_fill,), 0.0, False, 1.0)
        if self.tilt_lag_fill > 0.0 and not self.tilt_additive:
            raise ConfigError(
                f"CueingParams.tilt_lag_fill = {self.tilt_lag_fill!r} needs tilt_additive "
                "(the translation renders the tilt's lag on top of its own force)"
            )
        _check("tilt_forward_ratio", (self.tilt_forward_ratio,), 0.0, True, 4.0)
        if self.tilt_forward_ratio != 1.0 and self.tilt_scale is None:
            raise ConfigError(
                f"CueingParams.tilt_forward_ratio = {self.tilt_forward_ratio!r} needs "
                "tilt_scale (the tilt's own gain, of which it is a share)"
            )
        _check("tilt_reach_exponent", (self.tilt_reach_exponent,), 1.0, False, 8.0)
        if self.tilt_fz_guard is not None:
            guard = self.tilt_fz_guard
            if len(guard) != 3:
                raise ConfigError(
                    f"CueingParams.tilt_fz_guard = {guard!r} is invalid; allowed: "
                    "(loss_m_s2, above_m_s2, wn_rad_s)"
                )
            _check("tilt_fz_guard loss_m_s2", (guard[0],), 0.0, True, 9.8)
            _check("tilt_fz_guard above_m_s2", (guard[1],), 0.0, False, 100.0)
            _check("tilt_fz_guard wn_rad_s", (guard[2],), 0.0, True, 100.0)
        if self.tilt_adapt_peak_m_s2 is not None:
            peak = self.tilt_adapt_peak_m_s2
            if len(peak) != 2:
                raise ConfigError(
                    f"CueingParams.tilt_adapt_peak_m_s2 = {peak!r} is invalid; allowed: two "
                    "numbers (x, y)"
                )
            _check("tilt_adapt_peak_m_s2", peak, 0.0, False, 50.0)
            if self.tilt_scale is None:
                raise ConfigError(
                    f"CueingParams.tilt_adapt_peak_m_s2 = {peak!r} needs tilt_scale (the "
                    "tilt's own gain, which it lowers)"
                )
        _check("tilt_adapt_tau_s", (self.tilt_adapt_tau_s,), 0.1, False, 3600.0)
        _check("tilt_adapt_start_m_s2", (self.tilt_adapt_start_m_s2,), 0.0, False, 100.0)
        if self.tilt_offset_m is not None:
            off = self.tilt_offset_m
            if len(off) != 3 or any(len(r) != 5 for r in off):
                raise ConfigError(
                    f"CueingParams.tilt_offset_m = {off!r} is invalid; allowed: 3 rows (x, y, "
                    "z) of 5 numbers (roll, pitch, roll^2, pitch^2, roll pitch)"
                )
            _check("tilt_offset_m", tuple(abs(v) for r in off for v in r), 0.0, False, 10.0)
        if self.tilt_additive and self.tilt_scale is None:
            raise ConfigError(
                "CueingParams.tilt_additive = True needs tilt_scale (the tilt's own gain)"
            )
        if self.intensity_gentle is not None:
            self._check_intensity(self.intensity_gentle)
        if len(self.head_offset_m) != 3:
            raise ConfigError(
                f"CueingParams.head_offset_m = {self.head_offset_m!r} is invalid; 3 numbers"
            )
        _check("head_offset_m", tuple(abs(v) for v in self.head_offset_m), 0.0, False, 10.0)
        if len(self.dofs) != 6 or not all(isinstance(d, bool) for d in self.dofs):
            raise ConfigError(f"CueingParams.dofs = {self.dofs!r} is invalid; 6 booleans")
        for name in ("f_scale", "w_scale"):  # a negative gain would cue the wrong way
            _check(name, getattr(self, name), 0.0, False, 100.0)
        for name in (
            "f_limit_m_s2",
            "w_limit_rad_s",
            "trans_wn_rad_s",
            "trans_zeta",
            "rot_wn_rad_s",
            "rot_zeta",
        ):
            _check(name, getattr(self, name), 0.0, True, 1e6)
        _check("trans_wb_rad_s", self.trans_wb_rad_s, 0.0, False, 1e6)
        _check("soft_knee", (self.soft_knee,), 0.0, True, 1.0)
        for name in ("tilt_wn_rad_s", "tilt_zeta", "tilt_rate_limit_rad_s"):
            _check(name, (getattr(self, name),), 0.0, True, 1e6)
        _check("tilt_limit_rad", (self.tilt_limit_rad,), 0.0, True, math.radians(60.0))
        _check("reject_f_m_s2", (self.reject_f_m_s2,), 0.0, True, 1e9)
        _check("reject_w_rad_s", (self.reject_w_rad_s,), 0.0, True, 1e9)
        if len(self.workspace) != 6:
            raise ConfigError(f"CueingParams.workspace = {self.workspace!r}; 6 numbers")
        _check("workspace", self.workspace, 0.0, False, 1e6)

    def _check_intensity(self, gentle: tuple[float, ...]) -> None:
        """The gentle end has one value per key of the algorithm's range, and its tuning plan
        accepts them for this preset (:class:`motioncue.cueing.TunePlan`
        ``check_intensity``)."""
        from ._algorithm import cueing_entry

        keys = intensity_keys(self.algorithm)
        if len(gentle) != len(keys):
            raise ConfigError(
                f"CueingParams.intensity_gentle has {len(gentle)} values; allowed for "
                f"algorithm {self.algorithm!r}: {len(keys)} ({', '.join(keys)})"
            )
        plan = cueing_entry(self.algorithm).tune
        assert plan is not None  # intensity_keys refuses an algorithm without one
        plan.check_intensity(self, gentle)


def _number_rows(
    table: ConfigReader, key: str, n_rows: int | None, row_len: int, allowed: str
) -> list[list[float]]:
    """The rows of numbers ``key`` of ``table`` (a TOML list of ``n_rows`` lists, each of
    ``row_len`` numbers; ``n_rows`` None: one or more), as floats.

    Raises
    ------
    ConfigError
        ``table.error(key, value, allowed)`` for anything else (a boolean is not a number).
    """
    raw = table.raw(key)
    if (
        not isinstance(raw, list)
        or (not raw if n_rows is None else len(raw) != n_rows)
        or any(
            not isinstance(r, list)
            or len(r) != row_len
            or any(isinstance(v, bool) or not isinstance(v, int | float) for v in r)
            for r in raw
        )
    ):
        raise table.error(key, raw, allowed)
    return [[float(v) for v in r] for r in raw]


FALLBACK_PRESET = "racing"
"""The preset used when neither the command nor the platform file names one (``choose_preset``
of the CLI, the demo)."""


def load_cueing(name_or_path: str | Path) -> CueingParams:
    """Load a cueing preset by bundled name (``racing``) or from a TOML path.

    The file layout (every key required unless marked optional; unknown keys are rejected)::

        description = "..."                        # optional
        algorithm = "classical"                    # optional (default); a registered name
        dofs = ["x", "y", "z", "roll", "pitch", "yaw"]
        [scaling]
        f_scale = [0.5, 0.5, 0.3]
        f_limit_m_s2 = [6.0, 6.0, 4.0]
        w_scale = [0.5, 0.5, 0.5]
        w_limit_deg_s = [30.0, 30.0, 30.0]
        soft_knee = 0.7
        f_shape = [2.0, 2.0, 2.0]                  # optional: compressive curve exponent of
        w_shape = [2.0, 2.0, 2.0]                  #   each channel (default: the knee)
        lead_s = [0.1, 0.1]                        # optional: phase lead on fx, fy (s)
        [translational]
        wn_rad_s = [4.0, 4.0, 6.0]
        zeta = [1.0, 1.0, 1.0]
        wb_rad_s = [0.5, 0.5, 0.5]                 # 0 = second order only
        [tilt]
        wn_rad_s = 5.0
        zeta = 1.0
        rate_limit_deg_s = 3.0
        limit_deg = 12.0
        scale = [0.5, 0.5]                         # optional: tilt gain on f_x, f_y
                                                   #   (default: the [scaling] force)
        accel_limit_deg_s2 = 20.0                  # optional: tilt acceleration limit
                                                   #   (default: none)
        shape = 2.0                                # optional: compressive tilt (needs scale
        reach_deg = [14.0, 14.0, 12.0, 13.0]       #   and reach_deg: the platform's reach,
        reach_use = 0.8                            #   roll-, roll+, pitch-, pitch+; the
                                                   #   share used, default 1)
        additive = true                            # optional (needs scale): translation
                                                   #   adds to the tilt (default false)
        rate_mix = [[0.76, 0.68], [0.97, 0.32]]    # optional: joint rate limit, every row
                                                   #   a |roll'| + b |pitch'| <= rate_limit
        lag_fill = 0.5                             # optional (needs additive): share of the
                                                   #   tilt's lag the translation renders
        forward_ratio = 0.5                        # optional (needs scale): tilt gain on
                                                   #   forward force / on rearward (default 1)
        reach_exponent = 2.0                       # optional: roll and pitch together in
                                                   #   |r/R|^q + |p/P|^q <= 1 (default 2)
        fz_guard = [0.15, 2.0, 1.0]                # optional: the tilt's fz loss at most
                                                   #   0.15 m/s^2 while the vehicle's
                                                   #   low-passed (1 rad/s) f_z - g > 2 m/s^2
        offset_mm = [[0, 0, 0, 0, 0],              # optional: x, y, z of the origin with the
                     [120, 0, 0, 0, 0],            #   tilt (mm per rad of roll, pitch; per
                     [0, -60, -40, -80, 0]]        #   rad^2 of roll^2, pitch^2, roll pitch)
        [rotational]
        wn_rad_s = [1.0, 1.0, 0.5]
        zeta = [1.0, 1.0, 1.0]
        [input]
        reject_f_m_s2 = 100.0
        reject_w_deg_s = 1000.0
        [workspace]
        half_range_mm = [100.0, 100.0, 100.0]
        half_range_deg = [15.0, 15.0, 20.0]
        [head]                                     # optional table
        offset_mm = [0.0, 0.0, 0.0]                # rider's head from the platform origin,
                                                   #   platform frame x fwd, y left, z up
        [mpc]                                      # optional: "mpc" and "optimal" settings
                                                   #   (as in configs/cueing/mpc-hexapod.toml)
        [intensity.gentle]                         # optional: the 0 % end of the intensity
        f_scale_x = 0.1                            #   range, one value per key of the
        ...                                        #   algorithm (classical: INTENSITY_KEYS,
                                                   #   needs [tilt] shape; mpc and optimal:
                                                   #   PLAN_INTENSITY_KEYS)

    Raises
    ------
    ConfigError
        Unknown preset, missing or unknown key, or a value out of range (named); an
        ``algorithm`` that is not registered (the message lists the known ones).
    """
    from ._algorithm import check_algorithm_name, parameter_tables

    path = find_config("cueing", name_or_path)
    top = ConfigReader(load_toml(path), path.name)
    top.string("description", "")
    algorithm = top.string("algorithm", "classical")
    try:
        check_algorithm_name(algorithm)
    except ConfigError as exc:
        raise ConfigError(f"{path.name}: {exc}") from exc
    dof_list = top.raw("dofs")
    if (
        not isinstance(dof_list, list)
        or not dof_list
        or any(d not in DOF_NAMES for d in dof_list)
        or len(set(dof_list)) != len(dof_list)
    ):
        raise top.error("dofs", dof_list, f"a list of distinct names from {DOF_NAMES}")
    dofs = tuple(n in dof_list for n in DOF_NAMES)

    sc = top.table("scaling")
    f_scale = _vec3(sc.vector("f_scale", 3))
    f_limit = _vec3(sc.vector("f_limit_m_s2", 3))
    w_scale = _vec3(sc.vector("w_scale", 3))
    w_limit = _vec3(tuple(v * _D2R for v in sc.vector("w_limit_deg_s", 3)))
    knee = sc.number("soft_knee", lo=0.0, hi=1.0, lo_open=True)
    f_shape = _vec3(sc.vector("f_shape", 3)) if sc.has("f_shape") else None
    w_shape = _vec3(sc.vector("w_shape", 3)) if sc.has("w_shape") else None
    lead = None
    if sc.has("lead_s"):
        lv = sc.vector("lead_s", 2)
        lead = (lv[0], lv[1])
    sc.finish()

    tr = top.table("translational")
    t_wn = _vec3(tr.vector("wn_rad_s", 3))
    t_zeta = _vec3(tr.vector("zeta", 3))
    t_wb = _vec3(tr.vector("wb_rad_s", 3))
    tr.finish()

    ti = top.table("tilt")
    tilt_wn = ti.number("wn_rad_s", lo=0.0, lo_open=True)
    tilt_zeta = ti.number("zeta", lo=0.0, lo_open=True)
    tilt_rate = ti.number("rate_limit_deg_s", lo=0.0, lo_open=True) * _D2R
    tilt_limit = ti.number("limit_deg", lo=0.0, hi=60.0, lo_open=True) * _D2R
    tilt_scale = None
    if ti.has("scale"):
        ks = ti.vector("scale", 2)
        tilt_scale = (ks[0], ks[1])
    tilt_accel = None
    if ti.has("accel_limit_deg_s2"):
        tilt_accel = ti.number("accel_limit_deg_s2", lo=0.0, lo_open=True) * _D2R
    tilt_shape = ti.number("shape", lo=1.0, hi=50.0) if ti.has("shape") else None
    reach = None
    if ti.has("reach_deg"):
        rd = ti.vector("reach_deg", 4)
        reach = (rd[0] * _D2R, rd[1] * _D2R, rd[2] * _D2R, rd[3] * _D2R)
    reach_use = 1.0
    if ti.has("reach_use"):
        reach_use = ti.number("reach_use", lo=0.0, hi=1.0, lo_open=True)
    additive = ti.boolean("additive") if ti.has("additive") else False
    rate_mix = None
    if ti.has("rate_mix"):
        rows = _number_rows(ti, "rate_mix", None, 2, "a list of [roll, pitch] pairs of numbers")
        rate_mix = tuple((r[0], r[1]) for r in rows)
    lag_fill = ti.number("lag_fill", lo=0.0, hi=1.0) if ti.has("lag_fill") else 0.0
    fwd = 1.0
    if ti.has("forward_ratio"):
        fwd = ti.number("forward_ratio", lo=0.0, hi=4.0, lo_open=True)
    reach_q = ti.number("reach_exponent", lo=1.0, hi=8.0) if ti.has("reach_exponent") else 2.0
    fz_guard = None
    if ti.has("fz_guard"):
        gv = ti.vector("fz_guard", 3)
        fz_guard = (gv[0], gv[1], gv[2])
    adapt_peak = None
    if ti.has("adapt_peak_m_s2"):
        av = ti.vector("adapt_peak_m_s2", 2)
        adapt_peak = (av[0], av[1])
    adapt_tau = ti.number("adapt_tau_s", lo=0.1, hi=3600.0) if ti.has("adapt_tau_s") else 30.0
    adapt_start = GRAVITY_M_S2
    if ti.has("adapt_start_m_s2"):
        adapt_start = ti.number("adapt_start_m_s2", lo=0.0, hi=100.0)
    offset = None
    if ti.has("offset_mm"):
        rows = _number_rows(ti, "offset_mm", 3, 5, "3 rows (x, y, z) of 5 numbers")
        offset = tuple(tuple(v * 1e-3 for v in r) for r in rows)
    ti.finish()

    ro = top.table("rotational")
    r_wn = _vec3(ro.vector("wn_rad_s", 3))
    r_zeta = _vec3(ro.vector("zeta", 3))
    ro.finish()

    inp = top.table("input")
    reject_f = inp.number("reject_f_m_s2", lo=0.0, lo_open=True)
    reject_w = inp.number("reject_w_deg_s", lo=0.0, lo_open=True) * _D2R
    inp.finish()

    ws = top.table("workspace")
    lin = ws.vector("half_range_mm", 3)
    ang = ws.vector("half_range_deg", 3)
    ws.finish()
    head: Vec3 = (0.0, 0.0, 0.0)
    if top.has("head"):
        hd = top.table("head")
        head = _vec3(tuple(v * 1e-3 for v in hd.vector("offset_mm", 3)))
        hd.finish()
    tables = {t.name: t.read(top.table(t.name)) for t in parameter_tables() if top.has(t.name)}
    mpc = tables.pop("mpc", None)
    gentle = None
    if top.has("intensity"):
        it = top.table("intensity")
        gt = it.table("gentle")
        # finite numbers >= 0 here; the algorithm's plan checks the rest (CueingParams)
        gentle = tuple(gt.number(k, lo=0.0) for k in intensity_keys(algorithm))
        gt.finish()
        it.finish()
    top.finish()

    try:
        return CueingParams(
            name=path.stem,
            algorithm=algorithm,
            dofs=(dofs[0], dofs[1], dofs[2], dofs[3], dofs[4], dofs[5]),
            f_scale=f_scale,
            f_limit_m_s2=f_limit,
            w_scale=w_scale,
            w_limit_rad_s=w_limit,
            soft_knee=knee,
            trans_wn_rad_s=t_wn,
            trans_zeta=t_zeta,
            trans_wb_rad_s=t_wb,
            tilt_wn_rad_s=tilt_wn,
            tilt_zeta=tilt_zeta,
            tilt_rate_limit_rad_s=tilt_rate,
            tilt_limit_rad=tilt_limit,
            tilt_scale=tilt_scale,
            tilt_accel_limit_rad_s2=tilt_accel,
            f_shape=f_shape,
            w_shape=w_shape,
            lead_s=lead,
            tilt_shape=tilt_shape,
            tilt_reach_rad=reach,
            tilt_reach_use=reach_use,
            tilt_additive=additive,
            tilt_rate_mix=rate_mix,
            tilt_lag_fill=lag_fill,
            tilt_forward_ratio=fwd,
            tilt_offset_m=offset,
            tilt_reach_exponent=reach_q,
            tilt_fz_guard=fz_guard,
            tilt_adapt_peak_m_s2=adapt_peak,
            tilt_adapt_tau_s=adapt_tau,
            tilt_adapt_start_m_s2=adapt_start,
            head_offset_m=head,
            rot_wn_rad_s=r_wn,
            rot_zeta=r_zeta,
            reject_f_m_s2=reject_f,
            reject_w_rad_s=reject_w,
            workspace=(
                lin[0] * 1e-3,
                lin[1] * 1e-3,
                lin[2] * 1e-3,
                ang[0] * _D2R,
                ang[1] * _D2R,
                ang[2] * _D2R,
            ),
            mpc=mpc if isinstance(mpc, MpcParams) else None,
            intensity_gentle=gentle,
            tables=tables,
        )
    except ConfigError as exc:
        raise ConfigError(f"{path.name}: {exc}") from exc
