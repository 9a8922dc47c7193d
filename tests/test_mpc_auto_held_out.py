"""Issue 20 item 7 for ``mpc-hexapod-auto`` on the drives never tuned on.

``mpc-hexapod``'s plan started from the default's washout, with its tracked fx gain adapting
to the drive (its header says how it was searched, on the tuning drives only). Issue 20 asks
``mpc`` for a rendered share at least 1.15 times the classical default's
(``racing-hexapod-auto``), with reversals <= 2 %, all false cues <= 15 %, corr fx >= 0.95 and
fy >= 0.90, clamped <= 1 %. Every bundled held-out car drive and the lap, ``stewart6-linear``
with ``mbox6``, through the chain of ``motioncue compare`` (``tests/_held_out.py``), whole
drives:

* the issue's error figures on every drive, and no frame changed by the actuator limiter;
* fx and fy at least the default's on these three drives (fy falls to 0.96-0.98x on two of
  the generated formula drives: the preset's header); the issue's 1.15x in fx on every
  drive (since session 32, when the plan priced the error to the car's whole fx: 1.26 /
  1.38 / 1.22x, was 1.16 / 1.09 / 1.06x), in fy only on forest-rally (:data:`FY_RATIO_MET`),
  stated, not hidden: on flowing-formula and the lap fy is 1.03 / 1.08x;
* pinned at the measured shares (:data:`MEASURED`) within 0.002.
"""

from __future__ import annotations

import numpy as np
import pytest

from _held_out import DRIVES, check_plan_figures, default_preset, held_out_metrics
from motioncue.cueing._metrics import CueMetrics

PRESET = "mpc-hexapod-auto"
FY_RATIO_MET = {"forest-rally.csv"}  # fy 1.34x; flowing-formula 1.03x, lap 1.08x
MEASURED = {  # share fx, fy
    "forest-rally.csv": (0.126, 0.179),
    "flowing-formula.csv": (0.044, 0.099),
    "lap.csv": (0.082, 0.141),
}

Metrics = dict[str, tuple[CueMetrics, int]]


@pytest.fixture(scope="module")
def metrics() -> dict[str, Metrics]:
    return {name: held_out_metrics(name) for name in (PRESET, default_preset())}


@pytest.mark.parametrize("name", DRIVES)
def test_the_issue_figures_and_the_ratio_to_the_default(
    metrics: dict[str, Metrics], name: str
) -> None:
    m, limited = metrics[PRESET][name]
    d, _ = metrics[default_preset()][name]
    assert default_preset() == "racing-hexapod-auto"
    check_plan_figures(m, limited)
    ratio = m.rendered_share[:2] / d.rendered_share[:2]
    assert np.all(ratio >= 1.0), ratio
    assert ratio[0] >= 1.15, ratio
    assert (ratio[1] >= 1.15) == (name in FY_RATIO_MET), ratio
    assert set(MEASURED) == set(DRIVES)
    np.testing.assert_allclose(m.rendered_share[:2], MEASURED[name], atol=0.002)
