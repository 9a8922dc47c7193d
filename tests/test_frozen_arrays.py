"""The array fields of frozen models are read-only copies (``motioncue._frozen.readonly``)."""

from __future__ import annotations

import numpy as np
import pytest

from motioncue._frozen import readonly
from motioncue.kinematics import load_platform
from motioncue.kinematics._drive import Drive


def test_readonly_is_a_read_only_copy_of_the_given_type() -> None:
    src = np.array([1.0, 2.5, -3.0])
    out = readonly(src, np.int64)
    assert out.dtype == np.int64
    assert out.tolist() == [1, 2, -3]
    assert not out.flags.writeable
    src[0] = 9.0  # the caller's array stays writable and does not reach the copy
    assert out[0] == 1
    with pytest.raises(ValueError):
        out[0] = 5


def test_drive_and_platform_arrays_cannot_be_written() -> None:
    home = np.array([0.0, -0.01])
    drive = Drive.linear(0.005, 10000, home)
    home[0] = 1.0
    assert drive.q_home.tolist() == [0.0, -0.01]
    platform = load_platform("stewart6-linear")
    for arr in (
        drive.pulses_per_rev,
        drive.direction,
        drive.q_home,
        platform.q_min,
        platform.q_park,
    ):
        assert not arr.flags.writeable
        with pytest.raises(ValueError):
            arr[0] = arr[0]
