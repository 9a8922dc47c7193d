"""The gentle end of an intensity range is gentler in every channel (issue 20).

``motioncue tune --gentle-end`` maximises the strength (the geometric mean of the fx and fy
shares) within tighter cue-quality targets. Overall gentler is not enough: a gentle end
stronger than the strong end in fx made 0/50/100 % non-monotone in fx. So the targets carry a
per-channel cap (:attr:`StrengthTargets.max_share`, ``--gentle-share`` times the strong end's
shares): checked here against hand-computed violations, and on the tuner, which must find the
known optimum of a synthetic problem whose cap binds in one channel.
"""

from __future__ import annotations

import math

import pytest

from motioncue._errors import ConfigError
from motioncue.analysis._tune import ChainMetrics, StrengthTargets, tune_cueing
from test_tune_strength import _cue, _Synthetic


def _m(sx: float, sy: float, false: float = 0.0) -> ChainMetrics:
    return ChainMetrics(0.0, (0.0,), duration_s=1.0, strength=math.sqrt(sx * sy),
                        cue=_cue(sx, sy, false))  # fmt: skip


def test_the_cap_counts_each_channel_on_its_own() -> None:
    t = StrengthTargets(max_share=(0.02, 0.08))
    assert t.violation(_m(0.02, 0.08)) == 0.0  # on the cap: met
    assert t.violation(_m(0.01, 0.05)) == 0.0
    # fx 0.03 over 0.02: 0.5, relative to the cap; fy within
    assert t.violation(_m(0.03, 0.05)) == pytest.approx(0.5)
    # fy 0.12 over 0.08: 0.5; both: 0.5 + 0.5
    assert t.violation(_m(0.01, 0.12)) == pytest.approx(0.5)
    assert t.violation(_m(0.03, 0.12)) == pytest.approx(1.0)
    # the other targets add as before (false cues 0.18 over 0.15: 0.2)
    assert t.violation(_m(0.03, 0.05, false=0.18)) == pytest.approx(0.7)
    # gentler overall but stronger in fx (last session's gentle end): not met
    assert math.sqrt(0.042 * 0.05) < math.sqrt(0.038 * 0.12)
    assert StrengthTargets(max_share=(0.038, 0.12)).violation(_m(0.042, 0.05)) > 0.0
    assert StrengthTargets().violation(_m(0.042, 0.05)) == 0.0  # without the cap it was


@pytest.mark.parametrize("bad", [(0.0, 0.1), (0.1, -1.0), (0.1, math.nan), (0.1,), (0.1, 11.0)])
def test_a_bad_cap_is_refused_with_its_value(bad: tuple[float, ...]) -> None:
    with pytest.raises(ConfigError, match="max_share"):
        StrengthTargets(max_share=bad)  # type: ignore[arg-type]


def test_the_tuner_finds_the_optimum_where_the_cap_binds_in_one_channel() -> None:
    """Strength sqrt(kx ky), false cues 0.1 (kx + ky) <= 0.15, and share fx <= 0.3: the
    best is kx = 0.3 on the cap and ky = 1.2 on the false-cue budget (strength 0.6); without
    the cap it is kx = ky = 0.75 (``test_tune_strength``)."""
    obj = _Synthetic()
    obj.targets = StrengthTargets(max_share=(0.3, 5.0))
    res = tune_cueing(obj, seed=3, generations=100, popsize=3, budget_s=600.0)
    kx, ky = res.params.tilt_scale  # type: ignore[misc]
    assert kx == pytest.approx(0.3, rel=0.03)
    assert ky == pytest.approx(1.2, rel=0.03)
    assert res.after.strength == pytest.approx(0.6, rel=0.03)
    assert obj.targets.violation(res.after) == 0.0
