"""BeamNG MotionSim (BNG1) decoder: layout, axis conversion, bad datagrams."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ProtocolError
from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._beamng import BNG1, MAGIC, BeamNGDecoder, BeamNGMotion

Z3 = (0.0, 0.0, 0.0)


def _motion(**kw: object) -> BeamNGMotion:
    base: dict[str, object] = dict(
        pos=(10.0, 20.0, 1.0), vel=(0.0, -15.0, 0.0), acc=Z3, up_vec=(0.0, 0.0, 1.0),
        roll_pos=0.0, pitch_pos=0.0, yaw_pos=0.0, roll_rate=0.0, pitch_rate=0.0,
        yaw_rate=0.0, roll_acc=0.0, pitch_acc=0.0, yaw_acc=0.0,
    )  # fmt: skip
    base.update(kw)
    return BeamNGMotion(**base)  # type: ignore[arg-type]


def test_layout_is_88_bytes_with_documented_offsets() -> None:
    p = _motion(acc=(1.0, 2.0, 3.0), roll_rate=0.4, pitch_rate=0.5, yaw_rate=0.6).pack()
    assert len(p) == BNG1.size == 88
    assert p[:4] == b"BNG1"
    # by hand: magic 4 + pos 12 + vel 12 -> acc at 28; rates after up (12) and angles (12)
    assert struct.unpack_from("<3f", p, 28) == (1.0, 2.0, 3.0)
    assert struct.unpack_from("<3f", p, 4 + 4 * 15) == pytest.approx((0.4, 0.5, 0.6))
    assert BeamNGMotion.unpack(p) == BeamNGMotion.unpack(BeamNGMotion.unpack(p).pack())
    with pytest.raises(ProtocolError, match="magic"):
        BeamNGMotion.unpack(b"XXXX" + p[4:])


def test_at_rest_level_reads_plus_one_g() -> None:
    s = decoder_for("beamng").feed(_motion().pack(), 3.0)
    assert s is not None and s.game == "beamng" and not s.paused and s.t_s == 3.0
    assert s.f == pytest.approx((0.0, 0.0, G0_M_S2), abs=1e-12)
    assert s.w == (0.0, 0.0, 0.0)


def test_axis_map_by_hand() -> None:
    """acc = -sensor, sensor frame (x left, y rear, z up): acc = (right, forward, down);
    rates in the aerospace convention (roll right-down, pitch nose-up, yaw nose-right)."""
    s = BeamNGDecoder().feed(
        _motion(acc=(1.0, 2.0, 3.0), roll_rate=0.1, pitch_rate=0.2, yaw_rate=0.3).pack(), 0.0
    )
    assert s is not None
    assert s.f == pytest.approx((2.0, -1.0, -3.0 + G0_M_S2), abs=1e-6)
    assert s.w == pytest.approx((0.1, -0.2, -0.3), abs=1e-7)


def test_pitch_and_roll_add_gravity() -> None:
    """pitchPos = +0.2 is nose up: an accelerometer at rest reads +g sin(0.2) forward;
    rollPos = +0.3 is left side down: it reads toward the raised right side (f_y < 0)."""
    s = BeamNGDecoder().feed(_motion(pitch_pos=0.2, roll_pos=0.3).pack(), 0.0)
    assert s is not None
    th, ph = -0.2, -0.3  # ISO pitch and roll
    up = (-math.sin(th), math.sin(ph) * math.cos(th), math.cos(ph) * math.cos(th))
    assert s.f[0] > 0 and s.f[1] < 0
    assert s.f == pytest.approx(tuple(G0_M_S2 * u for u in up), abs=1e-5)


def test_bad_datagrams_are_counted() -> None:
    dec = BeamNGDecoder()
    good = _motion().pack()
    outgauge = struct.pack("<I4sH", 0, b"beam", 0) + bytes(80)  # BeamNG's other protocol
    cases = {
        b"": "skipped: foreign",
        b"BNG": "skipped: foreign",
        b"BNG2" + good[4:]: "skipped: foreign",
        outgauge: "skipped: foreign",
        good[:50]: "skipped: truncated",
        good + b"\0": "skipped: wrong size",
        _motion(acc=(math.nan, 0.0, 0.0)).pack(): "skipped: non-finite",
        _motion(roll_pos=math.inf).pack(): "skipped: non-finite",
        _motion(yaw_rate=-math.inf).pack(): "skipped: non-finite",
        _motion(acc=(0.0, 3e4, 0.0)).pack(): "skipped: out of range",
    }
    for data, reason in cases.items():
        assert dec.decode(data, 0.0).reason == reason, reason
    assert "sample" not in dec.stats and sum(dec.stats.values()) == len(cases)


finite = st.floats(-50, 50, allow_nan=False, width=32)


@given(
    acc=st.tuples(finite, finite, finite),
    rates=st.tuples(finite, finite, finite),
    pitch=st.floats(-1.5, 1.5, width=32),
    roll=st.floats(-3.0, 3.0, width=32),
)
def test_gravity_only_rotates(
    acc: tuple[float, float, float], rates: tuple[float, float, float], pitch: float, roll: float
) -> None:
    m = _motion(acc=acc, pitch_pos=pitch, roll_pos=roll, roll_rate=rates[0],
                pitch_rate=rates[1], yaw_rate=rates[2])  # fmt: skip
    s = BeamNGDecoder().feed(m.pack(), 0.0)
    assert s is not None
    a_iso = (acc[1], -acc[0], -acc[2])
    g = [fi - ai for fi, ai in zip(s.f, a_iso, strict=True)]
    assert math.sqrt(sum(x * x for x in g)) == pytest.approx(G0_M_S2, rel=1e-5)
    assert MAGIC == b"BNG1"


@given(
    vals=st.lists(st.floats(allow_nan=False, allow_infinity=False, width=32), min_size=21,
                  max_size=21)
)  # fmt: skip
def test_pack_unpack_round_trip(vals: list[float]) -> None:
    m = BeamNGMotion(
        tuple(vals[0:3]), tuple(vals[3:6]), tuple(vals[6:9]), tuple(vals[9:12]),  # type: ignore[arg-type]
        *vals[12:21],
    )  # fmt: skip
    p = m.pack()
    assert len(p) == 88 and BeamNGMotion.unpack(p) == m
