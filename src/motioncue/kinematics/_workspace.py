"""Workspace: the reachable range of each pose component alone, and a plot of it.

A component's range is found along that component with the others at zero: an outward march
from the neutral pose on :meth:`Platform.check` to the first failing sample, then bisection, so
it is the range connected to neutral (features narrower than a march step can be missed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from ._platform import DOF_NAMES, Platform

__all__ = ["WorkspaceRanges", "dof_ranges", "plot_workspace"]

_MARCH = 720  # outward samples before bisection: 1.4 mm / 0.5 deg steps
_SEARCH = np.array([1.0, 1.0, 1.0, 2 * math.pi, 2 * math.pi, 2 * math.pi])  # m, rad


@dataclass(frozen=True)
class WorkspaceRanges:
    """Range of each pose component alone.

    Attributes
    ----------
    lower, upper
        ``(6,)`` most negative / positive value reachable (m, rad); 0 for components the
        machine does not produce.
    supported
        ``(6,)`` bool, the platform's ``dof_mask``.
    capped
        ``(6, 2)`` bool: the search bound (1 m, 2 pi rad) was reached, the true range is wider.
    """

    lower: np.ndarray
    upper: np.ndarray
    supported: np.ndarray
    capped: np.ndarray

    def as_dict(self) -> dict[str, dict[str, float | bool]]:
        """``{dof: {"min": .., "max": .., "unit": ..}}`` in mm and degrees, for humans/JSON."""
        out: dict[str, dict[str, float | bool]] = {}
        for k, name in enumerate(DOF_NAMES):
            scale = 1e3 if k < 3 else 180.0 / math.pi
            out[name] = {
                "min": float(self.lower[k] * scale),
                "max": float(self.upper[k] * scale),
                "supported": bool(self.supported[k]),
            }
        return out


def dof_ranges(platform: Platform, *, iterations: int = 40) -> WorkspaceRanges:
    """Reachable range of each pose component alone, by bisection on ``platform.check``.

    Parameters
    ----------
    platform
        The machine.
    iterations
        Bisection steps after the outward march (40 resolve a step below 1e-14).

    Returns
    -------
    WorkspaceRanges
    """
    dirs = np.concatenate([-np.eye(6), np.eye(6)]) * _SEARCH  # (12, 6): bound per direction
    # March outwards from neutral to the first failing sample (angles are periodic, so the
    # bound itself may be "reachable" again), then bisect between it and the last good one.
    fractions = np.linspace(0.0, 1.0, _MARCH + 1)[1:]
    ok = platform.check(dirs[:, None, :] * fractions[None, :, None]).ok  # (12, _MARCH)
    first_bad = np.where(ok.all(axis=1), _MARCH, np.argmin(ok, axis=1))
    at_bound = first_bad == _MARCH
    lo = np.where(first_bad > 0, fractions[np.maximum(first_bad - 1, 0)], 0.0)
    lo[at_bound] = 1.0
    hi = np.where(at_bound, 1.0, fractions[np.minimum(first_bad, _MARCH - 1)])
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        good = platform.check(dirs * mid[:, None]).ok
        lo = np.where(good, mid, lo)
        hi = np.where(good, hi, mid)
    mask = platform.dof_mask
    reach = lo * np.concatenate([_SEARCH, _SEARCH])
    lower = np.where(mask, -reach[:6], 0.0)
    upper = np.where(mask, reach[6:], 0.0)
    capped = np.stack([at_bound[:6], at_bound[6:]], axis=1) & mask[:, None]
    return WorkspaceRanges(lower=lower, upper=upper, supported=mask.copy(), capped=capped)


def _slice(
    platform: Platform, a: int, b: int, ra: float, rb: float, n: int = 121
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.bool_]]:
    xs = np.linspace(-ra, ra, n)
    ys = np.linspace(-rb, rb, n)
    grid = np.zeros((n, n, 6))
    grid[:, :, a] = xs[None, :]
    grid[:, :, b] = ys[:, None]
    return xs, ys, platform.check(grid).ok


def plot_workspace(
    platform: Platform, path: str | Path, ranges: WorkspaceRanges | None = None
) -> Path:
    """Save a PNG: the range of each component alone, and two-component slices.

    Parameters
    ----------
    platform
        The machine.
    path
        Output file (``.png``).
    ranges
        Precomputed :func:`dof_ranges`; computed when None.

    Returns
    -------
    Path
        The file written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ranges = ranges or dof_ranges(platform)
    mask = platform.dof_mask
    pairs = [(3, 4)]  # roll-pitch: every bundled machine tilts
    if mask[0] and mask[1]:
        pairs.insert(0, (0, 1))
    elif mask[2]:
        pairs.insert(0, (2, 4))
    elif mask[5]:
        pairs.append((4, 5))
    groups = [g for g in ((0, 1, 2), (3, 4, 5)) if any(mask[k] for k in g)]
    n_panels = len(groups) + len(pairs)
    fig, axes = plt.subplots(1, n_panels, figsize=(4.2 * n_panels, 4.2))
    for bar, group in zip(axes, groups, strict=False):
        scale, unit = (1e3, "mm") if group[0] < 3 else (180.0 / math.pi, "deg")
        ks = [k for k in group if mask[k]]
        lows = np.array([ranges.lower[k] * scale for k in ks])
        highs = np.array([ranges.upper[k] * scale for k in ks])
        ypos = np.arange(len(ks))
        bar.barh(ypos, highs - lows, left=lows, color="tab:blue", alpha=0.7)
        for y, lo_v, hi_v in zip(ypos, lows, highs, strict=True):
            bar.text(lo_v, y, f"{lo_v:.1f} ", ha="right", va="center", fontsize=8)
            bar.text(hi_v, y, f" {hi_v:.1f}", ha="left", va="center", fontsize=8)
        span = max(float(np.max(np.abs(np.concatenate([lows, highs])))), 1e-9)
        bar.set_xlim(-1.45 * span, 1.45 * span)
        bar.axvline(0.0, color="k", lw=0.8)
        bar.set_yticks(ypos, [DOF_NAMES[k] for k in ks])
        bar.set_xlabel(unit)
        bar.set_title("range of each alone")
        bar.grid(True, axis="x", alpha=0.3)
    axes = axes[len(groups) :]
    for ax, (a, b) in zip(axes, pairs, strict=True):
        sa = 1e3 if a < 3 else 180.0 / math.pi
        sb = 1e3 if b < 3 else 180.0 / math.pi
        ra = 1.2 * max(-ranges.lower[a], ranges.upper[a], 1e-6)
        rb = 1.2 * max(-ranges.lower[b], ranges.upper[b], 1e-6)
        xs, ys, ok = _slice(platform, a, b, ra, rb)
        ax.contourf(xs * sa, ys * sb, ok.astype(float), levels=[0.5, 1.5], colors=["tab:green"])
        ax.contour(xs * sa, ys * sb, ok.astype(float), levels=[0.5], colors="k", linewidths=0.8)
        ua = "mm" if a < 3 else "deg"
        ub = "mm" if b < 3 else "deg"
        ax.set_xlabel(f"{DOF_NAMES[a]} ({ua})")
        ax.set_ylabel(f"{DOF_NAMES[b]} ({ub})")
        ax.set_title(f"reachable {DOF_NAMES[a]}-{DOF_NAMES[b]} (others 0)")
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"{platform.name}: workspace")
    fig.tight_layout()
    out = Path(path)
    fig.savefig(out, dpi=100)
    plt.close(fig)
    return out
