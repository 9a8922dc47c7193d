"""IMAX wire format: layouts from the manual's tables, round trips, fuzzing, the encoder."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError, ProtocolError
from motioncue.output import imax, load_controller


def _be(*fields: tuple[int, int, bool]) -> bytes:
    return b"".join(v.to_bytes(n, "big", signed=s) for v, n, s in fields)


# -- layouts built field by field from the manual's tables ------------------------------------
def test_register_read_layout_2_2_2_1():
    # 0x55aa, 0x0000, 0x1101, channel 1 (PA), ff.ff, ff.ff, start 0x80, count 6, zeros
    raw = imax.RegisterRead(imax.CHANNEL_PA, 0x80, 6).encode()
    assert raw == bytes.fromhex("55AA00001101 0001 FFFFFFFF 0080 0006".replace(" ", "")) + bytes(12)
    assert imax.decode(raw) == imax.RegisterRead(1, 0x80, 6)


def test_register_write_to_dpf0_homes_2_2_2_3():
    # "if Object Channel is 2 and DPF0 is to be set, the start address is 00 00"
    raw = imax.RegisterWrite(imax.CHANNEL_DPF, 0, (0,)).encode()
    assert raw == bytes.fromhex("55AA000012010002FFFFFFFF000000010000")


def test_register_replies_put_error_code_in_channel_2_2_2_2():
    ok = imax.RegisterReply(0x1102, 1, 0x80, (3000, 0))
    assert ok.encode() == bytes.fromhex(
        "55AA0000110200010000000000800002 0BB8 0000".replace(" ", "")
    )
    err = imax.RegisterReply(0x1203, 21, 0x80, (1,))
    assert err.status == imax.ReplyStatus.ERROR and err.error_code == 21
    assert err.encode()[6:8] == (21).to_bytes(2, "big")
    for msg in (ok, err):
        assert imax.decode(msg.encode()) == msg


def test_absolute_frame_layout_2_2_2_5():
    # Frame L, absolute Time L, 6 x L positions (0xffffffff = -1), PortOut 2 bytes, Extend L
    msg = imax.MotionFrame(True, 9, 100, (1, -1, 2, 3, 4, 100), 0x0FFF, 0)
    expected = bytes.fromhex("55AA000013010001FFFFFFFF") + _be(
        (9, 4, False),
        (100, 4, False),
        (1, 4, True),
        (-1, 4, True),
        (2, 4, True),
        (3, 4, True),
        (4, 4, True),
        (100, 4, True),
        (0x0FFF, 2, False),
        (0, 4, False),
    )
    assert msg.encode() == expected and msg.size == len(expected) == 50
    assert expected[24:28] == b"\xff\xff\xff\xff"
    assert imax.decode(expected) == msg


def test_channel_codes_for_n_axes():
    assert [imax.channel_of_axes(n) for n in (3, 6, 2, 4, 12)] == [0, 1, 2, 4, 12]
    assert [imax.axes_of_channel(c) for c in (0, 1, 2, 4, 12)] == [3, 6, 2, 4, 12]
    raw = imax.MotionFrame(False, 0, 5, (1, 2, 3, 4)).encode()
    assert raw[6:8] == b"\x00\x04" and imax.frame_size(4) == 12 + 8 + 16 + 2 + 4
    with pytest.raises(ProtocolError):
        imax.axes_of_channel(13)


def test_vibration_frame_layout_2_2_2_11():
    msg = imax.VibrationFrame(False, 1, 20, (10, 20, 30), 0x5, ((8, 100), (16, 200), (0, 0)))
    expected = bytes.fromhex("55AA000019010000FFFFFFFF") + _be(
        (1, 4, False),
        (20, 4, True),
        (10, 4, True),
        (20, 4, True),
        (30, 4, True),
        (5, 2, False),
        (8, 2, False),
        (100, 2, False),
        (16, 2, False),
        (200, 2, False),
        (0, 2, False),
        (0, 2, False),
    )
    assert msg.encode() == expected
    assert imax.decode(expected) == msg


def test_servo_messages_use_33cc_and_at_most_six_registers_2_2_2_13():
    raw = imax.ServoRead(2, 0x01FC, 1).encode()  # PA508 of servo 2
    assert raw == bytes.fromhex("33CC000021010002FFFFFFFF01FC00010000")
    assert imax.decode(raw) == imax.ServoRead(2, 0x01FC, 1)
    assert imax.decode(imax.ServoWrite(1, 0x01FC, (7,)).encode()) == imax.ServoWrite(1, 0x1FC, (7,))
    with pytest.raises(ProtocolError, match="count 7"):
        imax.ServoRead(1, 0, 7)
    with pytest.raises(ProtocolError, match="7 values"):
        imax.ServoWrite(1, 0, (0,) * 7)
    # the same function code under the wrong confirm code is unknown
    with pytest.raises(ProtocolError, match="unknown IMAX function"):
        imax.decode(b"\x55\xaa" + raw[2:])


def test_status_report_layout_2_2_2_15():
    rep = imax.StatusReport(0x0FC9, (100, -2), (5, -6), (0, 10), 21, 0x3, 0x1)
    expected = bytes.fromhex("33CC00003101 0FC9 0002".replace(" ", "")) + _be(
        (100, 4, True),
        (-2, 4, True),
        (5, 2, True),
        (-6, 2, True),
        (0, 2, False),
        (10, 2, False),
        (21, 2, False),
        (3, 2, False),
        (1, 2, False),
    )
    assert rep.encode() == expected
    assert imax.decode(expected) == rep


def test_function_0x1001_is_refused_as_undocumented():
    with pytest.raises(ProtocolError, match="unknown IMAX function code 0x1001"):
        imax.decode(bytes.fromhex("55AA000010010000000000000000000100000000"))


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (b"\x55", "shorter than the 12-byte header"),
        (bytes.fromhex("AAAA000011010000FFFFFFFF000000010000"), "confirm code"),
        (bytes.fromhex("55AA000011010003FFFFFFFF000000010000"), "channel 3"),
        (bytes.fromhex("55AA000013010001FFFFFFFF") + bytes(10), "length 22 bytes, expected 50"),
        (bytes.fromhex("55AA00001301000DFFFFFFFF") + bytes(38), "frame channel 13"),
        (bytes.fromhex("33CC00003101 0001 000D".replace(" ", "")), "13 servos"),
        (bytes.fromhex("55AA000013020001000000000000"), "not 26 \\+ 4 n"),
    ],
)
def test_decode_errors_name_the_problem(data, words):
    with pytest.raises(ProtocolError, match=words):
        imax.decode(data)


# -- round trips -------------------------------------------------------------------------------
u16 = st.integers(0, 0xFFFF)
i16 = st.integers(-0x8000, 0x7FFF)
u32 = st.integers(0, 0xFFFFFFFF)
i32 = st.integers(-(2**31), 2**31 - 1)
words = st.lists(u16, min_size=1, max_size=30).map(tuple)
n_axes = st.integers(2, 12)
status = st.sampled_from(list(imax.ReplyStatus))


@st.composite
def motion(draw, reply=False, vib=False):
    n = draw(n_axes)
    absolute = draw(st.booleans())
    pos = tuple(draw(st.lists(i32, min_size=n, max_size=n)))
    t = draw(u32 if absolute else i32)
    vibration = tuple(draw(st.lists(st.tuples(u16, u16), min_size=n, max_size=n)))
    if reply:
        ch = draw(u16)
        if vib:
            return imax.VibrationFrameReply(
                draw(status), absolute, ch, draw(u32), t, pos, draw(u16), vibration
            )
        return imax.MotionFrameReply(
            draw(status), absolute, ch, draw(u32), t, pos, draw(u16), draw(u32)
        )
    if vib:
        return imax.VibrationFrame(
            absolute, draw(u32), t, pos, draw(u16), vibration, draw(u16), draw(u16)
        )
    return imax.MotionFrame(absolute, draw(u32), t, pos, draw(u16), draw(u32), draw(u16), draw(u16))


@st.composite
def status_reports(draw):
    n = draw(st.integers(0, 12))
    return imax.StatusReport(
        draw(u16),
        tuple(draw(st.lists(i32, min_size=n, max_size=n))),
        tuple(draw(st.lists(i16, min_size=n, max_size=n))),
        tuple(draw(st.lists(u16, min_size=n, max_size=n))),
        draw(u16),
        draw(u16),
        draw(u16),
    )


messages = st.one_of(
    st.builds(imax.RegisterRead, st.sampled_from([0, 1]), u16, st.integers(1, 256), u16, u16),
    st.builds(imax.RegisterWrite, st.sampled_from([0, 1, 2]), u16, words, u16, u16),
    st.builds(
        imax.RegisterReply,
        st.sampled_from([0x1102, 0x1103, 0x1104, 0x1105, 0x1202, 0x1203, 0x1204, 0x1205]),
        u16,
        u16,
        words,
    ),
    st.builds(imax.ServoRead, u16, u16, st.integers(1, 6), u16, u16),
    st.builds(
        imax.ServoWrite, u16, u16, st.lists(u16, min_size=1, max_size=6).map(tuple), u16, u16
    ),
    st.builds(
        imax.ServoReply,
        st.sampled_from([0x2102, 0x2103, 0x2202, 0x2205]),
        u16,
        u16,
        st.lists(u16, max_size=6).map(tuple),
    ),
    motion(),
    motion(reply=True),
    motion(vib=True),
    motion(reply=True, vib=True),
    status_reports(),
)


@given(messages)
def test_round_trip_every_message_type(msg):
    raw = msg.encode()
    assert len(raw) == msg.size
    assert imax.decode(raw) == msg


# -- fuzzing -------------------------------------------------------------------------------------
_PREFIXES = [
    bytes.fromhex(h)
    for h in (
        "55AA00001101",
        "55AA00001102",
        "55AA00001103",
        "55AA00001201",
        "55AA00001205",
        "55AA00001301",
        "55AA00001302",
        "55AA00001401",
        "55AA00001404",
        "55AA00001801",
        "55AA00001802",
        "55AA00001901",
        "55AA00001903",
        "33CC00002101",
        "33CC00002102",
        "33CC00002201",
        "33CC00002205",
        "33CC00003101",
    )
]


def test_random_bytes_raise_only_protocol_error():
    rng = np.random.default_rng(2)
    blob = os.urandom(100_000 * 80)
    lengths = rng.integers(0, 80, size=100_000)
    deep = 0  # rejections that got past the header to a message's own checks
    for i, n in enumerate(lengths):
        data = blob[i * 80 : i * 80 + int(n)]
        if i % 2:
            data = _PREFIXES[i % len(_PREFIXES)] + data
        try:
            imax.decode(data)
        except ProtocolError as exc:
            text = str(exc)
            deep += not any(w in text for w in ("confirm", "pass code", "unknown", "header"))
    assert deep > 10_000


@given(messages, st.data())
def test_mutations_near_valid_messages_raise_only_protocol_error(msg, data):
    raw = bytearray(msg.encode())
    action = data.draw(st.sampled_from(["truncate", "extend", "flip"]))
    if action == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw) - 1))]
    elif action == "extend":
        raw += data.draw(st.binary(min_size=1, max_size=8))
    else:
        i = data.draw(st.integers(0, len(raw) - 1))
        raw[i] ^= data.draw(st.integers(1, 255))
    try:
        imax.decode(bytes(raw))
    except ProtocolError:
        pass


# -- encoder, config ---------------------------------------------------------------------------
def test_encoder_frames_and_vibration():
    ctrl = load_controller("imax3")
    enc = ctrl.frame_encoder(absolute_time=False, t0_s=0.0)
    a = imax.decode(enc.encode(0.01, [1, 2, 3], dout=0x801)[0])
    b = imax.decode(enc.encode(0.02, [4, 5, 6], vibration=[(8, 50)] * 3)[0])
    assert isinstance(a, imax.MotionFrame) and (a.frame, a.time_ms, a.port_out) == (0, 10, 0x801)
    assert isinstance(b, imax.VibrationFrame) and (b.frame, b.time_ms) == (1, 10)
    assert b.vibration == ((8, 50),) * 3 and not b.absolute


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"dout": 0x1000}, "Y01..Y12"),
        ({"dacs": (1, 0)}, "no analogue"),
        ({"vibration": [(8, 70000)] * 3}, "u16"),
        ({"vibration": [(8, 1)] * 2}, "2 vibration"),
    ],
)
def test_encoder_refuses_what_the_imax_cannot_carry(kwargs, words):
    enc = load_controller("imax3").frame_encoder()
    with pytest.raises(ProtocolError, match=words):
        enc.encode(0.0, [0, 0, 0], **kwargs)
    assert imax.decode(enc.encode(0.0, [0, 0, 0])[0]).frame == 0


@pytest.mark.parametrize("bad", [[math.nan, 0, 0], [0, math.inf, 0], [2**31, 0, 0], [0.25, 0, 0]])
def test_encoder_refuses_non_finite_and_out_of_range(bad):
    with pytest.raises(ProtocolError):
        load_controller("imax3").frame_encoder().encode(0.0, bad)


def test_stroke_from_config_with_lift_offset():
    import dataclasses

    # counts per turn from PA54 (4 x 5000 lines) when the config gives none
    ctrl = dataclasses.replace(load_controller("imax6"), counts_per_rev=None)
    assert ctrl.pulses_per_mm == 20000 / 5.0  # 4 x 5000 lines, 5 mm lead
    assert load_controller("imax6").pulses_per_mm == 10000 / 5.0  # counts_per_rev = 10000
    assert ctrl.stroke_pulses is None

    c2 = dataclasses.replace(ctrl, stroke_mm=100.0)
    assert c2.stroke_pulses == (-40_000, 360_000)  # lift PA40 = 10 mm
    enc = c2.frame_encoder()
    enc.encode(0.0, [-40_000] * 6)
    with pytest.raises(LimitError):
        enc.encode(0.01, [360_001] * 6)


def test_bundled_imax_configs():
    c3, c6 = load_controller("imax3"), load_controller("imax6")
    assert (c3.kind, c3.n_axes, c6.n_axes) == ("imax", 3, 6)
    assert c6.parameters["PA02"] == 6 and c3.parameters["PA02"] == 3
    assert c6.controller_address == ("192.168.15.201", 7408)
    assert c6.host_address == ("192.168.15.101", 8410)
    assert c6.max_frame_rate_hz == 1000.0  # PA59 = 1 ms
    # min(PA07 3000, PAa0 x PAb0 = 2 x 1500) rpm x 10000 counts / turn (counts_per_rev) / 60 s
    assert c6.counts_per_rev == 10000
    assert c6.max_speed_pulses_s[0] == pytest.approx(500_000.0)
    assert c6.with_parameters(PA80=600).max_speed_rpm(0) == 600


def test_imax_config_errors(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('kind = "imax"\naxes = 6\n[parameters]\nPA02 = 3\n')
    with pytest.raises(ConfigError, match="PA02 = 3 but axes = 6"):
        load_controller(path)
    path.write_text('kind = "imax"\naxes = 6\n[parameters]\nPAa0 = 0\n')
    with pytest.raises(ConfigError, match=r"PAa0 = 0 .*\[1, 3000\]"):
        load_controller(path)
    path.write_text('kind = "imax"\naxes = 6\n[parameters]\nPAzz = 0\n')
    with pytest.raises(ConfigError, match="PAzz"):
        load_controller(path)


def test_signed_positions_of_section_5_7():
    # 5.7: "100 is 0x00000064, -100 is 0xfffff9c" (printed with a digit missing: -100 is
    # 0xFFFFFF9C in 32-bit two's complement, as 2.2.2.5's "0xffffffff is -1" implies)
    raw = imax.MotionFrame(True, 0, 0, (100, -100, -1)).encode()
    assert raw[20:32] == bytes.fromhex("00000064 FFFFFF9C FFFFFFFF".replace(" ", ""))
