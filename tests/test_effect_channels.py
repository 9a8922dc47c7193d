"""Optional channels for the effect layer. F1: suspension velocity from Motion Ex (real
captures), engine rpm and gear from Car Telemetry (id 6) written at the documented offsets.
Forza: engine rpm and its maximum from the Sled head."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from motioncue.telemetry import decoder_for
from motioncue.telemetry._f1 import CAR_TELEMETRY_SIZE

DATA = Path("/work/shared/data/f1")

needs_f1 = pytest.mark.skipif(not DATA.is_dir(), reason="real F1 captures not on this machine")


def _packets(year: int) -> tuple[bytes, bytes]:
    d = DATA / str(year)
    return (d / "packet-0.bin").read_bytes(), (d / "packet-13.bin").read_bytes()


def _car_telemetry(motion: bytes, gear: int, rpm: int, uid: int | None = None) -> bytes:
    """Header of the Motion packet with packetId 6; the player's gear (int8 @+15) and
    engineRPM (uint16 @+16) in its 60-byte block at 29 + 60 * playerCarIndex."""
    b = bytearray(CAR_TELEMETRY_SIZE)
    b[:29] = motion[:29]
    b[6] = 6
    if uid is not None:
        struct.pack_into("<Q", b, 7, uid)
    struct.pack_into("<bH", b, 29 + 60 * motion[27] + 15, gear, rpm)
    return bytes(b)


@needs_f1
@pytest.mark.parametrize("year", [2023, 2024])
def test_suspension_velocity_comes_from_motion_ex_in_m_s_front_first(year: int) -> None:
    motion, ex = _packets(year)
    rl, rr, fl, fr = struct.unpack_from("<4f", ex, 29 + 16)  # suspensionVelocity, mm/s
    dec = decoder_for("f1")
    dec.feed(ex, 0.0)
    s = dec.feed(motion, 0.0)
    assert s is not None and s.rpm != s.rpm and s.gear is None  # no car telemetry yet: unknown
    assert s.suspension_velocity_m_s == pytest.approx((fl / 1e3, fr / 1e3, rl / 1e3, rr / 1e3))
    assert max(abs(v) for v in s.suspension_velocity_m_s) < 1.0  # m/s, not mm/s


@needs_f1
def test_car_telemetry_gives_rpm_and_gear_of_the_same_session() -> None:
    motion, ex = _packets(2024)
    assert CAR_TELEMETRY_SIZE == 1352
    dec = decoder_for("f1")
    assert dec.decode(_car_telemetry(motion, 5, 11250), 0.0).reason == "state: car telemetry"
    dec.feed(ex, 0.0)
    s = dec.feed(motion, 0.0)
    assert s is not None and s.rpm == 11250.0 and s.gear == 5
    dec.decode(_car_telemetry(motion, -1, 3000), 0.0)
    s = dec.feed(motion, 0.0)
    assert s is not None and s.gear == -1 and s.rpm == 3000.0
    other = decoder_for("f1")
    other.decode(_car_telemetry(motion, 4, 9000, uid=123), 0.0)  # another session
    other.feed(ex, 0.0)
    s = other.feed(motion, 0.0)
    assert s is not None and s.gear is None
    short = _car_telemetry(motion, 4, 9000)[:-1]
    assert other.decode(short, 0.0).reason == "ignored: other packet id"


def test_forza_passes_engine_rpm_and_its_maximum() -> None:
    from motioncue.telemetry._forza import ForzaMotion

    z = (0.0, 0.0, 0.0)
    raw = ForzaMotion(1, 5, 8500.0, 900.0, 4321.5, z, z, z, 0.0, 0.0, 0.0).pack()
    s = decoder_for("forza").feed(raw + bytes(232 - len(raw)), 0.0)
    assert s is not None and s.rpm == 4321.5 and s.rpm_max == 8500.0 and s.gear is None
    raw = ForzaMotion(1, 5, 8500.0, 900.0, float("nan"), z, z, z, 0.0, 0.0, 0.0).pack()
    s = decoder_for("forza").feed(raw + bytes(232 - len(raw)), 0.0)
    assert s is not None and s.rpm != s.rpm  # a bad channel is dropped, the motion is kept
