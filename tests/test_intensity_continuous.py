"""``--intensity`` is continuous up to 100 % (issue 20, Build item 5).

:func:`motioncue.cueing.at_intensity` interpolates between the gentle end (the preset with
its ``[intensity.gentle]`` table, as the tuner writes it) and the preset's own values, not
their image in the tuner's space (one f_limit for x and y, ``tilt_shape`` at most 8, every
value clipped to its bounds): before, ``racing-hexapod-adaptive`` (f_limit x/y 0.163/0.239,
tilt shape 20) stepped between 99 and 100 % (the lap's fy share 0.126 -> 0.132).

Checked on every bundled preset with an intensity range, against closed forms written here
(not the module's helpers): every field the tuned parameters write (:data:`TOUCHED`, listed
by hand from the knob table) is at 99.99 % within :data:`REL_99_99` of the preset, every other
field is the preset's; 0 % is the old definition exactly (the preset with the gentle table
clipped to :data:`STRENGTH_TUNED_PARAMETERS`' bounds); 50 % is the element-wise geometric
mean of the two ends; each element moves monotonically through 0, 25, 50, 75 and 100 %; and
on the held-out drives and the lap (the chain of ``motioncue compare``, ``tests/_held_out.py``)
the shares at 99 % and 100 % differ by less than :data:`SHARE_STEP`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import replace

import numpy as np
import pytest

from _held_out import held_out_metrics
from motioncue._errors import ConfigError
from motioncue.cli._preset import presets_with_intensity
from motioncue.cueing import CueingParams, at_intensity, load_cueing
from motioncue.cueing._tune import STRENGTH_TUNED_PARAMETERS, params_from_vector

TOUCHED = (
    "f_scale", "f_limit_m_s2", "f_shape", "trans_wn_rad_s", "trans_wb_rad_s", "tilt_scale",
    "tilt_shape", "tilt_reach_use", "tilt_wn_rad_s", "tilt_rate_limit_rad_s",
    "tilt_accel_limit_rad_s2", "w_scale", "rot_wn_rad_s", "lead_s",
)  # fmt: skip
"""The :class:`CueingParams` fields :data:`STRENGTH_TUNED_PARAMETERS` write."""
BUNDLED = ("racing-hexapod-adaptive", "racing-hexapod-auto", "racing-hexapod-firm",
           "racing-hexapod-strong")  # fmt: skip
PRESETS = [p for p in presets_with_intensity() if load_cueing(p).algorithm == "classical"]
"""The classical ranges (a plan's range moves its cost's terms: tests/test_plan_intensity.py)."""
REL_99_99 = 1e-3  # |ln(v0 / v100)| <= 2.5 here (tilt shape 1.67 -> 20), so 1e-4 of it: 2.5e-4
SHARE_STEP = 0.002  # measured: at most 0.0010 (firm, forest-rally fy); the old step 0.0061
LEVELS = (0.0, 25.0, 50.0, 75.0, 100.0)


def _elements(p: CueingParams, name: str) -> np.ndarray:
    v = getattr(p, name)
    assert v is not None, name  # every bundled range sets all of them
    return np.atleast_1d(np.asarray(v, dtype=float))


def _old_gentle_end(p: CueingParams, name: str) -> CueingParams:
    """The 0 % end as it was defined before the change: the gentle table clipped to the
    tuner's bounds, in log space, through the tuner's ``params_from_vector``."""
    assert p.intensity_gentle is not None
    x = [
        math.log(min(max(v, t.lo), t.hi))
        for v, t in zip(p.intensity_gentle, STRENGTH_TUNED_PARAMETERS, strict=True)
    ]
    return params_from_vector(p, x, name=name)


def test_every_bundled_range_is_checked() -> None:
    assert set(BUNDLED) <= set(PRESETS), PRESETS  # the parametrisation below is not empty


@pytest.mark.parametrize("preset", PRESETS)
def test_just_below_100_is_the_preset(preset: str) -> None:
    p = load_cueing(preset)
    q = at_intensity(p, 99.99)
    for name in TOUCHED:
        got, want = _elements(q, name), _elements(p, name)
        np.testing.assert_allclose(got, want, rtol=REL_99_99, atol=0.0, err_msg=name)
    for f in dataclasses.fields(CueingParams):
        if f.name not in TOUCHED and f.name != "name":
            assert getattr(q, f.name) == getattr(p, f.name), f.name  # the adapt_* keys too
    assert q.name == f"{preset}@99.99%"
    assert at_intensity(p, 100.0) is p


@pytest.mark.parametrize("preset", PRESETS)
def test_gentle_end_is_the_old_definition(preset: str) -> None:
    p = load_cueing(preset)
    assert at_intensity(p, 0.0) == _old_gentle_end(p, f"{preset}@0%")


@pytest.mark.parametrize("preset", PRESETS)
def test_midpoint_is_the_geometric_mean_of_the_ends(preset: str) -> None:
    p = load_cueing(preset)
    gentle, mid = _old_gentle_end(p, ""), at_intensity(p, 50.0)
    for name in TOUCHED:
        a, b = _elements(gentle, name), _elements(p, name)
        assert np.all(a > 0.0) and np.all(b > 0.0), name
        np.testing.assert_allclose(_elements(mid, name), np.sqrt(a * b), rtol=1e-12, err_msg=name)


@pytest.mark.parametrize("preset", PRESETS)
def test_each_element_moves_monotonically(preset: str) -> None:
    p = load_cueing(preset)
    points = [at_intensity(p, pct) for pct in LEVELS]
    moved = 0
    for name in TOUCHED:
        v = np.array([_elements(q, name) for q in points])  # levels x elements
        d = np.diff(v, axis=0)
        up, down = np.all(d >= 0.0, axis=0), np.all(d <= 0.0, axis=0)
        assert np.all(up | down), (name, v)
        moved += int(np.count_nonzero(v[0] != v[-1]))
    assert moved >= 10, moved  # not a trivial range: the ends differ in many elements


@pytest.mark.parametrize("preset", PRESETS)
def test_no_step_between_99_and_100(preset: str) -> None:
    p = load_cueing(preset)
    at99, at100 = held_out_metrics(at_intensity(p, 99.0)), held_out_metrics(p)
    assert "lap.csv" in at100
    for drive, (m, _) in at100.items():
        s99, s100 = at99[drive][0].rendered_share[:2], m.rendered_share[:2]
        assert np.all(np.abs(np.subtract(s100, s99)) < SHARE_STEP), (drive, s99, s100)


def test_a_zero_element_is_interpolated_linearly() -> None:
    # no third-order break on x, y (wb 0) at 100 %; the gentle end writes the tuner's value
    p = replace(load_cueing("racing-hexapod-adaptive"), trans_wb_rad_s=(0.0, 0.0, 1.0))
    wb0 = at_intensity(p, 0.0).trans_wb_rad_s[0]
    assert wb0 > 0.0
    got = [at_intensity(p, pct).trans_wb_rad_s[0] for pct in (25.0, 50.0, 99.99)]
    assert got == pytest.approx([0.75 * wb0, 0.5 * wb0, 1e-4 * wb0], rel=1e-9)
    assert at_intensity(p, 50.0).trans_wb_rad_s[2] == 1.0


def test_an_unset_field_is_read_as_the_tuner_reads_it() -> None:
    # lead_s None (no lead): the tuner reads it at its lower bound, 0.02 s
    p = replace(load_cueing("racing-hexapod-adaptive"), lead_s=None)
    assert p.intensity_gentle is not None
    lx0 = p.intensity_gentle[[t.name for t in STRENGTH_TUNED_PARAMETERS].index("lead_x_s")]
    lead = at_intensity(p, 50.0).lead_s
    assert lead is not None and lead[0] == pytest.approx(math.sqrt(lx0 * 0.02), rel=1e-12)
    assert at_intensity(p, 100.0).lead_s is None


def test_a_plan_algorithm_with_a_classical_gentle_table_is_refused() -> None:
    # the classical gentle table is a point of the washout's parameters, not of an [mpc]
    # plan's: refused where the preset is made, before any intensity is asked for
    base = load_cueing("mpc-hexapod")
    gentle = load_cueing("racing-hexapod-firm").intensity_gentle
    assert base.tilt_shape is not None and gentle is not None
    with pytest.raises(ConfigError, match="allowed for algorithm 'mpc': 6"):
        replace(base, intensity_gentle=gentle)
