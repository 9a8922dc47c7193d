"""Live for Speed OutSim: golden packets at the documented offsets both ways, the options
word, world-to-car rotation, random bytes only counted."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue._errors import ConfigError
from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._lfs import OSO_ALL, LFSDecoder, OutSimMain, outsim2_size
from motioncue.telemetry._sample import up_in_body_from_angles


def _golden() -> bytes:
    """OutSim2 with OutSim Opts 1ff, written at the documented byte offsets by hand."""
    b = bytearray(280)
    b[0:4] = b"LFST"  # OSO_HEADER
    struct.pack_into("<i", b, 4, 7)  # OSO_ID
    struct.pack_into("<I", b, 8, 123_456)  # OSO_TIME (ms)
    struct.pack_into("<3f", b, 12, 0.1, 0.2, 0.3)  # AngVel (world)
    struct.pack_into("<3f", b, 24, 0.0, 0.0, 0.0)  # Heading, Pitch, Roll
    struct.pack_into("<3f", b, 36, 1.5, 3.0, -0.5)  # Accel (world)
    struct.pack_into("<3f", b, 48, 0.0, 30.0, 0.0)  # Vel
    struct.pack_into("<3i", b, 60, 65536, 2 * 65536, 0)  # Pos (1 m = 65536)
    b[92] = 4  # OSO_DRIVE @ 4+4+4+60+20: gear (third)
    struct.pack_into("<f", b, 96, 600.0)  # engine angular velocity (rad/s)
    return bytes(b)


def test_sizes_of_the_options_word() -> None:
    assert outsim2_size(OSO_ALL) == 280
    assert outsim2_size(0xFF) == 272  # the usual "all but extra"
    assert outsim2_size(0x08) == 60


def test_golden_packet_decodes_by_hand() -> None:
    s = decoder_for("lfs").feed(_golden(), 4.0)
    assert s is not None and s.game == "lfs" and s.t_s == 4.0 and not s.paused
    # level, heading 0: car (right, forward, up) = world (X, Y, Z); ISO (fwd, left, up)
    assert s.f == pytest.approx((3.0, -1.5, -0.5 + G0_M_S2), abs=1e-6)
    assert s.w == pytest.approx((0.2, -0.1, 0.3), abs=1e-7)
    assert s.rpm == pytest.approx(600.0 * 30 / math.pi) and s.gear == 3


def test_golden_packet_is_packed_back_bit_for_bit() -> None:
    data = _golden()
    m = OutSimMain.unpack(data, 12)
    assert m.accel == (1.5, 3.0, -0.5) and m.pos == (65536, 131072, 0)
    out = bytearray(m.outsim2(OSO_ALL, 123_456, gear=4, engine_rad_s=600.0))
    out[4:8] = struct.pack("<i", 7)  # the ID is the game's, not the encoder's
    assert bytes(out) == data
    assert LFSDecoder().feed(m.classic(123_456), 0.0) is not None
    assert LFSDecoder().feed(m.classic(1, outsim_id=3), 0.0) is not None


def test_heading_pitch_and_roll_rotate_world_vectors_into_the_car() -> None:
    dec = LFSDecoder()
    # heading +90 deg (anticlockwise from above): the car faces world -X
    s = dec.feed(OutSimMain((0.0, 0.0, 0.5), math.pi / 2, 0.0, 0.0, (-3.0, 0.0, 0.0),
                            (-20.0, 0.0, 0.0)).outsim2(), 0.0)  # fmt: skip
    assert s is not None
    assert s.f == pytest.approx((3.0, 0.0, G0_M_S2), abs=1e-5)  # pushed forward
    assert s.w == pytest.approx((0.0, 0.0, 0.5), abs=1e-7)  # turning left
    # nose up (pitch anticlockwise seen from the right) at rest: f leans forward
    s = dec.feed(OutSimMain((0.0, 0.0, 0.0), 0.0, 0.2, 0.0, (0.0, 0.0, 0.0),
                            (0.0, 0.0, 0.0)).outsim2(), 0.0)  # fmt: skip
    assert s is not None
    assert s.f == pytest.approx((G0_M_S2 * math.sin(0.2), 0.0, G0_M_S2 * math.cos(0.2)), abs=1e-5)
    # roll anticlockwise seen from the front: the right side goes down, and world up (the
    # specific force at rest) leans towards the raised left side: as up_in_body_from_angles
    s = dec.feed(OutSimMain((0.0, 0.0, 0.0), 0.0, 0.0, 0.3, (0.0, 0.0, 0.0),
                            (0.0, 0.0, 0.0)).outsim2(), 0.0)  # fmt: skip
    assert s is not None
    assert s.f == pytest.approx(tuple(G0_M_S2 * c for c in up_in_body_from_angles(0.0, 0.3)),
                                abs=1e-5)  # fmt: skip


def test_other_options_and_bad_datagrams_are_counted_by_reason() -> None:
    dec = LFSDecoder(0xFF)
    m = OutSimMain((0.0, 0.0, 0.0), 0.0, 0.0, 0.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))
    assert dec.feed(m.outsim2(0xFF), 0.0) is not None
    assert dec.feed(m.outsim2(OSO_ALL), 0.0) is None  # the game sends 1ff, we were told ff
    assert dec.feed(b"XXXX" + m.outsim2(0xFF)[4:], 0.0) is None
    assert dec.feed(m.outsim2(0xFF)[:100], 0.0) is None  # cut short: another size of LFST
    assert dec.feed(bytes(100), 0.0) is None
    bad = bytearray(m.outsim2(0xFF))
    struct.pack_into("<f", bad, 24, 50.0)  # a heading of 50 rad is not an angle
    assert dec.feed(bytes(bad), 0.0) is None
    struct.pack_into("<f", bad, 24, math.inf)
    assert dec.feed(bytes(bad), 0.0) is None
    assert dec.stats == {"sample": 1, "skipped: other options": 2, "skipped: foreign": 2,
                         "skipped: truncated": 1, "skipped: non-finite": 1}  # fmt: skip
    with pytest.raises(ConfigError, match="OSO_MAIN"):
        LFSDecoder(0x07)


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=400))
def test_random_bytes_are_only_counted(data: bytes) -> None:
    dec = LFSDecoder()
    r = dec.decode(data, 0.0)
    assert sum(dec.stats.values()) == 1
    if len(data) not in (64, 68, 280):
        assert r.sample is None
    if r.sample is not None:
        assert all(math.isfinite(v) and abs(v) <= 1000 for v in r.sample.f + r.sample.w)
