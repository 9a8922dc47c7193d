"""EA SPORTS WRC: motioncue's packet structure (golden packets at its offsets, both ways),
projections on the car's axes, angular velocity from the turning axes, pause, structure
files, random bytes only counted."""

from __future__ import annotations

import json
import math
import struct
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue._errors import ConfigError
from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._wrc import MOTIONCUE_STRUCTURE, WRCDecoder, structure_json

TOOLS = Path(__file__).resolve().parents[1] / "tools" / "wrc"


def _golden(t: float, stage: float, fwd=(0.0, 0.0, 1.0), left=(1.0, 0.0, 0.0),
            up=(0.0, 1.0, 0.0), acc=(0.5, 0.0, 3.0)) -> bytes:  # fmt: skip
    """A motioncue session_update packet written at its byte offsets by hand."""
    b = bytearray(93)
    struct.pack_into("<Q", b, 0, 77)  # packet_uid
    struct.pack_into("<3f", b, 8, t, 1 / 120, stage)  # total, delta, stage time
    struct.pack_into("<f", b, 20, 25.0)  # vehicle_speed
    struct.pack_into("<3f", b, 24, 0.0, 0.0, 25.0)  # velocity (world)
    struct.pack_into("<3f", b, 36, *acc)  # acceleration (world)
    struct.pack_into("<3f", b, 48, *left)
    struct.pack_into("<3f", b, 60, *fwd)
    struct.pack_into("<3f", b, 72, *up)
    struct.pack_into("<2f", b, 84, 8000.0, 5500.0)  # rpm max, current
    b[92] = 10  # gear index 10 = reverse
    return bytes(b)


def test_golden_packets_both_ways() -> None:
    dec = WRCDecoder()
    assert dec.layout.packer.size == 93
    data = _golden(10.0, 5.0)
    values = dict(zip(dec.layout.channels, dec.layout.packer.unpack(data), strict=True))
    assert values["vehicle_acceleration_z"] == 3.0 and values["vehicle_gear_index"] == 10
    assert dec.layout.pack(values) == data


def test_level_car_by_hand() -> None:
    dec = decoder_for("wrc")
    assert dec.decode(_golden(10.0, 5.0), 0.0).status == "partial"  # the first: no rates yet
    s = dec.feed(_golden(10.01, 5.01), 3.0)
    assert s is not None and s.game == "wrc" and s.t_s == 3.0 and not s.paused
    # projections on (forward, left, up) = world (z, x, y); gravity along world +y
    assert s.f == pytest.approx((3.0, 0.5, G0_M_S2), abs=1e-6)
    assert s.w == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)
    assert s.rpm == 5500.0 and s.rpm_max == 8000.0 and s.gear == -1


def test_turning_axes_give_the_angular_velocity() -> None:
    """Yaw left by 0.01 rad in 0.01 s about world up: 1 rad/s of ISO yaw rate; then roll."""
    dec = WRCDecoder()
    dec.feed(_golden(1.0, 1.0), 0.0)
    th = 0.01
    fwd = (math.sin(th), 0.0, math.cos(th))  # turned towards the left axis (world +x)
    left = (math.cos(th), 0.0, -math.sin(th))
    s = dec.feed(_golden(1.01, 1.01, fwd=fwd, left=left), 0.0)
    assert s is not None and s.w == pytest.approx((0.0, 0.0, 1.0), abs=0.01)
    up = (-math.sin(th) * math.cos(th), math.cos(th), math.sin(th) * math.sin(th))
    left2 = (left[0] * math.cos(th), math.sin(th), left[2] * math.cos(th))  # left side rises
    s = dec.feed(_golden(1.02, 1.02, fwd=fwd, left=left2, up=up), 0.0)
    assert s is not None and s.w[0] == pytest.approx(1.0, abs=0.02)  # roll right side down


def test_stage_clock_stopped_is_paused_and_gaps_restart() -> None:
    dec = WRCDecoder()
    dec.feed(_golden(1.0, 3.0), 0.0)
    s = dec.feed(_golden(1.01, 3.0), 0.0)
    assert s is not None and s.paused
    assert dec.decode(_golden(1.5, 3.5), 0.0).status == "partial"  # 0.49 s gap
    assert dec.decode(_golden(1.4, 3.6), 0.0).status == "partial"  # clock backwards


def test_bad_datagrams_are_counted_by_reason() -> None:
    dec = WRCDecoder()
    g = _golden(1.0, 1.0)
    assert dec.feed(g[:50], 0.0) is None
    assert dec.feed(g + b"\0", 0.0) is None
    assert dec.feed(_golden(1.0, 1.0, up=(0.0, 2.0, 0.0)), 0.0) is None
    assert dec.feed(_golden(1.0, 1.0, up=(0.0, math.nan, 0.0)), 0.0) is None
    assert dec.stats == {"skipped: truncated": 1, "skipped: wrong size": 1,
                         "skipped: foreign": 1, "skipped: non-finite": 1}  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.binary(max_size=200), st.binary(min_size=93, max_size=93)))
def test_random_bytes_are_only_counted(data: bytes) -> None:
    dec = WRCDecoder()
    r = dec.decode(data, 0.0)
    assert sum(dec.stats.values()) == 1 and r.sample is None


def test_shipped_structure_files_are_the_decoders(tmp_path: Path) -> None:
    made = structure_json()
    assert json.loads((TOOLS / "motioncue.json").read_text()) == made["structure"]
    assert json.loads((TOOLS / "config-entry.json").read_text()) == made["config_entry"]
    channels = {"channels": [{"id": n, "type": t, "units": "", "description": ""}
                             for n, t in MOTIONCUE_STRUCTURE]}  # fmt: skip
    (tmp_path / "channels.json").write_text(json.dumps(channels))
    dec = WRCDecoder.from_structure(TOOLS / "motioncue.json", tmp_path / "channels.json")
    assert dec.layout.channels == WRCDecoder().layout.channels
    (tmp_path / "bad.json").write_text("{}")
    with pytest.raises(ConfigError, match="not a WRC structure"):
        WRCDecoder.from_structure(tmp_path / "bad.json", tmp_path / "channels.json")
    with pytest.raises(ConfigError, match="needs"):
        WRCDecoder([("packet_uid", "uint64")])
    with pytest.raises(ConfigError, match="type"):
        WRCDecoder([("packet_uid", "complex")])
