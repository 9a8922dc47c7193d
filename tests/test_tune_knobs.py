"""Each tuned parameter is written where it is read (the plans' name-keyed tables).

For every bundled tune table, each parameter is moved alone to a new point of its range:
the preset it gives reads back that point in that parameter and the base's value in every
other one (so no parameter writes into another's field or component), and a preset field
outside the table is left as it was.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from motioncue.cueing import load_cueing
from motioncue.cueing._tune import params_from_vector, tuned_parameters, vector_from_params

# one preset per table: classical plain and compressive, plan plain and compressive
PRESETS = ("racing", "racing-hexapod-strong", "mpc-seat3", "mpc-hexapod")
GUARDS = (0.7, 0.7, 0.0, 1.0, 0.5, 0.0)
"""A sign guard on roll and pitch rate (only a guarded axis takes the tuned guard)."""


def _base(preset: str):  # type: ignore[no-untyped-def]
    base = load_cueing(preset)
    if base.mpc is not None and base.mpc.ref_shape > 0.0:
        base = replace(base, mpc=replace(base.mpc, sign_guard=GUARDS))
    return base


@pytest.mark.parametrize("preset", PRESETS)
def test_each_parameter_is_read_back_alone(preset: str) -> None:
    base = _base(preset)
    table = tuned_parameters(base)
    x0 = vector_from_params(base)
    # the base read back through its own table (values inside the bounds come back as read)
    again = vector_from_params(params_from_vector(base, x0.tolist()))
    np.testing.assert_allclose(again, x0, rtol=0, atol=1e-12)
    for i, p in enumerate(table):
        x = x0.copy()
        lo, hi = math.log(p.lo), math.log(p.hi)
        # a point away from the base's value: a quarter of the way from the far bound
        x[i] = lo + 0.25 * (hi - lo) if x0[i] > 0.5 * (lo + hi) else hi - 0.25 * (hi - lo)
        moved = params_from_vector(base, x.tolist(), name="moved")
        back = vector_from_params(moved)
        np.testing.assert_allclose(back, x, rtol=0, atol=1e-12, err_msg=p.name)
        assert moved.name == "moved"
        assert moved.workspace == base.workspace  # outside every table
        assert moved.reject_f_m_s2 == base.reject_f_m_s2


def test_an_unguarded_axis_keeps_its_sign_guard_off() -> None:
    base = load_cueing("mpc-hexapod")
    base = replace(base, mpc=replace(base.mpc, sign_guard=(0.7, 0.7, 0.0, 0.0, 0.9, 0.0)))
    x = vector_from_params(base)
    x[-1] = math.log(2.0)  # sign_guard_rp, last of the compressive plan's table
    assert tuned_parameters(base)[-1].name == "sign_guard_rp"
    moved = params_from_vector(base, x.tolist())
    assert moved.mpc is not None
    assert moved.mpc.sign_guard == pytest.approx((0.7, 0.7, 0.0, 0.0, 2.0, 0.0), abs=1e-12)
