"""A short excerpt of the bundled lap recording (``configs/recordings/lap.csv``) as a CSV file.

Shared by the tests that need a few seconds of real driving (``test_compare``,
``test_view_vehicle``) so the excerpt is cut the same way everywhere.
"""

from __future__ import annotations

import csv
from pathlib import Path

LAP = Path(__file__).resolve().parents[1] / "configs" / "recordings" / "lap.csv"


def lap_excerpt(path: Path, start: int, n: int) -> Path:
    """Write ``n`` samples of the bundled lap from sample ``start`` to ``path``, times from zero.

    Parameters
    ----------
    path : Path
        The CSV file to write (same header as the lap).
    start : int
        Index of the first data row taken (0: the lap's first sample).
    n : int
        Number of data rows taken.

    Returns
    -------
    Path
        ``path``.
    """
    with open(LAP, newline="") as fh:
        rows = list(csv.reader(fh))
    head, body = rows[0], rows[1 + start : 1 + start + n]
    t0 = float(body[0][0])
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(head)
        for r in body:
            w.writerow([f"{float(r[0]) - t0:.6f}", *r[1:]])
    return path
