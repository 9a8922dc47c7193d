"""Motion cueing: vehicle specific force and angular velocity to platform poses.

The cueing interface (:class:`CueingAlgorithm`; :func:`make_cueing` builds the algorithm a
preset names with ``algorithm = "..."``, :func:`register_cueing` adds one), the classical
washout of Reid & Nahon (:class:`ClassicalWashout`, registered as ``"classical"``), its
parameters (:class:`CueingParams`, :func:`load_cueing` for ``configs/cueing/*.toml``) and the
evaluation of cue quality through vestibular models (:func:`evaluate_cueing`; cue strength
and cue errors: :func:`cue_metrics`).

Example
-------
>>> from motioncue.cueing import load_cueing, make_cueing
>>> design = make_cueing(load_cueing("racing"), fs_hz=100.0)
>>> type(design).__name__
'ClassicalWashout'
>>> state = design.initial_state()
>>> pose = design.step(state, (0.0, 0.0, 9.80665), (0.0, 0.0, 0.0))
>>> [round(v, 12) for v in pose]
[0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
"""

from ._algorithm import (
    CueingAlgorithm,
    CueingEntry,
    CueingFactory,
    CueingResult,
    CueingState,
    ParameterTable,
    Rig,
    cueing_algorithms,
    cueing_entry,
    make_cueing,
    register_cueing,
    unregister_cueing,
)
from ._bound import BOUND_CHANNELS, CueBound, ReachPolygon, RigReach, cue_bound
from ._classical import ClassicalWashout, WashoutResult, WashoutState
from ._evaluate import (
    AXIS_NAMES,
    OTOLITH,
    SEMICIRCULAR_CANAL,
    CueingEvaluation,
    VestibularModel,
    evaluate_cueing,
    simulator_motion,
)
from ._metrics import JOLT_CUTOFF_HZ, CueMasks, CueMetrics, cue_masks, cue_metrics, jolt
from ._params import DOF_NAMES, FALLBACK_PRESET, GRAVITY_M_S2, CueingParams, load_cueing
from ._plot import plot_cueing
from ._score import (
    ACTIVE_FRACTION,
    CORRELATION_WEIGHTS,
    FALSE_CUE_WEIGHT,
    MISSED_CUE_WEIGHT,
    CueScore,
    cue_score,
)
from ._tune import TunableParameter, TunePlan, at_intensity
from ._vestibular import (
    DEFAULT_MODEL_SET,
    DEFAULT_WEIGHTS,
    MODEL_SETS,
    VestibularModelSet,
    get_model_set,
    perceived_motion_error,
)

__all__ = [
    "ACTIVE_FRACTION",
    "AXIS_NAMES",
    "BOUND_CHANNELS",
    "CORRELATION_WEIGHTS",
    "DEFAULT_MODEL_SET",
    "DEFAULT_WEIGHTS",
    "DOF_NAMES",
    "FALLBACK_PRESET",
    "FALSE_CUE_WEIGHT",
    "GRAVITY_M_S2",
    "JOLT_CUTOFF_HZ",
    "MISSED_CUE_WEIGHT",
    "MODEL_SETS",
    "OTOLITH",
    "SEMICIRCULAR_CANAL",
    "ClassicalWashout",
    "CueBound",
    "CueMasks",
    "CueMetrics",
    "CueScore",
    "CueingAlgorithm",
    "CueingEntry",
    "CueingEvaluation",
    "CueingFactory",
    "CueingParams",
    "CueingResult",
    "CueingState",
    "ParameterTable",
    "ReachPolygon",
    "Rig",
    "RigReach",
    "TunableParameter",
    "TunePlan",
    "VestibularModel",
    "VestibularModelSet",
    "WashoutResult",
    "WashoutState",
    "at_intensity",
    "cue_bound",
    "cue_masks",
    "cue_metrics",
    "cue_score",
    "cueing_algorithms",
    "cueing_entry",
    "evaluate_cueing",
    "get_model_set",
    "jolt",
    "load_cueing",
    "make_cueing",
    "perceived_motion_error",
    "plot_cueing",
    "register_cueing",
    "simulator_motion",
    "unregister_cueing",
]

_MOVED = {"rig_reach", "tilt_reach"}
"""Names that moved to :mod:`motioncue.analysis` (they need the platform's kinematics),
still importable from here (not in ``__all__``), resolved on first use: cueing imports no
later stage."""


def __getattr__(name: str) -> object:
    if name in _MOVED:
        from .. import analysis

        return getattr(analysis, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
