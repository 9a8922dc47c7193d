"""Limits of another actuator count than the platform's are refused, with one message, by
the cueing rig and by the OMCT (``motioncue.cueing._algorithm.check_rig``)."""

from __future__ import annotations

import pytest

from motioncue import ConfigError
from motioncue.analysis import run_omct
from motioncue.cueing import ClassicalWashout, Rig, load_cueing
from motioncue.kinematics import load_platform
from motioncue.trajectory import ActuatorLimits

MESSAGE = "limits have 3 actuators; platform 'stewart6-linear' has 6"


def _three_actuator_limits() -> ActuatorLimits:
    return ActuatorLimits.from_platform(load_platform("seat3"))


def test_rig_refuses_limits_of_another_actuator_count() -> None:
    platform = load_platform("stewart6-linear")
    with pytest.raises(ConfigError) as exc:
        Rig(platform, _three_actuator_limits())
    assert str(exc.value) == MESSAGE
    rig = Rig(platform, ActuatorLimits.from_platform(platform))
    assert rig.limits.n_actuators == 6


def test_omct_refuses_them_before_running_with_the_same_message() -> None:
    platform = load_platform("stewart6-linear")
    design = ClassicalWashout(load_cueing("racing"), 100.0)
    with pytest.raises(ConfigError) as exc:
        run_omct(design, platform, _three_actuator_limits(), paths=["p-p"])
    assert str(exc.value) == MESSAGE
