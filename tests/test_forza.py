"""Forza Data Out decoder: layouts, axis conversion, pause, bad datagrams."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._forza import FORZA_LAYOUTS, SLED_HEAD, ForzaDecoder, ForzaMotion


def _packet(
    *,
    race_on: int = 1,
    acc: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ang: tuple[float, float, float] = (0.0, 0.0, 0.0),
    pitch: float = 0.0,
    roll: float = 0.0,
    size: int = 232,
) -> bytes:
    m = ForzaMotion(race_on, 123, 8000.0, 800.0, 3000.0, acc, (1.0, 0.0, 20.0), ang, 0.3, pitch,
                    roll)  # fmt: skip
    return m.pack() + bytes(size - SLED_HEAD.size)


def test_documented_offsets_by_hand() -> None:
    """Offsets from the Turn 10 documentation: IsRaceOn @0, AccelerationX @20, AngularVelocityX
    @44, Yaw @56, Pitch @60, Roll @64."""
    p = _packet(acc=(1.5, -2.5, 3.5), ang=(0.1, 0.2, 0.3), pitch=0.05, roll=-0.07)
    assert struct.unpack_from("<i", p, 0) == (1,)
    assert struct.unpack_from("<3f", p, 20) == (1.5, -2.5, 3.5)
    assert struct.unpack_from("<3f", p, 44) == pytest.approx((0.1, 0.2, 0.3))
    assert struct.unpack_from("<3f", p, 56) == pytest.approx((0.3, 0.05, -0.07))
    assert ForzaMotion.unpack(p).pack() == p[: SLED_HEAD.size]


@pytest.mark.parametrize("size", sorted(FORZA_LAYOUTS))
def test_every_layout_at_rest_level_reads_plus_one_g(size: int) -> None:
    dec = decoder_for("forza")
    s = dec.feed(_packet(size=size), 2.0)
    assert s is not None and s.game == "forza" and s.t_s == 2.0 and not s.paused
    assert s.f == pytest.approx((0.0, 0.0, G0_M_S2), abs=1e-12)
    assert s.w == (0.0, 0.0, 0.0)
    assert dec.layouts == {FORZA_LAYOUTS[size]: 1}  # type: ignore[attr-defined]


def test_axis_map_by_hand() -> None:
    """Forza local (X right, Y up, Z forward): forward acceleration is +x, rightward is -y,
    upward +z (gravity added); a positive yaw rate about +Y (left-handed: turning right) is
    a negative ISO yaw rate; pitch rate about +X (nose down) is +q; roll about +Z is -p."""
    s = ForzaDecoder().feed(_packet(acc=(2.0, 3.0, 4.0), ang=(0.1, 0.2, 0.3)), 0.0)
    assert s is not None
    assert s.f == pytest.approx((4.0, -2.0, 3.0 + G0_M_S2), abs=1e-6)
    assert s.w == pytest.approx((-0.3, 0.1, -0.2), abs=1e-7)


@pytest.mark.parametrize(
    ("pitch", "roll", "expected"),
    [
        # nose down (Forza pitch +, left-hand rule about +X): specific force points back
        (0.2, 0.0, (-math.sin(0.2), 0.0, math.cos(0.2))),
        # Forza roll + raises the right side: left side down, f_y = -g sin
        (0.0, 0.3, (0.0, -math.sin(0.3), math.cos(0.3))),
    ],
)
def test_attitude_adds_gravity(
    pitch: float, roll: float, expected: tuple[float, float, float]
) -> None:
    s = ForzaDecoder().feed(_packet(pitch=pitch, roll=roll), 0.0)
    assert s is not None
    assert s.f == pytest.approx(tuple(G0_M_S2 * e for e in expected), abs=1e-5)


def test_race_off_is_paused_and_bad_flag_is_foreign() -> None:
    dec = ForzaDecoder()
    s = dec.feed(_packet(race_on=0), 0.0)
    assert s is not None and s.paused
    assert dec.decode(_packet(race_on=5), 0.0).reason == "skipped: foreign"


def test_bad_datagrams_are_counted() -> None:
    dec = ForzaDecoder()
    good = _packet()
    cases = {
        good[:100]: "skipped: truncated",
        good[:231]: "skipped: truncated",
        good + b"\0": "skipped: wrong size",
        bytes(300): "skipped: wrong size",
        _packet(acc=(math.nan, 0, 0)): "skipped: non-finite",
        _packet(ang=(0, math.inf, 0)): "skipped: non-finite",
        _packet(pitch=math.inf): "skipped: non-finite",
        _packet(acc=(0, 5e3, 0)): "skipped: out of range",
        _packet(ang=(0, 0, 500.0)): "skipped: out of range",
    }
    for data, reason in cases.items():
        assert dec.decode(data, 0.0).reason == reason, reason
    assert sum(dec.stats.values()) == len(cases)
    assert "sample" not in dec.stats


finite = st.floats(-50, 50, allow_nan=False, width=32)


@given(
    acc=st.tuples(finite, finite, finite),
    ang=st.tuples(finite, finite, finite),
    pitch=st.floats(-1.5, 1.5, width=32),
    roll=st.floats(-3.0, 3.0, width=32),
    size=st.sampled_from(sorted(FORZA_LAYOUTS)),
)
def test_specific_force_minus_gravity_recovers_the_acceleration(
    acc: tuple[float, float, float],
    ang: tuple[float, float, float],
    pitch: float,
    roll: float,
    size: int,
) -> None:
    """Invariant: |f - a_iso| = G0 for any attitude (gravity only rotates), and w keeps |w|."""
    s = ForzaDecoder().feed(_packet(acc=acc, ang=ang, pitch=pitch, roll=roll, size=size), 0.0)
    assert s is not None
    a_iso = (acc[2], -acc[0], acc[1])
    g = [fi - ai for fi, ai in zip(s.f, a_iso, strict=True)]
    assert math.sqrt(sum(x * x for x in g)) == pytest.approx(G0_M_S2, rel=1e-5)
    assert math.hypot(*s.w) == pytest.approx(math.hypot(*ang), rel=1e-6, abs=1e-9)


f32 = st.floats(allow_nan=False, allow_infinity=False, width=32)


@given(
    ints=st.tuples(st.integers(-(2**31), 2**31 - 1), st.integers(0, 2**32 - 1)),
    v=st.lists(f32, min_size=15, max_size=15),
)
def test_pack_unpack_round_trip(ints: tuple[int, int], v: list[float]) -> None:
    m = ForzaMotion(ints[0], ints[1], v[0], v[1], v[2], (v[3], v[4], v[5]), (v[6], v[7], v[8]),
                    (v[9], v[10], v[11]), v[12], v[13], v[14])  # fmt: skip
    raw = m.pack()
    assert len(raw) == SLED_HEAD.size == 68 and ForzaMotion.unpack(raw) == m
