"""Compare numeric CSV text written from floating point, to the precision it was written with.

A value computed on another machine (another libm, BLAS or numpy build, another CPU's SIMD
path) may differ from ours in its last bits; written with ``d`` decimals, the two texts then
differ by one unit in the ``d``-th decimal whenever the two floats straddle a rounding boundary
(``10.676713`` against ``10.676712``). Text is therefore compared as numbers, with

    |got - want| <= 10**-d + RTOL * |want|

per cell, ``d`` the decimals the committed text shows in that cell: one unit in the last
written place (two roundings of nearly equal numbers on either side of a boundary), plus a
relative ``RTOL`` for the floats' own difference between builds and for reading decimal text
into binary. A generator that changes a value by two units in the last written place or more,
or writes another number of decimals, rows or columns, is still caught.
"""

from __future__ import annotations

import numpy as np

# Relative difference allowed between the floats of two builds before rounding: far above
# the ulp-level differences of libm/SIMD paths (1e-16, or 1e-12 after 1e4 accumulated
# steps), far below one unit of the 6th decimal of any value the recordings hold (< 1e3).
RTOL = 1e-9


def _table(text: str) -> tuple[list[str], list[str], list[int]]:
    """Header, all data cells (row-major) and the number of cells of each data row."""
    lines = text.splitlines()
    assert lines, "empty CSV text"
    rows = [ln.split(",") for ln in lines[1:]]
    return lines[0].split(","), [c for r in rows for c in r], [len(r) for r in rows]


def _decimals(cells: list[str]) -> np.ndarray:
    return np.array([len(c) - c.index(".") - 1 if "." in c else 0 for c in cells])


def csv_text_mismatch(got: str, want: str, rtol: float = RTOL) -> str | None:
    """Why ``got`` is not ``want`` to the precision ``want`` is written with (None: it is).

    Parameters
    ----------
    got, want : str
        CSV texts: one header line, then rows of decimal numbers (no exponents).
    rtol : float
        Relative tolerance for the floats' own difference (see the module docstring).

    Returns
    -------
    str or None
        The first difference found, in words, or None when the texts agree: same header,
        same shape, the same number of decimals in every cell, and every value within one
        unit in its last written place plus ``rtol`` relative.
    """
    head_g, cells_g, widths_g = _table(got)
    head, cells_w, widths_w = _table(want)
    if head_g != head:
        return f"header {head_g} != {head}"
    if widths_g != widths_w:
        return f"rows of {sorted(set(widths_g))} cells != rows of {sorted(set(widths_w))}"

    def where(k: int) -> str:
        row, col = divmod(k, len(head))
        return f"row {row + 1}, {head[col]}: {cells_g[k]} vs {cells_w[k]}"

    dec_w = _decimals(cells_w)
    shape = np.flatnonzero(_decimals(cells_g) != dec_w)
    if shape.size:
        return f"{shape.size} values not written like the others; first: {where(shape[0])}"
    g = np.array(cells_g, dtype=float)
    w = np.array(cells_w, dtype=float)
    bad = np.flatnonzero(np.abs(g - w) > 10.0 ** -dec_w.astype(float) + rtol * np.abs(w))
    if bad.size:
        return (
            f"{bad.size} values differ by more than one unit in their last written place; "
            f"first: {where(bad[0])}"
        )
    return None
