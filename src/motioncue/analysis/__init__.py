r"""Analysis tools above the stages: compare presets, the OMCT, automatic tuning.

Layers (each imports only the ones below it)::

    cli
    analysis (compare, omct, tune)
    pipeline (generate, bridge, play, ...; the offline chain, pipeline._chain)
    stages: cueing -> trajectory -> telemetry / kinematics / output

Every tool here runs a cueing algorithm through the chain a ride goes through, written once
(:func:`offline_chain`: cueing -> workspace limiting
with the pulse-rounding-tightened limits -> the live actuator limiter -> forward kinematics),
the chain ``generate`` also uses (its workspace stage). The algorithm is built with the
rig the tool is given (:class:`motioncue.cueing.Rig`) and never named here: what it can do
(tunable parameters, streaming) comes from its registry entry
(:func:`motioncue.cueing.cueing_entry`).

* :func:`compare_cueing`: several presets side by side on recordings, as felt;
* :func:`run_omct`: the Objective Motion Cueing Test of the whole chain;
* :func:`tune_cueing` with :class:`TuneObjective`: the strongest cue within cue-quality
  targets and the platform's limits;
* :func:`rig_reach`, :func:`reach_coupling`, :func:`tilt_reach`: what a rig can reach (for
  the physical bound and the compressive tilt).
"""

import importlib
from typing import TYPE_CHECKING

from ..pipeline._chain import ChainRun, Cued, Delivered, deliver, offline_chain, run_cueing

if TYPE_CHECKING:
    from ._compare import (
        COLUMN_NOTES,
        COMPARE_AXES,
        CompareResult,
        CompareRun,
        compare_cueing,
        compare_figure,
        plot_file_names,
        run_chain,
        write_compare_report,
    )
    from ._omct import (
        MEASURE_PERIODS,
        OMCT_FREQUENCIES_RAD_S,
        OMCT_PATHS,
        OmctPath,
        OmctPoint,
        OmctResult,
        linear_response,
        omct_amplitude,
        platform_motion,
        plot_omct,
        run_omct,
    )
    from ._reach import rig_reach
    from ._reach_coupling import reach_coupling
    from ._tune import (
        MAX_CLAMPED_FRACTION,
        OBJECTIVES,
        PENALTY_BASE,
        ChainMetrics,
        StrengthTargets,
        TuneObjective,
        TuneResult,
        chain_metrics,
        tilt_reach,
        tune_cueing,
        write_preset,
    )

_LAZY: dict[str, str] = {
    "COLUMN_NOTES": "._compare",
    "COMPARE_AXES": "._compare",
    "ChainMetrics": "._tune",
    "CompareResult": "._compare",
    "CompareRun": "._compare",
    "MAX_CLAMPED_FRACTION": "._tune",
    "MEASURE_PERIODS": "._omct",
    "OBJECTIVES": "._tune",
    "OMCT_FREQUENCIES_RAD_S": "._omct",
    "OMCT_PATHS": "._omct",
    "OmctPath": "._omct",
    "OmctPoint": "._omct",
    "OmctResult": "._omct",
    "PENALTY_BASE": "._tune",
    "StrengthTargets": "._tune",
    "TuneObjective": "._tune",
    "TuneResult": "._tune",
    "chain_metrics": "._tune",
    "compare_cueing": "._compare",
    "compare_figure": "._compare",
    "linear_response": "._omct",
    "omct_amplitude": "._omct",
    "platform_motion": "._omct",
    "plot_file_names": "._compare",
    "plot_omct": "._omct",
    "reach_coupling": "._reach_coupling",
    "rig_reach": "._reach",
    "run_chain": "._compare",
    "run_omct": "._omct",
    "tilt_reach": "._tune",
    "tune_cueing": "._tune",
    "write_compare_report": "._compare",
    "write_preset": "._tune",
}
"""The tools, imported on first use: the offline chain (which ``generate`` imports) does not
pull in compare, the OMCT and tune."""


def __getattr__(name: str) -> object:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(module, __name__), name)


__all__ = [
    "COLUMN_NOTES",
    "COMPARE_AXES",
    "MAX_CLAMPED_FRACTION",
    "MEASURE_PERIODS",
    "OBJECTIVES",
    "OMCT_FREQUENCIES_RAD_S",
    "OMCT_PATHS",
    "PENALTY_BASE",
    "ChainMetrics",
    "ChainRun",
    "CompareResult",
    "CompareRun",
    "Cued",
    "Delivered",
    "OmctPath",
    "OmctPoint",
    "OmctResult",
    "StrengthTargets",
    "TuneObjective",
    "TuneResult",
    "chain_metrics",
    "compare_cueing",
    "compare_figure",
    "deliver",
    "linear_response",
    "offline_chain",
    "omct_amplitude",
    "platform_motion",
    "plot_file_names",
    "plot_omct",
    "reach_coupling",
    "rig_reach",
    "run_chain",
    "run_cueing",
    "run_omct",
    "tilt_reach",
    "tune_cueing",
    "write_compare_report",
    "write_preset",
]
