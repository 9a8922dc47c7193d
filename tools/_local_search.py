"""The (1+2) random local search the classical strength searches share (tools only).

Each round perturbs 1..``k_max - 1`` coordinates of the best point by normal steps of
``sigma`` (in the searches' log space), clips to ``[lo, hi]``, evaluates two such candidates
and keeps the better when it is no worse than the best, until ``budget_s`` of wall time.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import TypeVar

import numpy as np

R = TypeVar("R")


def one_plus_two(
    evaluate: Callable[[np.ndarray], tuple[float, R]],
    x0: np.ndarray,
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    seed: int,
    budget_s: float,
    k_max: int,
    sigma: float,
    on_better: Callable[[int, float, float, np.ndarray, R], None],
) -> tuple[np.ndarray, float, R]:
    """Minimise ``evaluate(x)[0]``; ``on_better(it, elapsed_s, fit, x, extra)`` on each kept
    step. Returns the best point, its fitness and its ``extra``."""
    rng = np.random.default_rng(seed)
    t0 = time.time()
    best = x0.copy()
    fit, extra = evaluate(best)
    it = 0
    while time.time() - t0 < budget_s:
        it += 1
        cands = []
        for _ in range(2):
            x = best.copy()
            k = int(rng.integers(1, k_max))
            idx = rng.choice(len(x), size=k, replace=False)
            x[idx] += rng.normal(0.0, sigma, size=k)
            x = np.clip(x, lo, hi)
            f, r = evaluate(x)
            cands.append((f, x, r))
        f, x, r = min(cands, key=lambda c: c[0])
        if f <= fit:
            best, fit, extra = x, f, r
            on_better(it, time.time() - t0, fit, best, extra)
    return best, fit, extra
