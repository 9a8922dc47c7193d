"""Stroke and crank ranges of the platform constructors: one pair for every actuator or
one pair each, finite with min < max; anything else refused with the value and what is
allowed (``kinematics._platform._ranges``)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.kinematics import Seat3, Stewart6Rotary


def _seat3(stroke: object) -> Seat3:
    # configs/platforms/seat3.toml's anchors (m), legs 0.37 m long at neutral
    anchors = np.array([[0.2, 0.25, 0.0], [0.2, -0.25, 0.0], [-0.3, 0.0, 0.0]])
    return Seat3(anchors, anchors, 0.37, stroke)  # type: ignore[arg-type]


def _rotary(crank_range: object) -> Stewart6Rotary:
    rb, rp, crank, rod = 0.3, 0.25, 0.1, 0.4
    base, plat, zero = [], [], []
    for i in range(6):
        c, s = 120.0 * (i // 2), -1.0 if i % 2 == 0 else 1.0
        a, b = math.radians(c + s * 10.0), math.radians(c + s * 45.0)
        base.append([rb * math.cos(a), rb * math.sin(a), 0.0])
        plat.append([rp * math.cos(b), rp * math.sin(b), 0.0])
        zero.append([-s * math.sin(a), s * math.cos(a), 0.0])
    base_a, plat_a, zero_a = np.array(base), np.array(plat), np.array(zero)
    span = float(np.linalg.norm(plat_a[0, :2] - (base_a[0] + crank * zero_a[0])[:2]))
    height = math.sqrt(rod**2 - span**2)
    axes = np.cross(zero_a, [0.0, 0.0, 1.0])
    return Stewart6Rotary(base_a, axes, zero_a, crank, rod, plat_a, height, crank_range)  # type: ignore[arg-type]


def test_one_stroke_pair_is_every_legs_and_bad_strokes_are_refused() -> None:
    one = _seat3((0.32, 0.42))
    each = _seat3([(0.32, 0.42)] * 3)
    assert np.array_equal(one.q_min, each.q_min) and np.array_equal(one.q_max, each.q_max)
    assert np.allclose(one.q_max - one.q_min, 0.1, atol=1e-12)
    allowed = "allowed: (min_length_m, max_length_m) with min < max, or one such pair per leg"
    for bad in [(0.42, 0.32), (0.32, math.nan), [(0.32, 0.42)] * 2]:
        with pytest.raises(ConfigError) as exc:
            _seat3(bad)
        assert str(exc.value) == f"stroke = {bad!r} is invalid; {allowed}"


def test_one_crank_pair_is_every_cranks_and_bad_ranges_are_refused() -> None:
    lim = (-math.radians(60), math.radians(60))
    one = _rotary(lim)
    each = _rotary([lim] * 6)
    assert np.array_equal(one.q_min, each.q_min) and np.array_equal(one.q_max, each.q_max)
    assert np.allclose(one.q_max - one.q_min, math.radians(120), atol=1e-12)
    for bad in [(1.0, -1.0), (-1.0, math.inf), [lim] * 5]:
        with pytest.raises(ConfigError) as exc:
            _rotary(bad)
        assert str(exc.value) == (
            f"crank_range = {bad!r} is invalid; allowed: (min_rad, max_rad), min < max"
        )
