"""Project CARS 2 / Automobilista 2 axes and signs pinned on real captures
(``tests/fixtures/games/pcars2/README.md``): the decoded f_x against the derivative of the
speed, the yaw rate against the heading's rate, f_y against speed x yaw rate, and which side
is left (the ride height of the left and right wheels when the car corners)."""

from __future__ import annotations

import gzip
import struct
from pathlib import Path

import numpy as np
import pytest

from motioncue.telemetry import G0_M_S2
from motioncue.telemetry._pcars2 import TELEMETRY_SIZE, PCars2Decoder, PCars2Telemetry

FIXTURES = Path(__file__).parent / "fixtures" / "games" / "pcars2"
CAPTURES = ["ams2-nurburgring", "pc2-nurburgring"]

_PCAP_HEADER = struct.Struct("<IHHiIII")
_PCAP_RECORD = struct.Struct("<IIII")


def _udp_payloads(pcap: bytes) -> list[tuple[float, bytes]]:
    """(capture time s, UDP payload) of each IPv4/UDP frame of a little-endian Ethernet pcap."""
    magic, _, _, _, _, _, linktype = _PCAP_HEADER.unpack_from(pcap)
    assert magic == 0xA1B2C3D4 and linktype == 1  # microsecond pcap, Ethernet
    out = []
    off = _PCAP_HEADER.size
    while off < len(pcap):
        sec, usec, incl, _orig = _PCAP_RECORD.unpack_from(pcap, off)
        frame = pcap[off + 16 : off + 16 + incl]
        off += 16 + incl
        ip = frame[14:]
        udp = ip[(ip[0] & 0x0F) * 4 :]
        length = struct.unpack_from(">H", udp, 4)[0]
        out.append((sec + usec * 1e-6, udp[8:length]))
    return out


@pytest.fixture(scope="module", params=CAPTURES)
def capture(request: pytest.FixtureRequest) -> dict[str, np.ndarray]:
    datagrams = _udp_payloads(gzip.decompress((FIXTURES / f"{request.param}.pcap.gz").read_bytes()))
    dec = PCars2Decoder()
    rows = []
    for t, d in datagrams:
        assert len(d) == TELEMETRY_SIZE
        s = dec.feed(d, t)
        assert s is not None
        m = PCars2Telemetry.unpack(d)
        ride_height = struct.unpack_from("<4f", d, 296)  # sRideHeight FL, FR, RL, RR (m)
        tick = struct.unpack_from("<I", d, 555)[0]  # the packet's last field: +1 a packet
        rows.append((tick, t, m.speed_m_s, m.orientation[1], *ride_height, *s.f, *s.w))
    assert dec.stats == {"sample": len(datagrams)}
    a = np.array(rows)
    # the clock: the counter at byte 555, whose period is fitted to the capture times (the
    # replayed captures' arrival times bunch up; the counter goes up by one every packet)
    assert np.all(np.diff(a[:, 0]) == 1)
    period_s = float(np.polyfit(a[:, 0], a[:, 1], 1)[0])
    assert period_s == pytest.approx(1 / 60, rel=0.02)  # the captures' 60 Hz
    t = (a[:, 0] - a[0, 0]) * period_s
    return {"t": t, "v": a[:, 2], "psi": a[:, 3], "rh": a[:, 4:8], "f": a[:, 8:11],
            "w": a[:, 11:14]}  # fmt: skip


def _smooth(x: np.ndarray) -> np.ndarray:
    from scipy.signal import savgol_filter

    return np.asarray(savgol_filter(x, 61, 2, axis=0))  # ~1 s at the captures' 60 Hz


def _fit(x: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """(slope of y on x, correlation)."""
    return float(np.polyfit(x, y, 1)[0]), float(np.corrcoef(x, y)[0, 1])


def test_capture_longitudinal_force_is_the_derivative_of_speed(capture: dict) -> None:
    t, v, f = capture["t"], capture["v"], capture["f"]
    m = v > 8.0
    slope, corr = _fit(np.gradient(_smooth(v), t)[m], _smooth(f[:, 0])[m])
    assert corr > 0.95 and slope == pytest.approx(1.0, abs=0.1), (slope, corr)


def test_capture_yaw_rate_is_the_heading_rate(capture: dict) -> None:
    """``sOrientation[1]`` turns world vectors about up in the game's left-handed axes, so
    the ISO heading is its negative (module docstring of ``_pcars2``)."""
    t, v, w = capture["t"], capture["v"], capture["w"]
    heading_rate = np.gradient(_smooth(-np.unwrap(capture["psi"])), t)
    m = v > 8.0
    slope, corr = _fit(heading_rate[m], _smooth(w[:, 2])[m])
    assert corr > 0.99 and slope == pytest.approx(1.0, abs=0.05), (slope, corr)


def test_capture_lateral_force_is_speed_times_yaw_rate(capture: dict) -> None:
    """In a turn the centripetal acceleration is v r, towards the inside (ISO: f_y and r of
    one sign). The axes these captures replaced had f_y and r of opposite signs."""
    v, f, w = capture["v"], capture["f"], capture["w"]
    m = v > 8.0
    slope, corr = _fit(_smooth(v * w[:, 2])[m], _smooth(f[:, 1])[m])
    assert corr > 0.95 and slope == pytest.approx(1.0, abs=0.1), (slope, corr)


def test_capture_left_is_left(capture: dict) -> None:
    """Which side is left, from the wheels the game names: cornering, a car rolls outward,
    so with f_y > 0 (a left turn) its right wheels (FR, RR) ride lower than its left ones."""
    v, f, rh = capture["v"], capture["f"], capture["rh"]
    left_minus_right = (rh[:, 0] + rh[:, 2] - rh[:, 1] - rh[:, 3]) / 2
    m = v > 8.0
    _, corr = _fit(_smooth(f[:, 1])[m], _smooth(left_minus_right)[m])
    assert corr > 0.9, corr


def test_capture_vertical_force_averages_one_g(capture: dict) -> None:
    assert float(np.mean(capture["f"][:, 2])) == pytest.approx(G0_M_S2, abs=0.3)
