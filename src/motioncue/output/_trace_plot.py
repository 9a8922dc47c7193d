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
        Drawn as red marks at their time on their axis (or on every axis).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    n = trace.positions.shape[1] if trace.positions.ndim == 2 else 0
    fig, axes = plt.subplots(
        max(n, 1), 1, sharex=True, figsize=(9, 1.6 * max(n, 1) + 0.8), squeeze=False
    )
    for i in range(n):
        ax = axes[i, 0]
        ax.step(trace.t_s, trace.positions[:, i], where="post", lw=1.0)
        ax.set_ylabel(f"axis {i}\n[pulses]")
        ax.grid(True, alpha=0.3)
        for v in violations:
            if v.axis is None or v.axis == i:
                ax.axvline(v.t_s, color="red", alpha=0.4, lw=0.8)
    axes[-1, 0].set_xlabel("controller playback time [s]")
    fig.suptitle(
        title or f"commanded positions, {len(trace)} frames, {len(violations)} violation(s) (red)"
    )
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
