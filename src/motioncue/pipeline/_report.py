"""Ride reports: cue quality, poses, and actuators against their limits (PNG + JSON + text)."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..cueing import evaluate_cueing, plot_cueing
from ._generate import GenerateReport
from ._ridefile import Ride
from ._verify import limits_arrays

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..cueing import CueingParams
    from ..kinematics import Platform

__all__ = ["delivered_poses", "plot_actuators", "write_report"]


def delivered_poses(platform: Platform, report: GenerateReport) -> np.ndarray:
    """Poses the platform really makes after the actuator limits, to first order.

    ``pose + J^+ (q - q_desired)`` with the Jacobian at the workspace-limited pose: exact to
    first order in the (millimetre-sized) optimisation deviation, and vectorised.
    """
    poses = np.asarray(report.poses, dtype=float)
    dq = np.asarray(report.q, dtype=float) - np.asarray(report.q_desired, dtype=float)
    mask = np.asarray(platform.dof_mask, dtype=bool)
    jac = platform.jacobian(poses)[..., mask]
    dpose = np.einsum("nij,nj->ni", np.linalg.pinv(jac), dq)
    out = poses.copy()
    out[:, mask] += dpose
    return out


def plot_actuators(
    ride: Ride,
    path: str | Path,
    q_desired_pulses: np.ndarray | None = None,
    *,
    preset: str | None = None,
) -> Path:
    """Positions against the stroke, speeds and accelerations against their limits.

    Parameters
    ----------
    ride : Ride
        The frames (pulses) and the limits table they were made for.
    path : path
        PNG file to write.
    q_desired_pulses : (N, n) array, optional
        The positions asked for before the actuator limits (pulses), drawn dashed on top.
    preset : str, optional
        The cueing preset, named in the title.

    Notes
    -----
    Positions are in pulses (left axis) and, when every actuator has the same pulses per unit,
    in mm (or deg) from home on the right axis. Axes are numbered from 1, as the controllers'
    manuals number them.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lim = limits_arrays(ride.limits)
    t = ride.t_s
    p = ride.pulses.astype(float)
    v = np.zeros_like(p)
    v[1:] = np.diff(p, axis=0) / np.diff(t)[:, None]
    a = np.zeros_like(v)
    a[1:] = np.diff(v, axis=0) / np.diff(t)[:, None]
    names = ride.actuator_names
    fig, axes = plt.subplots(3, 1, figsize=(13, 11), sharex=True, layout="constrained")
    for i, name in enumerate(names):
        label = f"axis {i + 1}" + ("" if str(name) == str(i + 1) else f" ({name})")
        (line,) = axes[0].plot(t, p[:, i], lw=0.9, label=label)
        if q_desired_pulses is not None:
            axes[0].plot(
                t, q_desired_pulses[:, i], lw=1.3, ls=(0, (4, 2)), alpha=0.75,
                color=line.get_color(), zorder=3,
                label="desired (before the actuator limits)" if i == 0 else None,
            )  # fmt: skip
        axes[1].plot(t, v[:, i] / lim["v"][i], lw=0.8, color=line.get_color())
        axes[2].plot(t, a[:, i] / lim["a"][i], lw=0.8, color=line.get_color())
    for k, (lo, hi) in enumerate(zip(lim["lo"], lim["hi"], strict=True)):
        end_label = "stroke ends" if k == 0 else None
        axes[0].axhline(lo, color="k", lw=0.6, ls=":", label=end_label)
        axes[0].axhline(hi, color="k", lw=0.6, ls=":")
    axes[0].set_ylabel("position [pulses]")
    scale = _si_per_pulse(ride)
    if scale is not None:
        factor, unit = scale
        axes[0].secondary_yaxis(
            "right", functions=(lambda x: x * factor, lambda y: y / factor)
        ).set_ylabel(f"position from home [{unit}]")
    axes[0].legend(loc="upper left", bbox_to_anchor=(0.0, -0.04), ncol=len(names) + 2,
                   fontsize=8, frameon=False)  # fmt: skip
    for ax, what in ((axes[1], "speed"), (axes[2], "acceleration")):
        ax.axhline(1.0, color="r", lw=0.8)
        ax.axhline(-1.0, color="r", lw=0.8)
        ax.set_ylabel(f"{what} / its limit\n(red: the limit)")
        ax.set_ylim(-1.15, 1.15)
    axes[2].set_xlabel("ride time t [s]")
    for ax in axes:
        ax.grid(alpha=0.3)
    what = f"preset {preset}, " if preset else ""
    fig.suptitle(
        f"{what}platform {ride.platform}, controller {ride.controller}: "
        f"actuators against their limits ({ride.rate_hz:g} Hz)"
    )
    path = Path(path)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _si_per_pulse(ride: Ride) -> tuple[float, str] | None:
    """mm (or deg) per pulse when every actuator shares it, else None."""
    rows = ride.limits.get("actuators", []) if isinstance(ride.limits, dict) else []
    per = {(r.get("kind"), r.get("pulses_per_unit")) for r in rows}
    if len(per) != 1:
        return None
    kind, ppu = next(iter(per))
    if not isinstance(ppu, (int, float)) or ppu <= 0:
        return None
    if kind == "linear":
        return 1e3 / float(ppu), "mm"
    return 180.0 / np.pi / float(ppu), "deg"


def write_report(
    out_dir: str | Path,
    ride: Ride,
    report: GenerateReport,
    platform: Platform,
    cueing: CueingParams,
) -> dict[str, Any]:
    """Write ``cueing.png``, ``actuators.png``, ``metrics.json`` and ``summary.txt``.

    Returns the metrics dictionary (also written as JSON).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    poses = delivered_poses(platform, report)[report.cue_slice]
    ev = evaluate_cueing(
        report.f_vehicle,
        report.w_vehicle,
        poses,
        ride.rate_hz,
        workspace=cueing.workspace,
        head_offset_m=cueing.head_offset_m,
        clamped_share=min(1.0, report.poses_clamped / max(len(poses), 1)),
    )
    plot_cueing(
        ev,
        poses,
        out / "cueing.png",
        title=f"{ride.source} on {ride.platform}",
        preset=cueing.name,
        platform=f"{ride.platform}, controller {ride.controller}",
    )
    desired = platform.drives.to_pulses(report.q_desired)
    plot_actuators(ride, out / "actuators.png", desired, preset=cueing.name)
    opt = report.optimisation
    check = report.frame_check

    def fin(x: ArrayLike) -> list[float | None]:
        arr = np.asarray(x, dtype=float)
        return [None if not math.isfinite(v) else float(v) for v in arr.ravel()]

    metrics: dict[str, Any] = {
        "frames": ride.n_frames,
        "duration_s": ride.duration_s,
        "rate_hz": ride.rate_hz,
        "bad_samples": report.bad_samples,
        "poses_clamped": report.poses_clamped,
        "max_pose_scale_loss": report.max_pose_scale_loss,
        "optimisation": {
            "status": str(opt.status),
            "max_deviation_si": float(opt.max_deviation),
            "where_frame_actuator": [int(i) for i in opt.where_index],
            "windows": int(opt.n_windows),
        },
        "limit_use": {
            "stroke": fin(check.stroke_use),
            "speed": fin(check.speed_use),
            "accel": fin(check.accel_use),
        },
        "cue": {
            "axes": ["fx", "fy", "fz", "wx", "wy", "wz"],
            "units": ["m/s^2", "m/s^2", "m/s^2", "rad/s", "rad/s", "rad/s"],
            "model_set": ev.model_set,
            "thresholds": fin(ev.thresholds),
            "perceived_motion_error": float(ev.perceived_error),
            "weights": fin(ev.weights),
            "head_offset_m": fin(ev.head_offset_m),
            "rms_error": fin(ev.rms_error),
            "correlation": fin(ev.correlation),
            "delay_s": fin(ev.delay_s),
            "false_cue_count": [int(c) for c in ev.false_cue_count],
            "false_cue_time_s": fin(ev.false_cue_time_s),
            "missed_cue_time_s": fin(ev.missed_cue_time_s),
            "workspace_use": fin(ev.workspace_use),
            # share, gain, missed/reversed/spurious/false cues: motioncue.cueing.cue_metrics
            "metrics": ev.metrics.to_dict(),
        },
        "stage_s": report.stage_s,
    }
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2))
    (out / "summary.txt").write_text(
        f"ride: {ride.n_frames} frames, {ride.duration_s:.1f} s at {ride.rate_hz:g} Hz\n"
        f"limits check: {check.summary()}\n"
        f"optimisation: {opt.status}, max deviation {opt.max_deviation * 1e3:.2f} mm\n"
        f"input samples held: {report.bad_samples}; poses clamped: {report.poses_clamped}\n\n"
        + ev.summary()
        + "\n"
    )
    return metrics
