"""Several cueing presets side by side on the same recordings and platform, as felt.

For each recording and preset the chain of a real ride is run: resample to the frame rate,
the preset's cueing algorithm, workspace limiting (:func:`motioncue.trajectory.limit_pose`)
with the platform's actuator limits tightened by the controller's pulse rounding, then the
actuator speed/acceleration (and jerk) limits the live bridge applies
(:class:`~motioncue.trajectory.RealtimeLimiter` or :class:`~motioncue.trajectory.JerkLimiter`),
mapped back to poses by forward kinematics where they changed a frame. The delivered poses
are evaluated with :func:`motioncue.cueing.evaluate_cueing` against the vehicle's motion
(through the chosen vestibular model set, at the preset's head offset).

The result is a table with one row per recording and preset (:class:`CompareResult`), written
as CSV, JSON and text, plus one overlay plot of perceived motion per recording.

Axis names in this module: ``fx, fy, fz`` (specific force, m/s^2) and ``p, q, r`` (roll,
pitch and yaw rate, the evaluation's ``wx, wy, wz``; shown in deg/s).
"""

from __future__ import annotations

import csv
import io
import json
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from .._errors import ConfigError
from ..cueing import JOLT_CUTOFF_HZ, CueingParams, Rig, jolt, make_cueing
from ..cueing._bound import CORR_MIN, CueBound, RigReach, cue_bound
from ..cueing._evaluate import CueingEvaluation, evaluate_cueing
from ..cueing._plot import rider_axis
from ..cueing._score import cue_score
from ..cueing._vestibular import get_model_set
from ..pipeline._chain import offline_chain
from ..telemetry._recording import resample
from ..trajectory import pulse_rounding_limits
from ._reach import rig_reach
from ._reach_coupling import reach_coupling

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.figure import Figure

    from ..kinematics import Platform
    from ..telemetry import Recording
    from ..trajectory import ActuatorLimits

__all__ = [
    "COLUMN_NOTES",
    "COMPARE_AXES",
    "CompareResult",
    "CompareRun",
    "compare_cueing",
    "compare_figure",
    "plot_file_names",
    "run_chain",
    "write_compare_report",
]

COMPARE_AXES: tuple[str, ...] = ("fx", "fy", "fz", "p", "q", "r")
"""Channel names in the comparison (``p, q, r`` = the evaluation's ``wx, wy, wz``)."""
_UNIT = ("m/s^2", "m/s^2", "m/s^2", "deg/s", "deg/s", "deg/s")
_PLOT_UNIT = ("m/s²", "m/s²", "m/s²", "deg/s", "deg/s", "deg/s")
_WHAT = (
    "longitudinal specific force",
    "lateral specific force",
    "vertical specific force",
    "roll rate",
    "pitch rate",
    "yaw rate",
)
_K = (1.0, 1.0, 1.0, 180.0 / math.pi, 180.0 / math.pi, 180.0 / math.pi)


def _unit_tag(i: int) -> str:
    return "m_s2" if i < 3 else "deg_s"


def _event_notes(key: str, event: str, per_axis: str) -> dict[str, str]:
    """Notes of one cue-event family's columns: ``{key}_s_{axis}`` per axis, then
    ``{key}_s_any`` and ``{key}_pct_any``.

    Parameters
    ----------
    key : str
        Column stem (``"false_cue"``).
    event : str
        The event with its article (``"a false cue"``).
    per_axis : str
        Note of the per-axis column, ``{a}`` standing for the axis name.
    """
    return {
        **{f"{key}_s_{a}": per_axis.format(a=a) for a in COMPARE_AXES},
        f"{key}_s_any": f"time (s) with {event} on at least one of the six channels",
        f"{key}_pct_any": f"{key}_s_any as % of duration_s",
    }


COLUMN_NOTES: dict[str, str] = {
    "recording": "the input recording (file name)",
    "preset": "the cueing preset",
    "duration_s": "length of the resampled recording (s)",
    "objective_J": "perceived-motion error J (dimensionless, in perception thresholds): "
    "sqrt(sum_i w_i mean((sim_i - veh_i)/thr_i)^2 / sum_i w_i) over fx fy fz p q r; lower "
    "is better (relative to standing still, one term of cue_score)",
    "cue_score": "cue score (dimensionless, lower is better; the objective of motioncue "
    "tune): J relative to a platform that stands still, plus the lost correlation of the "
    "perceived channels, 2 x the false-cue fraction and 0.5 x the missed-cue fraction "
    "(motioncue.cueing.cue_score)",
    **{
        f"corr_{a}": f"Pearson correlation of perceived simulator and perceived vehicle "
        f"{_WHAT[i]} (1 = same shape; empty/null when either is constant)"
        for i, a in enumerate(COMPARE_AXES)
    },
    **{
        f"rms_{a}_{_unit_tag(i)}": f"RMS over time of perceived simulator minus perceived "
        f"vehicle {_WHAT[i]} ({_UNIT[i]})"
        for i, a in enumerate(COMPARE_AXES)
    },
    **_event_notes(
        "false_cue",
        "a false cue",
        "time (s) with |perceived simulator {a}| above its threshold and "
        "of the opposite sign to the vehicle's (a cue in the wrong direction)",
    ),
    **_event_notes(
        "missed_cue",
        "a missed cue",
        "time (s) with |perceived vehicle {a}| above its threshold and "
        "|perceived simulator| at or below it (a cue the rider does not get)",
    ),
    **{
        f"share_{a}": f"rendered share of the {_WHAT[i]}: rms(perceived simulator) / "
        "rms(perceived vehicle) (1 = full size, 0 = nothing; empty/null when the vehicle's "
        "is zero)"
        for i, a in enumerate(COMPARE_AXES)
    },
    **{
        f"gain_{a}": f"gain of the {_WHAT[i]}: least-squares slope of perceived simulator on "
        "perceived vehicle, sum(sim veh) / sum(veh veh) (the in-phase share)"
        for i, a in enumerate(COMPARE_AXES)
    },
    **_event_notes(
        "reversal",
        "a reversal",
        "time (s) with both |perceived vehicle {a}| and |perceived "
        "simulator| above the threshold and of opposite signs (a reversal)",
    ),
    **_event_notes(
        "spurious",
        "a spurious cue",
        "time (s) with |perceived simulator {a}| above the threshold "
        "and |perceived vehicle| at or below it (a cue the vehicle does not give, either sign)",
    ),
    **{
        f"jolt_{a}": f"brief pulses of the perceived simulator {a}: its rms above "
        f"{JOLT_CUTOFF_HZ:g} Hz, in thresholds (motioncue.cueing.jolt; compare jolt_vehicle_{a})"
        for a in COMPARE_AXES
    },
    **{
        f"jolt_vehicle_{a}": f"the same of the perceived vehicle {a} (its own road texture and "
        "kerbs): a simulator far above it gives pulses the vehicle did not have"
        for a in COMPARE_AXES
    },
    "clamped_pct": "% of the cue poses outside the platform's workspace (incl. the "
    "controller's stroke and pulse rounding), scaled back towards neutral",
    "actuator_limited_pct": "% of frames changed by the actuator speed/acceleration/jerk "
    "limits after workspace limiting",
    "bad_samples": "input samples (NaN, inf, spikes) the cueing algorithm replaced by the "
    "last good one",
    **{
        f"bound_error_{a}_m_s2": f"the physical bound (compare --bound; "
        "motioncue.cueing.cue_bound): the least RMS perceived error of the "
        f"{_WHAT[i]} any motion of this platform within its limits could reach on this "
        "recording (m/s^2; a certified lower bound, the same for every preset; empty/null "
        "without --bound)"
        for i, a in enumerate(COMPARE_AXES[:2])
    },
    **{
        f"bound_gain_{a}": "the physical bound: the largest gain (in-phase rendered share) of "
        f"the {_WHAT[i]} any motion of this platform could give without a reversal "
        "(an upper bound; empty/null without --bound)"
        for i, a in enumerate(COMPARE_AXES[:2])
    },
    **{
        f"share_of_bound_pct_{a}": f"share_{a} as % of bound_gain_{a}: how much of what the "
        "platform could give without a reversal the preset gives (empty/null without --bound)"
        for a in COMPARE_AXES[:2]
    },
    **{
        f"bound_share_corr_{a}": "the physical bound: the largest rendered share of the "
        f"{_WHAT[i]} any motion of this platform could give with a perceived correlation of at "
        f"least {c:g} (bounds' corr_min; an upper bound; empty/null without --bound)"
        for i, (a, c) in enumerate(zip(COMPARE_AXES[:2], CORR_MIN, strict=True))
    },
    **{
        f"share_of_corr_bound_pct_{a}": f"share_{a} as % of bound_share_corr_{a}: how much of "
        "what the platform could give at that correlation the preset gives (empty/null "
        "without --bound)"
        for a in COMPARE_AXES[:2]
    },
}
"""Every column of the metrics table and what it means, with units."""

COLUMNS: tuple[str, ...] = tuple(COLUMN_NOTES)

Row = dict[str, Any]
"""A metrics row: :data:`COLUMNS` to labels (str) and numbers (float, int for counts; NaN
where undefined); keyed by column name, so its values are typed by the column."""


@dataclass(frozen=True, eq=False)
class CompareRun:
    """One preset on one recording.

    Attributes
    ----------
    recording, preset : str
        Labels (unique within the comparison).
    evaluation : CueingEvaluation
        :func:`evaluate_cueing` of the delivered poses.
    poses : (N, 6) array
        Delivered poses (m, rad).
    poses_clamped : int
        Cue poses scaled back by workspace limiting.
    actuator_limited : int
        Frames changed by the actuator limiter.
    bad_samples : int
        Input samples the cueing algorithm held.
    bound : CueBound or None
        The recording's physical bound on this platform (:func:`cue_bound`), when computed.
    """

    recording: str
    preset: str
    evaluation: CueingEvaluation
    poses: NDArray[np.float64]
    poses_clamped: int
    actuator_limited: int
    bad_samples: int
    bound: CueBound | None = None

    def row(self) -> Row:
        """The metrics row: :data:`COLUMNS` to numbers (NaN where undefined)."""
        ev = self.evaluation
        n = ev.perceived_sim.shape[0]
        fs = ev.fs_hz
        dur = n / fs
        sim, veh, thr = ev.perceived_sim, ev.perceived_vehicle, ev.thresholds
        m = ev.metrics
        row: Row = {
            "recording": self.recording,
            "preset": self.preset,
            "duration_s": dur,
            "objective_J": float(ev.perceived_error),
            "cue_score": cue_score(veh, sim, thr).score,
        }
        for i, a in enumerate(COMPARE_AXES):
            row[f"corr_{a}"] = float(ev.correlation[i])
        for i, a in enumerate(COMPARE_AXES):
            row[f"rms_{a}_{_unit_tag(i)}"] = float(ev.rms_error[i]) * _K[i]
        for i, a in enumerate(COMPARE_AXES):
            row[f"false_cue_s_{a}"] = float(ev.false_cue_time_s[i])
        row["false_cue_s_any"] = m.false_any * dur
        row["false_cue_pct_any"] = 100.0 * m.false_any
        for i, a in enumerate(COMPARE_AXES):
            row[f"missed_cue_s_{a}"] = float(ev.missed_cue_time_s[i])
        row["missed_cue_s_any"] = m.missed_any * dur
        row["missed_cue_pct_any"] = 100.0 * m.missed_any
        for i, a in enumerate(COMPARE_AXES):
            row[f"share_{a}"] = float(m.rendered_share[i])
        for i, a in enumerate(COMPARE_AXES):
            row[f"gain_{a}"] = float(m.gain[i])
        for i, a in enumerate(COMPARE_AXES):
            row[f"reversal_s_{a}"] = float(m.reversals[i]) * dur
        row["reversal_s_any"] = m.reversals_any * dur
        row["reversal_pct_any"] = 100.0 * m.reversals_any
        for i, a in enumerate(COMPARE_AXES):
            row[f"spurious_s_{a}"] = float(m.spurious[i]) * dur
        row["spurious_s_any"] = m.spurious_any * dur
        row["spurious_pct_any"] = 100.0 * m.spurious_any
        j_sim, j_veh = jolt(sim, fs, thr), jolt(veh, fs, thr)
        for i, a in enumerate(COMPARE_AXES):
            row[f"jolt_{a}"] = float(j_sim[i])
        for i, a in enumerate(COMPARE_AXES):
            row[f"jolt_vehicle_{a}"] = float(j_veh[i])
        b = self.bound
        for i, a in enumerate(COMPARE_AXES[:2]):
            row[f"bound_error_{a}_m_s2"] = math.nan if b is None else float(b.error_rms[i])
        for i, a in enumerate(COMPARE_AXES[:2]):
            row[f"bound_gain_{a}"] = math.nan if b is None else float(b.gain_max[i])
        for i, a in enumerate(COMPARE_AXES[:2]):
            g = math.nan if b is None else float(b.gain_max[i])
            ok = math.isfinite(g) and g > 0.0
            row[f"share_of_bound_pct_{a}"] = 100.0 * row[f"share_{a}"] / g if ok else math.nan
        for i, a in enumerate(COMPARE_AXES[:2]):
            sc = math.nan if b is None else float(b.share_max_at_corr[i])
            ok = math.isfinite(sc) and sc > 0.0
            row[f"bound_share_corr_{a}"] = sc
            row[f"share_of_corr_bound_pct_{a}"] = 100.0 * row[f"share_{a}"] / sc if ok else math.nan
        row["clamped_pct"] = 100.0 * self.poses_clamped / n if n else 0.0
        row["actuator_limited_pct"] = 100.0 * self.actuator_limited / n if n else 0.0
        row["bad_samples"] = int(self.bad_samples)
        return row


def run_chain(
    f_vehicle: NDArray[np.float64],
    w_vehicle: NDArray[np.float64],
    params: CueingParams,
    platform: Platform,
    limits: ActuatorLimits,
    rate_hz: float,
    *,
    model: str = "telban-cardullo-2005",
    recording: str = "",
    preset: str = "",
) -> CompareRun:
    """Cueing, workspace limiting, actuator limits and evaluation of one preset.

    Parameters
    ----------
    f_vehicle, w_vehicle : (N, 3) arrays
        Vehicle specific force (m/s^2) and angular velocity (rad/s), uniform at ``rate_hz``.
    params : CueingParams
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits
        The platform's limits with the controller's (``ActuatorLimits.from_platform``);
        tightened here by the pulse rounding, as in ``generate`` and the bridge.
    rate_hz : float
        Frame rate (Hz).
    model : str
        Vestibular model set.
    recording, preset : str
        Labels for the result.

    Returns
    -------
    CompareRun
    """
    tight = pulse_rounding_limits(limits, platform, 1.0 / rate_hz)
    design = make_cueing(params, rate_hz, Rig(platform, limits))
    run = offline_chain(design, f_vehicle, w_vehicle, platform, tight, rate_hz)
    out = run.delivered
    poses = out.poses
    clamped = out.clamped
    ev = evaluate_cueing(
        run.cued.f_used,
        run.cued.w_used,
        poses,
        rate_hz,
        workspace=params.workspace,
        model=model,
        head_offset_m=params.head_offset_m,
        clamped_share=clamped / len(poses) if len(poses) else 0.0,
    )
    return CompareRun(
        recording=recording,
        preset=preset,
        evaluation=ev,
        poses=poses,
        poses_clamped=clamped,
        actuator_limited=out.actuator_limited,
        bad_samples=run.cued.bad_samples,
    )


def _cell(v: object) -> str:
    """A CSV cell: floats in full precision, empty where undefined."""
    if isinstance(v, float):
        return repr(v) if math.isfinite(v) else ""
    return str(v)


def _fmt(v: object, spec: str) -> str:
    if isinstance(v, float) and not math.isfinite(v):
        return ""
    return format(v, spec)


@dataclass(frozen=True, eq=False)
class CompareResult:
    """Every run of a comparison and how it was made.

    Attributes
    ----------
    runs : tuple of CompareRun
        Recording-major: all presets of the first recording, then the second's, ...
    recordings, presets : tuple of str
        Labels, in the order given.
    platform, controller : str
    rate_hz : float
    model_set : str
    """

    runs: tuple[CompareRun, ...]
    recordings: tuple[str, ...]
    presets: tuple[str, ...]
    platform: str
    controller: str
    rate_hz: float
    model_set: str
    t_s: dict[str, NDArray[np.float64]] = field(default_factory=dict)
    reach: RigReach | None = None

    def rows(self) -> list[Row]:
        """One metrics row per run (:data:`COLUMNS`)."""
        return [r.row() for r in self.runs]

    def runs_of(self, recording: str) -> list[CompareRun]:
        return [r for r in self.runs if r.recording == recording]

    def to_dict(self, plots: Sequence[str] = ()) -> dict[str, object]:
        """JSON-ready: the setting, the column notes, the rows (NaN as null), the plots."""

        def clean(v: object) -> object:
            return None if isinstance(v, float) and not math.isfinite(v) else v

        return {
            "platform": self.platform,
            "controller": self.controller,
            "rate_hz": self.rate_hz,
            "vestibular_models": self.model_set,
            "recordings": list(self.recordings),
            "presets": list(self.presets),
            "columns": dict(COLUMN_NOTES),
            "rows": [{k: clean(v) for k, v in row.items()} for row in self.rows()],
            "plots": list(plots),
            # the physical bound of each recording (compare --bound; motioncue.cueing.cue_bound)
            "bounds": {r.recording: r.bound.to_dict() for r in self.runs if r.bound is not None},
        }

    def csv_text(self) -> str:
        """The metrics as CSV (header :data:`COLUMNS`; empty cells where undefined)."""
        buf = io.StringIO()
        writer = csv.writer(buf, lineterminator="\n")
        writer.writerow(COLUMNS)
        for row in self.rows():
            writer.writerow([_cell(row[c]) for c in COLUMNS])
        return buf.getvalue()

    def table(self) -> str:
        """The compact text table (one row per recording and preset), with a units row.

        Correlation of the six channels, then the cue strength and cue errors of
        :func:`motioncue.cueing.cue_metrics` for the horizontal forces (rendered share, gain,
        missed cues) and over all channels (reversals, all false cues, missed cues), and the
        clamped poses; the per-channel figures are in the CSV and JSON.
        """
        rows = self.rows()
        wr, wp = _key_widths(rows)
        corr = " ".join(f"{'c' + a:>6}" for a in COMPARE_AXES)
        xy = ("fx", "fy")
        strength = " ".join(
            f"{k + ' ' + a:>{w}}" for k, w in (("share", 8), ("gain", 7), ("miss", 7)) for a in xy
        )
        with_bound = any(r.bound is not None for r in self.runs)
        head = (
            f"{'recording':<{wr}} {'preset':<{wp}} {'J':>6} {'score':>6} {corr} {strength} "
            f"{'rev %':>6} {'false %':>7} {'missed %':>8} {'clamp %':>7}"
        )
        if with_bound:
            head += f" {'bound fx':>8} {'bound fy':>8} {'@corr fx':>8} {'@corr fy':>8}"
        units = (
            f"{'':<{wr}} {'':<{wp}} {'thr':>6} {'':>6} "
            + " ".join(f"{'':>6}" for _ in _UNIT)
            + f" {'rms/rms':>8} {'rms/rms':>8} {'slope':>7} {'slope':>7} {'% time':>7} "
            f"{'% time':>7} {'any ax':>6} {'any ax':>7} {'any ax':>8} {'poses':>7}"
        )
        if with_bound:
            units += f" {'% share':>8} {'% share':>8} {'% share':>8} {'% share':>8}"
        lines = [head, units]
        for r in rows:
            cs = " ".join(f"{_fmt(r[f'corr_{a}'], '6.3f'):>6}" for a in COMPARE_AXES)
            dur = r["duration_s"]
            miss = [100.0 * r[f"missed_cue_s_{a}"] / dur if dur > 0 else 0.0 for a in xy]
            st = (
                " ".join(f"{_fmt(r[f'share_{a}'], '8.3f'):>8}" for a in xy)
                + " "
                + " ".join(f"{_fmt(r[f'gain_{a}'], '7.3f'):>7}" for a in xy)
                + " "
                + " ".join(f"{v:7.1f}" for v in miss)
            )
            lines.append(
                f"{r['recording']:<{wr}} {r['preset']:<{wp}} {r['objective_J']:6.3f} "
                f"{r['cue_score']:6.3f} {cs} {st} {r['reversal_pct_any']:6.2f} "
                f"{r['false_cue_pct_any']:7.2f} {r['missed_cue_pct_any']:8.2f} "
                f"{r['clamped_pct']:7.2f}"
            )
            if with_bound:
                lines[-1] += " " + " ".join(
                    f"{_fmt(r[f'{col}_{a}'], '8.1f'):>8}"
                    for col in ("share_of_bound_pct", "share_of_corr_bound_pct")
                    for a in xy
                )
        return "\n".join(lines)

    def bound_text(self) -> str:
        """The physical bound of each recording (empty without ``bound``): the rig's reach,
        the least RMS perceived error and the largest gain without a reversal, fx and fy."""
        bounds = {r.recording: r.bound for r in self.runs if r.bound is not None}
        if not bounds or self.reach is None:
            return ""
        rr = self.reach
        lines = [
            "Physical bound (motioncue.cueing.cue_bound; docs/cue-metrics.md): what any motion "
            "of this platform within its limits could give, per recording.",
            f"  reach fx/fy: stroke {rr.stroke_m[0] * 1e3:.0f}/{rr.stroke_m[1] * 1e3:.0f} mm, "
            f"speed {rr.speed_m_s[0]:.2f}/{rr.speed_m_s[1]:.2f} m/s, accel "
            f"{rr.accel_m_s2[0]:.1f}/{rr.accel_m_s2[1]:.1f} m/s^2, tilt "
            f"{math.degrees(rr.tilt_rad[0]):.1f}/{math.degrees(rr.tilt_rad[1]):.1f} deg, tilt "
            f"rate {math.degrees(rr.tilt_rate_rad_s[0]):.0f}/"
            f"{math.degrees(rr.tilt_rate_rad_s[1]):.0f} deg/s"
            + ("; translation and tilt coupled through the legs" if rr.coupling else ""),
        ]
        wr = max([len("recording"), *(len(k) for k in bounds)])
        lines.append(
            f"  {'recording':<{wr}} {'veh rms fx':>10} {'veh rms fy':>10} {'err >= fx':>10} "
            f"{'err >= fy':>10} {'gain <= fx':>10} {'gain <= fy':>10} {'share <= fx':>11} "
            f"{'share <= fy':>11} {'found fx':>8} {'found fy':>8}"
        )
        for rec, b in bounds.items():
            lines.append(
                f"  {rec:<{wr}} {b.vehicle_rms[0]:10.3f} {b.vehicle_rms[1]:10.3f} "
                f"{b.error_rms[0]:10.3f} {b.error_rms[1]:10.3f} "
                + " ".join(f"{_fmt(float(g), '10.3f'):>10}" for g in b.gain_max)
                + " "
                + " ".join(f"{_fmt(float(s), '11.3f'):>11}" for s in b.share_max_at_corr)
                + " "
                + " ".join(f"{_fmt(float(s), '8.3f'):>8}" for s in b.share_at_corr_primal)
            )
        cm = next(iter(bounds.values())).corr_min
        lines.append(
            "  (veh rms: the vehicle's perceived motion, m/s^2; err >=: no motion of the "
            "platform gets the perceived error below this, m/s^2; gain <=: no motion without "
            "a reversal gives a larger gain; bound fx/fy in the table = share / gain <=;"
        )
        lines.append(
            f"   share <=: no motion with a perceived correlation >= {_fmt(float(cm[0]), '.2f')} "
            f"(fx) / {_fmt(float(cm[1]), '.2f')} (fy) renders a larger share; found: the share "
            "of the best such motion found (non-causal), the bound's tightness; @corr fx/fy in "
            "the table = share / share <=)"
        )
        return "\n".join(lines)

    def summary(self, plots: Sequence[str] = ()) -> str:
        """Text report: the setting, the table, per-axis cue times, the column notes."""
        lines = [
            f"motioncue compare: platform {self.platform}, controller {self.controller}, "
            f"{self.rate_hz:g} Hz frames, vestibular models {self.model_set}",
            "chain: resample -> cueing -> workspace limiting (platform + controller limits, "
            "pulse rounding) -> actuator speed/acceleration limits -> delivered motion -> "
            "vestibular models",
            "",
            self.table(),
            "",
        ]
        if self.bound_text():
            lines += [self.bound_text(), ""]
        lines += [
            "False and missed cue time per channel (s):",
        ]
        rows = self.rows()
        wr, wp = _key_widths(rows)
        cols = [
            *((f"false {a}", f"false_cue_s_{a}", 8) for a in COMPARE_AXES),
            *((f"missed {a}", f"missed_cue_s_{a}", 9) for a in COMPARE_AXES),
            ("dur s", "duration_s", 8),
        ]
        lines.append(
            f"{'recording':<{wr}} {'preset':<{wp}} " + " ".join(f"{h:>{w}}" for h, _, w in cols)
        )
        for r in rows:
            lines.append(
                f"{r['recording']:<{wr}} {r['preset']:<{wp}} "
                + " ".join(f"{r[k]:{w}.2f}" for _, k, w in cols)
            )
        lines += [
            "",
            "Columns (text table: J = objective_J; score = cue_score; c<axis> = corr_<axis>; "
            "share <axis> = share_<axis>; gain <axis> "
            "= gain_<axis>; miss <axis> = missed_cue_s_<axis> as % of duration_s; rev % / "
            "false % / missed % = reversal_pct_any / false_cue_pct_any / missed_cue_pct_any; "
            "clamp % = clamped_pct; bound fx / fy = share_of_bound_pct_fx / _fy; @corr fx / fy = "
            "share_of_corr_bound_pct_fx / _fy; definitions "
            "and sources of share, gain, missed, reversal, spurious and false cues and of the "
            "bound: docs/cue-metrics.md, motioncue.cueing.cue_metrics, cue_bound):",
        ]
        lines += [f"  {k:<22} {v}" for k, v in COLUMN_NOTES.items()]
        lines += [
            "  Perceived motion: vehicle and delivered simulator motion through the "
            f"{self.model_set} models (otoliths for fx fy fz, semicircular canals for p q r), "
            "from rest; thresholds are the model set's.",
        ]
        if plots:
            lines += ["", "Plots (perceived motion per channel, vehicle and each preset):"]
            lines += [f"  {p}" for p in plots]
        return "\n".join(lines) + "\n"


def _key_widths(rows: Sequence[Row]) -> tuple[int, int]:
    """Widths of the recording and preset columns of the text tables (characters)."""
    wr = max([len("recording"), *(len(r["recording"]) for r in rows)])
    wp = max([len("preset"), *(len(r["preset"]) for r in rows)])
    return wr, wp


def compare_cueing(
    recordings: Sequence[tuple[str, Recording]],
    presets: Sequence[tuple[str, CueingParams]],
    platform: Platform,
    limits: ActuatorLimits,
    *,
    rate_hz: float = 100.0,
    model: str = "telban-cardullo-2005",
    platform_name: str | None = None,
    controller_name: str = "",
    progress: Callable[[str], None] | None = None,
    bound: bool = False,
    bound_corr_cuts: int = 2,
) -> CompareResult:
    """Run every preset on every recording through the platform's chain.

    Parameters
    ----------
    recordings : sequence of (label, Recording)
        Labels must be unique; recordings at any sample times (resampled to ``rate_hz``).
    presets : sequence of (label, CueingParams)
        Labels must be unique.
    platform : motioncue.kinematics.Platform
    limits : motioncue.trajectory.ActuatorLimits
        ``ActuatorLimits.from_platform(platform, controller, rate_hz=rate_hz)``.
    rate_hz : float
    model : str
        Vestibular model set name.
    progress : callable, optional
        Called with one line before each run (``"run 2/6: lap x mpc-hexapod"``) and after
        the last one (with the elapsed time, s).
    bound : bool
        Also compute each recording's physical bound on the platform (:func:`cue_bound`
        with :func:`rig_reach` of the platform and ``limits``, translation and tilt coupled
        by :func:`reach_coupling`; about a minute or two of CPU per recording), reported in
        the ``bound_*`` and ``share_of_bound_*`` columns.
    bound_corr_cuts : int
        ``cue_bound``'s ``corr_cuts``: each cut costs one cone programme per channel and
        tightens ``share_max_at_corr`` (0: one programme per channel, a looser valid bound).

    Returns
    -------
    CompareResult
    """
    import time

    ms = get_model_set(model)
    if not (math.isfinite(rate_hz) and rate_hz > 0.0):
        raise ConfigError(f"rate {rate_hz!r} Hz is invalid; allowed: a finite number > 0")
    for what, items in (("recording", recordings), ("preset", presets)):
        labels = [k for k, _ in items]
        if not labels:
            raise ConfigError(f"no {what}s to compare; give at least one")
        if len(set(labels)) != len(labels):
            raise ConfigError(f"{what} labels repeat: {labels!r}; each must be unique")
    runs: list[CompareRun] = []
    t_s: dict[str, NDArray[np.float64]] = {}
    n_runs = len(recordings) * len(presets)
    t0 = time.perf_counter()
    reach = None
    if bound:
        lims = pulse_rounding_limits(limits, platform, 1.0 / rate_hz)
        # the boxes, then translation and tilt coupled through the legs (docs/cue-metrics.md)
        reach = reach_coupling(platform, lims, rig_reach(platform, lims))
    for rec_label, rec in recordings:
        uniform = resample(rec, rate_hz)
        t_s[rec_label] = np.asarray(uniform.t_s, dtype=float)
        rec_bound = None
        if reach is not None and len(uniform) >= 4:
            rec_bound = cue_bound(
                np.asarray(uniform.f, dtype=float),
                rate_hz,
                reach,
                model=ms,
                corr_cuts=bound_corr_cuts,
            )
        for preset_label, params in presets:
            if progress is not None:
                progress(
                    f"run {len(runs) + 1}/{n_runs}: {rec_label} x {preset_label} "
                    f"({time.perf_counter() - t0:.1f} s)"
                )
            run = run_chain(
                np.asarray(uniform.f, dtype=float),
                np.asarray(uniform.w, dtype=float),
                params,
                platform,
                limits,
                rate_hz,
                model=ms.name,
                recording=rec_label,
                preset=preset_label,
            )
            runs.append(replace(run, bound=rec_bound) if rec_bound is not None else run)
    if progress is not None:
        progress(f"{n_runs} run(s) done in {time.perf_counter() - t0:.1f} s")
    return CompareResult(
        runs=tuple(runs),
        recordings=tuple(k for k, _ in recordings),
        presets=tuple(k for k, _ in presets),
        platform=platform_name or platform.name,
        controller=controller_name,
        rate_hz=float(rate_hz),
        model_set=ms.name,
        t_s=t_s,
        reach=reach,
    )


def compare_figure(result: CompareResult, recording: str) -> Figure:
    """The overlay figure of one recording: perceived motion per channel, vehicle and presets.

    Six panels (fx, fy, fz in m/s², p, q, r in deg/s), the vehicle as a thick dark line on
    the left axis, each preset in its own colour on the right axis, scaled to show the
    rider's cue (the scaling of ``motioncue cue``'s plot: zero at the same height; the
    presets' rendered share in the legend), the perception threshold as a grey band; one
    legend naming the vehicle and every preset; the title names the recording, platform,
    controller, frame rate and vestibular model set. Returns the matplotlib figure (Agg;
    close it after use).
    """
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    runs = result.runs_of(recording)
    if not runs:
        raise ConfigError(f"recording {recording!r} is not in the comparison")
    t = result.t_s.get(recording)
    ev0 = runs[0].evaluation
    if t is None or len(t) != ev0.perceived_vehicle.shape[0]:
        t = np.arange(ev0.perceived_vehicle.shape[0]) / ev0.fs_hz
    fig = Figure(figsize=(14, 9.5), layout="constrained")
    axes = fig.subplots(3, 2, sharex=True)
    colours = [f"C{k % 10}" for k in range(len(runs))]
    handles: list[Artist] = []
    labels: list[str] = []
    for i, name in enumerate(COMPARE_AXES):
        ax = axes[i % 3, i // 3]
        k = _K[i]
        thr = float(ev0.thresholds[i]) * k
        sims = [run.evaluation.perceived_sim[:, i] * k for run in runs]
        right = rider_axis(ax, ev0.perceived_vehicle[:, i] * k, list(sims), thr)
        band = right.axhspan(-thr, thr, color="0.88", lw=0, zorder=0)
        (veh,) = ax.plot(t, ev0.perceived_vehicle[:, i] * k, color="0.1", lw=1.8)
        lines = [
            right.plot(t, sim, color=c, lw=0.9, alpha=0.85)[0]
            for sim, c in zip(sims, colours, strict=True)
        ]
        ax.set_ylabel(f"vehicle, perceived {name} [{_PLOT_UNIT[i]}]", fontsize=8)
        right.set_ylabel(f"presets, right axis [{_PLOT_UNIT[i]}]", fontsize=8)
        shares = " / ".join(
            f"{v:.0%}" if math.isfinite(v) else "-"
            for v in (float(r.evaluation.metrics.rendered_share[i]) for r in runs)
        )
        ax.set_title(f"{name}: {_WHAT[i]}; share {shares}", fontsize=9, loc="left")
        ax.grid(alpha=0.3)
        if i % 3 == 2:
            ax.set_xlabel("t [s]")
        if i == 0:
            handles = [veh, *lines, band]
            labels = [
                "vehicle",
                *(f"preset {r.preset}" for r in runs),
                "perception threshold (±)",
            ]
    fig.legend(
        handles,
        labels,
        loc="outside lower center",
        ncol=min(len(labels), 4),
        title="vehicle on the left axis; presets and the threshold on the right axis, scaled "
        "to show the rider's cue; 'share': each preset's rendered share, in legend order",
        title_fontsize=9,
    )
    fig.suptitle(
        f"perceived motion, recording {recording}\nplatform {result.platform} | controller "
        f"{result.controller or 'not given'} | {result.rate_hz:g} Hz | vestibular models "
        f"{result.model_set}"
    )
    return fig


def plot_file_names(recordings: Sequence[str]) -> list[str]:
    """File names of the overlay plots, one per recording (unique, file-system safe)."""
    names: list[str] = []
    for label in recordings:
        stem = re.sub(r"[^A-Za-z0-9._-]+", "_", Path(label).stem) or "recording"
        name = f"perceived-{stem}.png"
        k = 2
        while name in names:
            name = f"perceived-{stem}-{k}.png"
            k += 1
        names.append(name)
    return names


def write_compare_report(result: CompareResult, folder: str | Path) -> dict[str, Path]:
    """Write ``metrics.csv``, ``metrics.json``, ``summary.txt`` and one PNG per recording.

    Every file is written atomically (temporary name, renamed on success). Returns the paths
    by role (``"csv"``, ``"json"``, ``"summary"``, and the recording labels for the plots).
    """
    from .._atomic import atomic_write_bytes

    out = Path(folder)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ConfigError(f"{out}: cannot create the report folder: {exc}") from exc
    if not out.is_dir():
        raise ConfigError(f"{out}: not a folder")
    names = plot_file_names(result.recordings)
    paths: dict[str, Path] = {}
    for label, name in zip(result.recordings, names, strict=True):
        fig = compare_figure(result, label)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=80)
        paths[label] = out / name
        _write(paths[label], buf.getvalue(), atomic_write_bytes)
    paths["csv"] = out / "metrics.csv"
    _write(paths["csv"], result.csv_text().encode(), atomic_write_bytes)
    paths["json"] = out / "metrics.json"
    text = json.dumps(result.to_dict(names), indent=2, allow_nan=False) + "\n"
    _write(paths["json"], text.encode(), atomic_write_bytes)
    paths["summary"] = out / "summary.txt"
    _write(paths["summary"], result.summary(names).encode(), atomic_write_bytes)
    return paths


def _write(path: Path, data: bytes, writer: Callable[[Path, bytes], Path]) -> None:
    try:
        writer(path, data)
    except OSError as exc:
        raise ConfigError(f"{path}: cannot write: {exc}") from exc
