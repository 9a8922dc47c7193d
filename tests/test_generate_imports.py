"""What ``motioncue generate`` imports: toppra without matplotlib.pyplot until pyplot is used.

toppra imports ``matplotlib.pyplot`` when it is imported (plotting helpers generate never
calls); :func:`motioncue.trajectory._transition._defer_pyplot`, called where toppra is
imported, puts a placeholder in its place, which imports the real module at the first use of
one of its attributes; setting or deleting an attribute through it reaches the real module
(tests/test_cli_defects.py monkeypatches ``plt.close`` in a worker that may hold the
placeholder). In a fresh process (this one may have imported pyplot already).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

SRC = Path(__file__).resolve().parents[1] / "src"

_PROBE = """
import sys, types
from motioncue.trajectory._transition import _defer_pyplot
_defer_pyplot()
import toppra, toppra.algorithm
import matplotlib
import matplotlib.pyplot as plt
held = toppra.algorithm.algorithm.plt
assert plt is held and matplotlib.pyplot is plt, "one placeholder, also matplotlib's attribute"
assert "matplotlib.figure" not in sys.modules, "pyplot's own imports were made"
assert not hasattr(plt, "__file__") and "matplotlib.figure" not in sys.modules, "dunder imported"
fig = plt.figure()  # the first use: the real pyplot
assert "matplotlib.figure" in sys.modules
import matplotlib.pyplot as real
assert real is not held and type(real) is types.ModuleType
assert real.figure is held.figure and fig.number in real.get_fignums()
assert sys.modules["matplotlib.pyplot"] is real and matplotlib.pyplot is real
# a monkeypatch through the placeholder (code that imported it earlier) reaches the real module
orig, marker = real.close, object()
held.close = marker
assert real.close is marker and held.close is marker
held.close = orig
held.extra_attr = 1
del held.extra_attr
assert real.close is orig and not hasattr(real, "extra_attr")
print("ok")
"""


def test_toppra_comes_without_pyplot_and_pyplot_loads_at_its_first_use() -> None:
    env = {**os.environ, "PYTHONPATH": str(SRC), "MPLBACKEND": "Agg"}
    res = subprocess.run(
        [sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=120
    )
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "ok"
