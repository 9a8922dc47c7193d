"""Gran Turismo 7: encryption both ways (against real packets), golden packets, flags,
gaps and jumps, random bytes only counted, heartbeat, and axes pinned on three real laps."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue._errors import ConfigError
from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._gt7 import SIZES, GT7Decoder, GT7Packet, decrypt, encrypt

HERE = Path(__file__).parent / "fixtures" / "games" / "gt7"
LAPS = {  # file -> net turns of the lap in ISO yaw (+ anticlockwise seen from above)
    "interlagos.gt7lap": +1,  # Autódromo José Carlos Pace: driven anticlockwise
    "nurburgring-gp.gt7lap": -1,  # Nürburgring GP-Strecke: clockwise
}


def _plain(pid: int, v: tuple[float, float, float], q=(0.0, 0.0, 0.0, 1.0),
           w=(0.0, 0.0, 0.0), flags: int = 1, size: int = 296) -> bytes:  # fmt: skip
    """A plain packet written at the documented byte offsets by hand."""
    b = bytearray(size)
    struct.pack_into("<i", b, 0x00, 0x47375330)
    struct.pack_into("<3f", b, 0x04, 1.0, 2.0, 3.0)  # position
    struct.pack_into("<3f", b, 0x10, *v)  # velocity (world)
    struct.pack_into("<4f", b, 0x1C, *q)  # quaternion x, y, z, w
    struct.pack_into("<3f", b, 0x2C, *w)  # angular velocity (car axes)
    struct.pack_into("<f", b, 0x3C, 5500.0)  # engine rpm
    struct.pack_into("<f", b, 0x4C, math.sqrt(sum(c * c for c in v)))  # speed
    struct.pack_into("<i", b, 0x70, pid)  # packet id
    struct.pack_into("<H", b, 0x8A, 7200)  # rev-limit alert rpm
    struct.pack_into("<H", b, 0x8E, flags)
    return bytes(b)


def _feed(dec: GT7Decoder, plain: bytes, t: float = 0.0, iv: int = 0x12345678):
    return dec.decode(encrypt(plain, iv), t)


@pytest.fixture(scope="module")
def real_packets() -> list[bytes]:
    d = (HERE / "interlagos.gt7lap").read_bytes()
    return [d[i : i + 296] for i in range(0, len(d), 296)]


def test_real_packets_decrypt_and_encrypt_back_bit_for_bit(real_packets: list[bytes]) -> None:
    first = real_packets[0]
    plain = decrypt(first)
    assert plain is not None and plain[:4] == b"0S7G"
    p = GT7Packet.unpack(plain)
    assert p.packet_id == 152105 and p.speed_m_s == pytest.approx(67.756, abs=1e-3)
    assert math.sqrt(sum(c * c for c in p.quaternion)) == pytest.approx(1.0, abs=1e-5)
    iv = struct.unpack_from("<I", first, 0x40)[0]
    assert encrypt(plain, iv) == first
    assert all(decrypt(x) is not None for x in real_packets)


def test_golden_packets_both_ways() -> None:
    plain = _plain(7, (0.0, 0.0, -20.0), w=(0.1, 0.2, 0.3), flags=9)
    p = GT7Packet.unpack(plain)
    assert p.velocity == (0.0, 0.0, -20.0) and p.packet_id == 7 and p.flags == 9
    assert p.pack() == plain
    for size in SIZES:
        q = GT7Packet(9, (0.0, 0.0, 0.0), (1.0, 2.0, 3.0), (0.0, 0.0, 0.0, 1.0),
                      (0.0, 0.0, 0.0), extended=(0.5, 0.0, 1.0, 2.0, 3.0))  # fmt: skip
        data = q.pack(size)
        assert len(data) == size and decrypt(encrypt(data, 99)) is not None
        back = GT7Packet.unpack(decrypt(encrypt(data, 99)) or b"")
        assert back.velocity == (1.0, 2.0, 3.0)
        assert back.extended == ((0.5, 0.0, 1.0, 2.0, 3.0) if size > 296 else None)


def test_level_car_braking_and_turning_by_hand() -> None:
    """Identity attitude: the car faces world -z. 0.5 m/s lost in one frame (1/60 s) forward
    is 30 m/s^2 of deceleration; the angular velocity (x, y, z) maps to (-z, -x, y)."""
    dec = GT7Decoder()
    assert _feed(dec, _plain(100, (0.0, 0.0, -20.0))).status == "partial"
    r = _feed(dec, _plain(101, (0.0, 0.0, -19.5), w=(0.1, 0.2, 0.3)), 5.0)
    s = r.sample
    assert s is not None and s.game == "gt7" and s.t_s == 5.0 and not s.paused
    assert s.f == pytest.approx((-30.0, 0.0, G0_M_S2), abs=1e-4)
    assert s.w == pytest.approx((-0.3, -0.1, 0.2), abs=1e-7)
    assert s.rpm == 5500.0 and s.rpm_max == 7200.0


def test_yawed_car_rotates_the_world_acceleration_into_car_axes() -> None:
    """The car yawed 90 deg left (about world +y): it faces world -x. A world velocity
    change towards -z is then a push to the car's right: f_y < 0."""
    c = math.cos(math.pi / 4)
    q = (0.0, c, 0.0, c)
    dec = GT7Decoder()
    _feed(dec, _plain(10, (-20.0, 0.0, 0.0), q=q))
    s = _feed(dec, _plain(12, (-20.0, 0.0, -0.2), q=q)).sample  # 2 frames: 6 m/s^2
    assert s is not None
    assert s.f == pytest.approx((0.0, -6.0, G0_M_S2), abs=1e-4)


@pytest.mark.parametrize(("flags", "paused"), [(1, False), (9, False), (3, True), (5, True),
                                              (0, True), (8, True)])  # fmt: skip
def test_flags_pause_menus_and_loading(flags: int, paused: bool) -> None:
    dec = GT7Decoder()
    _feed(dec, _plain(1, (0.0, 0.0, -5.0), flags=flags))
    s = _feed(dec, _plain(2, (0.0, 0.0, -5.0), flags=flags)).sample
    assert s is not None and s.paused is paused


def test_gaps_jumps_and_repeats_restart_the_difference() -> None:
    dec = GT7Decoder(max_gap_frames=6)
    v = (0.0, 0.0, -30.0)
    assert _feed(dec, _plain(50, v)).status == "partial"
    assert _feed(dec, _plain(50, v)).reason == "ignored: repeated"
    assert _feed(dec, _plain(56, v)).status == "sample"
    assert _feed(dec, _plain(70, (0.0, 0.0, 0.0))).status == "partial"  # 14 frames: restart
    assert _feed(dec, _plain(20, v)).status == "partial"  # replay seek backwards: no spike
    s = _feed(dec, _plain(21, v)).sample
    assert s is not None and s.f == pytest.approx((0.0, 0.0, G0_M_S2), abs=1e-5)
    assert dec.stats == {"partial": 3, "ignored: repeated": 1, "sample": 2}


def test_bad_datagrams_are_counted_by_reason() -> None:
    dec = GT7Decoder()
    good = encrypt(_plain(1, (0.0, 0.0, -5.0)), 5)
    assert dec.feed(good[:200], 0.0) is None
    assert dec.feed(good + b"\0", 0.0) is None
    assert dec.feed(bytes(296), 0.0) is None  # decrypts to noise: no magic
    bad_q = encrypt(_plain(2, (0.0, 0.0, -5.0), q=(0.0, 0.0, 0.0, 2.0)), 5)
    assert dec.feed(bad_q, 0.0) is None
    nan = encrypt(_plain(3, (math.nan, 0.0, -5.0)), 5)
    assert dec.feed(nan, 0.0) is None
    assert dec.stats == {"skipped: truncated": 1, "skipped: wrong size": 1,
                         "skipped: foreign": 2, "skipped: non-finite": 1}  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.one_of(st.binary(max_size=400), st.sampled_from(sorted(SIZES)).flatmap(
    lambda n: st.binary(min_size=n, max_size=n))))  # fmt: skip
def test_random_bytes_are_only_counted(data: bytes) -> None:
    dec = GT7Decoder()
    r = dec.decode(data, 0.0)
    assert r.sample is None and r.status == "skipped"
    assert sum(dec.stats.values()) == 1


def test_heartbeat_every_second_and_options() -> None:
    dec = decoder_for("gt7")
    assert isinstance(dec, GT7Decoder)
    assert dec.requests(10.0) == [b"A"]
    assert dec.requests(10.5) == []
    assert dec.requests(11.0) == [b"A"]
    assert dec.farewell() == []
    assert GT7Decoder("~").requests(0.0) == [b"~"]
    with pytest.raises(ConfigError, match="heartbeat"):
        GT7Decoder("Z")
    with pytest.raises(ConfigError, match="max_gap_frames"):
        GT7Decoder(max_gap_frames=0)


def test_source_spec_for_a_console() -> None:
    from motioncue.telemetry._source import parse_live_spec

    assert parse_live_spec("gt7") == ("gt7", "127.0.0.1", 33740)
    assert parse_live_spec("gt7@192.168.1.20") == ("gt7", "0.0.0.0", 33740)


# -- real laps ----------------------------------------------------------------------------


def _lap(name: str) -> dict[str, np.ndarray]:
    d = (HERE / name).read_bytes()
    dec = GT7Decoder(max_gap_frames=600)  # the files keep ~1 packet in 12-100: difference them
    rows = []
    for i in range(0, len(d), 296):
        r = dec.decode(d[i : i + 296], 0.0)
        p = GT7Packet.unpack(decrypt(d[i : i + 296]) or b"")
        s = r.sample
        f = s.f if s is not None else (math.nan,) * 3
        w = s.w if s is not None else (math.nan,) * 3
        rows.append((p.packet_id / 60.0, p.speed_m_s, *p.velocity, *p.quaternion, *f, *w))
    a = np.array(rows)
    assert dec.stats == {"partial": 1, "sample": len(a) - 1}
    return {"t": a[:, 0], "speed": a[:, 1], "v": a[:, 2:5], "q": a[:, 5:9], "f": a[:, 9:12],
            "w": a[:, 12:15]}  # fmt: skip


@pytest.mark.parametrize("name", sorted(LAPS))
def test_lap_the_car_moves_forward_along_iso_x(name: str) -> None:
    from scipy.spatial.transform import Rotation

    lap = _lap(name)
    v_car = Rotation.from_quat(lap["q"]).inv().apply(lap["v"])  # car axes: x right, y up, z back
    v_iso = np.c_[-v_car[:, 2], -v_car[:, 0], v_car[:, 1]]
    np.testing.assert_allclose(v_iso[:, 0], lap["speed"], rtol=0.02, atol=0.5)
    assert np.max(np.abs(v_iso[:, 1]) / np.maximum(lap["speed"], 5.0)) < 0.15  # small slip


@pytest.mark.parametrize("name", sorted(LAPS))
def test_lap_yaw_rate_follows_the_course_and_the_lap_closes(name: str) -> None:
    lap = _lap(name)
    t, v, w = lap["t"], lap["v"], lap["w"]
    # course angle of the world velocity as ISO yaw: car forward is -z, left is -x (y up)
    course = np.unwrap(np.arctan2(-v[:, 0], -v[:, 2]))
    assert (course[-1] - course[0]) / (2 * math.pi) == pytest.approx(LAPS[name], abs=0.05)
    dt = np.diff(t)
    rate = np.diff(course) / dt
    mean_w = (w[1:, 2] + w[:-1, 2]) / 2
    ok = np.isfinite(mean_w) & (dt < 0.5)
    assert ok.sum() > 50
    assert np.corrcoef(rate[ok], mean_w[ok])[0, 1] > 0.95
    assert np.polyfit(rate[ok], mean_w[ok], 1)[0] == pytest.approx(1.0, abs=0.1)


@pytest.mark.parametrize("name", sorted(LAPS))
def test_lap_differenced_force_agrees_with_speed_and_yaw_rate(name: str) -> None:
    """Over the gaps of the file the differenced specific force is a mean: its forward part
    against the change of the speed field, its lateral part against speed x yaw rate (the
    angular-velocity field, an independent one); sign and size."""
    lap = _lap(name)
    t, speed, f, w = lap["t"], lap["speed"], lap["f"], lap["w"]
    dt = np.diff(t)
    ok = dt < 0.4
    dv = np.diff(speed) / dt
    assert np.polyfit(dv[ok], f[1:, 0][ok], 1)[0] == pytest.approx(1.0, abs=0.15)
    assert np.corrcoef(dv[ok], f[1:, 0][ok])[0, 1] > 0.9
    centripetal = ((speed * w[:, 2])[1:] + (speed * w[:, 2])[:-1]) / 2
    ok &= np.isfinite(centripetal)
    assert np.corrcoef(centripetal[ok], f[1:, 1][ok])[0, 1] > 0.9
    assert np.polyfit(centripetal[ok], f[1:, 1][ok], 1)[0] == pytest.approx(1.0, abs=0.15)
    assert float(np.nanmedian(f[:, 2])) == pytest.approx(G0_M_S2, abs=1.5)


@settings(max_examples=100, deadline=None)
@given(
    q=st.tuples(*[st.floats(-1.0, 1.0)] * 4).filter(lambda q: sum(c * c for c in q) > 0.1),
    v0=st.tuples(*[st.floats(-80.0, 80.0)] * 3),
    dv=st.tuples(*[st.floats(-2.0, 2.0)] * 3),
    frames=st.integers(1, 6),
)
def test_force_in_car_axes_against_scipy(q, v0, dv, frames) -> None:  # type: ignore[no-untyped-def]
    """The written-out rotation of the decoder against scipy's: the world specific force
    (velocity difference over the game's clock, minus gravity) taken into car axes, as ISO."""
    from scipy.spatial.transform import Rotation

    n = math.sqrt(sum(c * c for c in q))
    qn = tuple(np.float32(c / n) for c in q)  # what the packet's f32 can carry
    v1 = tuple(a + b for a, b in zip(v0, dv, strict=True))
    dec = GT7Decoder()
    _feed(dec, _plain(100, v0, q=qn))
    s = _feed(dec, _plain(100 + frames, v1, q=qn)).sample
    assert s is not None
    v0_32, v1_32 = np.float32(v0).astype(float), np.float32(v1).astype(float)
    f_world = (v1_32 - v0_32) * 60.0 / frames + np.array([0.0, G0_M_S2, 0.0])
    c = Rotation.from_quat(np.array(qn, dtype=float)).inv().apply(f_world)
    np.testing.assert_allclose(s.f, (-c[2], -c[0], c[1]), rtol=1e-5, atol=1e-4)


@pytest.mark.parametrize(("size", "layout"), [(316, "B"), (344, "~"), (368, "C")])
def test_extended_packets_decode_but_sway_heave_surge_do_not_move_the_rig(
    size: int, layout: str
) -> None:
    """The longer layouts: the five floats at 0x128 (written here by hand at the offsets of
    PDTools' SimulatorPacket.cs) are read, but the motion comes from the differenced velocity
    alone (their units and signs are unpinned: docs/games/gt7.md), the same as for ``A``."""
    extended = (0.25, -0.5, 7.0, -3.0, 11.0)  # wheel rotation, filler, sway, heave, surge

    def plain(pid: int, v: tuple[float, float, float], ext: tuple[float, ...]) -> bytes:
        b = bytearray(_plain(pid, v, w=(0.1, 0.2, 0.3), size=size))
        struct.pack_into("<5f", b, 0x128, *ext)
        return bytes(b)

    p = GT7Packet.unpack(decrypt(encrypt(plain(1, (0.0, 0.0, -20.0), extended), 7)) or b"")
    assert p.extended == extended
    out = []
    for ext in (extended, (0.0,) * 5, (1e30, 1e30, 1e30, 1e30, 1e30)):
        dec = GT7Decoder()
        _feed(dec, plain(1, (0.0, 0.0, -20.0), ext))
        s = _feed(dec, plain(2, (0.0, 0.0, -19.5), ext)).sample
        assert s is not None and dec.layouts == {layout: 2}
        out.append((s.f, s.w))
    assert out[0] == out[1] == out[2]
    assert out[0][0] == pytest.approx((-30.0, 0.0, G0_M_S2), abs=1e-4)


@pytest.mark.parametrize(
    ("dv", "w", "reason"),
    [
        (0.5, (0.0, math.nan, 0.0), "skipped: non-finite"),
        (0.5, (0.0, 0.0, 1e6), "skipped: out of range"),
        (100.0, (0.0, 0.0, 0.0), "skipped: out of range"),  # 6000 m/s^2 in one frame
        (100.0, (math.inf, 0.0, 0.0), "skipped: out of range"),  # f is judged before w
        (0.5, (0.0, 0.0, 0.0), "sample"),
    ],
)
def test_absurd_or_non_finite_motion_is_counted_by_its_first_reason(
    dv: float, w: tuple[float, float, float], reason: str
) -> None:
    dec = GT7Decoder()
    _feed(dec, _plain(1, (0.0, 0.0, -20.0)))
    r = _feed(dec, _plain(2, (0.0, 0.0, -20.0 + dv), w=w))
    assert r.reason == reason and (r.sample is None) == (reason != "sample")


def test_absurd_rpm_is_dropped_not_the_sample() -> None:
    dec = GT7Decoder()
    b = bytearray(_plain(1, (0.0, 0.0, -20.0)))
    _feed(dec, bytes(b))
    b = bytearray(_plain(2, (0.0, 0.0, -20.0)))
    struct.pack_into("<f", b, 0x3C, 1e9)  # engine rpm
    s = _feed(dec, bytes(b)).sample
    assert s is not None and math.isnan(s.rpm) and s.rpm_max == 7200.0
