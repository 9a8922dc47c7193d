"""The ``strength`` objective of the tuner (issue 20, Build item 4).

The tuner finds the known optimum of a synthetic problem (strength against a false-cue
budget: the constrained maximum lies on the budget's boundary, not at standing still), a
platform at rest scores no better than zero, and the constraint bookkeeping is checked
against hand-computed violations.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from motioncue.analysis._tune import ChainMetrics, StrengthTargets, TuneObjective, tune_cueing
from motioncue.cueing import load_cueing
from motioncue.cueing._metrics import CueMetrics
from motioncue.cueing._tune import (
    STRENGTH_TUNED_PARAMETERS,
    params_from_vector,
    vector_from_params,
)


def _cue(share_x: float, share_y: float, false: float, rev: float = 0.0,
         corr: tuple[float, float] = (1.0, 1.0)) -> CueMetrics:  # fmt: skip
    z = np.zeros(6)
    return CueMetrics(
        rendered_share=np.array([share_x, share_y, 0.1, 0.1, 0.1, 0.1]),
        gain=z.copy(), correlation=np.array([corr[0], corr[1], 1, 1, 1, 1.0]),
        missed=z.copy(), reversals=z.copy(), spurious=z.copy(), false_cues=z.copy(),
        vehicle_above=z.copy(), missed_any=0.0, reversals_any=rev, spurious_any=0.0,
        false_any=false, clamped=0.0, thresholds=np.ones(6), n_samples=100,
    )  # fmt: skip


def _strength_base():  # type: ignore[no-untyped-def]
    base = load_cueing("racing-hexapod")
    r = math.radians(12.0)
    return replace(base, tilt_scale=(0.2, 0.2), tilt_shape=2.0, tilt_reach_rad=(r, r, r, r),
                   f_shape=(2.0, 2.0, 2.0))  # fmt: skip


class _Synthetic(TuneObjective):
    """Strength = sqrt(kt_x kt_y) (the tilt scales as rendered shares); false cues
    0.1 (kt_x + kt_y): the budget of 15 % allows kt_x + kt_y <= 1.5, so the best is
    kt_x = kt_y = 0.75 (strength 0.75), whatever the other 19 parameters."""

    def __init__(self) -> None:  # no drives, no platform: the chain is the formula
        self.base = _strength_base()
        self.objective = "strength"
        self.targets = StrengthTargets()
        self.rate_hz = 100.0

    def metrics(self, params, *, full=False):  # type: ignore[no-untyped-def,override]
        a, b = params.tilt_scale
        cue = _cue(a, b, false=0.1 * (a + b))
        return ChainMetrics(objective=0.0, per_drive_objective=(0.0,), duration_s=1.0,
                            strength=math.sqrt(a * b), cue=cue)  # fmt: skip


def test_tuner_finds_the_known_optimum_of_a_synthetic_problem() -> None:
    obj = _Synthetic()
    res = tune_cueing(obj, seed=5, generations=400, popsize=5, budget_s=600.0)
    kx, ky = res.params.tilt_scale  # type: ignore[misc]
    assert kx == pytest.approx(0.75, rel=0.03)
    assert ky == pytest.approx(0.75, rel=0.03)
    assert res.after.strength == pytest.approx(0.75, rel=0.03)
    assert obj.targets.violation(res.after) == 0.0  # on the boundary, not over it
    # the base (0.2, 0.2) met the budget too: the tuner moved 3.7x away from it
    assert res.before.strength == pytest.approx(0.2)


def test_standing_still_cannot_win_and_violations_rank_below_every_feasible() -> None:
    obj = _Synthetic()
    still = ChainMetrics(0.0, (0.0,), duration_s=1.0, strength=0.0, cue=_cue(0, 0, 0.0))
    faint = ChainMetrics(0.0, (0.0,), duration_s=1.0, strength=0.03,
                         cue=_cue(0.03, 0.08, 0.02))  # fmt: skip
    over = ChainMetrics(0.0, (0.0,), duration_s=1.0, strength=0.5,
                        cue=_cue(0.5, 0.5, 0.18, rev=0.03, corr=(0.90, 0.95)))  # fmt: skip
    assert obj.score(still) == 0.0
    assert obj.score(faint) == pytest.approx(-0.03)
    # 0.18 vs 0.15: 0.2; 0.03 vs 0.02: 0.5; corr fx 0.90 vs 0.95 over 0.05: 1.0
    assert obj.targets.violation(over) == pytest.approx(0.2 + 0.5 + 1.0)
    assert obj.score(over) == pytest.approx(1.0 + 1.7)
    assert obj.score(over) > obj.score(still) > obj.score(faint)
    clamped = replace(faint, clamped_fraction=0.02)  # beyond the 1 % of the limits
    assert obj.score(clamped) >= 1e6


def test_strength_vector_round_trips() -> None:
    p = replace(_strength_base(), tilt_reach_use=0.7, f_limit_m_s2=(1.5, 1.5, 3.0))
    x = vector_from_params(p)
    assert len(x) == len(STRENGTH_TUNED_PARAMETERS)
    q = params_from_vector(p, x.tolist())
    for name in ("f_scale", "tilt_scale", "tilt_shape", "tilt_reach_use", "tilt_wn_rad_s",
                 "tilt_rate_limit_rad_s", "w_scale", "rot_wn_rad_s"):  # fmt: skip
        np.testing.assert_allclose(getattr(q, name), getattr(p, name), rtol=1e-12)
    np.testing.assert_allclose(q.f_limit_m_s2[:2], (1.5, 1.5), rtol=1e-12)
