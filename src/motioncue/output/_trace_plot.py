"""A picture of what an emulated controller was told to do."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from ._udp_emulator import Trace, Violation

__all__ = ["plot_trace"]


def plot_trace(
    trace: Trace, path: str | Path, *, violations: Sequence[Violation] = (), title: str = ""
) -> Path:
    """Write a PNG of the commanded positions per axis against time, violations marked.

    Parameters
    ----------
    trace : Trace
        ``t_s`` (N,) and ``positions`` (N, n_axes) in pulses.
    path : path
        PNG file to write.
    violations : sequence of Violation
        Drawn as red crosses at their time on their axis (one collection per axis), a
        violation of no particular axis as a red vertical line on every axis.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    n = trace.positions.shape[1] if trace.positions.ndim == 2 else 0
    fig, axes = plt.subplots(
        max(n, 1), 1, sharex=True, figsize=(9, 1.6 * max(n, 1) + 0.8), squeeze=False
    )
    t_all = np.array([v.t_s for v in violations], dtype=float)
    on_axis = np.array([-1 if v.axis is None else v.axis for v in violations], dtype=int)
    t_trace = np.asarray(trace.t_s, dtype=float)
    for i in range(n):
        ax = axes[i, 0]
        ax.step(t_trace, trace.positions[:, i], where="post", lw=1.0, label="commanded")
        # axes are numbered from 1, as the controllers' manuals number them
        ax.set_ylabel(f"axis {i + 1}\n[pulses]")
        ax.grid(True, alpha=0.3)
        mine = t_all[on_axis == i]
        if mine.size and t_trace.size:
            # one marker per violation, at the commanded position then (one collection)
            k = np.clip(np.searchsorted(t_trace, mine, side="right") - 1, 0, t_trace.size - 1)
            ax.scatter(
                mine, trace.positions[k, i], marker="x", s=18, color="red", zorder=3,
                label="violation on this axis",
            )  # fmt: skip
        common = t_all[on_axis < 0]
        if common.size:
            ax.vlines(
                np.unique(common), 0, 1, transform=ax.get_xaxis_transform(), color="red",
                alpha=0.4, lw=0.8, label="violation of the whole frame",
            )  # fmt: skip
        if mine.size or common.size:
            ax.legend(loc="upper right", fontsize=7)
    axes[-1, 0].set_xlabel("controller playback time [s]")
    fig.suptitle(
        title or f"commanded positions, {len(trace)} frames, {len(violations)} violation(s) (red)"
    )
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
