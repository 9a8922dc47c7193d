"""The physical bound: how much of a drive any motion of a given rig could render.

For a drive, a platform and its limits, per horizontal channel (``fx``, ``fy``):

``error_rms``
    a **lower bound** on the RMS perceived error (perceived platform minus perceived vehicle,
    m/s^2; :class:`CueingEvaluation` ``rms_error``) that *any* motion of the rig reaches;
``gain_max``
    an **upper bound** on the gain (:func:`motioncue.cueing.cue_metrics`, the least-squares
    slope of felt on vehicle, i.e. the in-phase rendered share) of any motion of the rig that
    gives **no reversal** on the channel; ``gain_max_any`` the same with reversals allowed.

``share_max_at_corr``
    an **upper bound** on the rendered share (``rms(H s) / rms(H d)``, uncentred, as
    :func:`motioncue.cueing.cue_metrics`) of any motion of the rig whose perceived
    correlation with the vehicle is at least ``corr_min`` (0.95 fx, 0.90 fy by default: issue
    20's acceptance); ``share_at_corr_primal`` the share of a motion of ``S`` with that
    correlation (non-causal), which it found: the true optimum lies between the two.

A preset's ``share / gain_max`` (``compare``'s ``bound_pct``) says how much of what the rig
could give without a reversal it gives; ``share / share_max_at_corr`` how much of what it
could give at the acceptance's correlation.

The relaxation
--------------
The platform's specific force on the channel is modelled, to first order in the angles
(the rotation of the translational acceleration by the tilt, ``(cos tilt - 1) a`` and
``sin tilt * a_z``, and by yaw is neglected; the rider's head at the platform origin), as ::

    s[k] = (p[k+1] - 2 p[k] + p[k-1]) fs^2 + g tau[k]

(the central difference of :func:`simulator_motion`, the pose held before the first sample
and continued at its last velocity after the last one, so ``s[N-1] = g tau[N-1]``: the end
of the data charges no stop), with the translation ``p`` and the tilt term
``tau = sin(tilt)`` (pitch for ``fx``, roll for ``fy``) in boxes from the rig's reach
(:func:`motioncue.analysis.rig_reach`)::

    |p| <= stroke, |p[k+1] - p[k]| fs <= speed, |second difference| fs^2 <= accel,
    |tau| <= sin(tilt), |tau[k+1] - tau[k]| fs <= tilt rate.

Every motion of the rig whose translation and tilt stay within those numbers is in this
convex set ``S``. When the reach has a ``coupling`` (:class:`ReachPolygon`, from
:func:`motioncue.analysis.reach_coupling`, which ``compare --bound`` uses), ``S`` also
has, at every sample, the half-planes ``normals @ (p[k], tau[k]) <= offsets`` (a hexapod
cannot reach its largest stroke and its largest tilt at once: the legs couple them) and on
every step ``rate_normals @ (p[k+1] - p[k], tau[k+1] - tau[k]) fs <= rate_offsets`` (the
step's mean rate lies in the convex hull of the rates the actuator speeds allow, whatever
the pose). Both come from the exact kinematics (the projected workspace's support in each
direction, found from below and multiplied by the reach's margin), with no linearisation of
the legs; the other degrees of freedom are free, so ``S`` still contains every motion of the
rig (to first order in the angles in the specific force, as above), only fewer others. Only
the half-planes that cut the boxes enter the programmes; the LPs of the support function
then become one joint LP over ``(p, tau)``. Without a coupling the DOFs are bounded apart,
the looser relaxation.

The perceived motion is the model set's otolith ``H`` (linear, from rest). Then

* ``error_rms``: ``min_{s in S} ||H s - H d||`` (``d`` the vehicle's specific force on the
  channel minus rest) is a convex QP. It is solved by OSQP (through CasADi) in the
  states of ``H``, and then **certified** by weak duality: for any ``z``,
  ``||H s - v||^2 >= 2 z'(H s - v) - ||z||^2``, so
  ``min_S ||H s - v||^2 >= -||z||^2 - 2 z'v - 2 sigma_S(-H'z)`` with ``sigma_S`` the support
  function of ``S`` (two LPs, HiGHS). With ``z`` the solver's residual this equals the
  optimum when the solver converged and is below it otherwise: the reported figure is a
  valid lower bound whatever the solver's accuracy (to the LP tolerance, ~1e-7 relative).
* ``gain_max``: ``max_{s in S} <H s, H d> / <H d, H d>`` subject to no reversal
  (``H s >= -thr`` wherever ``H d > thr`` and ``H s <= thr`` wherever ``H d < -thr``), an LP
  (HiGHS). ``gain_max_any`` drops the reversal constraints: ``sigma_S(H'H d) / <Hd, Hd>``.
  ``share_at_gain_max`` is the rendered share of the motion attaining ``gain_max`` (its
  gain equals ``gain_max``; the share is at least the gain).

* ``share_max_at_corr``: with ``y = H s``, ``v = H d``, ``~`` the mean removed,
  ``u = v~ / ||v~||`` and ``tan t = sqrt(1 - c^2) / c``, ``corr(y, v) >= c`` exactly when
  ``||y~ - <u, y> u|| <= tan t <u, y>`` (a second-order cone), and then
  ``||y~|| <= <u, y> / c``. With ``a = <u, y>`` and ``b = sqrt(N) mean(y)`` (``u`` and
  ``1 / sqrt(N)`` are orthonormal), ``share^2 ||v||^2 = ||y~||^2 + b^2 <= a^2 / c^2 + b^2``.
  The set ``K`` of ``(a, b)`` of the motions of ``S`` with the correlation is convex, so it
  lies in the polygon of the cuts ``cos(phi) a + sin(phi) b <= h(phi)`` and ``a >= 0``, and
  the bound is the largest ``a^2 / c^2 + b^2`` over the polygon's vertices. Each ``h(phi)``
  is certified by Lagrangian weak duality: for any ``mu >= 0`` and ``z`` with ``||z|| <= 1``,
  centred and orthogonal to ``u``, ``||w|| >= <z, w>`` for ``w = y~ - a u``, so
  ``max_K cos(phi) a + sin(phi) b <= sigma_S(H'(g + mu tan t u - mu z))`` with
  ``g = cos(phi) u + sin(phi) / sqrt(N)`` (``phi = +-pi/2`` without the cone:
  ``sigma_S(H' 1 / sqrt(N))``, ``S`` being symmetric). ``mu`` and ``z`` are the multiplier
  and the normal of the cone at the optimum of the cone programme in direction ``phi``,
  solved by IPOPT through CasADi (the cone written ``c^2 ||y~||^2 <= a^2``, ``a >= 0``), which
  also gives the motion behind ``share_at_corr_primal``; ``phi = 0`` first, then cuts
  through the polygon's best vertex (normal to the level set of ``a^2 / c^2 + b^2`` there)
  until the bound is attained or ``corr_cuts`` more were made. Whatever the solver returns,
  the figure is a valid bound (to the LP tolerance). Long drives: the cone programme at
  ``fs / k`` with a zero-order-hold otolith (the bilinear one is blind near the decimated
  Nyquist frequency), its motion interpolated to the full rate (checked in the boxes there),
  ``z`` interpolated plus the part of ``u`` the decimated problem cannot see, the
  certificates at the full rate.

No false rotation cue
---------------------
``cue_bound(..., w_vehicle=w, forbid_false_rotation=True)`` bounds the smaller convex set
``S'`` of the motions of ``S`` that give no spurious and no reversed rotation cue on the
channel's tilt axis (pitch for fx, roll for fy). The platform's rate on that axis is, to first
order in the angles as above, ``sign * (tau[k] - tau[k-1]) fs`` (``tau[-1] = 0``: from the
neutral pose at rest, as the otolith; ``sign = -1`` for fx, ``tau = -sin(pitch)``, ``+1`` for
fy), and its perception ``r = C (rate)`` through the model set's canal on that axis (linear,
from rest); with ``w_v = C w`` the vehicle's perceived rate on the axis and ``thr`` the canal
threshold::

    -thr <= r[k]         unless w_v[k] < -thr     (no spurious cue, no reversal)
            r[k] <= thr  unless w_v[k] > thr

(both where the vehicle's perceived rate is below threshold). With ``rotation_rule="false"``
the rows are only those against a *false* cue (``cue_metrics``' ``false``: beyond the
threshold with the sign opposite to the vehicle's, whatever the vehicle's size)::

    -thr <= r[k]   where w_v[k] > 0,        r[k] <= thr   where w_v[k] < 0

a larger set ``S''`` (``S'`` within ``S''`` within ``S``): a spurious cue with the vehicle's
own sign is allowed, as issue 20's "all false cues" allows it. ``C`` enters every programme
as its second-order sections: one vector of extra variables per section, tied to ``tau`` and
to each other by banded equalities (exactly :func:`scipy.signal.sosfilt` from rest), the last
one ``r`` bounded as above. The QP, the gain LP and the cone programme get these rows, and
the certificates are the same with ``sigma_S'`` (the support LP with the rows) in place of
``sigma_S``, so every figure stays a certified bound, now over ``S'``. ``S'`` is not
symmetric (the rows follow the vehicle's sign), so ``b``'s two cuts are two support LPs.
``0`` is in ``S'`` and ``S'`` is convex, so a motion is brought into it by scaling down
(the primals are checked at the full rate).

The moving-average bound of ``tests/test_mpc_acceptance.py`` (``|M s| <= 2 v_max / T +
g sin(tilt_max)``) is one dual certificate of this family; the QP's is the best.

Sources: the perceived-motion error through vestibular models as the measure of cue
quality, and its minimisation over the platform's reachable motion as the ideal of optimal
cueing, are those of Telban & Cardullo (NASA/CR-2005-213747, 2005) and Reid & Nahon (UTIAS
296, 1985); the bound on the rig's motion by a convex relaxation is motioncue's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError
from ._metrics import correlation
from ._params import GRAVITY_M_S2
from ._vestibular import DEFAULT_MODEL_SET, VestibularModel, VestibularModelSet, get_model_set

if TYPE_CHECKING:
    import casadi
    from scipy.optimize import OptimizeResult
    from scipy.sparse import sparray

__all__ = [
    "BOUND_CHANNELS",
    "CORR_MIN",
    "REACH_MARGIN",
    "CueBound",
    "ReachPolygon",
    "RigReach",
    "cue_bound",
]

BOUND_CHANNELS: tuple[str, ...] = ("fx", "fy")
"""The channels bounded (longitudinal: surge and pitch; lateral: sway and roll)."""

CORR_MIN: tuple[float, float] = (0.95, 0.90)
"""The correlations (fx, fy) :func:`cue_bound`'s ``share_max_at_corr`` is for by default: those
of issue 20's acceptance."""

_TILT_AXIS = (1, 0)
"""The rotation axis (index into roll, pitch, yaw) of each channel's tilt: pitch for fx,
roll for fy."""

_TILT_SIGN = (-1.0, 1.0)
"""The tilt axis's rate over ``d tau / dt`` to first order: ``tau = -sin(pitch)`` for fx,
``cos(pitch) sin(roll)`` for fy (:class:`ReachPolygon`)."""

REACH_MARGIN = 1.05
""":func:`rig_reach` multiplies what it found by this: the sampled maxima are below the
true ones by the sampling's resolution, and the bound needs numbers at or above them."""


@dataclass(frozen=True, eq=False)
class ReachPolygon:
    """The coupled reach of one channel: half-planes containing every pose and every rate.

    ``normals @ (p, tau) <= offsets`` holds for the translation ``p`` (m) and the tilt term
    ``tau`` (``-sin(pitch)`` for fx, ``cos(pitch) sin(roll)`` for fy: the specific force of
    the tilt divided by g) of every reachable pose, and ``rate_normals @ (pdot, taudot) <=
    rate_offsets`` for their rates (m/s, 1/s) within the actuator speed limits at every
    reachable pose, the other degrees of freedom free (at whatever value or rate helps).
    A hexapod cannot reach its largest stroke and its largest tilt at once: these half-planes
    cut the corners of :class:`RigReach`'s boxes.

    Attributes
    ----------
    normals : (m, 2) array
        Pose half-plane normals (dimensionless, applied to ``(p [m], tau [-])``).
    offsets : (m,) array
        Their offsets (> 0: the neutral pose is inside).
    rate_normals : (k, 2) array
    rate_offsets : (k,) array
        The same for ``(pdot [m/s], taudot [1/s])``.
    """

    normals: NDArray[np.float64]
    offsets: NDArray[np.float64]
    rate_normals: NDArray[np.float64]
    rate_offsets: NDArray[np.float64]

    def __post_init__(self) -> None:
        for nm, off in (("normals", "offsets"), ("rate_normals", "rate_offsets")):
            a = np.array(getattr(self, nm), dtype=float).reshape(-1, 2)
            b = np.array(getattr(self, off), dtype=float).reshape(-1)
            if a.shape[0] != b.shape[0] or not (np.isfinite(a).all() and np.isfinite(b).all()):
                raise ConfigError(
                    f"reach polygon {nm}/{off} have shapes {a.shape}/{b.shape} or are not "
                    "finite; allowed: (m, 2) and (m,) finite numbers"
                )
            if np.any(b <= 0.0):
                raise ConfigError(
                    f"reach polygon {off} {b.tolist()!r} are invalid; allowed: > 0 (the "
                    "neutral pose at rest inside)"
                )
            a.setflags(write=False)
            b.setflags(write=False)
            object.__setattr__(self, nm, a)
            object.__setattr__(self, off, b)


@dataclass(frozen=True)
class RigReach:
    """What a rig can do along the two horizontal channels (index 0: fx, 1: fy).

    Attributes
    ----------
    stroke_m : (2,) tuple
        Largest ``|x|``, ``|y|`` of a reachable pose (m).
    speed_m_s : (2,) tuple
        Largest surge / sway speed within the actuator speed limits (m/s).
    accel_m_s2 : (2,) tuple
        Largest surge / sway acceleration within the actuator acceleration limits (m/s^2).
    tilt_rad : (2,) tuple
        Largest ``|pitch|`` (for fx) and ``|roll|`` (for fy) of a reachable pose (rad).
    tilt_rate_rad_s : (2,) tuple
        Largest pitch / roll rate within the actuator speed limits (rad/s).
    coupling : (2,) tuple of ReachPolygon, optional
        The coupled reach of each channel (translation with tilt); None: the boxes alone
        (each DOF apart, the looser relaxation).
    """

    stroke_m: tuple[float, float]
    speed_m_s: tuple[float, float]
    accel_m_s2: tuple[float, float]
    tilt_rad: tuple[float, float]
    tilt_rate_rad_s: tuple[float, float]
    coupling: tuple[ReachPolygon, ReachPolygon] | None = None

    def __post_init__(self) -> None:
        if self.coupling is not None and (
            len(self.coupling) != 2 or not all(isinstance(c, ReachPolygon) for c in self.coupling)
        ):
            raise ConfigError("rig reach coupling is invalid; allowed: None or two ReachPolygon")
        for name in ("stroke_m", "speed_m_s", "accel_m_s2", "tilt_rad", "tilt_rate_rad_s"):
            v = tuple(float(x) for x in getattr(self, name))
            if len(v) != 2 or not all(math.isfinite(x) and x >= 0.0 for x in v):
                raise ConfigError(
                    f"rig reach {name} {getattr(self, name)!r} is invalid; allowed: two "
                    "finite numbers >= 0 (fx, fy)"
                )
            if name == "tilt_rad" and any(x >= math.pi / 2 for x in v):
                raise ConfigError(f"rig reach tilt {v!r} rad is invalid; allowed: < pi/2")
            object.__setattr__(self, name, v)


@dataclass(frozen=True, eq=False)
class CueBound:
    """The physical bound of one drive on one rig (module docstring), per :data:`BOUND_CHANNELS`.

    Attributes
    ----------
    error_rms : (2,) array
        Certified lower bound on the RMS perceived error any motion of the rig reaches (m/s^2).
    gain_max : (2,) array
        Upper bound on the gain of any motion without a reversal on the channel.
    gain_max_any : (2,) array
        Upper bound on the gain of any motion (reversals allowed).
    share_at_gain_max : (2,) array
        Rendered share of the motion attaining ``gain_max`` (of the decimated problem's when
        the drive is longer than ``primal_samples``).
    vehicle_rms : (2,) array
        RMS of the vehicle's perceived motion (m/s^2): ``error_rms`` of a rig at rest.
    reach : RigReach
    share_max_at_corr : (2,) array
        Certified upper bound on the rendered share of any motion of the rig whose perceived
        correlation with the vehicle is at least ``corr_min`` (NaN if not computed).
    share_at_corr_primal : (2,) array
        Rendered share of the best motion of the relaxation found with that correlation
        (non-causal, at the full rate): how tight ``share_max_at_corr`` is.
    corr_at_primal : (2,) array
        Its correlation (``>= corr_min``).
    corr_min : (2,) array
        The correlation each channel's ``share_max_at_corr`` is for (default 0.95 fx, 0.90 fy).
    share_max_at_corr_zero_mean : (2,) array
        The same bound for the motions whose perceived mean is zero: the share is uncentred,
        so a steady tilt adds to it without changing the correlation; this says how much of
        ``share_max_at_corr`` that can be.
    fs_hz : float
    model_set : str
    solver : dict
        The solvers used and the decimation of the certificate problems (``"1"``: none).
    rotation_cues : str
        ``"allowed"``: the bound over every motion of the rig; ``"forbidden"``: over those
        with no spurious and no reversed rotation cue on the channels' tilt axes
        (``cue_bound(..., forbid_false_rotation=True)``); ``"no-false"``: over those with no
        false rotation cue there (``rotation_rule="false"``).
    """

    error_rms: NDArray[np.float64]
    gain_max: NDArray[np.float64]
    gain_max_any: NDArray[np.float64]
    share_at_gain_max: NDArray[np.float64]
    vehicle_rms: NDArray[np.float64]
    reach: RigReach
    fs_hz: float
    model_set: str = DEFAULT_MODEL_SET
    solver: dict[str, str] = field(default_factory=dict)
    share_max_at_corr: NDArray[np.float64] = field(default_factory=lambda: np.full(2, np.nan))
    share_at_corr_primal: NDArray[np.float64] = field(default_factory=lambda: np.full(2, np.nan))
    corr_at_primal: NDArray[np.float64] = field(default_factory=lambda: np.full(2, np.nan))
    corr_min: NDArray[np.float64] = field(default_factory=lambda: np.full(2, np.nan))
    share_max_at_corr_zero_mean: NDArray[np.float64] = field(
        default_factory=lambda: np.full(2, np.nan)
    )
    rotation_cues: str = "allowed"

    def to_dict(self) -> dict[str, object]:
        """JSON-ready: per channel ``{name: {channel: value}}`` and the reach used."""

        def ch(a: NDArray[np.float64]) -> dict[str, float | None]:
            return {
                c: (float(v) if math.isfinite(v) else None)
                for c, v in zip(BOUND_CHANNELS, a, strict=True)
            }

        r = self.reach
        return {
            "error_rms_m_s2": ch(self.error_rms),
            "gain_max": ch(self.gain_max),
            "gain_max_any": ch(self.gain_max_any),
            "share_at_gain_max": ch(self.share_at_gain_max),
            "vehicle_rms_m_s2": ch(self.vehicle_rms),
            "share_max_at_corr": ch(self.share_max_at_corr),
            "share_at_corr_primal": ch(self.share_at_corr_primal),
            "corr_at_primal": ch(self.corr_at_primal),
            "corr_min": ch(self.corr_min),
            "share_max_at_corr_zero_mean": ch(self.share_max_at_corr_zero_mean),
            "rotation_cues": self.rotation_cues,
            "reach": {
                "stroke_m": list(r.stroke_m),
                "speed_m_s": list(r.speed_m_s),
                "accel_m_s2": list(r.accel_m_s2),
                "tilt_rad": list(r.tilt_rad),
                "tilt_rate_rad_s": list(r.tilt_rate_rad_s),
                "coupled": r.coupling is not None,
            },
        }


# ---------------------------------------------------------------- the convex problems


def _second_difference(n: int, fs: float) -> sparray:
    """D2 (N, N): the central second difference times fs^2 in the convention of
    :func:`simulator_motion`: the pose held before the first sample (row 0 is
    ``p[1] - p[0]``) and continued at its last velocity after the last one (row N-1 is zero)."""
    import scipy.sparse as sp

    if n <= 2:
        d2 = sp.lil_matrix((n, n))
        if n == 2:
            d2[0, 0], d2[0, 1] = -1.0, 1.0
        return sp.csr_matrix(d2) * (fs * fs)
    main = -2.0 * np.ones(n)
    main[0] += 1.0
    main[-1] = 0.0
    lower = np.ones(n - 1)
    lower[-1] = 0.0
    upper = np.ones(n - 1)
    d2 = sp.diags([lower, main, upper], [-1, 0, 1], shape=(n, n), format="csr")
    d2.eliminate_zeros()
    return d2 * (fs * fs)


@dataclass(frozen=True, eq=False)
class _Rotation:
    """The no-false-rotation rows of one channel's tilt axis: the platform's rotation rate
    is ``sign * d tau / dt`` (to first order in the angles; pitch for fx: ``sign = -1``,
    roll for fy: ``+1``), perceived through ``canal`` from rest; ``omega`` is the vehicle's
    rate on that axis (rad/s) at the channel's rate, ``thr`` the canal threshold (rad/s)."""

    canal: VestibularModel
    sign: float
    omega: NDArray[np.float64]
    thr: float
    rule: str = "spurious"

    def bounds(self, fs: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(lo, hi)`` of the platform's perceived rate per sample. ``rule`` ``"spurious"``:
        within the threshold where the vehicle's is (no spurious cue), not opposite where it
        is above (no reversal). ``"false"``: not beyond the threshold with the sign opposite
        to the vehicle's, whatever the vehicle's size (no false cue, ``cue_metrics``'
        definition; free where the vehicle's is exactly 0)."""
        v = self.canal.apply(self.omega, fs)
        if self.rule == "false":
            lo = np.where(v > 0.0, -self.thr, -np.inf)
            hi = np.where(v < 0.0, self.thr, np.inf)
            return lo, hi
        lo = np.where(v < -self.thr, -np.inf, -self.thr)
        hi = np.where(v > self.thr, np.inf, self.thr)
        return lo, hi

    def perceived(self, tau: NDArray[np.float64], fs: float) -> NDArray[np.float64]:
        """The platform's perceived rate of the tilt term ``tau``, from the neutral pose at
        rest before the first sample (as the otolith: the first sample's tilt is a step)."""
        w = np.diff(tau, prepend=0.0) * (self.sign * fs)
        return self.canal.apply(w, fs)


@dataclass(frozen=True)
class _Channel:
    """One channel's relaxation: boxes and the otolith as a state-space system."""

    stroke: float
    speed: float
    accel: float
    tilt: float  # bound on tau = sin(tilt)
    tilt_rate: float
    fs: float
    model: VestibularModel
    poly: ReachPolygon | None = None
    rot: _Rotation | None = None

    @property
    def sos(self) -> NDArray[np.float64]:
        return self.model.sos(self.fs)

    def filt(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        from scipy.signal import sosfilt

        return np.asarray(sosfilt(self.sos, x))

    def filt_t(self, x: NDArray[np.float64]) -> NDArray[np.float64]:
        """``H' x``: the transpose of the causal filter is the filter run backwards."""
        return self.filt(x[::-1])[::-1]

    def ss(self) -> tuple[NDArray[np.float64], ...]:
        from scipy.signal import sos2zpk, zpk2ss

        a, b, c, d = zpk2ss(*sos2zpk(self.sos))
        return np.asarray(a), np.asarray(b), np.asarray(c), np.asarray(d)


LP_METHODS = ("highs", "highs-ipm", "highs-ds")
"""HiGHS's methods, tried in turn: its default choice sometimes stops with "numerical
difficulties" (status 4, "HiGHS Status 0: Not Set") on an LP that has a solution (the gain LP on
flowing-formula's samples 5000-5200 at 100 Hz); its interior-point method with crossover then
solves it. The bound is the LP's optimum, whichever method finds it."""


def _linprog(c: NDArray[np.float64], **kw: object) -> OptimizeResult:
    """``scipy.optimize.linprog`` with HiGHS, retried with the next method of
    :data:`LP_METHODS` while one stops on numerical difficulties (status 4); the last result
    is returned (its ``status`` is checked by the caller)."""
    from scipy.optimize import linprog

    res = None
    for method in LP_METHODS:
        res = linprog(c, method=method, **kw)
        if res.status != 4:
            break
    return res


def _linprog_box_chain(
    c: NDArray[np.float64], bound: float, step: float, second: float | None, d2: sparray
) -> float:
    """max c'x s.t. |x| <= bound, |x[k+1]-x[k]| <= step, (optionally) |d2 x| <= second."""
    import scipy.sparse as sp

    n = c.shape[0]
    if bound <= 0.0 or not np.any(c):
        return 0.0
    if n == 1:
        return float(abs(c[0]) * bound)
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csr")
    rows = [d1, -d1]
    rhs = [np.full(n - 1, step), np.full(n - 1, step)]
    if second is not None:
        rows += [d2, -d2]
        rhs += [np.full(n, second), np.full(n, second)]
    res = _linprog(
        -c, A_ub=sp.vstack(rows, format="csr"), b_ub=np.concatenate(rhs), bounds=(-bound, bound)
    )
    if res.status != 0:
        raise ConfigError(f"the bound's support LP failed: {res.message}")
    return float(-res.fun)


def _poly_rows(ch: _Channel, n: int) -> tuple[sparray, NDArray[np.float64]] | None:
    """The coupled reach's rows over ``[p (n), tau (n)]`` (``A x <= b``): the pose half-planes
    at every sample, the rate half-planes on every step (the first difference times fs: the
    mean rate over the step, which lies in the rate polygon when the rate does); None
    without a polygon."""
    import scipy.sparse as sp

    if ch.poly is None:
        return None
    pp = ch.poly
    # only the half-planes that cut the boxes (the others are implied by them)
    keep = np.abs(pp.normals) @ np.array([ch.stroke, ch.tilt]) > pp.offsets * (1.0 + 1e-9)
    rate_box = np.array([ch.speed, ch.tilt_rate])
    rkeep = np.abs(pp.rate_normals) @ rate_box > pp.rate_offsets * (1.0 + 1e-9)
    pp = ReachPolygon(pp.normals[keep], pp.offsets[keep], pp.rate_normals[rkeep],
                      pp.rate_offsets[rkeep])  # fmt: skip
    eye = sp.identity(n, format="csr")
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csr")
    d1 = d1 * ch.fs
    rows = [
        sp.hstack([sp.kron(eye, pp.normals[:, :1]), sp.kron(eye, pp.normals[:, 1:])]),
        sp.hstack([sp.kron(d1, pp.rate_normals[:, :1]), sp.kron(d1, pp.rate_normals[:, 1:])]),
    ]
    rhs = np.concatenate([np.tile(pp.offsets, n), np.tile(pp.rate_offsets, n - 1)])
    return sp.vstack(rows, format="csr"), rhs


def _rot_rows(
    ch: _Channel, n: int
) -> tuple[sparray, sparray, NDArray[np.float64], NDArray[np.float64]] | None:
    """The no-false-rotation rows (None without them): the canal's sections as equalities
    ``T tau + Q q = 0`` over ``m n`` extra variables ``q`` (each section's output, sample-major
    per section, from rest: exactly :func:`scipy.signal.sosfilt`), the last section's output
    ``r`` (the platform's perceived rate) in ``lo <= r <= hi``. Returns ``(T (m n, n),
    Q (m n, m n), lo (n), hi (n))``."""
    import scipy.sparse as sp

    if ch.rot is None:
        return None
    sos = ch.rot.canal.sos(ch.fs)
    m = sos.shape[0]

    def band(c: NDArray[np.float64]) -> sparray:
        diags = [np.full(n - j, float(c[j])) for j in range(3) if j < n]
        return sp.diags(diags, [-j for j in range(len(diags))], shape=(n, n), format="csr")

    dw = sp.diags([np.ones(n), -np.ones(n - 1)], [0, -1], shape=(n, n), format="csr")
    dw = dw * (ch.rot.sign * ch.fs)  # the rate fs (tau[k] - tau[k-1]), from tau[-1] = 0
    t_blocks = [-band(sos[0, :3]) @ dw] + [sp.csr_matrix((n, n))] * (m - 1)
    q_rows = []
    for j in range(m):
        row = [sp.csr_matrix((n, n))] * m
        row[j] = band(sos[j, 3:] / sos[j, 3])
        if j > 0:
            row[j - 1] = -band(sos[j, :3] / sos[j, 3])
        q_rows.append(sp.hstack(row, format="csr"))
    t_blocks[0] = t_blocks[0] / sos[0, 3]
    lo, hi = ch.rot.bounds(ch.fs)
    return sp.vstack(t_blocks, format="csr"), sp.vstack(q_rows, format="csr"), lo, hi


def _rot_var_bounds(ch: _Channel, n: int) -> list[tuple[float | None, float | None]]:
    """linprog bounds of the rows' extra variables (the sections free, the last bounded)."""
    rr = _rot_rows(ch, n)
    if rr is None:
        return []
    m = rr[1].shape[1] // n
    last = [(None if not np.isfinite(a) else float(a), None if not np.isfinite(b) else float(b))
            for a, b in zip(rr[2], rr[3], strict=True)]  # fmt: skip
    return [(None, None)] * ((m - 1) * n) + last


_ROT_FALLBACKS = [0]
"""Support LPs with the no-false-rotation rows that HiGHS could not solve (every method),
replaced by the support of the larger set without them (``CueBound.solver``)."""


def _support(ch: _Channel, c: NDArray[np.float64], d2: sparray) -> float:
    """sigma_S(c) = max_{s in S} c's (two LPs, translation and tilt; one joint LP when the
    channel has a coupled reach)."""
    if ch.poly is None and ch.rot is None:
        trans = _linprog_box_chain(np.asarray(d2.T @ c), ch.stroke, ch.speed / ch.fs, ch.accel, d2)
        tilt = GRAVITY_M_S2 * _linprog_box_chain(c, ch.tilt, ch.tilt_rate / ch.fs, None, d2)
        return trans + tilt
    import scipy.sparse as sp

    n = c.shape[0]
    cost = -np.concatenate([np.asarray(d2.T @ c), GRAVITY_M_S2 * c])
    if not np.any(cost):
        return 0.0
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csr")
    zn = sp.csr_matrix((n - 1, n))
    zz = sp.csr_matrix((n, n))
    poly = _poly_rows(ch, n)
    a_ub = sp.vstack(
        [
            sp.hstack([d1, zn]),
            sp.hstack([-d1, zn]),
            sp.hstack([zn, d1]),
            sp.hstack([zn, -d1]),
            sp.hstack([d2, zz]),
            sp.hstack([-d2, zz]),
            *([] if poly is None else [poly[0]]),
        ],
        format="csr",
    )
    b_ub = np.concatenate(
        [
            np.full(2 * (n - 1), ch.speed / ch.fs),
            np.full(2 * (n - 1), ch.tilt_rate / ch.fs),
            np.full(2 * n, ch.accel),
            *([] if poly is None else [poly[1]]),
        ]
    )
    box_p: tuple[float | None, float | None] = (-ch.stroke, ch.stroke)
    box_t: tuple[float | None, float | None] = (-ch.tilt, ch.tilt)
    bounds = [box_p] * n + [box_t] * n
    extra: dict[str, object] = {}
    rot = _rot_rows(ch, n)
    if rot is not None:  # the canal's rows over extra variables
        nq = rot[1].shape[1]
        a_ub = sp.hstack([a_ub, sp.csr_matrix((a_ub.shape[0], nq))], format="csr")
        extra = {
            "A_eq": sp.hstack([sp.csr_matrix((nq, n)), rot[0], rot[1]], format="csr"),
            "b_eq": np.zeros(nq),
        }
        cost = np.concatenate([cost, np.zeros(nq)])
        bounds += _rot_var_bounds(ch, n)
    res = _linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, **extra)
    if res.status != 0 and ch.rot is not None:
        # S' is in S: sigma_S >= sigma_S', so every certificate stays valid (looser)
        _ROT_FALLBACKS[0] += 1
        return _support(replace(ch, rot=None), c, d2)
    if res.status != 0:
        raise ConfigError(f"the bound's support LP failed: {res.message}")
    return float(-res.fun)


def _dm(m: sparray) -> casadi.DM:
    """``casadi.DM(m)`` of a SciPy sparse matrix, built from its compressed columns as lists.

    The same matrix as casadi's own conversion (which also takes ``m.tocsc()``, keeping every
    stored entry, explicit zeros included), without its conversion element by element through
    numpy's flat iterators: 26 ms against 2 ms for a (3200, 5600) matrix of 9600 entries, and
    the cone programme converts one such matrix per solve.
    """
    import casadi

    c = m.tocsc()
    nrow, ncol = c.shape
    pattern = casadi.Sparsity(nrow, ncol, c.indptr.tolist(), c.indices.tolist())
    return casadi.DM(pattern, c.data.tolist())


def _qp_best_motion(ch: _Channel, v: NDArray[np.float64], d2: sparray) -> NDArray[np.float64]:
    """The platform specific force s in S minimising ||H s - v|| (OSQP via CasADi)."""
    import casadi
    import scipy.sparse as sp

    n = v.shape[0]
    a, b, c, d = ch.ss()
    nx = a.shape[0]
    eye = sp.identity(n, format="csr")
    g = GRAVITY_M_S2
    # variables z = [p (n), tau (n), x (nx n, sample-major), y (n)]; s = d2 p + g tau
    n_z = n * (3 + nx)
    iy = (2 + nx) * n  # first index of y
    s_op = sp.hstack([d2, g * eye, sp.csr_matrix((n, (nx + 1) * n))], format="csr")
    # x[k+1] = a x[k] + b s[k] (x[0] = 0); y[k] = c x[k] + d s[k]
    shift = sp.diags([np.ones(n - 1)], [-1], shape=(n, n), format="csr")
    x_next = sp.kron(sp.identity(n), sp.identity(nx)) - sp.kron(shift, sp.csr_matrix(a))
    dyn = sp.hstack(
        [
            -sp.kron(shift, sp.csr_matrix(b)) @ s_op[:, : 2 * n],
            x_next,
            sp.csr_matrix((nx * n, n)),
        ],
        format="csr",
    )
    out = sp.hstack(
        [
            -float(d[0, 0]) * s_op[:, : 2 * n],
            -sp.kron(eye, sp.csr_matrix(c)),
            eye,
        ],
        format="csr",
    )
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csr")
    z_p = sp.csr_matrix((n - 1, n))
    rows = [
        dyn,
        out,
        sp.hstack([sp.identity(n), sp.csr_matrix((n, n * (2 + nx)))]),
        sp.hstack([sp.csr_matrix((n, n)), sp.identity(n), sp.csr_matrix((n, n * (1 + nx)))]),
        sp.hstack([d1, z_p, sp.csr_matrix((n - 1, n * (1 + nx)))]),
        sp.hstack([z_p, d1, sp.csr_matrix((n - 1, n * (1 + nx)))]),
        sp.hstack([d2, sp.csr_matrix((n, n * (2 + nx)))]),
    ]
    lo = [
        np.zeros(nx * n),
        np.zeros(n),
        np.full(n, -ch.stroke),
        np.full(n, -ch.tilt),
        np.full(n - 1, -ch.speed / ch.fs),
        np.full(n - 1, -ch.tilt_rate / ch.fs),
        np.full(n, -ch.accel),
    ]
    lba = np.concatenate(lo)
    uba = -lba
    uba[: (nx + 1) * n] = 0.0
    poly = _poly_rows(ch, n)
    if poly is not None:
        rows.append(sp.hstack([poly[0], sp.csr_matrix((poly[1].size, n * (1 + nx)))]))
        lba = np.concatenate([lba, np.full(poly[1].size, -np.inf)])
        uba = np.concatenate([uba, poly[1]])
    rot = _rot_rows(ch, n)
    if rot is not None:  # the canal's rows over extra variables after y, the last bounded
        nq = rot[1].shape[1]
        n_z += nq
        rows = [sp.hstack([r, sp.csr_matrix((r.shape[0], nq))], format="csr") for r in rows]
        rows.append(sp.hstack([sp.csr_matrix((nq, n)), rot[0], sp.csr_matrix((nq, (1 + nx) * n)),
                               rot[1]]))  # fmt: skip
        rows.append(sp.hstack([sp.csr_matrix((n, n_z - n)), sp.identity(n)]))
        lba = np.concatenate([lba, np.zeros(nq), rot[2]])
        uba = np.concatenate([uba, np.zeros(nq), rot[3]])
    m = sp.vstack(rows, format="csc")
    hess = sp.diags(
        np.concatenate([np.zeros(iy), np.full(n, 2.0), np.zeros(n_z - iy - n)]),
        0,
        shape=(n_z, n_z),
        format="csc",
    )
    q = np.zeros(n_z)
    q[iy : iy + n] = -2.0 * v
    hs = _dm(hess)
    ms = _dm(m)
    solver = casadi.conic(
        "bound",
        "osqp",
        {"h": hs.sparsity(), "a": ms.sparsity()},
        {
            "osqp": {
                "eps_abs": 1e-5,
                "eps_rel": 1e-5,
                "max_iter": 4000,
                "polish": True,
                "verbose": False,
            },
            "error_on_fail": False,
        },
    )
    sol = solver(h=hs, g=q, a=ms, lba=lba, uba=uba)
    zz = np.asarray(sol["x"], dtype=float).ravel()
    p = np.clip(zz[:n], -ch.stroke, ch.stroke)
    tau = np.clip(zz[n : 2 * n], -ch.tilt, ch.tilt)
    return np.asarray(d2 @ p + g * tau)


def _gain_lp(
    ch: _Channel, v: NDArray[np.float64], thr: float, d2: sparray
) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """max <H s, v> over s in S with no reversal: the maximum, H s, and the multipliers of
    the no-reversal rows (>= 0, zero where the vehicle is below threshold)."""
    import scipy.sparse as sp

    n = v.shape[0]
    a, b, c, d = ch.ss()
    nx = a.shape[0]
    g = GRAVITY_M_S2
    eye = sp.identity(n, format="csr")
    s_op = sp.hstack([d2, g * eye], format="csr")  # s from [p, tau]
    shift = sp.diags([np.ones(n - 1)], [-1], shape=(n, n), format="csr")
    x_next = sp.identity(nx * n) - sp.kron(shift, sp.csr_matrix(a))
    # variables [p, tau, x, y]
    a_eq = sp.vstack(
        [
            sp.hstack(
                [-sp.kron(shift, sp.csr_matrix(b)) @ s_op, x_next, sp.csr_matrix((nx * n, n))]
            ),
            sp.hstack([-float(d[0, 0]) * s_op, -sp.kron(eye, sp.csr_matrix(c)), eye]),
        ],
        format="csr",
    )
    b_eq = np.zeros((nx + 1) * n)
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csr")
    zpad = sp.csr_matrix((n - 1, n))
    rest = sp.csr_matrix((n - 1, n * (1 + nx)))
    sign = np.where(v > thr, -1.0, np.where(v < -thr, 1.0, 0.0))
    idx = np.flatnonzero(sign)
    sel = sp.csr_matrix(
        (sign[idx], (np.arange(idx.size), idx)), shape=(idx.size, n)
    )  # -y <= thr where v > thr; y <= thr where v < -thr
    a_ub = sp.vstack(
        [
            sp.hstack([d1, zpad, rest]),
            sp.hstack([-d1, zpad, rest]),
            sp.hstack([zpad, d1, rest]),
            sp.hstack([zpad, -d1, rest]),
            sp.hstack([d2, sp.csr_matrix((n, n * (2 + nx)))]),
            sp.hstack([-d2, sp.csr_matrix((n, n * (2 + nx)))]),
            sp.hstack([sp.csr_matrix((idx.size, n * (2 + nx))), sel]),
        ],
        format="csr",
    )
    b_ub = np.concatenate(
        [
            np.full(2 * (n - 1), ch.speed / ch.fs),
            np.full(2 * (n - 1), ch.tilt_rate / ch.fs),
            np.full(2 * n, ch.accel),
            np.full(idx.size, thr),
        ]
    )
    poly = _poly_rows(ch, n)
    if poly is not None:  # before the no-reversal rows, whose multipliers are read last
        a_ub = sp.vstack(
            [a_ub[: a_ub.shape[0] - idx.size],
             sp.hstack([poly[0], sp.csr_matrix((poly[1].size, n * (1 + nx)))]),
             a_ub[a_ub.shape[0] - idx.size :]],
            format="csr",
        )  # fmt: skip
        b_ub = np.concatenate([b_ub[: b_ub.size - idx.size], poly[1], b_ub[b_ub.size - idx.size :]])
    box_p: tuple[float | None, float | None] = (-ch.stroke, ch.stroke)
    box_t: tuple[float | None, float | None] = (-ch.tilt, ch.tilt)
    free: tuple[float | None, float | None] = (None, None)
    bounds = [box_p] * n + [box_t] * n + [free] * ((nx + 1) * n)
    cost = np.concatenate([np.zeros((2 + nx) * n), -v])
    rot = _rot_rows(ch, n)
    if rot is not None:  # the canal's rows over extra variables after y
        nq = rot[1].shape[1]
        a_ub = sp.hstack([a_ub, sp.csr_matrix((a_ub.shape[0], nq))], format="csr")
        a_eq = sp.vstack(
            [sp.hstack([a_eq, sp.csr_matrix((a_eq.shape[0], nq))]),
             sp.hstack([sp.csr_matrix((nq, n)), rot[0], sp.csr_matrix((nq, (1 + nx) * n)),
                        rot[1]])],
            format="csr",
        )  # fmt: skip
        b_eq = np.zeros(a_eq.shape[0])
        cost = np.concatenate([cost, np.zeros(nq)])
        bounds = bounds + _rot_var_bounds(ch, n)
    res = _linprog(cost, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds)
    if res.status != 0 and rot is not None:
        # the larger set's LP: its maximum is above, its multipliers still a certificate
        _ROT_FALLBACKS[0] += 1
        return _gain_lp(replace(ch, rot=None), v, thr, d2)
    if res.status != 0:
        raise ConfigError(f"the bound's gain LP failed: {res.message}")
    y = np.asarray(res.x[(2 + nx) * n : (3 + nx) * n], dtype=float)
    lam = np.zeros(n)
    lam[idx] = -np.asarray(res.ineqlin.marginals, dtype=float)[-idx.size :] if idx.size else 0.0
    return float(-res.fun), y, np.maximum(lam, 0.0)


def _golden(
    fun: Callable[[float], float], lo: float, hi: float, evals: int, maximise: bool
) -> float:
    """Best value of a unimodal ``fun`` on [lo, hi] found by golden-section search (and the
    end points); every value tried is valid, so the best one is returned."""
    sign = 1.0 if maximise else -1.0
    best = max(sign * fun(lo), sign * fun(hi))
    r = (math.sqrt(5.0) - 1.0) / 2.0
    a, b = lo, hi
    c, d = b - r * (b - a), a + r * (b - a)
    fc, fd = sign * fun(c), sign * fun(d)
    for _ in range(max(0, evals - 4)):
        if fc > fd:
            b, d, fd = d, c, fc
            c = b - r * (b - a)
            fc = sign * fun(c)
        else:
            a, c, fc = c, d, fd
            d = a + r * (b - a)
            fd = sign * fun(d)
    return sign * max(best, fc, fd)


def _decimated(
    ch: _Channel, d: NDArray[np.float64], k: int
) -> tuple[_Channel, NDArray[np.float64], sparray]:
    """The channel at fs / k with the vehicle's force averaged over blocks of k samples."""

    n = d.shape[0]
    m = n // k
    dd = d[: m * k].reshape(m, k).mean(axis=1)
    fs_d = ch.fs / k
    rot = ch.rot
    if rot is not None:
        rot = replace(rot, omega=rot.omega[: m * k].reshape(m, k).mean(axis=1))
    return replace(ch, fs=fs_d, rot=rot), dd, _second_difference(m, fs_d)


def _channel_bound(
    ch: _Channel, d: NDArray[np.float64], thr: float, k: int, d2: sparray
) -> tuple[float, float, float, float, float]:
    """``(error bound, gain bound, gain bound with reversals, share, vehicle rms)`` of one
    channel (``k`` > 1: certificates from the problem decimated by ``k``; see cue_bound)."""
    n = d.shape[0]
    v = ch.filt(d)
    vv = float(v @ v)
    vrms = math.sqrt(vv / n)
    chd, dd, d2d = _decimated(ch, d, k) if k > 1 else (ch, d, d2)
    vd = chd.filt(dd)
    zd = chd.filt(_qp_best_motion(chd, vd, d2d)) - vd
    if k == 1:
        z = zd
    else:
        centres = (np.arange(zd.shape[0]) + 0.5) * k - 0.5
        z = np.interp(np.arange(n), centres, zd)

    def lower(b: float) -> float:
        zb = b * z
        return -float(zb @ zb) - 2.0 * float(zb @ v) - 2.0 * _support(ch, -ch.filt_t(zb), d2)

    lb = lower(1.0) if k == 1 else _golden(lower, 0.0, 1.5, 5, maximise=True)
    err = math.sqrt(max(lb, 0.0) / n)
    if vv <= 0.0:
        return err, math.nan, math.nan, math.nan, vrms
    gany = _support(ch, ch.filt_t(v), d2) / vv
    g_lp, yd, lam_d = _gain_lp(chd, vd, thr, d2d)
    share = math.sqrt(float(yd @ yd) / max(float(vd @ vd), 1e-300))
    if k == 1:
        return err, min(g_lp / vv, gany), gany, share, vrms
    sgn = np.where(v > thr, -1.0, np.where(v < -thr, 1.0, 0.0))
    lam = np.repeat(lam_d, k)
    lam = np.concatenate([lam, np.full(n - lam.shape[0], lam_d[-1] if lam_d.size else 0.0)])
    lam = np.where(sgn != 0.0, lam, 0.0)

    def upper(a: float) -> float:
        la = a * lam
        return (_support(ch, ch.filt_t(v - la * sgn), d2) + thr * float(la.sum())) / vv

    return err, min(gany, _golden(upper, 0.0, 2.0, 5, maximise=False)), gany, share, vrms


# ------------------------------------------------- the share at a given correlation


def _centred_unit(x: NDArray[np.float64]) -> NDArray[np.float64]:
    """``(x - mean x) / ||x - mean x||`` (zeros if ``x`` is constant)."""
    xc = x - x.mean()
    nrm = float(np.sqrt(np.sum(xc * xc)))
    return xc / nrm if nrm > 0.0 else np.zeros_like(x)


def _cone_split(y: NDArray[np.float64], u: NDArray[np.float64]) -> tuple[float, float, float]:
    """``(a, ||w||, b)`` of ``y``: ``a = <u, y>``, ``w = y~ - a u``, ``b = sqrt(N) mean(y)``."""
    yc = y - y.mean()
    a = float(np.sum(u * yc))
    w = yc - a * u
    return a, float(np.sqrt(np.sum(w * w))), float(y.mean() * math.sqrt(y.shape[0]))


def _zoh_ss(ch: _Channel) -> tuple[NDArray[np.float64], ...]:
    """The otolith as a state-space system at ``ch.fs`` by zero-order hold: unlike the
    bilinear one it is not blind near the Nyquist frequency, which matters at ``fs / k``."""
    from scipy.signal import cont2discrete, tf2ss

    num, den = ch.model.transfer_function()
    a, b, c, d = tf2ss(num, den)
    ad, bd, cd, dd, _ = cont2discrete((a, b, c, d), 1.0 / ch.fs, method="zoh")
    return np.asarray(ad), np.asarray(bd), np.asarray(cd), np.asarray(dd)


def _ss_filter(ss: tuple[NDArray[np.float64], ...], x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Run the state-space system ``ss`` on ``x`` from rest."""
    from scipy.signal import dlsim

    a, b, c, d = ss
    return np.asarray(dlsim((a, b, c, d, 1.0), x)[1], dtype=float).ravel()


def _socp_primal(
    ch: _Channel,
    u: NDArray[np.float64],
    phi: float,
    tan_t: float,
    d2: sparray,
    ss: tuple[NDArray[np.float64], ...] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], float]:
    """A motion of ``S`` maximising ``cos(phi) <u, y> + sin(phi) sqrt(N) mean(y)`` (``y = H s``)
    subject to ``||y~ - <u, y> u|| <= tan_t <u, y>`` (the correlation with ``u`` at least
    ``cos(atan(tan_t))``), by IPOPT through CasADi, the cone written as
    ``c^2 (||y||^2 - N ybar^2) <= a^2``, ``a >= 0`` (``tan_t = 0``: ``y = a u + ybar``).

    Returns ``(p, tau, z, mu)``: the translation and tilt term, and the dual direction of the
    cone (unit, centred, orthogonal to ``u``; zeros if the cone is inactive) with its
    multiplier, from which :func:`_share_at_corr` builds its certificate.
    """
    import casadi
    import scipy.sparse as sp

    n = u.shape[0]
    a_m, b_m, c_m, d_m = ch.ss() if ss is None else ss
    nx = a_m.shape[0]
    g = GRAVITY_M_S2
    eye = sp.identity(n, format="csr")
    s_op = sp.hstack([d2, g * eye], format="csr")
    shift = sp.diags([np.ones(n - 1)], [-1], shape=(n, n), format="csr")
    x_next = sp.identity(nx * n) - sp.kron(shift, sp.csr_matrix(a_m))
    # variables [p (n), tau (n), x (nx n), y (n), ybar, a]
    nz = (3 + nx) * n + 2
    iy = (2 + nx) * n
    col = sp.csr_matrix((n, 1))
    row1 = sp.csr_matrix(np.ones((1, n)))
    d1 = sp.diags([-np.ones(n - 1), np.ones(n - 1)], [0, 1], shape=(n - 1, n), format="csr")
    zpad = sp.csr_matrix((n - 1, n))
    rest = sp.csr_matrix((n - 1, n * (1 + nx) + 2))
    blocks = [
        sp.hstack(
            [-sp.kron(shift, sp.csr_matrix(b_m)) @ s_op, x_next, sp.csr_matrix((nx * n, n + 2))]
        ),
        sp.hstack([-float(d_m[0, 0]) * s_op, -sp.kron(eye, sp.csr_matrix(c_m)), eye, col, col]),
        sp.hstack([sp.csr_matrix((1, iy)), row1, sp.csr_matrix([[-float(n), 0.0]])]),
        sp.hstack(
            [sp.csr_matrix((1, iy)), sp.csr_matrix(u[None, :]), sp.csr_matrix([[0.0, -1.0]])]
        ),
    ]
    lo = [np.zeros((nx + 1) * n + 2)]
    # the translation moves only if none of its boxes is zero (else it is held at 0, and
    # its rows dropped: the solver refuses more equalities than free variables)
    moves = ch.stroke > 0.0 and ch.speed > 0.0 and ch.accel > 0.0
    if moves:
        blocks += [
            sp.hstack([d1, zpad, rest]),
            sp.hstack([d2, sp.csr_matrix((n, n * (2 + nx) + 2))]),
        ]
        lo += [np.full(n - 1, -ch.speed / ch.fs), np.full(n, -ch.accel)]
    if ch.tilt > 0.0:
        blocks.append(sp.hstack([zpad, d1, rest]))
        lo.append(np.full(n - 1, -ch.tilt_rate / ch.fs))
    if tan_t == 0.0:  # y = a u + ybar: linear
        blocks.append(sp.hstack([sp.csr_matrix((n, iy)), eye, -sp.csr_matrix(np.ones((n, 1))),
                                 -sp.csr_matrix(u[:, None])]))  # fmt: skip
        lo.append(np.zeros(n))
    lba = np.concatenate(lo)
    uba = -lba
    uba[: (nx + 1) * n + 2] = 0.0
    if tan_t == 0.0:
        uba[-n:] = 0.0
    poly = _poly_rows(ch, n)
    if poly is not None:  # first: the multipliers read below are those of the last rows
        blocks.insert(0, sp.hstack([poly[0], sp.csr_matrix((poly[1].size, n * (1 + nx) + 2))]))
        lba = np.concatenate([np.full(poly[1].size, -np.inf), lba])
        uba = np.concatenate([poly[1], uba])
    lin = sp.vstack(blocks, format="csc")
    nzb = nz  # [p, tau, x, y, ybar, a], then the canal's variables
    rot = _rot_rows(ch, n)
    if rot is not None:  # first: the multipliers read below are those of the last rows
        nq = rot[1].shape[1]
        nz += nq
        lin = sp.vstack(
            [sp.hstack([sp.csr_matrix((nq, n)), rot[0], sp.csr_matrix((nq, nzb - 2 * n)), rot[1]]),
             sp.hstack([lin, sp.csr_matrix((lin.shape[0], nq))])],
            format="csc",
        )  # fmt: skip
        lba = np.concatenate([np.zeros(nq), lba])
        uba = np.concatenate([np.zeros(nq), uba])
    zs = casadi.MX.sym("z", nz)
    y, ybar, a = zs[iy : iy + n], zs[nzb - 2], zs[nzb - 1]
    c2 = 1.0 / (1.0 + tan_t * tan_t)
    cons = [casadi.densify(casadi.mtimes(_dm(lin), zs))]  # D2 has an empty row (the end)
    lbg, ubg = [lba], [uba]
    if tan_t > 0.0:
        cons.append(c2 * (casadi.dot(y, y) - n * ybar * ybar) - a * a)
        lbg.append(np.array([-np.inf]))
        ubg.append(np.array([0.0]))
    obj = -(math.cos(phi) * a + math.sin(phi) * math.sqrt(n) * ybar)
    # A small penalty (<= 0.1 % of the objective's scale) on the translation's acceleration
    # and the tilt rate: at fs / k the Tustin otolith is blind near the Nyquist frequency, so
    # without it the solver leaves motion there that the full-rate rider would feel.
    scale = 1e-3 * math.sqrt(n) * (GRAVITY_M_S2 * ch.tilt + ch.accel)
    if ch.accel > 0.0:
        acc = casadi.mtimes(_dm(d2), zs[:n]) / ch.accel
        obj = obj + scale * casadi.dot(acc, acc) / n
    if ch.tilt_rate > 0.0:
        rate = (zs[n + 1 : 2 * n] - zs[n : 2 * n - 1]) * (ch.fs / ch.tilt_rate)
        obj = obj + scale * casadi.dot(rate, rate) / n
    lbx = np.full(nz, -np.inf)
    ubx = np.full(nz, np.inf)
    lbx[:n], ubx[:n] = (-ch.stroke, ch.stroke) if moves else (0.0, 0.0)
    lbx[n : 2 * n], ubx[n : 2 * n] = -ch.tilt, ch.tilt
    lbx[nzb - 1] = 0.0
    if rot is not None:
        lbx[nz - n :], ubx[nz - n :] = rot[2], rot[3]
    solver = casadi.nlpsol(
        "corr_bound",
        "ipopt",
        {"x": zs, "f": obj, "g": casadi.vertcat(*cons)},
        {
            "ipopt.print_level": 0,
            "ipopt.sb": "yes",
            "print_time": False,
            "ipopt.tol": 1e-9,
            "ipopt.max_iter": 500,
            "error_on_fail": False,
        },
    )
    x0 = np.zeros(nz)
    x0[nzb - 1] = 1e-3
    sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=np.concatenate(lbg), ubg=np.concatenate(ubg))
    zz = np.asarray(sol["x"], dtype=float).ravel()
    lam = np.asarray(sol["lam_g"], dtype=float).ravel()
    if not solver.stats()["success"] or not (np.isfinite(zz).all() and np.isfinite(lam).all()):
        zero = np.zeros(n)  # no motion, no dual direction: the certificates stay valid
        return zero, zero.copy(), zero.copy(), 0.0
    p = np.clip(zz[:n], -ch.stroke, ch.stroke)
    tau = np.clip(zz[n : 2 * n], -ch.tilt, ch.tilt)
    if tan_t > 0.0:
        # grad of the squared cone = 2 a c^2 tan_t (z - tan_t u) on the cone's boundary
        yv = zz[iy : iy + n]
        w = yv - yv.mean() - float(np.sum(u * (yv - yv.mean()))) * u
        nw = float(np.sqrt(np.sum(w * w)))
        mu = 2.0 * float(lam[-1]) * max(float(zz[nzb - 1]), 0.0) * c2 * tan_t
        z = w / nw if nw > 0.0 and mu > 0.0 else np.zeros(n)
    else:
        nu = lam[-n:]
        w = nu - nu.mean() - float(np.sum(u * (nu - nu.mean()))) * u
        mu = float(np.sqrt(np.sum(w * w)))
        z = w / mu if mu > 0.0 else np.zeros(n)
    return p, tau, z, abs(mu)


def _upsample_motion(
    ch: _Channel, p_d: NDArray[np.float64], tau_d: NDArray[np.float64], k: int, n: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """A full-rate motion of ``S`` from one at ``fs / k``: the tilt interpolated linearly, the
    translation interpolated and averaged over ``k`` samples (which spreads each velocity step
    over one decimated period, so its acceleration stays that of the decimated motion), then
    each scaled down until it is within every box at the full rate (checked, not assumed)."""
    centres = (np.arange(p_d.shape[0]) + 0.5) * k - 0.5
    t = np.arange(n, dtype=float)
    tau = np.interp(t, centres, tau_d)
    p = np.interp(t, centres, p_d)
    if k > 1:
        pad = np.concatenate([np.full(k, p[0]), p, np.full(k, p[-1])])
        p = np.convolve(pad, np.ones(k) / k, mode="same")[k:-k]
    d2p = np.concatenate([[p[1] - p[0]], p[2:] - 2 * p[1:-1] + p[:-2], [0.0]])  # as D2
    fs = ch.fs

    def fit(x: NDArray[np.float64], *pairs: tuple[float, float]) -> NDArray[np.float64]:
        ratio = max([1.0, *(m / lim if lim > 0.0 else (math.inf if m > 0.0 else 1.0)
                            for m, lim in pairs)])  # fmt: skip
        return x / ratio if math.isfinite(ratio) else np.zeros_like(x)

    p = fit(p, (float(np.abs(p).max()), ch.stroke),
            (float(np.abs(np.diff(p)).max()) * fs, ch.speed),
            (float(np.abs(d2p).max()) * fs * fs, ch.accel))  # fmt: skip
    tau = fit(tau, (float(np.abs(tau).max()), ch.tilt),
              (float(np.abs(np.diff(tau)).max()) * fs, ch.tilt_rate))  # fmt: skip
    return _fit_poly(ch, p, tau)


def _fit_poly(
    ch: _Channel, p: NDArray[np.float64], tau: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(p, tau)`` scaled down together until within the coupled reach's half-planes and
    the no-false-rotation rows (the neutral pose is inside both, so scaling down keeps the
    boxes)."""
    ratio = 1.0
    if ch.poly is not None:
        poly = _poly_rows(ch, p.shape[0])
        assert poly is not None
        lhs = np.asarray(poly[0] @ np.concatenate([p, tau]))
        ratio = max(ratio, float(np.max(lhs / poly[1])) if lhs.size else 1.0)
    if ch.rot is not None:
        r = ch.rot.perceived(tau, ch.fs)
        lo, hi = ch.rot.bounds(ch.fs)
        ratio = max(ratio, float(np.max(np.maximum(r / hi, r / lo))))  # lo < 0 < hi
    return p / ratio, tau / ratio


def _polygon_max(cuts: list[tuple[float, float]], c: float) -> tuple[float, float, float]:
    """``max a^2 / c^2 + b^2`` over ``{(a, b): a >= 0, cos(phi) a + sin(phi) b <= h}`` for the
    cuts ``(phi, h)`` (which must bound it): ``(value, a, b)`` at the best vertex."""
    lines = [(-1.0, 0.0, 0.0)] + [(math.cos(f), math.sin(f), h) for f, h in cuts]
    best = (0.0, 0.0, 0.0)
    for i in range(len(lines)):
        for j in range(i + 1, len(lines)):
            (a1, b1, h1), (a2, b2, h2) = lines[i], lines[j]
            det = a1 * b2 - a2 * b1
            if abs(det) < 1e-12:
                continue
            a = (h1 * b2 - h2 * b1) / det
            b = (a1 * h2 - a2 * h1) / det
            tol = 1e-9 * (1.0 + abs(a) + abs(b))
            if all(la * a + lb * b <= lh + tol for la, lb, lh in lines):
                val = a * a / (c * c) + b * b
                if val > best[0]:
                    best = (val, a, b)
    return best


def _share_at_corr(
    ch: _Channel, d: NDArray[np.float64], corr: float, k: int, d2: sparray, cuts: int = 2
) -> tuple[float, float, float, float]:
    """``(share bound, share of the best motion found, its correlation, share bound at zero
    perceived mean)`` of one channel at
    correlation ``>= corr`` (module docstring; ``k`` > 1: primals and dual directions from the
    problem decimated by ``k``, certificates at the full rate)."""
    n = d.shape[0]
    v = ch.filt(d)
    vv = float(np.sum(v * v))
    u = _centred_unit(v)
    if vv <= 0.0 or not np.any(u):
        return math.nan, math.nan, math.nan, math.nan
    if ch.tilt <= 0.0 and not (ch.stroke > 0.0 and ch.speed > 0.0 and ch.accel > 0.0):
        return 0.0, 0.0, math.nan, 0.0  # a rig at rest: S = {0}
    tan_t = math.sqrt(max(1.0 - corr * corr, 0.0)) / corr
    chd, dd, d2d = _decimated(ch, d, k) if k > 1 else (ch, d, d2)
    ss_d = _zoh_ss(chd) if k > 1 else None
    ud = _centred_unit(chd.filt(dd) if ss_d is None else _ss_filter(ss_d, dd))
    nd = ud.shape[0]
    e1 = np.full(n, 1.0 / math.sqrt(n))
    centres = (np.arange(nd) + 0.5) * k - 0.5
    # the part of u that fs / k cannot represent (centred, orthogonal to u's own LF part)
    u_lf = np.interp(np.arange(n), centres, u[: nd * k].reshape(nd, k).mean(axis=1))
    u_hf = u - u_lf
    u_hf = u_hf - u_hf.mean() - float(np.sum(u * (u_hf - u_hf.mean()))) * u

    def certificate(g: NDArray[np.float64], z: NDArray[np.float64], mu: float) -> float:
        return _support(ch, ch.filt_t(g + mu * tan_t * u - mu * z), d2)

    # b = sqrt(N) mean(y) over all of S: the cuts phi = +-pi/2 (S is symmetric unless the
    # no-false-rotation rows, which depend on the vehicle's sign, are in it)
    b_max = _support(ch, ch.filt_t(e1), d2)
    b_min = b_max if ch.rot is None else _support(ch, -ch.filt_t(e1), d2)
    found: list[tuple[float, float]] = []  # (share, corr) of the full-rate primals

    def direction(phi: float) -> float:
        # the primal is solved a little inside the cone (the solver's tolerance; at fs / k the
        # full-rate correlation differs): if the full-rate motion is outside, once more
        # further inside
        tan_p = tan_t * (1.0 - 1e-5 if k == 1 else 0.97)
        p_d, tau_d, z_d, mu0 = _socp_primal(chd, ud, phi, tan_p, d2d, ss_d)
        for attempt in range(3):
            if attempt > 0:
                p_d, tau_d, _, _ = _socp_primal(chd, ud, phi, tan_p, d2d, ss_d)
            p, tau = _upsample_motion(ch, p_d, tau_d, k, n) if k > 1 else _fit_poly(ch, p_d, tau_d)
            y = ch.filt(np.asarray(d2 @ p) + GRAVITY_M_S2 * tau)
            a, w, _ = _cone_split(y, u)
            # (at correlation 1: up to the solver's tolerance)
            tol = 1e-9 * a if tan_t > 0.0 else 1e-7 * float(np.sqrt(np.sum(y * y)))
            if a >= 0.0 and w <= tan_t * a + tol:
                found.append((math.sqrt(float(np.sum(y * y)) / vv), correlation(y, v)))
                break
            if a <= 0.0 or tan_t == 0.0:
                break
            tan_p *= 0.98 * tan_t * a / w
        g = math.cos(phi) * u + math.sin(phi) * e1
        if k == 1 or mu0 <= 0.0 or not np.any(z_d):
            # mu: the decimated problem's multiplier (its dual optimum); any mu >= 0 is valid
            return certificate(g, z_d if k == 1 else np.zeros(n), mu0 if np.any(z_d) else 0.0)
        z = np.interp(np.arange(n), centres, z_d)
        z = z - z.mean() - float(np.sum(u * (z - z.mean()))) * u
        nz = float(np.sqrt(np.sum(z * z)))
        if nz <= 0.0:
            return certificate(g, z, 0.0)
        z = z / nz
        # What fs / k cannot see: at the full-rate optimum the direction's part there vanishes
        # where no box binds, i.e. z_hf = (1 + mu tan) / mu u_hf. Where boxes bind it does
        # not, so both z are tried (each gives a valid bound).
        z_hf = ((1.0 + mu0 * tan_t) / mu0) * u_hf
        n_hf = float(np.sqrt(np.sum(z_hf * z_hf)))
        z_aug = z_hf + math.sqrt(1.0 - n_hf * n_hf) * z if n_hf < 1.0 else z_hf
        n_aug = float(np.sqrt(np.sum(z_aug * z_aug)))
        if n_aug <= 0.0:
            return certificate(g, z, mu0)
        # ||z|| <= 1 is what makes it a bound (z_hf and z need not be orthogonal)
        return min(certificate(g, z, mu0), certificate(g, z_aug / n_aug, mu0))

    planes = [(0.0, direction(0.0)), (math.pi / 2, b_max), (-math.pi / 2, b_min)]
    for _ in range(max(cuts, 0)):
        # a cut through the polygon's best vertex, normal to the share's level set there
        val, a, b = _polygon_max(planes, corr)
        if found and math.sqrt(val / vv) <= max(found)[0] * (1.0 + 1e-5):
            break  # the bound is attained
        phi = math.atan2(b, a / (corr * corr))
        if any(abs(phi - f) < 1e-4 for f, _ in planes):
            break
        planes.append((phi, direction(phi)))
    bound = math.sqrt(_polygon_max(planes, corr)[0] / vv)
    share, c_found = max(found) if found else (math.nan, math.nan)
    # motions whose perceived mean is zero: b = 0, a <= h(0)
    zero_mean = planes[0][1] / corr / math.sqrt(vv)
    return bound, share, c_found, min(zero_mean, bound)


def cue_bound(
    f_vehicle: ArrayLike,
    fs_hz: float,
    reach: RigReach,
    *,
    model: str | VestibularModelSet = DEFAULT_MODEL_SET,
    thresholds: ArrayLike | None = None,
    primal_samples: int = 1000,
    corr_min: ArrayLike | None = CORR_MIN,
    corr_cuts: int = 2,
    w_vehicle: ArrayLike | None = None,
    forbid_false_rotation: bool = False,
    rotation_rule: str = "spurious",
) -> CueBound:
    """The physical bound of a drive on a rig (definitions: the module docstring).

    Parameters
    ----------
    f_vehicle : (N, 3) array_like
        The vehicle's specific force (m/s^2, body frame, rest ``[0, 0, g]``) as the cueing
        algorithm used it (``f_used``), uniform at ``fs_hz``.
    fs_hz : float
    reach : RigReach
        The rig's reach (:func:`motioncue.analysis.rig_reach`).
    model : str or VestibularModelSet
        Vestibular model set (its otoliths and thresholds).
    thresholds : (6,) array_like, optional
        Perception thresholds (default the set's); fx and fy are used.
    primal_samples : int
        Longest problem solved at the full rate. A longer drive's QP and no-reversal LP are
        solved at ``fs / k`` (``k = ceil(N / primal_samples)``) only to find the certificate
        (the residual ``z``, the LP's multipliers ``lambda``), which is then evaluated and
        scaled at the full rate: ``-||b z||^2 - 2 b z'v - 2 sigma_S(-b H'z)``, maximised over
        the scalar ``b``, is a lower bound for every ``b``, and
        ``sigma_S(H'(v - a lambda sign)) + thr sum(a lambda)`` an upper bound on the gain for
        every ``a >= 0`` (Lagrangian weak duality). The figures stay valid bounds; they are
        only less tight than the full-rate optimum. The same holds for ``share_max_at_corr``
        (its primals, cone multipliers and dual directions at ``fs / k``).
    corr_min : (2,) array_like or None
        The correlation (fx, fy; each in (0, 1]) of ``share_max_at_corr``; None: not computed
        (NaN), which saves about half of the time.
    corr_cuts : int
        Cuts added to the first three (module docstring) while the bound is above the best
        motion found: each costs one SOCP at ``fs / k`` and one support function at the full
        rate, and tightens the bound.
    w_vehicle : (N, 3) array_like, optional
        The vehicle's angular velocity (rad/s, body frame: roll, pitch, yaw rates) as the
        cueing algorithm used it (``w_used``); needed by ``forbid_false_rotation``.
    forbid_false_rotation : bool
        Bound the smaller set of the motions that give no spurious and no reversed rotation
        cue on each channel's tilt axis (pitch for fx, roll for fy; module docstring, "No
        false rotation cue"). Every figure of the result is then over that set
        (``CueBound.rotation_cues == "forbidden"``); the programmes grow by the canal's
        sections (about twice the time).
    rotation_rule : {"spurious", "false"}
        With ``forbid_false_rotation``: ``"spurious"`` (default) forbids spurious and
        reversed rotation cues, as above; ``"false"`` forbids only *false* ones, the platform
        beyond the threshold with the sign opposite to the vehicle's whatever the vehicle's
        size (the ``false`` of :func:`motioncue.cueing.cue_metrics`, issue 20's "all false
        cues"): a larger set, so a looser bound, over the motions that are within that
        figure's budget with no false rotation cue at all
        (``CueBound.rotation_cues == "no-false"``).

    Returns
    -------
    CueBound

    Notes
    -----
    Cost: per channel one QP (OSQP) and one LP (HiGHS) of at most ``primal_samples``
    samples, then about a dozen support LPs at the full rate (about 2 s each for 3 minutes at
    100 Hz).
    """
    ms = get_model_set(model)
    f = np.asarray(f_vehicle, dtype=float)
    if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] < 4 or not np.isfinite(f).all():
        raise ConfigError(f"f_vehicle must be a finite (N >= 4, 3) array; got {f.shape}")
    if not (math.isfinite(fs_hz) and fs_hz > 0.0):
        raise ConfigError(f"sample rate {fs_hz!r} Hz is invalid; allowed: a finite number > 0")
    if primal_samples < 4:
        raise ConfigError(f"primal_samples {primal_samples!r} is invalid; allowed: >= 4")
    thr = np.asarray(ms.thresholds if thresholds is None else thresholds, dtype=float)
    if thr.shape != (6,) or not np.all(np.isfinite(thr)) or np.any(thr <= 0.0):
        raise ConfigError(f"thresholds {thr.tolist()!r} are invalid; allowed: 6 numbers > 0")
    cmin = np.full(2, np.nan)
    if corr_min is not None:
        cmin = np.asarray(corr_min, dtype=float).reshape(-1)
        if cmin.shape != (2,) or not np.all((cmin > 0.0) & (cmin <= 1.0)):
            raise ConfigError(
                f"corr_min {np.asarray(corr_min).tolist()!r} is invalid; allowed: two "
                "correlations in (0, 1] (fx, fy)"
            )
    if rotation_rule not in ("spurious", "false"):
        raise ConfigError(
            f"rotation_rule {rotation_rule!r} is invalid; allowed: 'spurious', 'false'"
        )
    n = f.shape[0]
    w = None
    if forbid_false_rotation:
        if w_vehicle is None:
            raise ConfigError(
                "forbid_false_rotation needs w_vehicle (the vehicle's angular velocity)"
            )
        w = np.asarray(w_vehicle, dtype=float)
        if w.shape != f.shape or not np.isfinite(w).all():
            raise ConfigError(
                f"w_vehicle must be a finite array shaped like f_vehicle {f.shape}; got {w.shape}"
            )
    d2 = _second_difference(n, fs_hz)
    _ROT_FALLBACKS[0] = 0
    at_corr: list[tuple[float, float, float, float]] = []
    k = max(1, math.ceil(n / primal_samples))
    res: dict[str, list[float]] = {key: [] for key in ("err", "gmax", "gany", "share", "vrms")}
    for i in range(2):
        ch = _Channel(
            stroke=reach.stroke_m[i],
            speed=reach.speed_m_s[i],
            accel=reach.accel_m_s2[i],
            tilt=math.sin(reach.tilt_rad[i]),
            tilt_rate=reach.tilt_rate_rad_s[i],
            fs=float(fs_hz),
            model=ms.otolith[i],
            poly=None if reach.coupling is None else reach.coupling[i],
            rot=None
            if w is None
            else _Rotation(
                canal=ms.canal[_TILT_AXIS[i]],
                sign=_TILT_SIGN[i],
                omega=np.ascontiguousarray(w[:, _TILT_AXIS[i]]),
                thr=float(thr[3 + _TILT_AXIS[i]]),
                rule=rotation_rule,
            ),
        )
        for key, val in zip(
            ("err", "gmax", "gany", "share", "vrms"),
            _channel_bound(ch, f[:, i], float(thr[i]), k, d2),
            strict=True,
        ):
            res[key].append(val)
        if corr_min is not None:
            at_corr.append(_share_at_corr(ch, f[:, i], float(cmin[i]), k, d2, corr_cuts))
        else:
            at_corr.append((math.nan, math.nan, math.nan, math.nan))
    return CueBound(
        error_rms=np.array(res["err"]),
        gain_max=np.array(res["gmax"]),
        gain_max_any=np.array(res["gany"]),
        share_at_gain_max=np.array(res["share"]),
        vehicle_rms=np.array(res["vrms"]),
        reach=reach,
        share_max_at_corr=np.array([x[0] for x in at_corr]),
        share_at_corr_primal=np.array([x[1] for x in at_corr]),
        corr_at_primal=np.array([x[2] for x in at_corr]),
        share_max_at_corr_zero_mean=np.array([x[3] for x in at_corr]),
        corr_min=cmin,
        fs_hz=float(fs_hz),
        model_set=ms.name,
        solver={
            "qp": "osqp (casadi)",
            "lp": "highs (scipy)",
            "socp": "ipopt (casadi)",
            "decimation": str(k),
            "coupling": "none" if reach.coupling is None else "translation-tilt polygons",
            "rotation_fallbacks": str(_ROT_FALLBACKS[0]),
        },
        rotation_cues="allowed"
        if w is None
        else ("forbidden" if rotation_rule == "spurious" else "no-false"),
    )
