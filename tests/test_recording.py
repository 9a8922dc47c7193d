"""Recording CSV reader/writer and resampling."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from motioncue import ConfigError
from motioncue.telemetry._recording import (
    Recording,
    read_recording_csv,
    resample,
    write_recording_csv,
)


def same(a: np.ndarray, b: np.ndarray) -> None:
    np.testing.assert_array_equal(a, b)  # NaN == NaN for assert_array_equal


@settings(max_examples=40)
@given(
    data=hnp.arrays(
        np.float64,
        st.tuples(st.integers(0, 30), st.just(6)),
        elements=st.floats(allow_nan=True, allow_infinity=True),
    ),
    t=hnp.arrays(np.float64, 30, elements=st.floats(-1e6, 1e6)),
)
def test_write_read_round_trip(tmp_path_factory: pytest.TempPathFactory, data, t) -> None:
    path = tmp_path_factory.mktemp("rec") / "r.csv"
    n = data.shape[0]
    rec = Recording(t[:n], data[:, :3], data[:, 3:])
    write_recording_csv(path, rec)
    back = read_recording_csv(path)
    same(back.t_s, rec.t_s)
    same(back.f, rec.f)
    same(back.w, rec.w)
    assert not np.isinf(back.f).any()  # non-finite kept as NaN


def test_columns_in_any_order_extra_ignored(tmp_path: Path) -> None:
    path = tmp_path / "r.csv"
    path.write_text(
        "speed, wz,t,fz ,fy,fx,gear,wy,wx\n"
        "12.5,0.3,0.0,9.8,0.2,0.1,3,0.02,0.01\n"
        "13.0,0.4,0.01,9.7,,nan,3,inf,-inf\n"
        "\n"
    )
    rec = read_recording_csv(path)
    same(rec.t_s, [0.0, 0.01])
    same(rec.f, [[0.1, 0.2, 9.8], [np.nan, np.nan, 9.7]])
    same(rec.w, [[0.01, 0.02, 0.3], [np.nan, np.nan, 0.4]])


@pytest.mark.parametrize(
    ("text", "pattern"),
    [
        ("t,fx,fy,fz,wx,wy\n0,0,0,9.8,0,0\n", "missing column.*wz"),
        ("t,fx,fy,fz,wx,wy,wz\n0,0,0,9.8,0,0,0\n0.1,0,zero,9.8,0,0,0\n", r"r\.csv:3.*'fy'"),
        ("t,fx,fy,fz,wx,wy,wz\n0,0,0,9.8,0,0\n", r"r\.csv:2: 6 fields"),
        ("t,fx,fy,fz,wx,wy,wz\nnan,0,0,9.8,0,0,0\n", r"r\.csv:2: time"),
        ("", "empty file"),
    ],
)
def test_clear_errors(tmp_path: Path, text: str, pattern: str) -> None:
    path = tmp_path / "r.csv"
    path.write_text(text)
    with pytest.raises(ConfigError, match=pattern):
        read_recording_csv(path)


def test_missing_file_is_a_config_error(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match="cannot read"):
        read_recording_csv(tmp_path / "none.csv")


def test_recording_validates_shapes() -> None:
    with pytest.raises(ConfigError, match="Recording needs"):
        Recording(np.zeros(3), np.zeros((3, 2)), np.zeros((3, 3)))
    with pytest.raises(ConfigError, match="finite"):
        Recording([0.0, math.inf], np.zeros((2, 3)), np.zeros((2, 3)))


def linear(t: np.ndarray) -> np.ndarray:
    return np.column_stack(
        [a + b * t for a, b in zip(range(6), (0.5, -1, 2, 0.1, 3, -0.7), strict=True)]
    )


def test_resample_irregular_linear_signal_is_exact() -> None:
    rng = np.random.default_rng(2)
    t = np.sort(rng.uniform(1.0, 11.0, 700))
    data = linear(t)
    out = resample(Recording(t, data[:, :3], data[:, 3:]), 50.0)
    assert out.t_s[0] == t[0]
    np.testing.assert_allclose(np.diff(out.t_s), 0.02, rtol=1e-9)
    assert out.t_s[-1] <= t[-1] and t[-1] - out.t_s[-1] < 0.02
    assert len(out) == math.floor((t[-1] - t[0]) * 50.0 + 1e-9) + 1
    want = linear(out.t_s)
    np.testing.assert_allclose(np.column_stack([out.f, out.w]), want, rtol=1e-9, atol=1e-9)


def test_resample_uniform_input_is_unchanged() -> None:
    t = np.arange(500) / 100.0
    data = np.random.default_rng(5).normal(size=(500, 6))
    out = resample(Recording(t, data[:, :3], data[:, 3:]), 100.0)
    same(out.t_s, t)
    same(out.f, data[:, :3])
    same(out.w, data[:, 3:])


def test_resample_unsorted_and_duplicates_last_wins() -> None:
    t = np.array([0.2, 0.0, 0.1, 0.1, 0.3])
    f = np.array([[2.0, 0, 0], [0.0, 0, 0], [1.0, 0, 0], [5.0, 0, 0], [3.0, 0, 0]])
    out = resample(Recording(t, f, np.zeros((5, 3))), 20.0)
    np.testing.assert_allclose(out.t_s, [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3])
    # at t = 0.1 the later row (5.0) wins
    np.testing.assert_allclose(out.f[:, 0], [0.0, 2.5, 5.0, 3.5, 2.0, 2.5, 3.0])


def test_resample_nan_touches_only_its_intervals() -> None:
    t = np.arange(6) * 0.1
    f = np.zeros((6, 3))
    f[:, 0] = [0.0, 1.0, np.nan, 3.0, 4.0, 5.0]
    out = resample(Recording(t, f, np.zeros((6, 3))), 20.0)
    x = out.f[:, 0]
    # grid 0, .05, ..., .5: NaN strictly between 0.1 and 0.3, exact samples kept
    assert np.isnan(x[[3, 4, 5]]).all()
    np.testing.assert_allclose(x[[0, 1, 2, 6, 7, 8, 9, 10]], [0, 0.5, 1, 3, 3.5, 4, 4.5, 5])


def test_resample_edge_cases() -> None:
    one = Recording([2.0], [[0, 0, 9.8]], [[0, 0, 0]])
    assert len(resample(one, 100.0)) == 1
    empty = Recording(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))
    assert len(resample(empty, 100.0)) == 0
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ConfigError, match="fs_hz"):
            resample(one, bad)
