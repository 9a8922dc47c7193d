"""Plots of limited rides: desired vs limited positions, and the speed/acceleration used."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ._limits import ActuatorLimits, finite_differences

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["plot_ride"]


def plot_ride(
    q_desired: ArrayLike,
    q_limited: ArrayLike,
    dt_s: float,
    limits: ActuatorLimits,
    path: str | Path,
    *,
    q_realtime: ArrayLike | None = None,
    title: str = "",
) -> Path:
    """Write a PNG: per actuator, position (desired, limited, optional real-time limiter)
    with the stroke, and speed and acceleration as fractions of their limits.

    Parameters
    ----------
    q_desired, q_limited : array_like, (N, n)
        Desired and limited actuator positions (SI).
    dt_s : float
        Frame period (s).
    limits : ActuatorLimits
    path : str or Path
        Output PNG file.
    q_realtime : array_like, (N, n), optional
        The real-time limiter's output on the same input, for comparison.

    Returns
    -------
    Path of the written file.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    qd = np.asarray(q_desired, dtype=float)
    ql = np.asarray(q_limited, dtype=float)
    n = ql.shape[1]
    t = np.arange(ql.shape[0]) * dt_s
    v, a, _ = finite_differences(ql, dt_s)
    fig, axes = plt.subplots(n, 2, figsize=(12, 2.2 * n), sharex=True, squeeze=False)
    for i in range(n):
        ax = axes[i, 0]
        f = 1e3 if limits.kinds[i] == "linear" else 180.0 / np.pi
        unit = "mm" if limits.kinds[i] == "linear" else "deg"
        ax.plot(t, qd[:, i] * f, color="0.6", lw=0.8, label="desired")
        if q_realtime is not None:
            qr = np.asarray(q_realtime, dtype=float)
            ax.plot(t, qr[:, i] * f, color="tab:orange", lw=0.8, label="real-time limiter")
        ax.plot(t, ql[:, i] * f, color="tab:blue", lw=1.0, label="limited")
        for lim in (limits.q_min[i], limits.q_max[i]):
            ax.axhline(lim * f, color="tab:red", lw=0.6, ls="--")
        ax.set_ylabel(f"{limits.names[i]} ({unit})")
        span = (limits.q_max[i] - limits.q_min[i]) * f
        ax.set_ylim(limits.q_min[i] * f - 0.3 * span, limits.q_max[i] * f + 0.3 * span)
        ax2 = axes[i, 1]
        ax2.plot(t[1:], v[:, i] / limits.v_max[i], color="tab:green", lw=0.8, label="speed / v_max")
        ax2.plot(
            t[2:], a[:, i] / limits.a_max[i], color="tab:purple", lw=0.8, label="accel / a_max"
        )
        ax2.axhline(1.0, color="tab:red", lw=0.6, ls="--")
        ax2.axhline(-1.0, color="tab:red", lw=0.6, ls="--")
        ax2.set_ylim(-1.2, 1.2)
    axes[0, 0].legend(loc="upper right", fontsize=7)
    axes[0, 1].legend(loc="upper right", fontsize=7)
    axes[-1, 0].set_xlabel("time (s)")
    axes[-1, 1].set_xlabel("time (s)")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=90)
    plt.close(fig)
    return out
