"""Shared timing helpers for the benchmark scripts: medians over repeats, and one line each.

Every figure is printed with its target, the ratio to the target (>= 1 meets it) and the same
figure in units of a *reference loop* timed in the same process (:func:`reference_loop_s`: a
fixed piece of Python and numpy work): a figure that is slow only because the machine is
busy or slow moves with the reference, one that regressed does not. A missed target makes
:func:`report` return False; each script exits non-zero when any of its figures missed
(``benchmarks/run.py`` then exits non-zero too).
"""

from __future__ import annotations

import functools
import statistics
import time
from collections.abc import Callable

import numpy as np

# seconds per unit, for the figures given as a time
_TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
# items per second, for the figures given as a rate
_RATE_UNITS = ("/s", "per s")


def median_time_s(fn: Callable[[], object], repeats: int = 7, number: int = 1) -> float:
    """Median wall time of ``number`` calls of ``fn``, over ``repeats`` runs, per call (s)."""
    fn()  # warm up
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return statistics.median(times)


def _reference_work() -> float:
    acc = 0.0
    for k in range(20_000):  # interpreter work, like the per-frame Python of the loops
        acc += (k % 7) * 0.5
    a = np.arange(40_000, dtype=float)
    for _ in range(10):  # numpy work on arrays, like the batch stages
        acc += float(np.sum(np.sin(a) * a))
    return acc


@functools.cache
def reference_loop_s() -> float:
    """Median wall time (s) of the fixed reference work in this process (11 runs, cached)."""
    t = median_time_s(_reference_work, repeats=11)
    print(
        f"reference loop (fixed Python + numpy work, this process): {t * 1e3:.2f} ms median "
        "of 11; 'ref' columns give each figure in units of it",
        flush=True,
    )
    return t


def in_reference_units(value: float, unit: str) -> str:
    """``value`` (in ``unit``) as reference loops per item (times) or items per reference loop
    (rates); empty when the unit is neither."""
    ref = reference_loop_s()
    per = unit.split("/", 1)[0]  # "us/frame": a time per item
    if per in _TIME_UNITS:
        return f"{value * _TIME_UNITS[per] / ref:8.3g} ref"
    if unit.endswith(_RATE_UNITS):
        return f"{value * ref:8.3g} /ref"
    return ""


def report(
    name: str,
    value: float,
    unit: str,
    target: float,
    higher_is_better: bool,
    reference: str | None = None,
) -> bool:
    """Print one figure with its target, the ratio (>= 1 means the target is met) and the
    figure against the reference loop; return whether the target is met.

    Parameters
    ----------
    name : str
        What is measured.
    value, target : float
        The figure (a median) and its target, in ``unit``.
    unit : str
        ``s``, ``ms``, ``us`` (or per item, ``us/frame``) or a rate (``.../s``); other units
        (ratios, ``x``) get no reference column.
    higher_is_better : bool
        True for rates (target is a minimum), False for times (target is a maximum).
    reference : str, optional
        The reference column as the caller measured it (e.g. a bare timer loop's jitter);
        default: :func:`in_reference_units`.
    """
    if higher_is_better:
        ratio = value / target
    else:
        ratio = target / value if value != 0 else float("inf")
    ok = bool(ratio >= 1.0)  # NaN (no figure) is a miss
    sign = ">=" if higher_is_better else "<="
    ref = in_reference_units(value, unit) if reference is None else reference
    print(
        f"{name:<48s} {value:>12.4g} {unit:<10s} target {sign} {target:<10.4g} "
        f"ratio {ratio:6.2f}  {'OK' if ok else 'MISS'}  {ref}",
        flush=True,
    )
    return ok
