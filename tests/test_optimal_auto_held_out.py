"""Issue 20 item 7 for ``optimal-hexapod-auto`` on the drives never tuned on.

``optimal-hexapod`` with its tracked fx gain adapting to the drive (``[mpc]
ref_adapt_peak_m_s2``; its header says how it was chosen). Issue 20 asks ``optimal`` for a
rendered share at least 1.3 times the classical default's (aim 1.5), with reversals <= 2 %, all
false cues <= 15 %, corr fx >= 0.95 and fy >= 0.90, clamped <= 1 %. Since session 29 the
classical default is ``racing-hexapod-auto``, whose fx ``optimal-hexapod`` no longer reaches
1.3 times of on forest-rally (0.92x; README). Every held-out car drive and the bundled lap,
``stewart6-linear`` with ``mbox6``, through the chain of ``motioncue compare``
(``tests/_held_out.py``), whole drives:

* the issue's figures on every drive, and no frame changed by the actuator limiter;
* share fx at least :data:`RATIO` times the default's on every drive, and fy where it is
  met (:data:`FY_RATIO_MET`); elsewhere fy's ratio is pinned between its measured floor and
  :data:`RATIO` (:data:`FY_RATIO_SHORT`), so that this test fails once it is met;
* pinned at the measured shares (:data:`MEASURED`) within 0.002.

Since session 31 the plan prices the steps of its input (``[mpc] w_jerk``,
tests/test_optimal_jerk.py). Before, part of its fy was felt pulses the vehicle did not have
(its perceived fy above 2 Hz 0.2-0.6 m/s^2; the default's 0.03-0.05): fy was 1.99 / 1.47 /
1.41x the default's on forest-rally / flowing-formula / the lap and is now 1.78 / 1.28 /
1.17x, with corr fy 0.980 / 0.939 / 0.953 (was 0.966 / 0.922 / 0.941).

Since session 32 the price of the error to the vehicle's whole fx, fy is higher (``[mpc]
w_vehicle`` 0.3 / 0.45 -> 0.8 / 0.52) and the guard on the rider's pitch rate is one
threshold instead of 0.77 (the preset's header): share fx 0.169 / 0.073 / 0.118 -> 0.208 /
0.096 / 0.144, fy 0.238 / 0.123 / 0.152 -> 0.241 / 0.127 / 0.153, so fy's 1.3x is now met
on flowing-formula too (1.28 -> 1.34x); corr fx 0.993 / 0.962 / 0.988 -> 0.993 / 0.958 /
0.983; all false cues 2.1 / 2.3 / 1.2 -> 3.0 / 3.9 / 2.9 %.

Since session 33 small fx cues are tracked with more gain (``[mpc] ref_small_gain`` fx 0.3,
knee 0.3 m/s^2) and the price on the whole fx is 0.7: missed fx on flowing-formula 37 -> 28 %,
so the issue's missed cues <= 35 % is now checked on every drive; share fx 0.208 / 0.096 /
0.144 -> 0.211 / 0.097 / 0.145, fy 0.241 / 0.127 / 0.153 -> 0.239 / 0.127 / 0.152, corr fx
0.993 / 0.958 / 0.983 -> 0.992 / 0.953 / 0.982.
"""

from __future__ import annotations

import numpy as np
import pytest

from _held_out import DRIVES, check_plan_figures, default_preset, held_out_metrics
from motioncue.cueing._metrics import CueMetrics

PRESET = "optimal-hexapod-auto"
RATIO = 1.3  # the issue's; measured fx 2.12 / 3.01 / 2.16, fy 1.79 / 1.34 / 1.18
FY_RATIO_MET = ("forest-rally.csv", "flowing-formula.csv")
FY_RATIO_SHORT = {"lap.csv": 1.15}  # measured 1.18
MEASURED = {  # share fx, fy
    "forest-rally.csv": (0.211, 0.239),
    "flowing-formula.csv": (0.097, 0.127),
    "lap.csv": (0.145, 0.152),
}


@pytest.fixture(scope="module")
def metrics() -> dict[str, dict[str, tuple[CueMetrics, int]]]:
    return {name: held_out_metrics(name) for name in (PRESET, default_preset())}


@pytest.mark.parametrize("name", DRIVES)
def test_the_issue_figures_and_the_ratio_to_the_default(
    metrics: dict[str, dict[str, tuple[CueMetrics, int]]], name: str
) -> None:
    m, limited = metrics[PRESET][name]
    d, _ = metrics[default_preset()][name]
    assert default_preset() == "racing-hexapod-auto"
    check_plan_figures(m, limited)
    assert m.missed[0] <= 0.35 and m.missed[1] <= 0.35, m.missed  # the issue's missed cues
    ratio = np.asarray(m.rendered_share[:2]) / np.asarray(d.rendered_share[:2])
    assert ratio[0] >= RATIO, ratio
    assert set(FY_RATIO_MET) | set(FY_RATIO_SHORT) == set(DRIVES)
    if name in FY_RATIO_MET:
        assert ratio[1] >= RATIO, ratio
    else:
        assert FY_RATIO_SHORT[name] <= ratio[1] < RATIO, ratio
    assert set(MEASURED) == set(DRIVES)
    np.testing.assert_allclose(m.rendered_share[:2], MEASURED[name], atol=0.002)
