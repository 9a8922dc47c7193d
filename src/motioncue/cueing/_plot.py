"""One-page plot of a cueing run: perceived motion, poses and metrics (matplotlib, Agg)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._errors import ConfigError
from ._evaluate import AXIS_NAMES, CueingEvaluation

__all__ = ["plot_cueing", "plot_title"]

_UNITS = ("m/s²", "m/s²", "m/s²", "deg/s", "deg/s", "deg/s")


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

    Vehicle lines are solid dark grey, simulator lines dashed red, the grey band is the
    axis's perception threshold; angular channels are shown in deg/s. The metrics table
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
    for i, name in enumerate(AXIS_NAMES):
        ax = fig.add_subplot(grid[i % 3, i // 3])
        k = 180.0 / math.pi if i >= 3 else 1.0
        thr = float(evaluation.thresholds[i]) * k
        ax.axhspan(-thr, thr, color="0.85", lw=0, label=f"threshold ±{thr:.2g} {_UNITS[i]}")
        ax.plot(t, evaluation.perceived_vehicle[:, i] * k, color="0.15", lw=1.6, label="vehicle")
        ax.plot(
            t,
            evaluation.perceived_sim[:, i] * k,
            color="tab:red",
            lw=1.0,
            ls="--",
            label="simulator",
        )
        ax.set_ylabel(f"perceived {name} [{_UNITS[i]}]")
        if i % 3 == 2:
            ax.set_xlabel("t [s]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper right", fontsize=8)
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
