"""DCS World: the shipped export script's datagram both ways, axes, pause, random bytes only
counted, and a loop and a roll through 90 deg of pitch without a kick."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from motioncue.telemetry import G0_M_S2, decoder_for
from motioncue.telemetry._dcs import DCSDecoder, DCSFrame

LUA = Path(__file__).resolve().parents[1] / "tools" / "dcs" / "MotioncueExport.lua"


def test_golden_datagram_decodes_by_hand() -> None:
    line = b"MCDCS1 12.5000 0.10000 1.20000 -0.30000 0.40000 0.05000 -0.20000"
    s = decoder_for("dcs").feed(line, 7.0)
    assert s is not None and s.game == "dcs" and s.t_s == 7.0 and not s.paused
    g = G0_M_S2
    # body (x nose, y up, z right wing) -> ISO (x, -z, y)
    assert s.f == pytest.approx((0.1 * g, 0.3 * g, 1.2 * g), abs=1e-9)
    assert s.w == pytest.approx((0.4, 0.2, 0.05), abs=1e-12)
    frame = DCSFrame.unpack(line)
    assert frame is not None and frame.pack() == line


def test_the_shipped_script_formats_what_the_decoder_reads() -> None:
    """The Lua script's string.format pattern, applied to the same values, gives the bytes
    DCSFrame.pack gives (Lua's %.Nf is C's, as Python's %-formatting)."""
    text = LUA.read_text()
    m = re.search(r'string\.format\("([^"]+)",\s*LoGetModelTime\(\), a\.x, a\.y, a\.z, '
                  r"w\.x, w\.y, w\.z\)", text)  # fmt: skip
    assert m is not None, "MotioncueExport.lua no longer sends the fields the decoder reads"
    values = (3.25, -0.125, 1.5, 0.0625, 0.5, -0.25, 0.75)
    frame = DCSFrame(values[0], values[1:4], values[4:7])
    assert (m.group(1) % values).encode() == frame.pack()
    assert "port = 20800" in text and "dofile(lfs.writedir()" in text


def test_repeated_model_time_is_paused() -> None:
    dec = DCSDecoder()
    f = DCSFrame(5.0, (0.0, 1.0, 0.0), (0.0, 0.0, 0.0)).pack()
    s1, s2 = dec.feed(f, 0.0), dec.feed(f, 0.1)
    assert s1 is not None and not s1.paused and s2 is not None and s2.paused


def test_bad_datagrams_are_counted() -> None:
    dec = DCSDecoder()
    for bad in (b"", b"MCDCS1 1 2 3", b"MCDCS1 a b c d e f g", b"XXXXX1 1 2 3 4 5 6 7",
                b"MCDCS1 " + b"1 " * 200, b"MCDCS1 nan 0 1 0 0 0 0",
                b"MCDCS1 1 0 inf 0 0 0 0", b"MCDCS1 1 0 1 0 500 0 0"):  # fmt: skip
        assert dec.feed(bad, 0.0) is None
    assert dec.stats == {"skipped: foreign": 5, "skipped: non-finite": 2,
                         "skipped: out of range": 1}  # fmt: skip


@settings(max_examples=300, deadline=None)
@given(st.binary(max_size=120))
def test_random_bytes_are_only_counted(data: bytes) -> None:
    dec = DCSDecoder()
    r = dec.decode(data, 0.0)
    assert sum(dec.stats.values()) == 1
    if not data.startswith(b"MCDCS1 "):
        assert r.sample is None


def _loop_and_roll(n: int = 1200, dt: float = 0.01) -> list[bytes]:
    """A 6 s inside loop (pitch through 360 deg at 1.05 rad/s, 150 m/s), then a 180 deg
    roll at 1.5 rad/s, as the flight model reports it: body rates and g-meter loads."""
    out = []
    v, q = 150.0, 2 * math.pi / 6.0
    theta = 0.0
    for k in range(n):
        t = k * dt
        if t < 6.0:
            theta = q * t
            # up (body y): centripetal v*q plus gravity's share; nose (x): at constant speed
            # the thrust holds gravity's share, so the g-meter reads +sin(pitch) along it
            ay = (v * q + G0_M_S2 * math.cos(theta)) / G0_M_S2
            ax = math.sin(theta)
            out.append(DCSFrame(t, (ax, ay, 0.0), (0.0, 0.0, q)).pack())
        else:
            phi = min(1.5 * (t - 6.0), math.pi)
            p = 1.5 if phi < math.pi else 0.0
            out.append(DCSFrame(t, (0.0, math.cos(phi), math.sin(phi)), (p, 0.0, 0.0)).pack())
    return out


def test_a_loop_and_a_roll_decode_without_a_kick() -> None:
    dec = DCSDecoder()
    samples = [dec.feed(d, k * 0.01) for k, d in enumerate(_loop_and_roll())]
    assert all(s is not None for s in samples)
    f = np.array([s.f for s in samples if s is not None])
    w = np.array([s.w for s in samples if s is not None])
    # through 90 deg of pitch (t = 1.5 s) and 180 deg of bank nothing jumps: the largest
    # change between frames is what the manoeuvre itself makes (1.5 rad/s rate switching)
    assert np.max(np.abs(np.diff(w, axis=0))) <= 1.5 + 1e-4
    assert np.max(np.abs(np.diff(f[:590], axis=0))) < 0.2  # smooth inside the loop
    assert w[:600, 1] == pytest.approx(-2 * math.pi / 6.0, abs=1e-4)  # nose-up: ISO q < 0
    assert f[150, 0] == pytest.approx(G0_M_S2, abs=1e-3)  # vertical climb: 1 g along the nose
