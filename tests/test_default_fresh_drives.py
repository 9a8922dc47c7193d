"""The stewart6-linear default on six more drives it was never tuned on (issue 20).

The bundled held-out set has two car drives and the lap; ``configs/recordings/generated.toml``
lists six more held-out car drives (GT, formula, road and rally cars on the four circuits),
not bundled, written here by their commands (``tools/make_generated_drives.py``). They were
made in session 29 before any choice and have been used for none since, so they are the
honest check of a preset searched on drives that share a held-out drive's car and circuit
(``racing-hexapod-auto``'s header). Through the chain of ``motioncue compare``
(``tests/_held_out.py``), whole drives, against ``racing-hexapod-firm`` (the default before):

* issue 20's error figures: corr fx >= 0.95 and fy >= 0.90, clamped <= 1 %, reversals
  <= 2 % (since session 32's fz guard on every drive: chicane-formula-402 was 2.09 %), and
  all false cues <= 10 % (the default's own budget, ``test_cue_acceptance``; the issue
  allows 15 %);
* at most :data:`LIMITED_MAX` of the frames changed by the actuator limiter (it keeps them
  within the limits; the bundled held-out drives have none);
* strength: fx and fy each at least 0.9x firm's on every drive, fx at least 1.5x firm's on
  the cars that are not formula cars (the adaptive tilt gain is for them);
* shares pinned at the measured ones (:data:`MEASURED`) within 0.002.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from _held_out import default_preset, fresh_held_out_paths, held_out_metrics
from motioncue.cueing._metrics import CueMetrics

FIRM = "racing-hexapod-firm"
MEASURED = {  # the default's share fx, fy (session 32)
    "street-gt-401.csv": (0.070, 0.130),
    "chicane-formula-402.csv": (0.039, 0.110),
    "flowing-formula-403.csv": (0.032, 0.096),
    "forest-road-404.csv": (0.105, 0.136),
    "chicane-rally-405.csv": (0.100, 0.135),
    "street-formula-406.csv": (0.045, 0.121),
}
LIMITED_MAX = 1e-3  # share of frames; measured 5 of 18 055 on forest-road-404, 0 elsewhere

Metrics = dict[str, tuple[CueMetrics, int]]


@pytest.fixture(scope="module")
def drives(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    return fresh_held_out_paths(tmp_path_factory.mktemp("fresh-drives"))


@pytest.fixture(scope="module")
def metrics(drives: list[Path]) -> dict[str, Metrics]:
    return {p: held_out_metrics(p, drives) for p in (default_preset(), FIRM)}


def test_the_six_drives_are_there_and_not_bundled(drives: list[Path]) -> None:
    from motioncue.telemetry import sample_drives

    assert [p.name for p in drives] == list(MEASURED)
    assert not {p.name for p in sample_drives()} & set(MEASURED)
    assert default_preset() == "racing-hexapod-auto"


@pytest.mark.parametrize("name", list(MEASURED))
def test_the_issue_figures(metrics: dict[str, Metrics], name: str) -> None:
    m, limited = metrics[default_preset()][name]
    assert m.correlation[0] >= 0.95 and m.correlation[1] >= 0.90, m.correlation
    assert m.clamped <= 0.01, m.clamped
    assert m.reversals_any <= 0.02, m.reversals_any  # measured at most 1.76 %
    assert m.false_any <= 0.10, m.false_any
    assert limited <= LIMITED_MAX * m.n_samples, (limited, m.n_samples)


@pytest.mark.parametrize("name", list(MEASURED))
def test_at_least_the_firm_default_and_much_more_fx_on_cars_that_are_not_formula(
    metrics: dict[str, Metrics], name: str
) -> None:
    m, _ = metrics[default_preset()][name]
    f, _ = metrics[FIRM][name]
    ratio = m.rendered_share[:2] / f.rendered_share[:2]
    assert np.all(ratio >= 0.9), ratio
    if "formula" not in name:
        assert ratio[0] >= 1.5, ratio
    np.testing.assert_allclose(m.rendered_share[:2], MEASURED[name], atol=0.002)
