"""The optional [limits] table of a platform config: the actuators' own limits, in SI."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue._config import find_config
from motioncue.kinematics import load_platform, platform_from_dict


def _data(name: str) -> dict:
    with open(find_config("platforms", name), "rb") as fh:
        return tomllib.load(fh)


def test_bundled_limits_are_converted_to_si() -> None:
    p = load_platform("stewart6-linear")
    np.testing.assert_allclose(p.v_max, 0.25)
    np.testing.assert_allclose(p.a_max, 12.0)
    assert p.j_max is None
    r = load_platform("stewart6-rotary")
    np.testing.assert_allclose(r.v_max, math.radians(180.0))
    y = load_platform("seat2-yaw")
    np.testing.assert_allclose(y.v_max, [0.2, 0.2, math.radians(90.0)])
    np.testing.assert_allclose(y.a_max, [10.0, 10.0, math.radians(360.0)])


def test_per_leg_lists_and_jerk() -> None:
    d = _data("seat3")
    d["limits"] = {"max_speed_mm_s": [100.0, 150.0, 200.0], "max_accel_mm_s2": 5000.0,
                   "max_jerk_mm_s3": 1e6}  # fmt: skip
    p = platform_from_dict(d, "x.toml", "seat3")
    np.testing.assert_allclose(p.v_max, [0.1, 0.15, 0.2])
    np.testing.assert_allclose(p.j_max, 1000.0)


@pytest.mark.parametrize(
    ("limits", "message"),
    [
        ({"max_speed_mm_s": -1.0}, "max_speed_mm_s"),
        ({"max_speed_mm_s": [1.0, 2.0]}, "max_speed_mm_s"),
        ({"max_sped_mm_s": 1.0}, "max_sped_mm_s"),
        ({"max_speed_deg_s": 10.0}, "max_speed_deg_s"),
    ],
)
def test_bad_limits_are_named(limits: dict, message: str) -> None:
    d = _data("stewart6-linear")
    d["limits"] = limits
    with pytest.raises(ConfigError, match=message):
        platform_from_dict(d, "x.toml", "p")


def test_yaw_axis_needs_its_own_limit() -> None:
    d = _data("seat2-yaw")
    del d["limits"]["yaw_max_speed_deg_s"]
    with pytest.raises(ConfigError, match="yaw_max_speed_deg_s"):
        platform_from_dict(d, "x.toml", "p")


def test_with_actuator_limits_validates() -> None:
    p = load_platform("seat3")
    with pytest.raises(ConfigError, match="a_max"):
        p.with_actuator_limits(a_max=[1.0, np.nan, 2.0])
    q = p.with_actuator_limits(v_max=0.5)
    np.testing.assert_allclose(q.v_max, 0.5)
    np.testing.assert_allclose(p.v_max, 0.2)  # the original is unchanged (frozen)
