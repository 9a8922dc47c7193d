"""F1 23/24 decoder against real captured packets, hand calculations and physics."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._f1 import HEADER, MOTION_EX_SIZES, MOTION_SIZE, F1Decoder, F1Header

DATA = Path("/work/shared/data/f1")
YEARS = (2023, 2024)

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="real F1 captures not on this machine")


def _packets(year: int) -> tuple[bytes, bytes]:
    return (DATA / str(year) / "packet-0.bin").read_bytes(), (
        DATA / str(year) / "packet-13.bin"
    ).read_bytes()


def _hand(year: int) -> dict[str, tuple[float, ...]]:
    """Read the fields by hand at the offsets the EA specification documents.

    Header: packetFormat u16 @0, packetId u8 @6, sessionTime f32 @15, playerCarIndex u8 @27.
    Motion: car i at 29 + 60 i; forward i16[3] @+24, right i16[3] @+30, gForceLateral f32
    @+36, gForceLongitudinal @+40, gForceVertical @+44; worldVelocity f32[3] @+12.
    Motion Ex: localVelocity f32[3] @ 29 + 4*33 = 161, angularVelocity f32[3] @ 173.
    """
    motion, ex = _packets(year)
    player = motion[27]
    base = 29 + 60 * player
    return {
        "format": struct.unpack("<H", motion[0:2]),
        "ids": (motion[6], ex[6]),
        "fwd": tuple(v / 32767 for v in struct.unpack("<3h", motion[base + 24 : base + 30])),
        "right": tuple(v / 32767 for v in struct.unpack("<3h", motion[base + 30 : base + 36])),
        "g": struct.unpack("<3f", motion[base + 36 : base + 48]),  # lat, long, vert
        "world_vel": struct.unpack("<3f", motion[base + 12 : base + 24]),
        "local_vel": struct.unpack("<3f", ex[161:173]),
        "ang_vel": struct.unpack("<3f", ex[173:185]),
        "lat_force": struct.unpack("<4f", ex[29 + 4 * 24 : 29 + 4 * 28]),
        "long_force": struct.unpack("<4f", ex[29 + 4 * 28 : 29 + 4 * 32]),
    }


def _decode_pair(year: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
    motion, ex = _packets(year)
    dec = decoder_for("f1")
    assert dec.feed(ex, 0.0) is None
    s = dec.feed(motion, 1.25)
    assert s is not None and s.game == "f1" and s.t_s == 1.25 and not s.paused
    assert dec.stats == {"partial: motion ex stored": 1, "sample": 1}
    return s.f, s.w


@pytest.mark.parametrize("year", YEARS)
def test_real_packets_have_the_documented_sizes_and_ids(year: int) -> None:
    motion, ex = _packets(year)
    h = _hand(year)
    assert h["format"] == (year,)
    assert h["ids"] == (0, 13)
    assert len(motion) == MOTION_SIZE == 1349
    assert len(ex) == MOTION_EX_SIZES[year] == {2023: 217, 2024: 237}[year]
    hm, he = F1Header.unpack(motion), F1Header.unpack(ex)
    assert hm.session_uid == he.session_uid
    assert hm.pack() == motion[: HEADER.size]  # header round trip on real bytes


@pytest.mark.parametrize("year", YEARS)
def test_conversion_matches_a_hand_calculation(year: int) -> None:
    """f = G0 (gLong + F_y, gLat - R_y, gVert + (R x F)_y), w = (w_z, w_x, w_y)."""
    h = _hand(year)
    fx_, fy_, fz_ = h["fwd"]
    rx_, ry_, rz_ = h["right"]
    g_lat, g_long, g_vert = h["g"]
    up_y = rz_ * fx_ - rx_ * fz_
    expected_f = (G0_M_S2 * (g_long + fy_), G0_M_S2 * (g_lat - ry_), G0_M_S2 * (g_vert + up_y))
    wx, wy, wz = h["ang_vel"]
    f, w = _decode_pair(year)
    assert f == pytest.approx(expected_f, abs=1e-9)
    assert w == pytest.approx((wz, wx, wy), abs=1e-12)


def test_pinned_values_of_the_f1_24_capture() -> None:
    """The F1 24 capture is a fast left-hand corner under braking (numbers by hand above)."""
    f, w = _decode_pair(2024)
    assert f == pytest.approx((-3.4610, 13.2025, 11.9764), abs=2e-4)
    assert w == pytest.approx((-0.21246, 0.077474, 0.37802), abs=2e-5)


def test_local_frame_is_left_up_forward_from_the_same_frame_capture() -> None:
    """Motion and Motion Ex of frame 40465 (F1 23): local velocity = world velocity on
    (-right, right x forward, forward). This pins local x = left, y = up, z = forward."""
    h = _hand(2023)
    F, R, v = h["fwd"], h["right"], h["world_vel"]
    U = (R[1] * F[2] - R[2] * F[1], R[2] * F[0] - R[0] * F[2], R[0] * F[1] - R[1] * F[0])
    dot = lambda a, b: sum(x * y for x, y in zip(a, b, strict=True))  # noqa: E731
    projected = (-dot(R, v), dot(U, v), dot(F, v))
    assert projected == pytest.approx(h["local_vel"], abs=5e-3)
    assert U[1] > 0.999  # the car's up is world +Y: level track, +Y up


def test_lateral_sign_agrees_with_yaw_rate_and_tyre_forces() -> None:
    """F1 24 capture: centripetal w x v, summed lateral tyre forces and the decoded lateral
    specific force all point the same way (ISO +y, left), with similar magnitudes."""
    h = _hand(2024)
    f, w = _decode_pair(2024)
    v_forward = h["local_vel"][2]
    centripetal_left = w[2] * v_forward  # ISO: a_y = r * u for steady turning
    assert centripetal_left > 5.0 and f[1] > 5.0
    assert f[1] == pytest.approx(centripetal_left, rel=0.3)
    assert sum(h["lat_force"]) > 0  # tyre forces along local +x (left)
    assert sum(h["long_force"]) < 0 and f[0] < 0  # braking: both backwards


def test_vertical_g_force_excludes_gravity_so_rest_gives_plus_one_g() -> None:
    """F1 23 capture: gForceVertical is 0.03 at 73 m/s on a level straight, so the decoder
    adds gravity; a car at rest, level (g-forces zero) must read f = (0, 0, +G0)."""
    h = _hand(2023)
    assert abs(h["g"][2]) < 0.1 and math.hypot(*h["world_vel"]) > 70
    motion, ex = _packets(2023)
    player = motion[27]
    base = 29 + 60 * player
    rest = bytearray(motion)
    # level, facing +Z; in the right-handed, +Y-up world the right side is then -X
    struct.pack_into("<3h3h", rest, base + 24, 0, 0, 32767, -32767, 0, 0)
    struct.pack_into("<3f", rest, base + 36, 0.0, 0.0, 0.0)
    ex_rest = bytearray(ex)
    struct.pack_into("<3f", ex_rest, 173, 0.0, 0.0, 0.0)
    dec = decoder_for("f1")
    dec.feed(bytes(ex_rest), 0.0)
    s = dec.feed(bytes(rest), 0.0)
    assert s is not None
    assert s.f == pytest.approx((0.0, 0.0, G0_M_S2), abs=1e-12)
    assert s.w == (0.0, 0.0, 0.0)


def test_nose_up_slope_reads_forward_specific_force() -> None:
    """At rest facing uphill by 10 deg an accelerometer reads +g sin(10 deg) forward."""
    motion, ex = _packets(2023)
    base = 29 + 60 * motion[27]
    th = math.radians(10)
    m = bytearray(motion)
    fwd = (0, round(32767 * math.sin(th)), round(32767 * math.cos(th)))
    struct.pack_into("<3h3h3f", m, base + 24, *fwd, -32767, 0, 0, 0.0, 0.0, 0.0)
    dec = F1Decoder()
    dec.feed(ex, 0.0)
    s = dec.feed(bytes(m), 0.0)
    assert s is not None
    assert s.f[0] == pytest.approx(G0_M_S2 * math.sin(th), abs=1e-3)
    assert s.f[2] == pytest.approx(G0_M_S2 * math.cos(th), abs=1e-3)


def test_motion_without_a_motion_ex_is_partial_and_stale_or_foreign_ex_is_not_used() -> None:
    motion, ex = _packets(2024)
    dec = F1Decoder(max_ex_age_s=0.1)
    assert dec.decode(motion, 0.0).reason == "partial: no motion ex"
    # an Ex from another session does not pair
    other = bytearray(ex)
    struct.pack_into("<Q", other, 7, 12345)
    dec.feed(bytes(other), 0.0)
    assert dec.decode(motion, 0.0).reason == "partial: no motion ex"
    # an Ex 0.5 s of session time older does not pair either
    old = bytearray(ex)
    (stime,) = struct.unpack_from("<f", motion, 15)
    struct.pack_into("<f", old, 15, stime - 0.5)
    dec.feed(bytes(old), 0.0)
    assert dec.decode(motion, 0.0).reason == "partial: no motion ex"
    dec.feed(ex, 0.0)  # 35 ms older: pairs
    assert dec.decode(motion, 0.0).status == "sample"


def _session(year: int, uid_from: bytes, paused: int, spectating: int = 0) -> bytes:
    h = F1Header.unpack(uid_from)
    hdr = F1Header(
        h.packet_format, h.game_year, 1, 17, 1, 1, h.session_uid, h.session_time, 1, 1, 0, 255
    )
    body = struct.pack("<BbbBHBbBHHBBBB", 0, 30, 20, 5, 5000, 10, 0, 0, 600, 900, 80, paused,
                       spectating, 0)  # fmt: skip
    return hdr.pack() + body + bytes(753 - HEADER.size - len(body))


@pytest.mark.parametrize("year", YEARS)
def test_session_packet_pauses_and_resumes(year: int) -> None:
    motion, ex = _packets(year)
    dec = F1Decoder(max_ex_age_s=1.0)
    dec.feed(ex, 0.0)

    def tick(k: int) -> bytes:  # the session clock runs, so only the Session flag pauses
        m = bytearray(motion)
        struct.pack_into("<f", m, 15, struct.unpack_from("<f", motion, 15)[0] + k / 60)
        return bytes(m)

    assert dec.decode(_session(year, motion, paused=1), 0.0).reason == "state: session"
    s = dec.feed(tick(0), 0.0)
    assert s is not None and s.paused
    dec.feed(_session(year, motion, paused=0, spectating=1), 0.0)
    s = dec.feed(tick(1), 0.0)
    assert s is not None and s.paused
    dec.feed(_session(year, motion, paused=0), 0.0)
    s = dec.feed(tick(2), 0.0)
    assert s is not None and not s.paused
    assert dec.stats["state: session"] == 3


def test_bad_session_flags_are_foreign() -> None:
    motion, _ = _packets(2024)
    assert F1Decoder().decode(_session(2024, motion, paused=7), 0.0).reason == "skipped: foreign"


@pytest.mark.parametrize("year", YEARS)
def test_truncated_long_foreign_and_old_format_packets_are_counted(year: int) -> None:
    motion, ex = _packets(year)
    dec = F1Decoder()
    dec.feed(ex, 0.0)
    cases = {
        motion[:-1]: "skipped: truncated",
        motion + b"\0": "skipped: wrong size",
        ex[:100]: "skipped: truncated",
        ex + b"\0\0\0\0": "skipped: wrong size",
        motion[:10]: "skipped: truncated",
        struct.pack("<H", 2022) + motion[2:]: "skipped: unsupported format",
        struct.pack("<H", 7) + motion[2:]: "skipped: foreign",
        motion[:6] + bytes([99]) + motion[7:]: "skipped: foreign",
        motion[:6] + bytes([2]) + motion[7:]: "ignored: other packet id",
        motion[:27] + bytes([22]) + motion[28:]: "skipped: bad player index",
    }
    for data, reason in cases.items():
        assert dec.decode(data, 0.0).reason == reason, reason
    for reason in set(cases.values()):
        assert dec.stats[reason] == sum(1 for r in cases.values() if r == reason)


def test_nan_and_inf_are_skipped_and_never_reach_a_sample() -> None:
    motion, ex = _packets(2024)
    base = 29 + 60 * motion[27]
    dec = F1Decoder()
    bad_ex = bytearray(ex)
    struct.pack_into("<f", bad_ex, 173, math.nan)
    assert dec.decode(bytes(bad_ex), 0.0).reason == "skipped: non-finite"
    dec.feed(ex, 0.0)
    for value, reason in ((math.inf, "skipped: non-finite"), (1e6, "skipped: out of range")):
        bad = bytearray(motion)
        struct.pack_into("<f", bad, base + 36, value)
        assert dec.decode(bytes(bad), 0.0).reason == reason
    assert dec.feed(motion, 0.0) is not None  # the good one still decodes


def test_vertical_g_force_sign_agrees_with_the_change_of_vertical_velocity() -> None:
    """F1 24 capture: Motion Ex (frame 39278) and Motion (frame 39280) are 35 ms apart; the
    car's up-velocity grows from 0.07 to 0.19 m/s, i.e. ~+3.5 m/s^2, and gForceVertical is
    +0.22 g: positive vertical g-force is upward acceleration (same sign, similar size)."""
    motion, ex = _packets(2024)
    h = _hand(2024)
    t_motion, t_ex = struct.unpack_from("<f", motion, 15)[0], struct.unpack_from("<f", ex, 15)[0]
    dt = t_motion - t_ex
    assert 0.02 < dt < 0.05
    F, R, v = h["fwd"], h["right"], h["world_vel"]
    U = (R[1] * F[2] - R[2] * F[1], R[2] * F[0] - R[0] * F[2], R[0] * F[1] - R[1] * F[0])
    v_up_now = sum(u * x for u, x in zip(U, v, strict=True))
    a_up = (v_up_now - h["local_vel"][1]) / dt
    g_vert = h["g"][2] * G0_M_S2
    assert a_up > 0 and g_vert > 0
    assert 0.3 < a_up / g_vert < 3.0


@pytest.mark.parametrize("roll_deg", [-8.0, 8.0])
def test_roll_sign_right_side_down_reads_leftward_specific_force(roll_deg: float) -> None:
    """ISO roll + is right side down; at rest the accelerometer then reads +g sin(roll) on
    y (toward the raised left side). Right side down means worldRightDir points below the
    horizon (negative Y)."""
    motion, ex = _packets(2023)
    base = 29 + 60 * motion[27]
    ph = math.radians(roll_deg)
    m = bytearray(motion)
    right = (round(-32767 * math.cos(ph)), round(-32767 * math.sin(ph)), 0)  # facing +Z
    struct.pack_into("<3h3h3f", m, base + 24, 0, 0, 32767, *right, 0.0, 0.0, 0.0)
    dec = F1Decoder()
    dec.feed(ex, 0.0)
    s = dec.feed(bytes(m), 0.0)
    assert s is not None
    assert s.f[1] == pytest.approx(G0_M_S2 * math.sin(ph), abs=1e-3)
    assert s.f[2] == pytest.approx(G0_M_S2 * math.cos(ph), abs=1e-3)


@given(
    st.tuples(
        st.integers(0, 65535), *(st.integers(0, 255) for _ in range(5)),
        st.integers(0, 2**64 - 1), st.floats(width=32, allow_nan=False),
        st.integers(0, 2**32 - 1), st.integers(0, 2**32 - 1), st.integers(0, 255),
        st.integers(0, 255),
    )
)  # fmt: skip
def test_header_pack_unpack_round_trip(fields: tuple) -> None:
    h = F1Header(*fields)
    raw = h.pack()
    assert len(raw) == HEADER.size == 29 and F1Header.unpack(raw) == h


def test_f1_25_motion_ex_layout_is_accepted_by_its_size() -> None:
    """F1 25 appends chassisPitch, wheelCamber[4], wheelCamberGain[4] (9 floats) to the F1 24
    Motion Ex: 273 bytes. Built from the real F1 24 packet with the format set to 2025."""
    motion, ex = _packets(2024)
    ex25 = bytearray(ex + bytes(36))
    struct.pack_into("<H", ex25, 0, 2025)
    m25 = bytearray(motion)
    struct.pack_into("<H", m25, 0, 2025)
    dec = F1Decoder()
    assert dec.decode(bytes(ex25[:237]), 0.0).reason == "skipped: truncated"
    assert dec.decode(bytes(ex25), 0.0).reason == "partial: motion ex stored"
    s = dec.feed(bytes(m25), 0.0)
    assert s is not None
    assert (s.f, s.w) == _decode_pair(2024)


def test_pairing_window_is_validated() -> None:
    from motioncue import ConfigError

    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ConfigError, match="max_ex_age_s"):
            F1Decoder(max_ex_age_s=bad)


def test_frozen_session_time_flags_pause_after_repeats() -> None:
    """A paused game that keeps sending repeats the same sessionTime: the third identical
    Motion (two repeats) is paused, a single duplicate is not, and time moving resumes."""
    motion, ex = _packets(2024)
    dec = F1Decoder()
    dec.feed(ex, 0.0)
    flags = []
    for _ in range(4):
        s = dec.feed(motion, 0.0)
        assert s is not None
        flags.append(s.paused)
    assert flags == [False, False, True, True]
    later = bytearray(motion)
    (stime,) = struct.unpack_from("<f", motion, 15)
    struct.pack_into("<f", later, 15, stime + 1 / 60)
    s = dec.feed(bytes(later), 0.0)
    assert s is not None and not s.paused
