"""One-page plot of a cueing run: perceived motion, poses and metrics (matplotlib, Agg)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._errors import ConfigError
from ._evaluate import AXIS_NAMES, CueingEvaluation

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["plot_cueing", "plot_title", "rider_axis"]

_UNITS = ("m/s²", "m/s²", "m/s²", "deg/s", "deg/s", "deg/s")


def rider_axis(ax: Axes, vehicle: ArrayLike, riders: list[ArrayLike], thr: float) -> Axes:
    """A right-hand axis for the rider's perceived motion, scaled to show it.

    The vehicle's perceived motion stays on ``ax`` (left); the rider's is often a few per
    cent of it and would be a flat line on that scale. The right axis spans the riders'
    99.5th percentile of ``|value|`` (at least twice the threshold ``thr``; brief spikes,
    e.g. of clamping, may leave the panel) symmetrically, and the left axis the vehicle's
    largest ``|value|``, so that zero is at the same height on both; when the rider's motion
    is at least half the vehicle's, both share the left axis's limits. Returns the right
    axis (draw the riders and the threshold band on it).
    """
    veh = np.asarray(vehicle, dtype=float)
    v_peak = float(np.max(np.abs(veh), initial=0.0))
    arrays = [np.abs(np.asarray(r, dtype=float)) for r in riders]
    r_peak = max([float(np.percentile(a, 99.5)) for a in arrays if a.size] + [2.0 * thr])
    left = 1.08 * max(v_peak, r_peak)
    right = left if r_peak >= 0.5 * v_peak else 1.08 * r_peak
    ax.set_ylim(-left, left)
    twin = ax.twinx()
    twin.set_ylim(-right, right)
    return twin


def plot_title(
    evaluation: CueingEvaluation,
    *,
    title: str = "",
    preset: str | None = None,
    platform: str | None = None,
) -> str:
    """The plot's title: ``title``, then preset, platform and vestibular model set."""
    what = (
        f"preset {preset or 'not given'} | "
        f"platform {platform or 'none (washout poses, no platform limits)'} | "
        f"vestibular models {evaluation.model_set}"
    )
    return f"{title}\n{what}" if title else what


def plot_cueing(
    evaluation: CueingEvaluation,
    poses: ArrayLike,
    path: str | Path,
    *,
    t_s: ArrayLike | None = None,
    title: str = "",
    preset: str | None = None,
    platform: str | None = None,
) -> Path:
    """Write a PNG: vehicle vs simulator perceived motion per axis, the poses, the metrics.

    Vehicle lines are solid dark grey on the left axis, simulator lines dashed red on the
    right axis, scaled to show the rider's cue (:func:`rider_axis`; zero at the same height,
    the rendered share in the legend), the grey band is the axis's perception threshold (on
    the right axis); angular channels are shown in deg/s. The metrics table
    with its notes (units, column meanings, the otolith gain convention) is printed under
    the plots.

    Parameters
    ----------
    evaluation : CueingEvaluation
    poses : (N, 6) array_like
        Platform poses (m, rad).
    path
        Output file (PNG).
    t_s : (N,) array_like, optional
        Sample times; ``k / fs`` otherwise.
    title : str
        First title line (e.g. the recording).
    preset, platform : str, optional
        Named in the title with the vestibular model set.

    Returns
    -------
    Path
        The file written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    p = np.asarray(poses, dtype=float)
    n = p.shape[0]
    t = np.arange(n) / evaluation.fs_hz if t_s is None else np.asarray(t_s, dtype=float)
    fig = plt.figure(figsize=(13, 20), layout="constrained")
    grid = fig.add_gridspec(5, 2, height_ratios=[1, 1, 1, 1, 2.0])
    share = evaluation.metrics.rendered_share
    for i, name in enumerate(AXIS_NAMES):
        ax = fig.add_subplot(grid[i % 3, i // 3])
        k = 180.0 / math.pi if i >= 3 else 1.0
        thr = float(evaluation.thresholds[i]) * k
        veh, sim = evaluation.perceived_vehicle[:, i] * k, evaluation.perceived_sim[:, i] * k
        right = rider_axis(ax, veh, [sim], thr)
        band = right.axhspan(-thr, thr, color="0.85", lw=0, zorder=0)
        (lv,) = ax.plot(t, veh, color="0.15", lw=1.6, label="vehicle")
        (ls,) = right.plot(t, sim, color="tab:red", lw=1.0, ls="--", label="simulator")
        ax.set_ylabel(f"vehicle, perceived {name} [{_UNITS[i]}]")
        right.set_ylabel(f"simulator [{_UNITS[i]}]", color="tab:red")
        right.tick_params(axis="y", colors="tab:red")
        if i % 3 == 2:
            ax.set_xlabel("t [s]")
        ax.grid(alpha=0.3)
        sh = f"{share[i]:.0%}" if math.isfinite(share[i]) else "-"
        ax.legend(
            [lv, ls, band],
            ["vehicle (left axis)", f"simulator (right axis; rendered share {sh})",
             f"threshold ±{thr:.2g} {_UNITS[i]} (right axis)"],
            loc="upper right", fontsize=8,
        )  # fmt: skip
    ax = fig.add_subplot(grid[3, 0])
    for j, name in enumerate(("x", "y", "z")):
        ax.plot(t, p[:, j] * 1e3, label=name, lw=1.0)
    ax.set_ylabel("platform translation [mm]")
    ax.set_xlabel("t [s]")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    ax = fig.add_subplot(grid[3, 1])
    for j, name in enumerate(("roll", "pitch", "yaw")):
        ax.plot(t, np.degrees(p[:, 3 + j]), label=name, lw=1.0)
    ax.set_ylabel("platform rotation [deg]")
    ax.set_xlabel("t [s]")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    ax = fig.add_subplot(grid[4, :])
    ax.axis("off")
    ax.text(0.0, 1.0, evaluation.summary(), family="monospace", va="top", fontsize=9)
    fig.suptitle(plot_title(evaluation, title=title, preset=preset, platform=platform))
    out = Path(path)
    try:
        fig.savefig(out, dpi=90)
    except OSError as exc:
        raise ConfigError(f"{out}: cannot write plot: {exc}") from exc
    finally:
        plt.close(fig)
    return out
