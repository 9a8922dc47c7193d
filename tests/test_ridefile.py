"""Ride files round-trip exactly; foreign, damaged and newer files are refused clearly."""

from __future__ import annotations

import io
import json
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError
from motioncue.pipeline import RIDE_FORMAT_VERSION, Ride, load_ride, save_ride


def _ride(n_frames: int = 5, n_axes: int = 6, seed: int = 0) -> Ride:
    rng = np.random.default_rng(seed)
    return Ride(
        platform="stewart6-linear",
        controller="mbox6",
        rate_hz=100.0,
        actuator_names=tuple(f"a{i}" for i in range(n_axes)),
        t_s=np.arange(n_frames) / 100.0,
        pulses=rng.integers(-(2**31), 2**31 - 1, size=(n_frames, n_axes), dtype=np.int64),
        dout=rng.integers(0, 0xFFFF, size=n_frames),
        dacs=rng.integers(0, 0xFFFF, size=(n_frames, 2)),
        limits={"max_speed_pulses_s": [1.5] * n_axes},
        effects=("seat-belt",),
        source="test",
        notes={"rms": 0.25},
    )


@given(
    n_frames=st.integers(1, 40),
    n_axes=st.integers(1, 12),
    seed=st.integers(0, 2**32 - 1),
)
def test_round_trip(
    tmp_path_factory: pytest.TempPathFactory, n_frames: int, n_axes: int, seed: int
) -> None:
    ride = _ride(n_frames, n_axes, seed)
    path = tmp_path_factory.mktemp("r") / "x.ride"
    back = load_ride(save_ride(path, ride))
    np.testing.assert_array_equal(back.pulses, ride.pulses)
    np.testing.assert_array_equal(back.t_s, ride.t_s)
    np.testing.assert_array_equal(back.dout, ride.dout)
    np.testing.assert_array_equal(back.dacs, ride.dacs)
    assert back.header() == ride.header()


def _rewrite_header(path: Path, **changes: object) -> None:
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files}
    header = json.loads(arrays["header"].tobytes())
    header.update(changes)
    arrays["header"] = np.frombuffer(json.dumps(header).encode(), dtype=np.uint8)
    buf = io.BytesIO()
    np.savez(buf, **arrays)
    path.write_bytes(buf.getvalue())


def test_newer_version_is_refused_with_a_clear_message(tmp_path: Path) -> None:
    path = save_ride(tmp_path / "x.ride", _ride())
    _rewrite_header(path, format_version=RIDE_FORMAT_VERSION + 1)
    with pytest.raises(ConfigError, match=r"version 2 is newer .* upgrade motioncue"):
        load_ride(path)


def test_foreign_format_is_refused(tmp_path: Path) -> None:
    path = save_ride(tmp_path / "x.ride", _ride())
    _rewrite_header(path, format="something-else")
    with pytest.raises(ConfigError, match="not a motioncue ride file"):
        load_ride(path)


@pytest.mark.parametrize("content", [b"", b"hello", b"PK\x03\x04garbage"])
def test_non_ride_bytes_are_refused(tmp_path: Path, content: bytes) -> None:
    path = tmp_path / "x.ride"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match="not a motioncue ride file"):
        load_ride(path)


def test_truncated_file_is_refused(tmp_path: Path) -> None:
    path = save_ride(tmp_path / "x.ride", _ride(200))
    data = path.read_bytes()
    path.write_bytes(data[: len(data) // 2])
    with pytest.raises(ConfigError):
        load_ride(path)


def test_a_damaged_npy_header_is_refused_without_a_warning(tmp_path: Path) -> None:
    """A member whose header text holds a stray backslash escape: refused with a clear
    error, and Python's literal parser (numpy reads the header with it) prints no
    "invalid escape sequence" warning on the user's terminal first."""
    path = save_ride(tmp_path / "x.ride", _ride())
    with zipfile.ZipFile(path) as zf:
        members = {i.filename: zf.read(i) for i in zf.infolist()}
    raw = members["pulses.npy"]
    head_len = int.from_bytes(raw[8:10], "little")
    head = raw[10 : 10 + head_len].decode("latin1").replace("'<i", "'<i\\s", 1)
    head = head[:head_len].ljust(head_len)[:-1] + "\n"
    assert "\\s" in head and len(head) == head_len
    members["pulses.npy"] = raw[:10] + head.encode("latin1") + raw[10 + head_len :]
    with zipfile.ZipFile(path, "w") as zf:
        for name, data in members.items():
            zf.writestr(name, data)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(ConfigError, match="damaged array 'pulses'"):
            load_ride(path)
    assert [str(w.message) for w in seen] == []


def test_zip_without_arrays_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "x.ride"
    with zipfile.ZipFile(path, "w") as zf:
        zf.writestr("readme.txt", "hi")
    with pytest.raises(ConfigError, match="missing"):
        load_ride(path)


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("t_s", np.array([0.0, 0.01, 0.01, 0.03, 0.04]), "strictly increasing"),
        ("t_s", np.array([0.0, np.nan, 0.02, 0.03, 0.04]), "finite"),
        ("pulses", np.zeros((5, 5), dtype=np.int64), "shape"),
        ("pulses", np.zeros((5, 6)), "integers"),
        ("pulses", np.full((5, 6), 2**31, dtype=np.int64), "int32"),
        ("dout", np.full(5, 70000), "0..65535"),
    ],
)
def test_invalid_rides_are_rejected(field: str, value: np.ndarray, message: str) -> None:
    ride = _ride()
    kwargs = {k: getattr(ride, k) for k in ride.__dataclass_fields__}
    kwargs[field] = value
    with pytest.raises(ConfigError, match=message):
        Ride(**kwargs)
