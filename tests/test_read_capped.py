"""Files read whole (configs, rides, recordings) are refused by size before they are read.

The three readers share :func:`motioncue._config.read_capped`: a file over the limit is
refused from its size (a sparse file, so nothing is written), a device without a size
(``/dev/zero``) after at most the limit plus one byte, and the wrong kind of file by its
first bytes.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from motioncue._config import MAX_CONFIG_BYTES, load_toml, read_capped
from motioncue._errors import ConfigError, ProtocolError
from motioncue.pipeline._ridefile import MAX_RIDE_BYTES, load_ride
from motioncue.telemetry._container import MAGIC, MAX_RECORDING_BYTES, read_recording_file

ZERO = Path("/dev/zero")


def _sparse(path: Path, size: int, head: bytes = b"") -> Path:
    with open(path, "wb") as fh:
        fh.write(head)
        fh.truncate(size)
    return path


def test_read_capped_reads_a_file_at_the_limit_and_refuses_one_byte_more(tmp_path: Path) -> None:
    data = read_capped(_sparse(tmp_path / "a", 100, b"xy"), 100, "a test file")
    assert data == b"xy" + bytes(98)
    with pytest.raises(ValueError, match="b: 101 bytes is larger than the 100 bytes a test file"):
        read_capped(_sparse(tmp_path / "b", 101), 100, "a test file", error=ValueError, where="b")


@pytest.mark.skipif(not ZERO.exists(), reason="needs /dev/zero (a file without a size)")
def test_read_capped_stops_a_device_one_byte_past_the_limit() -> None:
    with pytest.raises(ConfigError, match="/dev/zero: more than the 1000 bytes a test file"):
        read_capped(ZERO, 1000, "a test file")


def test_the_head_is_checked_before_the_size(tmp_path: Path) -> None:
    heads: list[bytes] = []

    def check_head(head: bytes) -> None:
        heads.append(head)
        raise ValueError("wrong kind")

    big = _sparse(tmp_path / "c", 10_000, b"XYZW")
    with pytest.raises(ValueError, match="wrong kind"):
        read_capped(big, 100, "a test file", check_head=check_head, head_size=4)
    assert heads == [b"XYZW"]


def test_a_config_over_the_limit_is_refused_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=f"{MAX_CONFIG_BYTES + 1} bytes is larger than the") as e:
        load_toml(_sparse(tmp_path / "big.toml", MAX_CONFIG_BYTES + 1))
    assert "\n" not in str(e.value)
    if ZERO.exists():
        with pytest.raises(ConfigError, match=f"more than the {MAX_CONFIG_BYTES} bytes"):
            load_toml(ZERO)


def test_a_ride_over_the_limit_is_refused_by_its_size(tmp_path: Path) -> None:
    big = _sparse(tmp_path / "big.ride", MAX_RIDE_BYTES + 1, b"PK\x03\x04")
    with pytest.raises(ConfigError, match=f"{MAX_RIDE_BYTES + 1} bytes is larger"):
        load_ride(big)
    with pytest.raises(ConfigError, match="not a zip archive"):
        load_ride(_sparse(tmp_path / "bad.ride", MAX_RIDE_BYTES + 1, b"XXXX"))


def test_a_recording_over_the_limit_is_refused_by_its_size(tmp_path: Path) -> None:
    big = _sparse(tmp_path / "big.mctr", MAX_RECORDING_BYTES + 1, MAGIC)
    with pytest.raises(ProtocolError, match="split it"):
        read_recording_file(big)
    with pytest.raises(ProtocolError, match="too short"):
        read_recording_file(_sparse(tmp_path / "short.mctr", 3, MAGIC[:3]))
    assert os.path.getsize(big) == MAX_RECORDING_BYTES + 1
