"""IMAX PortOut width: 2 bytes (the 0x1301 table, 2.2.2.5) or 4 bytes (0x1401, the replies and
the vibration frames, 2.2.2.6-2.2.2.12), chosen by the controller's ``port_out_bytes``.

The expected bytes are built here field by field from the manual's tables.
"""

from __future__ import annotations

import dataclasses
import os
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError, ProtocolError
from motioncue.output import imax, load_controller

WIDTHS = (2, 4)


def _be(*fields: tuple[int, int, bool]) -> bytes:
    return b"".join(v.to_bytes(n, "big", signed=s) for v, n, s in fields)


def _frame_bytes(function, channel, who, frame, time_ms, positions, port, port_bytes, tail):
    """Header (0x55AA, 0, function, channel, who accept, who reply), Frame L, Time L,
    positions L each (signed), PortOut ``port_bytes``, then ``tail`` (already bytes)."""
    head = _be((0x55AA, 2, False), (0, 2, False), (function, 2, False), (channel, 2, False))
    head += _be((who[0], 2, False), (who[1], 2, False))
    signed_time = function in (0x1401, 0x1901) or (function & 0xFFF0) in (0x1400, 0x1900)
    body = _be((frame, 4, False), (time_ms, 4, signed_time))
    body += b"".join(p.to_bytes(4, "big", signed=True) for p in positions)
    return head + body + port.to_bytes(port_bytes, "big") + tail


def _ctrl(name="imax6", width=2, **params):
    ctrl = load_controller(name)
    if params:
        ctrl = ctrl.with_parameters(**params)
    return dataclasses.replace(ctrl, port_out_bytes=width)


# -- golden bytes, both ways ------------------------------------------------------------------
@pytest.mark.parametrize("width", WIDTHS)
@pytest.mark.parametrize("absolute", [True, False])
def test_motion_frame_golden_bytes(width, absolute):
    function = 0x1301 if absolute else 0x1401
    time_ms = 250 if absolute else -3
    pos = (1, -1, 70000, -70000, 0, 2**31 - 1)
    golden = _frame_bytes(
        function, 1, (0xFFFF, 0xFFFF), 7, time_ms, pos, 0x0A5F, width, _be((0, 4, False))
    )
    assert len(golden) == (50 if width == 2 else 52)
    msg = imax.MotionFrame(absolute, 7, time_ms, pos, 0x0A5F, 0, port_out_bytes=width)
    assert msg.encode() == golden and msg.size == len(golden)
    assert imax.decode(golden, width) == msg  # the configured width
    assert imax.decode(golden) == msg  # either width: told apart by the length
    other = 4 if width == 2 else 2
    with pytest.raises(ProtocolError, match=f"expected {msg.size + other - width}"):
        imax.decode(golden, other)


@pytest.mark.parametrize("width", WIDTHS)
def test_frame_reply_golden_bytes(width):
    # 0x1402 reply (2.2.2.8): the frame echoed, PortOut carrying the inputs
    pos = (5, -6, 7)
    golden = _frame_bytes(0x1402, 0, (0, 0), 3, 10, pos, 0x0801, width, _be((9, 4, False)))
    rep = imax.MotionFrameReply(imax.ReplyStatus.OK, False, 0, 3, 10, pos, 0x0801, 9, width)
    assert rep.encode() == golden and len(golden) == 24 + width + 12
    assert imax.decode(golden, width) == rep and imax.decode(golden) == rep
    with pytest.raises(ProtocolError, match="is not"):
        imax.decode(golden, 6 - width)
    # an error reply (x = 3) carries the error code in the channel field
    err = imax.MotionFrameReply(imax.ReplyStatus.ERROR, True, 21, 3, 10, pos, 0, 0, width)
    raw = err.encode()
    assert raw[4:8] == bytes.fromhex("13030015") and imax.decode(raw, width) == err


@pytest.mark.parametrize("width", WIDTHS)
def test_vibration_frame_golden_bytes(width):
    # 0x1901 (2.2.2.11): ... PortOut, then per axis period u16 (0.125 ms), amplitude u16
    pos = (100, 200, 300)
    vib = ((8, 50), (16, 60), (24, 70))
    tail = b"".join(_be((a, 2, False), (b, 2, False)) for a, b in vib)
    golden = _frame_bytes(0x1901, 0, (0xFFFF, 0xFFFF), 1, 5, pos, 0x3, width, tail)
    msg = imax.VibrationFrame(False, 1, 5, pos, 0x3, vib, port_out_bytes=width)
    assert msg.encode() == golden and msg.size == len(golden) == 20 + 12 + width + 12
    assert imax.decode(golden, width) == msg and imax.decode(golden) == msg
    with pytest.raises(ProtocolError):
        imax.decode(golden, 6 - width)
    rep = imax.VibrationFrameReply(imax.ReplyStatus.OK, False, 0, 1, 5, pos, 0x3, vib, width)
    raw = rep.encode()
    assert raw[4:6] == bytes.fromhex("1902") and raw[12:] == golden[12:]
    assert imax.decode(raw, width) == rep and imax.decode(raw) == rep


def test_port_out_values_above_16_bits_need_the_4_byte_reading():
    assert imax.MotionFrame(True, 0, 0, (0, 0, 0), 0x10000, port_out_bytes=4).port_out == 0x10000
    with pytest.raises(ProtocolError):
        imax.MotionFrame(True, 0, 0, (0, 0, 0), 0x10000, port_out_bytes=2)
    with pytest.raises(ProtocolError, match="2 or 4"):
        imax.MotionFrame(True, 0, 0, (0, 0, 0), port_out_bytes=3)
    with pytest.raises(ProtocolError, match="2 or 4"):
        imax.decode(imax.MotionFrame(True, 0, 0, (0, 0, 0)).encode(), 1)


# -- the controller's configuration ----------------------------------------------------------
@pytest.mark.parametrize("width", WIDTHS)
def test_encoder_writes_the_configured_width(width):
    ctrl = _ctrl("imax3", width)
    for absolute in (True, False):
        enc = ctrl.frame_encoder(absolute_time=absolute, t0_s=0.0)
        raw = enc.encode(0.01, [1, -2, 3], dout=0xABC)[0]
        n_bytes = 24 + width + 12
        assert len(raw) == n_bytes
        assert raw[32 : 32 + width] == (0xABC).to_bytes(width, "big")  # PortOut after positions
        assert raw[32 + width :] == bytes(4)  # Extend
        msg = imax.decode(raw, width)
        assert (msg.port_out, msg.positions, msg.port_out_bytes) == (0xABC, (1, -2, 3), width)
        vib = enc.encode(0.02, [4, 5, 6], dout=0x5, vibration=[(8, 9)] * 3)[0]
        assert len(vib) == 20 + 12 + width + 12 and vib[32 : 32 + width] == (5).to_bytes(width)


def test_config_key_port_out_bytes(tmp_path):
    path = tmp_path / "four.toml"
    path.write_text('kind = "imax"\naxes = 3\nport_out_bytes = 4\n')
    assert load_controller(path).port_out_bytes == 4
    path.write_text('kind = "imax"\naxes = 3\n')
    assert load_controller(path).port_out_bytes == 2  # default: 0x1301's table
    for bad in ("3", "8", "0", '"4"', "2.0", "true"):
        path.write_text(f'kind = "imax"\naxes = 3\nport_out_bytes = {bad}\n')
        with pytest.raises(ConfigError, match="port_out_bytes"):
            load_controller(path)
    with pytest.raises(ConfigError, match="port_out_bytes = 3"):
        _ctrl("imax3", 3)
    assert load_controller("imax3").port_out_bytes == load_controller("imax6").port_out_bytes == 2


# -- the emulator -------------------------------------------------------------------------------
@pytest.mark.parametrize("width", WIDTHS)
def test_emulator_reads_and_answers_its_width_only(width):
    ctrl = _ctrl("imax6", width)
    emu = imax.ImaxEmulator(ctrl)
    enc = ctrl.frame_encoder()
    (rep,) = emu.handle(enc.encode(0.0, [0] * 6, dout=0x7)[0], 0.0)
    assert len(rep) == 24 + width + 24 and rep[4:6] == bytes.fromhex("1302")
    assert imax.decode(rep, width).frame == 0 and emu.outputs == 0x7
    (rep,) = emu.handle(enc.encode(0.01, [1] * 6, vibration=[(8, 1)] * 6)[0], 0.01)
    assert rep[4:6] == bytes.fromhex("1802") and len(rep) == 20 + 24 + width + 24
    # a frame of the other width: malformed, answered x = 5, not played
    other = imax.MotionFrame(True, 2, 20, (2,) * 6, port_out_bytes=6 - width).encode()
    (rep,) = emu.handle(other, 0.02)
    assert rep[4:6] == bytes.fromhex("1305") and len(rep) == 24 + width + 24
    assert [v.kind for v in emu.violations] == ["malformed"] and len(emu.trace) == 2


def test_emulator_over_udp_with_4_byte_port_out():
    ctrl = dataclasses.replace(_ctrl("imax6", 4), buffer_frames=1024)
    from motioncue.output import open_transport

    n = 200
    with imax.ImaxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder(absolute_time=False, t0_s=0.0)
        for k in range(n):
            tr.send(enc.encode(k * 0.01, [10 * k] * 6, dout=k & 0xFFF)[0])
        replies = []
        deadline = time.monotonic() + 5
        while len(replies) < n and time.monotonic() < deadline:
            r = tr.recv(0.2)
            if r is not None:
                replies.append(imax.decode(r, 4))
    assert emu.received == n and emu.violations == [] and emu.internal_errors == []
    assert [r.frame for r in replies] == list(range(n))
    assert all(r.port_out_bytes == 4 for r in replies)


@pytest.mark.parametrize("width", WIDTHS)
def test_raw_capture_splits_at_either_width(width):
    ctrl = _ctrl("imax3", width)
    enc = ctrl.frame_encoder()
    msgs = [enc.encode(k * 0.01, [k, -k, 2 * k])[0] for k in range(5)]
    msgs.insert(2, imax.RegisterRead(imax.CHANNEL_PA, 0x80, 3).encode())
    msgs.append(enc.encode(0.06, [0, 0, 0], vibration=[(1, 2)] * 3)[0])
    blob = b"".join(msgs)
    assert imax.split_stream(blob) == msgs
    assert imax.split_stream(blob, width) == msgs
    with pytest.raises(ProtocolError):
        imax.split_stream(blob, 6 - width)
    assert all(imax.inspect_decode(m) for m in msgs)


# -- round trips and random bytes -------------------------------------------------------------
u16 = st.integers(0, 0xFFFF)
u32 = st.integers(0, 0xFFFFFFFF)
i32 = st.integers(-(2**31), 2**31 - 1)


@st.composite
def frames(draw):
    width = draw(st.sampled_from(WIDTHS))
    n = draw(st.integers(2, 12))
    absolute = draw(st.booleans())
    pos = tuple(draw(st.lists(i32, min_size=n, max_size=n)))
    t = draw(u32 if absolute else i32)
    port = draw(u16 if width == 2 else u32)
    vib = tuple(draw(st.lists(st.tuples(u16, u16), min_size=n, max_size=n)))
    kind = draw(st.sampled_from(["frame", "reply", "vib", "vib_reply"]))
    status = draw(st.sampled_from(list(imax.ReplyStatus)))
    if kind == "frame":
        return imax.MotionFrame(
            absolute, draw(u32), t, pos, port, draw(u32), draw(u16), draw(u16), width
        )
    if kind == "reply":
        return imax.MotionFrameReply(
            status, absolute, draw(u16), draw(u32), t, pos, port, draw(u32), width
        )
    if kind == "vib":
        return imax.VibrationFrame(
            absolute, draw(u32), t, pos, port, vib, draw(u16), draw(u16), width
        )
    return imax.VibrationFrameReply(
        status, absolute, draw(u16), draw(u32), t, pos, port, vib, width
    )


@given(frames())
def test_round_trip_at_both_widths(msg):
    raw = msg.encode()
    assert len(raw) == msg.size
    assert imax.decode(raw, msg.port_out_bytes) == msg
    assert imax.decode(raw) == msg
    with pytest.raises(ProtocolError):
        imax.decode(raw, 6 - msg.port_out_bytes)


_FRAME_PREFIXES = [
    bytes.fromhex(h)
    for h in (
        "55AA00001301",
        "55AA00001302",
        "55AA00001303",
        "55AA00001401",
        "55AA00001402",
        "55AA00001405",
        "55AA00001801",
        "55AA00001802",
        "55AA00001901",
        "55AA00001904",
    )
]


def test_random_bytes_into_the_decoders_raise_only_protocol_error():
    # frame-shaped datagrams (a frame function code, a channel for 2..12 axes, random
    # lengths around the frame sizes) into the decoder at each width: decoded or refused
    # with ProtocolError, never anything else
    rng = np.random.default_rng(10)
    cases = 60_000
    blob = os.urandom(cases * 72)
    lengths = rng.integers(0, 72, size=cases)
    channels = rng.integers(0, 13, size=cases)
    decoded = {2: 0, 4: 0, None: 0}
    for i in range(cases):
        prefix = _FRAME_PREFIXES[i % len(_FRAME_PREFIXES)] + int(channels[i]).to_bytes(2, "big")
        data = prefix + blob[i * 72 : i * 72 + int(lengths[i])]
        width = (2, 4, None)[i % 3]
        try:
            msg = imax.decode(data, width)
        except ProtocolError:
            continue
        decoded[width] += 1
        assert width is None or msg.port_out_bytes == width
        # the body reads back; the header may not (replies send Who as 0, channel 6 = 6
        # axes is sent as the manual's 1)
        again = msg.encode()
        assert again[:6] == data[:6] and again[12:] == data[12:]
    assert min(decoded.values()) > 100  # the lengths hit real frame sizes at every width
    # the decode rate (60 000 of these in 30 s at least) is in benchmarks/bench_output.py
