"""Richard Burns Rally (RSF / NGP telemetry): golden packets at the header's offsets both
ways, the taken-as axes, pause by the step counter, random bytes only counted."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._rbr import PACKET_SIZE, RBRCar, RBRDecoder
from motioncue.telemetry._sample import up_in_body_from_angles


def _golden(steps: int = 1000, roll: float = 0.0, pitch: float = 0.0) -> bytes:
    """A TelemetryData datagram written at the NGP header's byte offsets by hand."""
    b = bytearray(664)
    struct.pack_into("<I", b, 0, steps)  # totalSteps
    struct.pack_into("<f", b, 12, 42.5)  # stage.raceTime
    struct.pack_into("<i", b, 44, 4)  # control.gear: third
    struct.pack_into("<f", b, 60, 90.0)  # car.speed (km/h)
    struct.pack_into("<3f", b, 76, roll, pitch, 30.0)  # car.roll, pitch, yaw (deg)
    struct.pack_into("<6f", b, 88, 25.0, 0.5, 0.1, 5.0, -10.0, 20.0)  # velocities
    struct.pack_into("<6f", b, 112, 3.0, -2.0, 0.5, 0.0, 0.0, 0.0)  # accelerations
    struct.pack_into("<f", b, 136, 6500.0)  # engine.rpm
    return bytes(b)


def test_golden_packet_decodes_by_hand() -> None:
    s = decoder_for("rbr").feed(_golden(), 2.0)
    assert s is not None and s.game == "rbr" and s.t_s == 2.0 and not s.paused
    assert s.f == pytest.approx((3.0, -2.0, 0.5 + G0_M_S2), abs=1e-6)
    d = math.pi / 180
    assert s.w == pytest.approx((5.0 * d, -10.0 * d, 20.0 * d), abs=1e-7)
    assert s.rpm == 6500.0 and s.gear == 3


def test_golden_packet_is_packed_back_bit_for_bit() -> None:
    data = _golden()
    car = RBRCar.unpack(data)
    assert car.total_steps == 1000 and car.gear == 4 and car.attitude_deg == (0.0, 0.0, 30.0)
    assert car.velocities[0] == 25.0 and car.accelerations[:3] == (3.0, -2.0, 0.5)
    assert car.pack() == data


@pytest.mark.parametrize(("roll", "pitch"), [(10.0, 0.0), (0.0, -8.0), (5.0, 12.0)])
def test_attitude_adds_gravity(roll: float, pitch: float) -> None:
    s = RBRDecoder().feed(_golden(roll=roll, pitch=pitch), 0.0)
    assert s is not None
    up = up_in_body_from_angles(math.radians(pitch), math.radians(roll))
    assert s.f == pytest.approx((3.0 + G0_M_S2 * up[0], -2.0 + G0_M_S2 * up[1],
                                 0.5 + G0_M_S2 * up[2]), abs=1e-5)  # fmt: skip


def test_a_repeated_step_is_paused() -> None:
    dec = RBRDecoder()
    a, b = dec.feed(_golden(7), 0.0), dec.feed(_golden(7), 0.01)
    c = dec.feed(_golden(8), 0.02)
    assert a is not None and not a.paused and b is not None and b.paused
    assert c is not None and not c.paused


def test_bad_datagrams_are_counted_by_reason() -> None:
    dec = RBRDecoder()
    g = _golden()
    assert dec.feed(g[:152], 0.0) is None
    assert dec.feed(g + b"\0", 0.0) is None
    assert dec.feed(_golden(roll=1000.0), 0.0) is None
    assert dec.feed(_golden(pitch=math.nan), 0.0) is None
    bad_gear = bytearray(g)
    struct.pack_into("<i", bad_gear, 44, 99)
    assert dec.feed(bytes(bad_gear), 0.0) is None
    assert dec.stats == {"skipped: truncated": 1, "skipped: wrong size": 1,
                         "skipped: foreign": 2, "skipped: non-finite": 1}  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.binary(max_size=800), st.binary(min_size=PACKET_SIZE, max_size=PACKET_SIZE)))
def test_random_bytes_are_only_counted(data: bytes) -> None:
    dec = RBRDecoder()
    r = dec.decode(data, 0.0)
    assert sum(dec.stats.values()) == 1
    if len(data) != PACKET_SIZE:
        assert r.sample is None
    if r.sample is not None:
        assert all(math.isfinite(v) and abs(v) <= 1000 for v in r.sample.f + r.sample.w)
