"""Assetto Corsa remote telemetry: golden packets both ways, the handshake the reader sends,
random bytes only counted, and axes pinned on a real capture (a lap of Monza)."""

from __future__ import annotations

import gzip
import math
import struct
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._ac import (
    CAR_INFO_SIZE,
    OP_DISMISS,
    OP_HANDSHAKE,
    OP_SUBSCRIBE_UPDATE,
    V0_M_S,
    ACCarInfo,
    ACDecoder,
    handshake_response,
    request,
)

CAPTURE = Path(__file__).parent / "fixtures" / "games" / "ac" / "monza-a8lms.raw.gz"


def _golden() -> bytes:
    """An RTCarInfo written at the documented byte offsets by hand."""
    b = bytearray(328)
    b[0:1] = b"a"
    struct.pack_into("<i", b, 4, 328)
    struct.pack_into("<3f", b, 8, 90.0, 90.0 / 1.609344, 25.0)  # km/h, mph, m/s
    struct.pack_into("<3f", b, 28, 0.5, -0.25, 0.75)  # accG: lateral, vertical, frontal
    struct.pack_into("<i", b, 40, 61_250)  # lapTime (ms)
    struct.pack_into("<f", b, 68, 6400.0)  # engineRPM
    struct.pack_into("<i", b, 76, 4)  # gear: 0 R, 1 N, 2 first...
    struct.pack_into("<3f", b, 316, 10.0, -2.0, 300.0)  # carCoordinates
    return bytes(b)


def test_golden_packet_decodes_by_hand() -> None:
    s = decoder_for("ac").feed(_golden(), 3.0)
    assert s is not None and s.game == "ac" and s.t_s == 3.0 and not s.paused
    g = G0_M_S2
    # f = G0 (frontal, lateral-left, 1 + vertical)
    assert s.f == pytest.approx((0.75 * g, 0.5 * g, 0.75 * g), abs=1e-9)
    # yaw rate: course rate a_y v / (v^2 + V0^2), positive (left) for a leftward a_y
    assert s.w == pytest.approx((0.0, 0.0, 0.5 * g * 25.0 / (25.0**2 + V0_M_S**2)), rel=1e-7)
    assert s.rpm == 6400.0 and s.gear == 3


def test_golden_packet_is_packed_back_bit_for_bit() -> None:
    data = _golden()
    m = ACCarInfo.unpack(data)
    assert m.acc_g == (0.5, -0.25, 0.75) and m.lap_time_ms == 61_250 and m.gear == 4
    assert m.coordinates == (10.0, -2.0, 300.0)
    packed = m.pack()
    assert len(packed) == CAR_INFO_SIZE
    # the encoder also fills km/h and mph from m/s; compare those to float32 precision
    assert packed[:8] == data[:8] and packed[20:] == data[20:]
    assert struct.unpack_from("<3f", packed, 8) == pytest.approx((90.0, 55.92341, 25.0), rel=1e-6)


def test_handshake_then_subscribe_then_resubscribe_and_dismiss() -> None:
    dec = ACDecoder()
    assert dec.requests(0.0) == [request(OP_HANDSHAKE)]
    assert dec.requests(0.5) == []  # one handshake a second
    assert dec.requests(1.0) == [request(OP_HANDSHAKE)]
    assert dec.farewell() == []  # nothing to dismiss yet
    r = dec.decode(handshake_response("ks_audi_r8_lms", "Tester", "monza"), 1.1)
    assert r.status == "state" and dec.car == "ks_audi_r8_lms" and dec.track == "monza"
    assert dec.requests(1.2) == [request(OP_SUBSCRIBE_UPDATE)]
    assert dec.requests(1.3) == []
    for k in range(10):
        assert dec.feed(_golden(), 1.4 + k * 0.1) is not None
    assert dec.requests(4.0) == []  # data 1.7 s ago: still subscribed
    assert dec.farewell() == [request(OP_DISMISS)]
    assert dec.requests(6.0) == [request(OP_HANDSHAKE)]  # silent 3 s: the game went away
    assert struct.unpack("<iii", request(OP_SUBSCRIBE_UPDATE)) == (1, 1, 1)


def test_bad_datagrams_are_counted_by_reason() -> None:
    dec = ACDecoder()
    g = _golden()
    assert dec.feed(g[:100], 0.0) is None
    assert dec.feed(g + b"\0", 0.0) is None
    assert dec.feed(b"b" + g[1:], 0.0) is None
    nan = bytearray(g)
    struct.pack_into("<f", nan, 28, math.nan)
    assert dec.feed(bytes(nan), 0.0) is None
    assert dec.decode(bytes(212), 0.0).status == "ignored"  # RTLap
    assert dec.stats == {
        "skipped: truncated": 1,
        "skipped: wrong size": 1,
        "skipped: foreign": 1,
        "skipped: non-finite": 1,
        "ignored": 1,
    }


@settings(max_examples=300, deadline=None)
@given(st.binary(min_size=0, max_size=600))
def test_random_bytes_are_only_counted(data: bytes) -> None:
    dec = ACDecoder()
    r = dec.decode(data, 0.0)
    assert sum(dec.stats.values()) == 1
    if len(data) != CAR_INFO_SIZE or data[0:1] != b"a":
        assert r.sample is None
    if r.sample is not None:
        assert all(math.isfinite(v) for v in r.sample.f + r.sample.w)


@settings(max_examples=200, deadline=None)
@given(st.binary(min_size=320, max_size=320))
def test_random_car_info_bodies_never_crash(body: bytes) -> None:
    data = b"a\0\0\0" + struct.pack("<i", 328) + body
    r = ACDecoder().decode(data, 0.0)
    assert r.status in ("sample", "skipped")
    if r.sample is not None:
        assert all(math.isfinite(v) and abs(v) <= 1000 for v in r.sample.f + r.sample.w)


# -- the real capture ---------------------------------------------------------------------


@pytest.fixture(scope="module")
def monza() -> dict[str, np.ndarray]:
    raw = gzip.open(CAPTURE).read()
    assert len(raw) % CAR_INFO_SIZE == 0
    dec = ACDecoder()
    rows = []
    for i in range(0, len(raw), CAR_INFO_SIZE):
        d = raw[i : i + CAR_INFO_SIZE]
        s = dec.feed(d, 0.0)
        assert s is not None
        m = ACCarInfo.unpack(d)
        rows.append((m.lap_time_ms, m.speed_m_s, *m.coordinates, *s.f, *s.w))
    a = np.array(rows)
    assert dec.stats == {"sample": len(raw) // CAR_INFO_SIZE}
    # the game's clock: lapTime (ms), restarting at the line; repeated stamps dropped
    step = np.diff(a[:, 0])
    step[(step < 0) | (step > 200)] = 16.0
    t = np.r_[0.0, np.cumsum(step)] / 1e3
    keep = np.r_[True, np.diff(t) > 0]
    a, t = a[keep], t[keep]
    return {"t": t, "v": a[:, 1], "pos": a[:, 2:5], "f": a[:, 5:8], "w": a[:, 8:11]}


def _smooth(x: np.ndarray, n: int = 9) -> np.ndarray:
    return np.convolve(x, np.ones(n) / n, mode="same")


def test_capture_longitudinal_force_is_the_derivative_of_speed(monza: dict) -> None:
    t, v, f = monza["t"], monza["v"], monza["f"]
    dv = _smooth(np.gradient(v, t))
    m = v > 10.0
    slope = np.polyfit(dv[m], f[m, 0], 1)[0]
    assert np.corrcoef(dv[m], f[m, 0])[0, 1] > 0.95
    assert slope == pytest.approx(1.0, abs=0.1)  # same sign, same size


def test_capture_yaw_rate_is_the_course_rate_of_the_coordinates(monza: dict) -> None:
    """The course angle of carCoordinates measured as ISO yaw (x, z ground plane, y up,
    right-handed: atan2(dx, dz) grows turning left) against the decoded yaw rate."""
    t, v, pos, w = monza["t"], monza["v"], monza["pos"], monza["w"]
    vel = np.gradient(pos, t, axis=0)
    course = np.unwrap(np.arctan2(vel[:, 0], vel[:, 2]))
    rate = _smooth(np.gradient(course, t))
    m = v > 15.0
    assert np.corrcoef(rate[m], w[m, 2])[0, 1] > 0.95
    assert np.polyfit(rate[m], w[m, 2], 1)[0] == pytest.approx(1.0, abs=0.1)
    # the lap: Monza is driven clockwise, one net right turn = -2 pi of ISO yaw
    turned = float(np.sum(w[1:, 2] * np.diff(t)))
    assert turned == pytest.approx(-2 * math.pi, abs=0.3)
    # lateral force agrees with v * course rate (the centripetal acceleration), sign and size
    assert np.polyfit(v[m] * rate[m], monza["f"][m, 1], 1)[0] == pytest.approx(1.0, abs=0.1)


def test_capture_vertical_force_averages_one_g(monza: dict) -> None:
    fz = monza["f"][:, 2]
    assert float(np.mean(fz)) == pytest.approx(G0_M_S2, abs=0.2)


def test_source_specs_name_the_game_to_ask() -> None:
    from motioncue._errors import ConfigError
    from motioncue.telemetry._source import parse_live_spec, split_peer

    assert parse_live_spec("ac") == ("ac", "127.0.0.1", 0)  # any local port: AC answers
    assert split_peer("ac@192.168.1.5") == ("ac", "192.168.1.5")
    assert parse_live_spec("ac@192.168.1.5") == ("ac", "0.0.0.0", 0)  # a remote PC answers
    assert parse_live_spec("ac@127.0.0.1:127.0.0.1:5000") == ("ac", "127.0.0.1", 5000)
    with pytest.raises(ConfigError, match="sends on its own"):
        split_peer("f1@192.168.1.5")
    with pytest.raises(ConfigError, match="needs the game's address"):
        split_peer("ac@")
