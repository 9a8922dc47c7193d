"""One actuator window of the offline ride problem as a sparse convex QP (casadi ``conic``).

The window problem of :mod:`motioncue.trajectory._offline` in scaled units (one unit = full
acceleration for one frame)::

    minimise    1/2 sum_k w[k] (x[k] - xd[k])**2
    subject to  lo <= x[k] <= hi,  |D1 x| <= vb,  |D2 x| <= ab  (|D3 x| <= jb)

where ``Dm`` are the backward differences of order ``m`` over ``[hist, x, tail]``: ``hist``
are the fixed frames before the window (2, or 3 with a jerk limit) and ``tail`` the fixed
frames after it (present when the window joins desired frames that are kept; then the
differences that reach into the tail are constraints too). The difference matrix is constant,
so each solver is built once per ``(length, has_tail)`` and reused; only the bounds, ``w``
and ``xd`` change between calls. The fixed frames enter as constants moved into the row
bounds: ``lba = -b - c``, ``uba = b - c`` with ``c`` the fixed frames' part of each row.

The solver is PIQP (a proximal interior-point method bundled with casadi): the problem is
convex and sparse (banded), so an interior-point method with a sparse factorisation solves
it to high accuracy in time linear in the window length, without the per-call overhead of
a general nonlinear solver.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, NamedTuple

import numpy as np

if TYPE_CHECKING:
    from scipy.sparse import csc_matrix

__all__ = ["PIQP_OPTIONS", "PIQP_OPTIONS_LOOSE", "ConicChunkSolver", "difference_rows"]

_COEF = {1: (1.0, -1.0), 2: (1.0, -2.0, 1.0), 3: (1.0, -3.0, 3.0, -1.0)}

# PIQP tolerances (scaled units, where the acceleration bound is 1): far inside the solver's
# limit tightening (1e-7 relative), so the exact repair pass normally changes nothing
PIQP_OPTIONS: dict[str, float | bool] = {
    "eps_abs": 1e-10,
    "eps_rel": 1e-12,
    "eps_duality_gap_abs": 1e-10,
    "eps_duality_gap_rel": 1e-12,
    "max_iter": 250,
    "verbose": False,
}
# PIQP's own default tolerances: the second attempt for a window whose numbers are so large
# (short frame periods make the scaled positions large) that the tight ones are below
# round-off and the solver stops at its iteration limit
PIQP_OPTIONS_LOOSE: dict[str, float | bool] = {
    **PIQP_OPTIONS,
    "eps_abs": 1e-8,
    "eps_rel": 1e-9,
    "eps_duality_gap_abs": 1e-8,
    "eps_duality_gap_rel": 1e-9,
}


class Window(NamedTuple):
    """One window of one actuator's ride problem, in scaled units: what a window solver
    (:class:`ConicChunkSolver`, ``_offline._ChunkSolver``) solves.

    Attributes
    ----------
    xd, w : ndarray, (L,)
        Target frames and weights (``w >= 0``).
    hist : ndarray, (h,)
        Fixed frames before the window, oldest first.
    tail : ndarray, (h,) or None
        Fixed frames after the window (required iff the solver was built with a tail).
    bounds : tuple of float
        ``(lo, hi, vb, ab, jb)``: stroke bounds and the bounds of the 1st/2nd/3rd
        differences.
    x_init : ndarray, (L,)
        Starting point (clipped into the stroke).
    """

    xd: np.ndarray
    w: np.ndarray
    hist: np.ndarray
    tail: np.ndarray | None
    bounds: tuple[float, float, float, float, float]
    x_init: np.ndarray


def difference_rows(length: int, jerk: bool, tail: bool) -> tuple[csc_matrix, np.ndarray]:
    """Difference rows over the stacked frames ``[hist (h), x (length), tail (h)]``.

    Parameters
    ----------
    length : int
        Window length ``L`` (frames).
    jerk : bool
        Include the third differences (then ``h = 3``, else ``h = 2``).
    tail : bool
        Include the rows that reach into the fixed tail frames.

    Returns
    -------
    M : scipy.sparse.csc_matrix, (m, h + L + h)
        One row per constraint: first differences, then second, then (jerk) third.
    order : ndarray of int, (m,)
        Difference order (1, 2 or 3) of each row.
    """
    import scipy.sparse as sps

    h = 3 if jerk else 2
    rows, cols, vals, orders = [], [], [], []
    r0 = 0
    for o in (1, 2, 3) if jerk else (1, 2):
        k = np.arange(length + (o if tail else 0))  # frame of each row (window index)
        for j, c in enumerate(_COEF[o]):
            rows.append(r0 + k)
            cols.append(h + k - j)
            vals.append(np.full(k.size, c))
        orders.append(np.full(k.size, o))
        r0 += k.size
    M = sps.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(r0, h + length + h),
    )
    M.sort_indices()
    return M, np.concatenate(orders)


class ConicChunkSolver:
    """Sparse QP (casadi ``conic``, PIQP) for one actuator window of fixed length.

    Parameters
    ----------
    length : int
        Window length ``L`` (frames).
    jerk : bool
        Whether the third differences are constrained.
    tail : bool
        Whether the window joins fixed frames after it (a ``tail`` is then required by
        :meth:`solve`).
    loose : bool
        Use PIQP's default tolerances (:data:`PIQP_OPTIONS_LOOSE`) instead of the tight
        ones (:data:`PIQP_OPTIONS`).
    """

    def __init__(self, length: int, jerk: bool, tail: bool, loose: bool = False) -> None:
        import casadi as ca
        import scipy.sparse as sps

        M, order = difference_rows(length, jerk, tail)
        h = 3 if jerk else 2
        self.length = length
        self.jerk = jerk
        self.tail = tail
        self.loose = loose
        self.h = h
        self._order = order
        self._M_hist = M[:, :h]
        self._M_tail = M[:, h + length :]
        A = sps.csc_matrix(M[:, h : h + length])
        A.sort_indices()  # casadi's Sparsity wants sorted row indices per column
        a_sp = ca.Sparsity(A.shape[0], A.shape[1], A.indptr.tolist(), A.indices.tolist())
        self._a = ca.DM(a_sp, A.data)
        self._h_sp = ca.Sparsity.diag(length)
        self._dm = ca.DM
        self.solver = ca.conic(
            "ride_chunk_qp",
            "piqp",
            {"h": self._h_sp, "a": a_sp},
            {"piqp": dict(PIQP_OPTIONS_LOOSE if loose else PIQP_OPTIONS), "error_on_fail": False},
        )

    def solve(self, win: Window) -> tuple[np.ndarray, bool]:
        """Solve one window.

        Returns
        -------
        x : ndarray, (L,)
            Solution (finite only if the solver returned finite numbers: check ``ok``).
        ok : bool
            The solver reported success and every value is finite.
        """
        xd, w, hist, tail, bounds, x_init = win
        if (tail is not None) != self.tail:
            raise ValueError("tail given to a solver built without one (or missing)")
        lo_x, hi_x, vb, ab, jb = bounds
        b = np.choose(self._order - 1, [vb, ab, jb])
        c = self._M_hist @ hist
        if tail is not None:
            c = c + self._M_tail @ tail
        L = self.length
        r = self.solver(
            h=self._dm(self._h_sp, w),
            g=-w * xd,
            a=self._a,
            lba=-b - c,
            uba=b - c,
            lbx=np.full(L, lo_x),
            ubx=np.full(L, hi_x),
            x0=np.clip(x_init, lo_x, hi_x),
        )
        x = np.asarray(r["x"], dtype=float).reshape(L)
        ok = bool(self.solver.stats().get("success", False)) and bool(np.all(np.isfinite(x)))
        return x, ok
