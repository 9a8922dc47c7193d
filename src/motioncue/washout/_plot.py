"""One-page plot of a cueing run: perceived motion, poses and metrics (matplotlib, Agg)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._errors import ConfigError
from ._evaluate import AXIS_NAMES, CueingEvaluation

__all__ = ["plot_cueing"]

_UNITS = ("m/s²", "m/s²", "m/s²", "deg/s", "deg/s", "deg/s")


def plot_cueing(
    evaluation: CueingEvaluation,
    poses: ArrayLike,
    path: str | Path,
    *,
    t_s: ArrayLike | None = None,
    title: str = "",
) -> Path:
    """Write a PNG: vehicle vs simulator perceived motion per axis, the poses, the metrics.

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
    fig = plt.figure(figsize=(13, 15), layout="constrained")
    grid = fig.add_gridspec(5, 2, height_ratios=[1, 1, 1, 1, 0.9])
    for i, name in enumerate(AXIS_NAMES):
        ax = fig.add_subplot(grid[i % 3, i // 3])
        k = 180.0 / math.pi if i >= 3 else 1.0
        ax.plot(t, evaluation.perceived_vehicle[:, i] * k, label="vehicle", lw=1.0)
        ax.plot(t, evaluation.perceived_sim[:, i] * k, label="simulator", lw=1.0)
        ax.set_ylabel(f"perceived {name} [{_UNITS[i]}]")
        ax.grid(alpha=0.3)
        if i == 0:
            ax.legend(loc="upper right")
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
    ax.text(0.0, 1.0, evaluation.summary(), family="monospace", va="top", fontsize=10)
    if title:
        fig.suptitle(title)
    out = Path(path)
    try:
        fig.savefig(out, dpi=90)
    except OSError as exc:
        raise ConfigError(f"{out}: cannot write plot: {exc}") from exc
    finally:
        plt.close(fig)
    return out
