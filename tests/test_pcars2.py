"""Project CARS 2 / AMS2 UDP decoder: golden packets from the documented offsets, axis map,
game-state pause, bad packets, round trips."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._pcars2 import (
    GAME_STATE_SIZE,
    TELEMETRY_SIZE,
    PCars2Decoder,
    PCars2Telemetry,
    game_state_packet,
)


def _golden(
    *,
    acc: tuple[float, float, float] = (0.5, -0.25, 2.0),
    ang: tuple[float, float, float] = (0.125, -0.5, 0.25),
    orientation: tuple[float, float, float] = (0.0, 1.0, 0.0),
) -> bytes:
    """A type-0 packet written at the byte offsets of SMS_UDP_Definitions.hpp by hand."""
    b = bytearray(559)
    struct.pack_into("<IIBBBB", b, 0, 77, 77, 1, 1, 0, 2)
    struct.pack_into("<f", b, 36, 41.5)  # sSpeed
    struct.pack_into("<HH", b, 40, 6500, 8200)  # sRpm, sMaxRpm
    b[45] = 0x63  # 6 gears, in 3rd
    struct.pack_into("<3f", b, 52, *orientation)  # sOrientation
    struct.pack_into("<3f", b, 64, 0.0, 0.0, -41.5)  # sLocalVelocity: forward is -z
    struct.pack_into("<3f", b, 88, *ang)  # sAngularVelocity
    struct.pack_into("<3f", b, 100, *acc)  # sLocalAcceleration
    struct.pack_into("<4f", b, 328, 0.1, -0.2, 0.3, -0.4)  # sSuspensionVelocity
    return bytes(b)


def test_golden_packet_decodes_by_hand() -> None:
    data = _golden()
    assert len(data) == TELEMETRY_SIZE == 559
    s = decoder_for("pcars2").feed(data, 5.0)
    assert s is not None and s.game == "pcars2" and s.t_s == 5.0 and not s.paused
    # local x left, y up, z back: a_iso = (-a_z, a_x, a_y) plus gravity (level: +G0 up);
    # w_iso = (-w_z, w_x, w_y)
    assert s.f == pytest.approx((-2.0, 0.5, -0.25 + G0_M_S2), abs=1e-12)
    assert s.w == pytest.approx((-0.25, 0.125, -0.5), abs=1e-12)
    assert s.rpm == 6500.0 and s.rpm_max == 8200.0 and s.gear == 3
    assert s.suspension_velocity_m_s == pytest.approx((0.1, -0.2, 0.3, -0.4))


def test_golden_packet_is_packed_back_bit_for_bit() -> None:
    data = _golden()
    m = PCars2Telemetry.unpack(data)
    assert m.local_velocity == (0.0, 0.0, -41.5) and m.gear_num_gears == 0x63
    assert m.pack() == data


@pytest.mark.parametrize(
    ("orientation", "expected"),
    [
        # rotation about +x (left) by +0.2 lifts the nose (forward = -z turns towards +y):
        # world up leans towards the body's forward axis, so f leans forward
        ((0.2, 0.0, 0.0), (math.sin(0.2), 0.0, math.cos(0.2))),
        # rotation about +z (backward) by +0.3 turns +x (the left side) towards +y: the left
        # side rises (ISO roll +0.3, right side down), world up leans left, so does f
        ((0.0, 0.0, 0.3), (0.0, math.sin(0.3), math.cos(0.3))),
    ],
)
def test_attitude_adds_gravity(
    orientation: tuple[float, float, float], expected: tuple[float, float, float]
) -> None:
    s = PCars2Decoder().feed(_golden(acc=(0, 0, 0), orientation=orientation), 0.0)
    assert s is not None
    assert s.f == pytest.approx(tuple(G0_M_S2 * e for e in expected), abs=1e-6)


def test_game_state_pauses_and_resumes_and_reverse_gear() -> None:
    dec = PCars2Decoder()
    assert dec.decode(game_state_packet(3), 0.0).status == "state"  # paused
    s = dec.feed(_golden(), 0.0)
    assert s is not None and s.paused
    assert dec.decode(game_state_packet(2), 0.0).reason == "state"  # playing
    s = dec.feed(_golden(), 0.0)
    assert s is not None and not s.paused
    raw = bytearray(_golden())
    raw[45] = 0x6F
    s = dec.feed(bytes(raw), 0.0)
    assert s is not None and s.gear == -1
    assert len(game_state_packet(4)) == GAME_STATE_SIZE


def test_bad_packets_are_counted() -> None:
    good = _golden()

    def with_header(ptype: int, part: int = 1, parts: int = 1, size: int = 559) -> bytes:
        b = bytearray(size)
        struct.pack_into("<IIBBBB", b, 0, 1, 1, part, parts, ptype, 2)
        return bytes(b)

    cases = {
        good[:11]: "skipped: truncated",
        good[:558]: "skipped: truncated",
        good + b"\0": "skipped: wrong size",
        with_header(9): "skipped: foreign",
        with_header(0, part=2, parts=1): "skipped: foreign",
        with_header(0, parts=0): "skipped: foreign",
        with_header(4, size=23): "skipped: truncated",
        with_header(4, size=25): "skipped: wrong size",
        with_header(3, size=1063): "ignored",
        with_header(3, size=1000): "skipped: wrong size",
        _golden(acc=(math.nan, 0, 0)): "skipped: non-finite",
        _golden(orientation=(math.inf, 0, 0)): "skipped: non-finite",
        _golden(ang=(0, 0, 1e4)): "skipped: out of range",
    }
    dec = PCars2Decoder()
    for data, reason in cases.items():
        assert dec.decode(data, 0.0).reason == reason, reason
    assert sum(dec.stats.values()) == len(cases) and "sample" not in dec.stats


f32 = st.floats(allow_nan=False, allow_infinity=False, width=32)
v3 = st.tuples(f32, f32, f32)


@given(
    num=st.integers(0, 2**32 - 1),
    speed=f32,
    rpm=st.integers(0, 65535),
    max_rpm=st.integers(0, 65535),
    gear=st.integers(0, 255),
    o=v3,
    lv=v3,
    av=v3,
    la=v3,
    sv=st.tuples(f32, f32, f32, f32),
)
def test_pack_unpack_round_trip(
    num: int, speed: float, rpm: int, max_rpm: int, gear: int, o: tuple, lv: tuple,
    av: tuple, la: tuple, sv: tuple,
) -> None:  # fmt: skip
    m = PCars2Telemetry(num, speed, rpm, max_rpm, gear, o, lv, av, la, sv)
    raw = m.pack()
    assert len(raw) == 559 and PCars2Telemetry.unpack(raw) == m


@given(
    acc=st.tuples(*[st.floats(-50, 50, width=32)] * 3),
    pitch=st.floats(-1.5, 1.5, width=32),
    roll=st.floats(-3, 3, width=32),
    ang=st.tuples(*[st.floats(-5, 5, width=32)] * 3),
)
def test_gravity_only_rotates_and_rates_keep_their_norm(
    acc: tuple[float, float, float], pitch: float, roll: float, ang: tuple[float, float, float]
) -> None:
    s = PCars2Decoder().feed(_golden(acc=acc, ang=ang, orientation=(pitch, 0.0, roll)), 0.0)
    assert s is not None
    a_iso = (-acc[2], acc[0], acc[1])
    g = [fi - ai for fi, ai in zip(s.f, a_iso, strict=True)]
    assert math.sqrt(sum(x * x for x in g)) == pytest.approx(G0_M_S2, rel=1e-6)
    assert math.hypot(*s.w) == pytest.approx(math.hypot(*ang), rel=1e-6, abs=1e-9)
