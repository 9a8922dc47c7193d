"""X-Plane DATA decoder: golden bytes from the documented layout, both versions' row 16,
signs, bad datagrams, round trips."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._xplane import (
    ROW,
    ROW_ANGULAR_VELOCITY,
    ROW_ENGINE_RPM,
    ROW_GLOAD,
    UNUSED,
    XPlaneDecoder,
    pack_data,
    unpack_data,
)

U = UNUSED

# Written by hand from the documented layout: "DATA", internal byte '*', then rows of
# (s32 index, 8 x f32), little-endian. Row 4 (Mach, VVI, g-load): Mach 0.25, VVI 500 fpm,
# normal 1.5 g, axial 0.25 g, side -0.125 g. Row 16 in X-Plane 12 order/unit: P 10 deg/s,
# Q -5 deg/s, R 2.5 deg/s.
GOLDEN_12 = (
    b"DATA*"
    + bytes.fromhex("04000000")
    + bytes.fromhex("0000803e" "00c079c4" "0000fa43" "00c079c4")
    + bytes.fromhex("0000c03f" "0000803e" "000000be" "00c079c4")
    + bytes.fromhex("10000000")
    + bytes.fromhex("00002041" "0000a0c0" "00002040" "00c079c4")
    + bytes.fromhex("00c079c4" "00c079c4" "00c079c4" "00c079c4")
)  # fmt: skip


def test_golden_datagram_decodes_by_hand() -> None:
    assert len(GOLDEN_12) == 5 + 2 * 36
    rows = unpack_data(GOLDEN_12)
    assert rows == {
        4: (0.25, U, 500.0, U, 1.5, 0.25, -0.125, U),
        16: (10.0, -5.0, 2.5, U, U, U, U, U),
    }
    s = decoder_for("xplane").feed(GOLDEN_12, 3.0)
    assert s is not None and s.game == "xplane" and s.t_s == 3.0 and not s.paused
    # f = G0 (axial, -side, normal); w = (P, -Q, -R) in rad/s
    assert s.f == pytest.approx((0.25 * G0_M_S2, 0.125 * G0_M_S2, 1.5 * G0_M_S2), abs=1e-12)
    d = math.pi / 180
    assert s.w == pytest.approx((10 * d, 5 * d, -2.5 * d), abs=1e-12)


def test_golden_datagram_is_packed_back_bit_for_bit() -> None:
    rows = {
        4: (0.25, U, 500.0, U, 1.5, 0.25, -0.125, U),
        16: (10.0, -5.0, 2.5),  # pack_data fills unused slots with -999
    }
    assert pack_data(rows) == GOLDEN_12


def test_xplane11_reads_row_16_as_q_p_r_in_rad_per_s() -> None:
    data = pack_data(
        {ROW_GLOAD: (0, U, 0, U, 1.0, 0.0, 0.0, U), ROW_ANGULAR_VELOCITY: (0.1, 0.2, 0.3)}
    )
    s11 = decoder_for("xplane11").feed(data, 0.0)
    s12 = decoder_for("xplane").feed(data, 0.0)
    assert s11 is not None and s12 is not None and s11.game == "xplane11"
    # X-Plane 11: Q=0.1, P=0.2, R=0.3 rad/s -> (P, -Q, -R)
    assert s11.w == pytest.approx((0.2, -0.1, -0.3), abs=1e-7)
    d = math.pi / 180  # X-Plane 12: P=0.1, Q=0.2, R=0.3 deg/s
    assert s12.w == pytest.approx((0.1 * d, -0.2 * d, -0.3 * d), abs=1e-9)


def test_level_flight_and_rest_read_plus_one_g_and_rows_may_come_in_any_order() -> None:
    data = pack_data({
        ROW_ANGULAR_VELOCITY: (0.0, 0.0, 0.0),
        17: (2.0, 0.0, 90.0, 88.0),
        ROW_GLOAD: (0.1, U, 0.0, U, 1.0, 0.0, 0.0, U),
        ROW_ENGINE_RPM: (2400.0, U, U, U, U, U, U, U),
    })  # fmt: skip
    s = XPlaneDecoder().feed(data, 0.0)
    assert s is not None
    assert s.f == (0.0, 0.0, G0_M_S2) and s.w == (0.0, -0.0, -0.0)
    assert s.rpm == 2400.0 and s.gear is None and s.suspension_velocity_m_s is None


def test_bad_datagrams_are_counted() -> None:
    good = pack_data({ROW_GLOAD: (0, U, 0, U, 1.0, 0, 0, U), ROW_ANGULAR_VELOCITY: (0, 0, 0)})

    def gw(normal: float, p: float) -> bytes:
        return pack_data({ROW_GLOAD: (0, U, 0, U, normal, 0, 0, U), 16: (p, 0, 0)})

    cases = {
        b"": "skipped: truncated",
        b"DATA*": "skipped: truncated",
        b"RREF," + bytes(8): "skipped: foreign",
        good[:-1]: "skipped: foreign",  # not a whole number of rows
        pack_data({ROW_GLOAD: (0, U, 0, U, 1.0, 0, 0, U)}): "skipped: missing rows",
        pack_data({ROW_ANGULAR_VELOCITY: (0, 0, 0)}): "skipped: missing rows",
        gw(math.nan, 0): "skipped: non-finite",
        gw(1, math.inf): "skipped: non-finite",
        gw(500.0, 0): "skipped: out of range",
        b"DATA*" + bytes(36 * 201): "skipped: foreign",
    }  # fmt: skip
    dec = XPlaneDecoder()
    for data, reason in cases.items():
        assert dec.decode(data, 0.0).reason == reason, reason
    assert sum(dec.stats.values()) == len(cases) and "sample" not in dec.stats


f32 = st.floats(allow_nan=False, allow_infinity=False, width=32)


@given(
    rows=st.dictionaries(
        st.integers(-(2**31), 2**31 - 1), st.tuples(*[f32] * 8), min_size=0, max_size=10
    ),
    internal=st.integers(0, 255),
)
def test_pack_unpack_round_trip(rows: dict[int, tuple[float, ...]], internal: int) -> None:
    raw = pack_data(rows, internal)
    assert len(raw) == 5 + ROW.size * len(rows) and raw[4] == internal
    assert unpack_data(raw) == rows


@given(
    g=st.tuples(*[st.floats(-5, 5, width=32)] * 3),
    pqr=st.tuples(*[st.floats(-3, 3, width=32)] * 3),
)
def test_conversion_is_a_proper_rotation_of_the_aero_axes(
    g: tuple[float, float, float], pqr: tuple[float, float, float]
) -> None:
    """Invariant: the aero body axes (x fwd, y right, z down) map to ISO by diag(1, -1, -1),
    a proper rotation (det +1): |f| and |w| are kept and f.w is kept up to the axis sign."""
    normal, axial, side = g
    data = pack_data({ROW_GLOAD: (0, U, 0, U, normal, axial, side, U), 16: pqr[1::-1] + pqr[2:]})
    s = decoder_for("xplane11").feed(data, 0.0)
    assert s is not None
    f_aero = (G0_M_S2 * axial, G0_M_S2 * side, -G0_M_S2 * normal)
    assert math.hypot(*s.f) == pytest.approx(math.hypot(*f_aero), rel=1e-12, abs=1e-12)
    assert math.hypot(*s.w) == pytest.approx(math.hypot(*pqr), rel=1e-6, abs=1e-9)
    dot_iso = sum(a * b for a, b in zip(s.f, s.w, strict=True))
    dot_aero = sum(a * b for a, b in zip(f_aero, pqr, strict=True))
    assert dot_iso == pytest.approx(dot_aero, rel=1e-5, abs=1e-6)
    assert struct.unpack_from("<i", data, 5)[0] == ROW_GLOAD
