"""Automatic tuning of a cueing preset: the strongest cue within cue-quality targets.

What is tuned
-------------
What the preset's algorithm declares tunable (its registry entry's
:class:`~motioncue.cueing.TunePlan`; the bundled plans: :mod:`motioncue.cueing._tune`), each
parameter within fixed bounds, searched in log space. Everything else is kept from the base
preset. :func:`motioncue.cueing._tune.tuned_parameters` gives the table of a preset.

The objective and the limits
----------------------------
Each candidate runs the offline chain (:mod:`motioncue.pipeline._chain`, its workspace
stage) on every recording (resampled once, up front): the cueing run, workspace limiting
(:func:`motioncue.trajectory.limit_pose` with the
pulse-rounding-tightened limits of the platform and controller) and the evaluation of the
*delivered* poses through the vestibular models: the mean over the recordings of the cue
score (:func:`motioncue.cueing.cue_score`: the perceived-motion error ``J`` relative to a
platform that stands still, plus the lost correlation, the false-cue and the missed-cue
fractions; its module says why ``J`` alone does not work on car drives) with
``objective="score"``; with ``objective="strength"`` (the default of ``motioncue tune``) the
geometric mean of the rendered shares of fx and fy of the recordings pooled
(:func:`motioncue.cueing.cue_metrics`), to be maximised subject to :class:`StrengthTargets`
(reversals, false cues, correlation, clamping): the cue score can be won by barely moving
(correlation is blind to scale, false cues and clamping fall as the motion shrinks), the
strength cannot. ``J`` itself is reported before and after. The full casadi ride
optimisation is not run.

The platform's limits are a **penalty** (Deb's feasibility rule folded into one number): a
candidate is feasible when its actuator positions after workspace limiting break no limit
(stroke, speed, acceleration, and jerk where the limits have one, with the discrete
definitions of :mod:`motioncue.trajectory._limits`) on any frame, and at most
:data:`MAX_CLAMPED_FRACTION` (1 %) of its poses were clamped by workspace limiting.
A feasible candidate scores its cue score; an infeasible one scores
``PENALTY_BASE * (1 + excess)``, above every feasible candidate, ranked by how far it is
from feasible (``excess`` = fraction of frames breaking a limit plus the clamped fraction
above 1 %). The result must be feasible, or nothing is written.

The optimiser
-------------
:func:`scipy.optimize.differential_evolution` (SciPy, maintained, already a dependency),
chosen over CMA-ES (the ``cma`` package) because it is bounded natively (no repair or
penalty for the box), is seeded and deterministic, evaluates a whole generation at once
(``updating="deferred"``) through a map-like ``workers`` callable, so the same code runs
the evaluations in-process, in a local process pool or on a Dask cluster, and it accepts the
base preset as a member of the first population (``x0``), so the result is never worse than
the base when the base is feasible. Polishing (a serial L-BFGS-B on a noisy, clamped
objective) is off.

Reproducibility: for a seed and a number of generations the candidates and their scores are
the same wherever they are evaluated (the map returns the results in order); a run stopped
by the wall-time budget depends on the machine's speed, so give ``generations`` for a
bit-identical reproduction.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable, Mapping, Sequence, Sized
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._errors import ConfigError, LimitError, TransportError
from ..cueing import CueingParams, make_cueing
from ..cueing._evaluate import simulator_motion
from ..cueing._metrics import CueMetrics, cue_metrics
from ..cueing._params import GRAVITY_M_S2
from ..cueing._score import cue_score
from ..cueing._tune import params_from_vector, tuned_parameters, vector_from_params
from ..cueing._vestibular import DEFAULT_MODEL_SET, get_model_set, normalised_error_rms
from ..pipeline._chain import deliver, run_cueing
from ..trajectory import reachable

if TYPE_CHECKING:
    from concurrent.futures import ProcessPoolExecutor
    from multiprocessing.context import BaseContext

    from scipy.optimize import OptimizeResult

    from ..cueing import Rig
    from ..kinematics import Platform
    from ..trajectory import ActuatorLimits

__all__ = [
    "MAX_CLAMPED_FRACTION",
    "OBJECTIVES",
    "PENALTY_BASE",
    "ChainMetrics",
    "StrengthTargets",
    "TuneObjective",
    "TuneResult",
    "chain_metrics",
    "tilt_reach",
    "tune_cueing",
    "write_preset",
]

OBJECTIVES: tuple[str, ...] = ("strength", "score")
"""The tuning objectives: ``"strength"`` (the largest rendered share within the cue-quality
targets, :class:`StrengthTargets`) and ``"score"`` (the cue score, lower is better)."""

MAX_CLAMPED_FRACTION = 0.01
"""Largest fraction of the poses workspace limiting may clamp in a feasible candidate."""

PENALTY_BASE = 1.0e6
"""Score of an infeasible candidate at zero excess (above any feasible ``J``)."""

_D2R = math.pi / 180.0


def tilt_reach(
    platform: Platform, limits: ActuatorLimits | None = None
) -> tuple[float, float, float, float]:
    """The platform's reach in pure tilt about neutral: ``(roll-, roll+, pitch-, pitch+)``.

    The largest angle (rad, magnitude, to 0.01 deg) such that every pure roll (or pitch) pose
    from neutral up to it in that direction is reachable
    (:func:`motioncue.trajectory.reachable`: inside the workspace and, with ``limits``, the
    stroke those limits allow). A direction the platform cannot tilt at all gives 0.01 deg
    (the least a preset accepts).

    Parameters
    ----------
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits, optional

    Returns
    -------
    tuple of 4 floats
    """
    angles = np.radians(np.arange(1, 6001) * 0.01)  # 0.01 .. 60 deg
    out = []
    for axis in (3, 4):
        for sign in (-1.0, 1.0):
            poses = np.zeros((angles.size, 6))
            poses[:, axis] = sign * angles
            ok = np.asarray(reachable(platform, poses, limits=limits), dtype=bool)
            first_bad = int(np.argmin(ok)) if not ok.all() else angles.size
            out.append(float(angles[max(first_bad - 1, 0)]))
    return (out[0], out[1], out[2], out[3])


def _log_bounds(params: CueingParams) -> list[tuple[float, float]]:
    return [(math.log(p.lo), math.log(p.hi)) for p in tuned_parameters(params)]


@dataclass(frozen=True)
class _Drive:
    """One recording, resampled: vehicle specific force and angular velocity (N, 3)."""

    label: str
    f: NDArray[np.float64]
    w: NDArray[np.float64]


@dataclass(frozen=True, eq=False)
class ChainMetrics:
    """What the cheap chain delivers on the recordings for one parameter set.

    Attributes
    ----------
    objective : float
        Mean cue score over the recordings (:func:`motioncue.cueing.cue_score`; lower is
        better): the tuning objective.
    per_drive_objective : tuple of float
    perceived_error : float
        Mean perceived-motion error ``J`` over the recordings (thresholds).
    correlation : (6,) array
        Mean over the recordings of the per-axis correlation (fx fy fz wx wy wz; a constant
        signal counts as 0).
    false_cue_time_s : (6,) array
        Total false-cue time per axis over the recordings (s).
    false_cue_fraction : float
        Fraction of all samples with a false cue on any axis.
    missed_cue_fraction : float
        Mean over the recordings of the score's missed-cue fraction.
    duration_s : float
        Total duration of the recordings (s).
    clamped_fraction : float
        Fraction of all poses clamped by workspace limiting.
    violating_frames : int
        Frames whose actuator positions break a limit (stroke, speed, acceleration, jerk).
    cue : CueMetrics or None
        Rendered share, gain, missed, reversed, spurious and false cues and the clamped
        share, pooled over the recordings (their samples concatenated;
        :func:`motioncue.cueing.cue_metrics`); None when the run stopped early.
    strength : float
        ``sqrt(rendered share fx * rendered share fy)`` of ``cue`` (the geometric mean:
        both count, neither can be dropped): the ``"strength"`` objective (higher is better;
        0 for a platform at rest).
    """

    objective: float
    per_drive_objective: tuple[float, ...]
    perceived_error: float = math.nan
    correlation: NDArray[np.float64] = field(default_factory=lambda: np.full(6, math.nan))
    false_cue_time_s: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    false_cue_fraction: float = 0.0
    missed_cue_fraction: float = 0.0
    duration_s: float = 0.0
    clamped_fraction: float = 0.0
    violating_frames: int = 0
    cue: CueMetrics | None = None
    strength: float = 0.0

    @property
    def feasible(self) -> bool:
        """Zero violating frames and at most 1 % of the poses clamped."""
        return self.violating_frames == 0 and self.clamped_fraction <= MAX_CLAMPED_FRACTION


@dataclass(frozen=True)
class StrengthTargets:
    """The cue-quality constraints of the ``"strength"`` objective (fractions, not %).

    A candidate within the actuator limits meets them when, over the recordings pooled
    (:attr:`ChainMetrics.cue`, the definitions of :func:`motioncue.cueing.cue_metrics`),
    reversals on any channel take at most ``max_reversals`` of the time, false cues on any
    channel at most ``max_false``, the fx and fy correlations are at least ``min_corr_fx``
    and ``min_corr_fy``, and at most ``max_clamped`` of all poses are clamped. The defaults
    are issue 20's acceptance figures; a tune meant to hold on other drives should ask for a
    margin.

    ``max_share = (s_x, s_y)`` (optional) also caps the pooled rendered share of fx and of fy
    (each channel on its own): the gentle end of an intensity range (``motioncue tune
    --gentle-end``) must be gentler than the strong end in every channel, not only overall,
    or the rides between the two would not grow stronger channel by channel. Its excess
    counts relative to the cap, like the others.
    """

    max_reversals: float = 0.02
    max_false: float = 0.15
    max_clamped: float = 0.01
    min_corr_fx: float = 0.95
    min_corr_fy: float = 0.90
    max_share: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        for name in ("max_reversals", "max_false", "max_clamped"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 < v <= 1.0):
                raise ConfigError(f"{name} = {v!r} is invalid; allowed: (0, 1]")
        for name in ("min_corr_fx", "min_corr_fy"):
            v = getattr(self, name)
            if not (math.isfinite(v) and -1.0 <= v < 1.0):
                raise ConfigError(f"{name} = {v!r} is invalid; allowed: [-1, 1)")
        if self.max_share is not None and (
            len(self.max_share) != 2
            or not all(math.isfinite(v) and 0.0 < v <= 10.0 for v in self.max_share)
        ):
            raise ConfigError(
                f"max_share = {self.max_share!r} is invalid; allowed: two shares (fx, fy) "
                "in (0, 10]"
            )

    def violation(self, m: ChainMetrics) -> float:
        """Sum of the relative excesses over the targets (0: all met; inf without
        :attr:`ChainMetrics.cue`)."""
        c = m.cue
        if c is None:
            return math.inf

        def over(value: float, bound: float, scale: float) -> float:
            if not math.isfinite(value):
                return 1.0
            return max(0.0, value - bound) / scale

        corr = np.nan_to_num(c.correlation, nan=0.0)
        total = (
            over(c.reversals_any, self.max_reversals, self.max_reversals)
            + over(c.false_any, self.max_false, self.max_false)
            + over(m.clamped_fraction, self.max_clamped, self.max_clamped)
            + over(self.min_corr_fx, float(corr[0]), 1.0 - self.min_corr_fx)
            + over(self.min_corr_fy, float(corr[1]), 1.0 - self.min_corr_fy)
        )
        if self.max_share is not None:
            for i, cap in enumerate(self.max_share):
                total += over(float(c.rendered_share[i]), cap, cap)
        return total


def _violating_frames(q: NDArray[np.float64], dt_s: float, limits: ActuatorLimits) -> int:
    """Frames (of the cue, starting at rest at its first pose) breaking a limit."""
    tol = 1e-9
    bad = np.any((q < limits.q_min - tol) | (q > limits.q_max + tol), axis=1)
    hist = np.concatenate([q[:1], q[:1], q[:1], q], axis=0)  # at rest before the first frame
    v = np.diff(hist, axis=0)[2:] / dt_s
    a = (hist[3:] - 2.0 * hist[2:-1] + hist[1:-2]) / dt_s**2
    bad |= np.any(np.abs(v) > limits.v_max * (1.0 + tol), axis=1)
    bad |= np.any(np.abs(a) > limits.a_max * (1.0 + tol), axis=1)
    if limits.j_max is not None:
        j = (hist[3:] - 3.0 * hist[2:-1] + 3.0 * hist[1:-2] - hist[:-3]) / dt_s**3
        bad |= np.any(np.abs(j) > limits.j_max * (1.0 + tol), axis=1)
    return int(np.count_nonzero(bad))


class TuneObjective:
    """The tuning objective: picklable (sent once to each process or Dask worker).

    Parameters
    ----------
    base : CueingParams
        Preset whose other parameters are kept.
    drives : sequence of (label, f, w)
        Recordings resampled to ``rate_hz``: specific force (N, 3) m/s^2, angular velocity
        (N, 3) rad/s.
    platform
        A :class:`motioncue.kinematics.Platform`.
    limits : motioncue.trajectory.ActuatorLimits
        The limits of the chain (pulse-rounding tightened, as ``generate`` uses them).
    rate_hz : float
    model : str
        Vestibular model set.
    objective : str
        ``"score"`` (default): minimise the mean cue score. ``"strength"``: maximise
        :attr:`ChainMetrics.strength` subject to ``targets`` (Deb's feasibility rule folded
        into one number, lower is better: ``-strength`` for a candidate meeting every
        target, ``1 + violation`` for one that does not, the limit penalty above both).
        Standing still scores 0, so it can no longer win.
    targets : StrengthTargets, optional
        Constraints of the ``"strength"`` objective (default: issue 20's acceptance).
    rig : Rig, optional
        The platform with its limits as given (not tightened), for an algorithm that plans
        in actuator space (:func:`motioncue.cueing.make_cueing`); ``motioncue tune`` gives it.
    """

    def __init__(
        self,
        base: CueingParams,
        drives: Sequence[tuple[str, NDArray[np.float64], NDArray[np.float64]]],
        platform: Platform,
        limits: ActuatorLimits,
        rate_hz: float,
        model: str = DEFAULT_MODEL_SET,
        objective: str = "score",
        targets: StrengthTargets | None = None,
        rig: Rig | None = None,
    ) -> None:
        get_model_set(model)
        if objective not in OBJECTIVES:
            raise ConfigError(f"objective {objective!r} is invalid; allowed: {OBJECTIVES}")
        self.objective = objective
        self.targets = targets if targets is not None else StrengthTargets()
        if not drives:
            raise ConfigError("tuning needs at least one recording")
        self.base = base
        self.drives = tuple(
            _Drive(lbl, np.ascontiguousarray(f, float), np.ascontiguousarray(w, float))
            for lbl, f, w in drives
        )
        self.platform = platform
        self.limits = limits
        self.rig = rig
        self.rate_hz = float(rate_hz)
        self.model = model
        self._models = get_model_set(model)
        self._pv_cache: dict[int, tuple[NDArray[np.float64], ...]] = {}

    def _perceived_vehicle(
        self, i: int, f: NDArray[np.float64], w: NDArray[np.float64]
    ) -> NDArray[np.float64]:
        """The vehicle's perceived motion on drive ``i`` (cached: it does not depend on the
        tuned parameters, only on the input the algorithm used)."""
        cached = self._pv_cache.get(i)
        if cached is not None and np.array_equal(cached[0], f) and np.array_equal(cached[1], w):
            return cached[2]
        rest = np.array([0.0, 0.0, GRAVITY_M_S2])
        pv = self._models.filter(np.concatenate([f - rest, w], axis=1), self.rate_hz)
        self._pv_cache[i] = (np.array(f), np.array(w), pv)
        return pv

    def metrics(self, params: CueingParams, *, full: bool = False) -> ChainMetrics:
        """Run the cheap chain with ``params`` on every recording.

        ``full``: compute every metric even for a candidate that is infeasible by its
        clamped poses alone; without it, such a candidate returns at once with an infinite
        objective and its clamped fraction (the penalty ranks it by that).
        """
        design = make_cueing(params, self.rate_hz, self.rig)
        runs = [run_cueing(design, d.f, d.w) for d in self.drives]
        if not full:
            # a candidate whose cue leaves the workspace too often is infeasible whatever the
            # rest: skip workspace limiting (slow on clamped poses) and the evaluation
            n_req = sum(int(r.poses.shape[0]) for r in runs)
            n_out = sum(
                int(np.count_nonzero(~reachable(self.platform, r.poses, limits=self.limits)))
                for r in runs
            )
            if n_out > MAX_CLAMPED_FRACTION * n_req:
                return ChainMetrics(
                    objective=math.inf,
                    per_drive_objective=(),
                    duration_s=n_req / self.rate_hz,
                    clamped_fraction=n_out / max(n_req, 1),
                )
        dt = 1.0 / self.rate_hz
        thr = self._models.thresholds
        ones = np.ones(6)
        scores: list[float] = []
        js: list[float] = []
        corr = np.zeros(6)
        false_s = np.zeros(6)
        false_any = 0
        missed = 0.0
        pvs: list[NDArray[np.float64]] = []
        pss: list[NDArray[np.float64]] = []
        n_all = clamped = violating = 0
        rest = np.array([0.0, 0.0, GRAVITY_M_S2])
        for i, cued in enumerate(runs):
            out = deliver(
                self.platform, cued.poses, self.limits, self.rate_hz, actuator_limits=False
            )
            poses = out.poses
            clamped += out.clamped
            n_all += poses.shape[0]
            violating += _violating_frames(out.q, dt, self.limits)
            pv = self._perceived_vehicle(i, cued.f_used, cued.w_used)
            f_s, w_s = simulator_motion(poses, self.rate_hz, head_offset_m=params.head_offset_m)
            ps = self._models.filter(np.concatenate([f_s - rest, w_s], axis=1), self.rate_hz)
            sc = cue_score(pv, ps, thr)
            scores.append(sc.score)
            js.append(normalised_error_rms(ps - pv, thr, ones))
            corr += np.nan_to_num(sc.correlation, nan=0.0)
            wrong = (np.abs(ps) > thr) & (ps * pv < 0.0)
            false_s += wrong.sum(axis=0) / self.rate_hz
            false_any += int(np.count_nonzero(wrong.any(axis=1)))
            missed += sc.missed_fraction
            pvs.append(pv)
            pss.append(ps)
        nd = len(self.drives)
        pooled = cue_metrics(
            np.concatenate(pvs), np.concatenate(pss), thr, clamped_share=clamped / max(n_all, 1)
        )
        share = np.nan_to_num(pooled.rendered_share, nan=0.0)
        return ChainMetrics(
            objective=float(np.mean(scores)),
            per_drive_objective=tuple(scores),
            perceived_error=float(np.mean(js)),
            correlation=corr / nd,
            false_cue_time_s=false_s,
            false_cue_fraction=false_any / max(n_all, 1),
            missed_cue_fraction=missed / nd,
            duration_s=n_all / self.rate_hz,
            clamped_fraction=clamped / max(n_all, 1),
            violating_frames=violating,
            cue=pooled,
            strength=float(math.sqrt(max(share[0], 0.0) * max(share[1], 0.0))),
        )

    def score(self, m: ChainMetrics) -> float:
        """The penalised objective of a run (see the module docstring)."""
        if m.feasible and not math.isfinite(m.objective):
            return PENALTY_BASE * 1e6
        if m.feasible and self.objective == "strength":
            v = self.targets.violation(m)
            return 1.0 + v if v > 0.0 else -m.strength
        if m.feasible:
            return m.objective
        n = max(m.duration_s * self.rate_hz, 1.0)
        excess = m.violating_frames / n + max(0.0, m.clamped_fraction - MAX_CLAMPED_FRACTION)
        return PENALTY_BASE * (1.0 + excess)

    def __call__(self, x: NDArray[np.float64]) -> float:
        """Penalised objective of a point ``x`` of the search space (log values)."""
        try:
            params = params_from_vector(self.base, np.asarray(x, dtype=float).tolist())
            return self.score(self.metrics(params))
        except ConfigError:
            return PENALTY_BASE * 1e6


# --------------------------------------------------------------------- evaluation back ends
_INSTALLED: list[TuneObjective] = []


def _install(objective: TuneObjective) -> None:
    _INSTALLED[:] = [objective]


def _score_installed(x: NDArray[np.float64]) -> float:
    return _INSTALLED[0](x)


def _score_with(objective: TuneObjective, x: NDArray[np.float64]) -> float:
    return objective(x)


_POOL_PRELOAD = ("motioncue.analysis._tune", "scipy.signal")
"""What a pool process needs to evaluate the objective (the chain; the vestibular models and
the washout filter with :func:`scipy.signal.sosfilt`), imported once in the fork server."""


def _pool_context() -> BaseContext:
    """The start method of the local pool: ``forkserver`` where there is one (POSIX).

    Each ``spawn`` process imports the chain and SciPy's signal package on its own (about
    1.4 s of CPU each); the fork server imports them once, with :data:`_POOL_PRELOAD`, and
    forks the pool's processes from itself, single-threaded (a fork of this process could
    copy a lock another thread holds). Elsewhere (Windows): ``spawn``.
    """
    import multiprocessing

    if "forkserver" not in multiprocessing.get_all_start_methods():
        return multiprocessing.get_context("spawn")
    ctx = multiprocessing.get_context("forkserver")
    ctx.set_forkserver_preload(list(_POOL_PRELOAD))  # no effect once the server runs
    return ctx


class _DaskFuture(Protocol):
    """A value or a result held on the Dask cluster (``distributed.Future``)."""

    def result(self) -> object: ...


class _DaskClient(Protocol):
    """What :class:`_Evaluator` uses of a ``distributed.Client`` (an optional package whose
    methods are untyped): the workers, the objective scattered once, scores mapped and
    gathered in order."""

    def scheduler_info(self) -> Mapping[str, object]: ...

    def wait_for_workers(self, n_workers: int, timeout: float | None = None) -> None: ...

    def scatter(self, data: TuneObjective, *, broadcast: bool, hash: bool) -> _DaskFuture: ...

    def map(
        self,
        func: Callable[[TuneObjective, NDArray[np.float64]], float],
        objectives: Sequence[_DaskFuture],
        points: Sequence[NDArray[np.float64]],
        /,
        *,
        pure: bool,
    ) -> Sequence[_DaskFuture]: ...

    def gather(self, futures: Sequence[_DaskFuture]) -> list[float]: ...

    def close(self) -> None: ...


def _n_workers(client: _DaskClient) -> int:
    """Workers the Dask scheduler knows of (its ``scheduler_info()["workers"]``)."""
    workers = client.scheduler_info().get("workers", {})
    return len(workers) if isinstance(workers, Sized) else 0


class _Evaluator:
    """Map-like ``(func, xs) -> list`` for differential_evolution, counting evaluations.

    ``func`` (SciPy's wrapper around the objective) is not shipped: each back end already
    holds the objective (in-process, installed in each pool process, or scattered to the
    Dask workers) and calls it on each ``x``; the results come back in order.
    """

    def __init__(self, objective: TuneObjective, workers: int, scheduler: str | None) -> None:
        self.objective = objective
        self.evaluations = 0
        self.where = "in-process"
        self._workers = workers
        self._pool: ProcessPoolExecutor | None = None
        self._client: _DaskClient | None = None
        self._future: _DaskFuture | None = None  # the scattered copy of the objective
        self._address = ""
        if scheduler is not None:
            self._start_dask(scheduler)
        elif workers > 1:
            from concurrent.futures import ProcessPoolExecutor

            self._pool = ProcessPoolExecutor(
                max_workers=workers,
                mp_context=_pool_context(),
                initializer=_install,
                initargs=(objective,),
            )
            self.where = f"{workers} local processes"

    def _start_dask(self, scheduler: str) -> None:
        try:
            from distributed import Client
        except ImportError as exc:
            raise ConfigError(
                "--scheduler needs the Dask distributed package: pip install 'motioncue[dask]'"
            ) from exc
        connect: Callable[..., _DaskClient] = Client  # its methods are untyped: see _DaskClient
        try:
            client = connect(scheduler, timeout=20, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ConfigError(f"cannot reach the Dask scheduler {scheduler}: {msg}") from exc
        self._client = client
        self._address = scheduler
        n = _n_workers(client)
        if n == 0:
            try:
                client.wait_for_workers(1, timeout=20)
            except (OSError, TimeoutError) as exc:
                client.close()
                raise ConfigError(f"the Dask scheduler {scheduler} has no workers") from exc
            n = _n_workers(client)
        self._future = client.scatter(self.objective, broadcast=True, hash=False)
        self.where = f"Dask scheduler {scheduler} ({n} workers)"

    def __call__(
        self, func: Callable[[NDArray[np.float64]], float], xs: Iterable[ArrayLike]
    ) -> list[float]:
        points = [np.asarray(x, dtype=float) for x in xs]
        self.evaluations += len(points)
        if self._client is not None and self._future is not None:  # both, or neither
            from distributed import KilledWorker

            futures = self._client.map(
                _score_with, [self._future] * len(points), points, pure=False
            )
            try:
                return [float(v) for v in self._client.gather(futures)]
            except (OSError, KilledWorker) as exc:
                msg = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                raise TransportError(f"Dask cluster {self._address}: {msg}") from exc
        if self._pool is not None:
            chunk = max(1, len(points) // (4 * self._workers))
            return [float(v) for v in self._pool.map(_score_installed, points, chunksize=chunk)]
        return [float(self.objective(x)) for x in points]

    def close(self) -> None:
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
        if self._client is not None:
            self._client.close()
            self._client = None


# --------------------------------------------------------------------- the tuner
@dataclass(frozen=True, eq=False)
class TuneResult:
    """The outcome of :func:`tune_cueing`.

    Attributes
    ----------
    params : CueingParams
        The tuned preset (feasible).
    before, after : ChainMetrics
        The base preset's and the tuned preset's full metrics on the recordings.
    x : (16,) array
        The best point (log values of :data:`TUNED_PARAMETERS`).
    generations : int
    evaluations : int
    wall_s : float
    stop_reason : str
    where : str
        Where the evaluations ran.
    """

    params: CueingParams
    before: ChainMetrics
    after: ChainMetrics
    x: NDArray[np.float64]
    generations: int
    evaluations: int
    wall_s: float
    stop_reason: str
    where: str


@dataclass
class _RunState:
    last: float
    gen: int = 0
    gen_s: float = 0.0
    stop: str = "converged"


Progress = Callable[[int, float, float, int], None]
"""``progress(generation, best_score, evaluations_per_s, evaluations)``."""


def tune_cueing(
    objective: TuneObjective,
    *,
    seed: int = 0,
    budget_s: float = 300.0,
    generations: int = 100,
    popsize: int = 6,
    workers: int = 1,
    scheduler: str | None = None,
    name: str = "tuned",
    progress: Progress | None = None,
    init_spread: float | None = None,
    hold: Sequence[int] = (),
) -> TuneResult:
    """Minimise the penalised perceived-motion error with differential evolution.

    Parameters
    ----------
    objective : TuneObjective
    seed : int
        Seed of the optimiser (same seed and generations: same result, wherever evaluated).
    budget_s : float
        Wall-time budget (s): no generation is started that would end past it (predicted from
        the last one); the first population is always evaluated.
    generations : int
        Most generations after the first population.
    popsize : int
        Population size per tuned parameter (population ``popsize * 16``).
    workers : int
        Local processes (1: in this process); ignored when ``scheduler`` is given.
    scheduler : str, optional
        Dask scheduler address (``tcp://host:port``): evaluate there. Its workers need
        motioncue (the same version) importable; the recordings travel with the objective.
    name : str
        Name of the tuned preset.
    progress : callable, optional
        Called after each generation.
    init_spread : float, optional
        Start from a population about the base preset instead of a Latin hypercube over the
        whole box: the base plus seeded normal steps of this standard deviation in the log
        space (0.3: about +-35 %), clipped to the bounds. A local search from a good base.
    hold : sequence of int
        Indices of tuned parameters (:func:`motioncue.cueing._tune.tuned_parameters` order)
        kept at the base's value: their bounds shrink to it (a gentle end that changes only
        how strongly the preset cues, not its filters).

    Raises
    ------
    ConfigError
        A bad argument, or the scheduler cannot be reached (or has no worker).
    TransportError
        The cluster failed during the run (a lost connection, a killed worker).
    LimitError
        No feasible candidate was found (zero violations, at most 1 % clamped).
    """
    from scipy.optimize import differential_evolution

    if not (isinstance(seed, int) and 0 <= seed < 2**32):
        raise ConfigError(f"seed {seed!r} is invalid; allowed: an integer in [0, 2^32)")
    if not (math.isfinite(budget_s) and budget_s > 0.0):
        raise ConfigError(f"budget {budget_s!r} s is invalid; allowed: a finite number > 0")
    if not (isinstance(generations, int) and 0 <= generations <= 100_000):
        raise ConfigError(f"generations {generations!r} is invalid; allowed: 0 to 100000")
    if not (isinstance(popsize, int) and 2 <= popsize <= 100):
        raise ConfigError(f"popsize {popsize!r} is invalid; allowed: 2 to 100")
    if not (isinstance(workers, int) and 1 <= workers <= 1024):
        raise ConfigError(f"workers {workers!r} is invalid; allowed: 1 to 1024")
    if init_spread is not None and not (math.isfinite(init_spread) and 0.0 < init_spread <= 5.0):
        raise ConfigError(f"init spread {init_spread!r} is invalid; allowed: (0, 5]")

    n_tuned = len(tuned_parameters(objective.base))
    for i in hold:
        if isinstance(i, bool) or not (isinstance(i, int) and 0 <= i < n_tuned):
            raise ConfigError(f"hold index {i!r} is invalid; allowed: 0 to {n_tuned - 1}")

    t0 = time.monotonic()  # the budget counts everything, connecting included
    evaluator = _Evaluator(objective, workers, scheduler)  # an unreachable cluster: first
    try:
        before = objective.metrics(objective.base, full=True)
    except BaseException:
        evaluator.close()
        raise
    x0 = vector_from_params(objective.base)
    bounds = _log_bounds(objective.base)
    for i in hold:
        bounds[i] = (float(x0[i]) - 1e-12, float(x0[i]) + 1e-12)
    init: str | NDArray[np.float64] = "latinhypercube"
    if init_spread is not None:
        lo = np.array([b[0] for b in bounds])
        hi = np.array([b[1] for b in bounds])
        steps = np.random.default_rng([seed, 1]).normal(
            0.0, init_spread, (popsize * len(x0), len(x0))
        )
        init = np.clip(x0 + steps, lo, hi)
        init[0] = x0
    state = _RunState(last=t0)

    def callback(intermediate_result: OptimizeResult) -> bool:
        now = time.monotonic()
        state.gen += 1
        state.gen_s = now - state.last
        state.last = now
        elapsed = now - t0
        if progress is not None:
            rate = evaluator.evaluations / elapsed if elapsed > 0 else 0.0
            progress(state.gen, float(intermediate_result.fun), rate, evaluator.evaluations)
        if elapsed + state.gen_s > budget_s:
            state.stop = f"wall-time budget {budget_s:g} s"
            return True
        return False

    try:
        res = differential_evolution(
            objective,
            bounds,
            maxiter=generations,
            popsize=popsize,
            rng=np.random.default_rng(seed),
            callback=callback,
            polish=False,
            updating="deferred",
            workers=evaluator,
            x0=x0,
            init=init,
            tol=1e-3,
        )
    finally:
        evaluator.close()
    wall = time.monotonic() - t0
    if state.stop == "converged" and state.gen >= generations:
        state.stop = f"{generations} generations"
    best = np.asarray(res.x, dtype=float)
    params = params_from_vector(objective.base, best.tolist(), name=name)
    after = objective.metrics(params, full=True)
    if not after.feasible:
        raise LimitError(
            f"no feasible parameter set found in {state.gen} generations "
            f"({evaluator.evaluations} evaluations): the best breaks a limit on "
            f"{after.violating_frames} frames and clamps {after.clamped_fraction:.2%} of "
            f"the poses (allowed: 0 and {MAX_CLAMPED_FRACTION:.0%}); nothing written"
        )
    return TuneResult(
        params=params,
        before=before,
        after=after,
        x=best,
        generations=state.gen,
        evaluations=evaluator.evaluations,
        wall_s=wall,
        stop_reason=state.stop,
        where=evaluator.where,
    )


def write_preset(path: str | Path, text: str) -> Path:
    """Write the preset text atomically (no half-written file on a failure)."""
    from .._atomic import atomic_write_bytes

    return atomic_write_bytes(path, text.encode("utf-8"), what="preset")


def chain_metrics(objective: TuneObjective, params: CueingParams) -> ChainMetrics:
    """Full metrics of ``params`` on the objective's recordings (correlation, false cues)."""
    return objective.metrics(params, full=True)
