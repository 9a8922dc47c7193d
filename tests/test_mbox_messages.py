"""SC-MBOX wire format: golden bytes from the manual, round trips, fuzzing, the encoder."""

from __future__ import annotations

import math
import os
import struct

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError, ProtocolError
from motioncue.output import load_controller, mbox
from motioncue.output._transports_file import ethernet_ipv4_udp

ESTOP_CAPTURE = bytes.fromhex("55AA000012010000FFFFFFFF009000010001")  # manual 4.5.2
RESET_PRINTED = bytes.fromhex("55AA000012010000FFFFFFFF000000010000")  # manual 4.5.1 text


# -- golden bytes, both directions ------------------------------------------------------------
def test_estop_capture_decodes_as_fn090_write_through_fxm():
    msg = mbox.decode(ESTOP_CAPTURE)
    assert msg == mbox.RegisterWrite(mbox.CHANNEL_FXM, 0x090, (1,), 0xFFFF, 0xFFFF)


def test_estop_capture_is_encoded_exactly():
    msg = mbox.RegisterWrite(mbox.CHANNEL_FXM, mbox.fn_address("Fn090"), (1,), 0xFFFF, 0xFFFF)
    assert msg.encode() == ESTOP_CAPTURE
    assert msg.size == len(ESTOP_CAPTURE) == 18


def test_reset_capture_as_printed_decodes_literally():
    # The printed bytes say channel 0 (an FXm write of Fn000 = 0) ...
    msg = mbox.decode(RESET_PRINTED)
    assert msg == mbox.RegisterWrite(0, 0, (0,), 0xFFFF, 0xFFFF)


def test_reset_capture_checksum_proves_channel_2_was_on_the_wire():
    # ... but Wireshark marked the capture's UDP checksum 0x582d correct, and only the
    # channel-2 (CX) datagram has that checksum. The IP header matches either way.
    src, dst = ("169.254.88.22", 8410), ("255.255.255.255", 7408)
    cx = mbox.RegisterWrite(mbox.CHANNEL_CX, 0, (0,), 0xFFFF, 0xFFFF).encode()
    assert cx == bytes.fromhex("55AA000012010002FFFFFFFF000000010000")
    wire = ethernet_ipv4_udp(src, dst, cx, ident=0x84DC)
    assert wire[24:26] == bytes.fromhex("f3ce") and wire[40:42] == bytes.fromhex("582d")
    printed = ethernet_ipv4_udp(src, dst, RESET_PRINTED, ident=0x84DC)
    assert printed[40:42] != bytes.fromhex("582d")
    # the e-stop capture is consistent as printed: IP 0xf27c, UDP 0x579e, 60 bytes
    estop = ethernet_ipv4_udp(src, dst, ESTOP_CAPTURE, ident=0x862E)
    assert len(estop) == 60
    assert estop[24:26] == bytes.fromhex("f27c") and estop[40:42] == bytes.fromhex("579e")


def test_frame_layout_by_hand():
    # 6-axis absolute frame, every field distinct, built field by field from the 4.2.7 table
    expected = (
        bytes.fromhex("55AA 0000 1301 0001 FFFF FFFF")
        + (7).to_bytes(4, "big")
        + (1234).to_bytes(4, "big")
        + b"".join(v.to_bytes(4, "big", signed=True) for v in (1, -1, 3, 400000, -5, 6))
        + bytes.fromhex("0ABC 1388 2710 0123")
    )
    msg = mbox.MotionFrame(True, 7, 1234, (1, -1, 3, 400000, -5, 6), 0xABC, 5000, 10000, 0x123)
    assert msg.encode() == expected
    assert len(expected) == 52 == mbox.frame_size(6) and mbox.frame_size(3) == 40
    assert mbox.decode(expected) == msg


def test_relative_frame_carries_signed_delta():
    msg = mbox.MotionFrame(False, 1, -20, (0, 0, 0))
    raw = msg.encode()
    assert raw[4:8] == bytes.fromhex("14010000") and raw[16:20] == bytes.fromhex("FFFFFFEC")
    assert mbox.decode(raw).time_ms == -20


def test_replies_and_error_replies():
    frame = mbox.MotionFrame(True, 3, 40, (1, 2, 3))
    for status, code in (
        (mbox.FrameStatus.OK, 0x1302),
        (mbox.FrameStatus.BUFFER_FULL, 0x1303),
        (mbox.FrameStatus.SHORT_FRAME, 0x1304),
    ):
        raw = mbox.MotionFrameReply(status, frame).encode()
        assert int.from_bytes(raw[4:6], "big") == code
        assert raw[8:12] == b"\0\0\0\0"  # replies address the host
        back = mbox.decode(raw)
        assert isinstance(back, mbox.MotionFrameReply) and back.status == status
        assert back.frame.positions == (1, 2, 3)
    err = mbox.RegisterError(0x1103, 1, 0xC1, 3, 7)
    assert err.encode() == bytes.fromhex("55AA000011030001000000000 0C1 0003 0007".replace(" ", ""))
    assert mbox.decode(err.encode()) == err


def test_status_report_layout():
    rep = mbox.StatusReport(0, 0x3E, (1, 2))
    assert rep.encode() == bytes.fromhex(
        "55AA0000100100000000000 0003E000200010002".replace(" ", "")
    )
    assert mbox.decode(rep.encode()) == rep


# -- decoding errors say what is wrong ---------------------------------------------------------
@pytest.mark.parametrize(
    ("data", "words"),
    [
        (b"\x55\xaa\x00", "shorter than the 12-byte header"),
        (bytes.fromhex("1234000012010000FFFFFFFF009000010001"), "confirm code"),
        (bytes.fromhex("33CC000012010000FFFFFFFF009000010001"), "0x55AA"),
        (bytes.fromhex("55AA000112010000FFFFFFFF009000010001"), "pass code"),
        (bytes.fromhex("55AA000099990000FFFFFFFF009000010001"), "unknown MBOX function"),
        (bytes.fromhex("55AA000012010000FFFFFFFF009000020001"), "Count says 2"),
        (bytes.fromhex("55AA000012010007FFFFFFFF009000010001"), "channel 7"),
        (ESTOP_CAPTURE[:-1], "length 17 bytes, expected an even length"),
        (mbox.MotionFrame(True, 0, 0, (1, 2, 3)).encode()[:-2], "length 38 bytes, expected 40"),
        (bytes.fromhex("55AA000013010005FFFFFFFF") + bytes(28), "frame channel 5"),
        (bytes.fromhex("55AA000011010000FFFFFFFF000000010001"), "Extra Data"),
    ],
)
def test_decode_errors_name_the_problem(data, words):
    with pytest.raises(ProtocolError, match=words):
        mbox.decode(data)


# -- round trips of every message type ---------------------------------------------------------
u16 = st.integers(0, 0xFFFF)
u32 = st.integers(0, 0xFFFFFFFF)
i32 = st.integers(-(2**31), 2**31 - 1)
words = st.lists(u16, min_size=1, max_size=40).map(tuple)


@st.composite
def frames(draw):
    n = draw(st.sampled_from([3, 6]))
    absolute = draw(st.booleans())
    return mbox.MotionFrame(
        absolute,
        draw(u32),
        draw(u32 if absolute else i32),
        tuple(draw(st.lists(i32, min_size=n, max_size=n))),
        draw(u16),
        draw(u16),
        draw(u16),
        draw(u16),
        draw(u16),
        draw(u16),
    )


messages = st.one_of(
    st.builds(mbox.RegisterRead, st.sampled_from([0, 1]), u16, st.integers(1, 256), u16, u16),
    st.builds(mbox.RegisterReadReply, st.sampled_from([0, 1]), u16, words, u16, u16),
    st.builds(mbox.RegisterWrite, st.sampled_from([0, 1, 2]), u16, words, u16, u16),
    st.builds(mbox.RegisterWriteReply, st.sampled_from([0, 1, 2]), u16, words, u16, u16),
    st.builds(mbox.RegisterError, st.sampled_from([0x1103, 0x1203]), u16, u16, u16, u16, u16, u16),
    st.builds(mbox.StatusReport, st.just(0), u16, words, u16, u16),
    frames(),
    st.builds(
        mbox.MotionFrameReply,
        st.sampled_from(list(mbox.FrameStatus)),
        frames().map(
            lambda f: mbox.MotionFrame(
                f.absolute,
                f.line,
                f.time_ms,
                f.positions,
                f.base_dout,
                f.dac1,
                f.dac2,
                f.ext_dout,
                0,
                0,
            )
        ),
    ),
)


@given(messages)
def test_round_trip_every_message_type(msg):
    raw = msg.encode()
    assert len(raw) == msg.size
    assert mbox.decode(raw) == msg
    assert mbox.decode(raw).encode() == raw


# -- fuzzing: nothing but ProtocolError --------------------------------------------------------
_PREFIXES = [
    bytes.fromhex(h)
    for h in (
        "55AA00001001",
        "55AA00001101",
        "55AA00001102",
        "55AA00001103",
        "55AA00001201",
        "55AA00001202",
        "55AA00001203",
        "55AA00001301",
        "55AA00001302",
        "55AA00001303",
        "55AA00001304",
        "55AA00001401",
        "55AA00001402",
        "55AA00001403",
        "55AA00001404",
    )
]


def test_random_bytes_raise_only_protocol_error():
    rng = np.random.default_rng(1)
    blob = os.urandom(100_000 * 64)
    lengths = rng.integers(0, 64, size=100_000)
    decoded = 0
    for i, n in enumerate(lengths):
        data = blob[i * 64 : i * 64 + int(n)]
        if i % 2:  # half of them with a valid confirm / pass / function prefix
            data = _PREFIXES[i % len(_PREFIXES)] + data
        try:
            mbox.decode(data)
            decoded += 1
        except ProtocolError:
            pass
    assert decoded > 0  # some random tails do decode (e.g. register messages)


@given(messages, st.data())
def test_mutations_near_valid_messages_raise_only_protocol_error(msg, data):
    raw = bytearray(msg.encode())
    action = data.draw(st.sampled_from(["truncate", "extend", "flip", "splice"]))
    if action == "truncate":
        raw = raw[: data.draw(st.integers(0, len(raw) - 1))]
    elif action == "extend":
        raw += data.draw(st.binary(min_size=1, max_size=8))
    elif action == "flip":
        i = data.draw(st.integers(0, len(raw) - 1))
        raw[i] ^= data.draw(st.integers(1, 255))
    else:
        i = data.draw(st.integers(0, len(raw)))
        raw[i:i] = data.draw(st.binary(min_size=1, max_size=4))
    try:
        out = mbox.decode(bytes(raw))
    except ProtocolError:
        return
    assert mbox.decode(out.encode()) == out
    # whatever decodes re-encodes to the same bytes, except what the decoder normalises:
    # a read request's zero padding and the Who fields of replies (don't care, 4.2.3)
    if not isinstance(out, mbox.RegisterRead | mbox.MotionFrameReply):
        assert out.encode() == bytes(raw)


# -- the frame encoder (the pipeline's contract) -----------------------------------------------
def test_encoder_numbers_frames_and_stamps_absolute_time():
    ctrl = load_controller("mbox6")
    enc = ctrl.frame_encoder(absolute_time=True)
    out = [mbox.decode(enc.encode(10.0 + 0.02 * k, [k] * 6)[0]) for k in range(5)]
    assert [m.line for m in out] == [0, 1, 2, 3, 4]
    assert [m.time_ms for m in out] == [0, 20, 40, 60, 80]
    assert all(m.absolute and m.n_axes == 6 for m in out)


def test_encoder_relative_time_does_not_drift():
    ctrl = load_controller("mbox3")
    enc = ctrl.frame_encoder(absolute_time=False, t0_s=0.0)
    times = [k / 60.0 for k in range(1, 601)]  # 60 Hz: 16.67 ms steps
    deltas = [mbox.decode(enc.encode(t, [0, 0, 0])[0]).time_ms for t in times]
    assert set(deltas) <= {16, 17}
    assert sum(deltas) == round(times[-1] * 1000)  # = 10000 ms exactly


def test_encoder_carries_outputs_and_dacs():
    enc = load_controller("mbox6").frame_encoder()
    msg = mbox.decode(enc.encode(0.0, [0] * 6, dout=0xABC123, dacs=(10000, 1))[0])
    assert (msg.base_dout, msg.ext_dout, msg.dac1, msg.dac2) == (0x123, 0xABC, 10000, 1)


@pytest.mark.parametrize(
    "bad",
    [
        [math.nan] * 6,
        [0, 0, 0, math.inf, 0, 0],
        [0.5] * 6,
        [2**31] * 6,
        [-(2**31) - 1] * 6,
        ["1"] * 6,
        [0] * 5,
        [0] * 7,
    ],
)
def test_encoder_refuses_bad_positions_and_counts_nothing(bad):
    enc = load_controller("mbox6").frame_encoder()
    with pytest.raises(ProtocolError):
        enc.encode(0.0, bad)
    assert mbox.decode(enc.encode(0.0, [1] * 6)[0]).line == 0


def test_encoder_accepts_numpy_and_integral_floats():
    enc = load_controller("mbox6").frame_encoder()
    a = enc.encode(0.0, np.arange(6, dtype=np.int64), np.int64(3), (np.int32(1), np.uint16(2)))[0]
    assert mbox.decode(a).base_dout == 3 and mbox.decode(a).dac2 == 2
    b = enc.encode(0.01, np.arange(6, dtype=float))[0]
    assert mbox.decode(a).positions == mbox.decode(b).positions == (0, 1, 2, 3, 4, 5)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"dout": 1 << 24}, "dout"),
        ({"dout": -1}, "dout"),
        ({"dacs": (10001, 0)}, "dacs"),
        ({"dacs": (0, -1)}, "dacs"),
        ({"dacs": (0,)}, "2 DACs"),
    ],
)
def test_encoder_refuses_bad_outputs(kwargs, words):
    with pytest.raises(ProtocolError, match=words):
        load_controller("mbox6").frame_encoder().encode(0.0, [0] * 6, **kwargs)


@pytest.mark.parametrize("t", [math.nan, math.inf, -1.0])
def test_encoder_refuses_bad_times(t):
    enc = load_controller("mbox6").frame_encoder(t0_s=0.0)
    with pytest.raises(ProtocolError):
        enc.encode(t, [0] * 6)


def test_encoder_refuses_time_going_back():
    enc = load_controller("mbox6").frame_encoder()
    enc.encode(1.0, [0] * 6)
    enc.encode(1.1, [0] * 6)
    with pytest.raises(ProtocolError, match="backwards"):
        enc.encode(1.05, [0] * 6)
    with pytest.raises(ProtocolError, match="from the run origin"):
        enc.encode(0.5, [0] * 6)


def test_encoder_refuses_positions_outside_the_stroke():
    ctrl = load_controller("mbox6").with_parameters(Fn0C0=3000)  # 300 mm x 2000 pulses/mm
    assert ctrl.stroke_pulses == (0, 600_000)
    enc = ctrl.frame_encoder()
    enc.encode(0.0, [600_000] * 6)
    with pytest.raises(LimitError, match="stroke"):
        enc.encode(0.01, [600_001] + [0] * 5)
    with pytest.raises(LimitError):
        enc.encode(0.02, [-1] + [0] * 5)


# -- the bundled configs -----------------------------------------------------------------------
def test_bundled_configs_carry_factory_defaults():
    c6, c3 = load_controller("mbox6"), load_controller("mbox3")
    assert (c6.kind, c6.n_axes, c3.n_axes) == ("mbox", 6, 3)
    p = c6.parameters
    assert (p["Fn0C0"], p["Fn0C1"], p["Fn0C2"], p["Fn012"], p["Fn01C"]) == (0, 2000, 50, 1200, 1)
    assert (p["Fn013"], p["Fn014"], p["Fn015"], p["Fn016"]) == (100, 10, 30, 10)
    assert c6.controller_address == ("192.168.15.201", 7408)
    assert c6.host_address == ("192.168.15.101", 8410)
    assert c6.default_target.startswith("udp://127.0.0.1:")
    assert c6.max_frame_rate_hz is None
    # 3000 rpm x 5 mm/turn x 2000 pulses/mm / 60 s
    assert c6.max_speed_pulses_s == (500_000.0,) * 6
    with pytest.raises(TypeError):
        p["Fn0C1"] = 1  # type: ignore[index]


def test_config_rejects_unknown_and_out_of_range(tmp_path):
    base = 'kind = "mbox"\naxes = 6\n'
    cases = {
        "unknown key": (base + "colour = 1\n", "colour"),
        "bad axes": ('kind = "mbox"\naxes = 4\n', "axes"),
        "unknown Fn": (base + "[parameters]\nFn0FE = 1\n", "Fn0FE"),
        "range": (base + "[parameters]\nFn0C1 = 0\n", r"Fn0C1 = 0 .*\[1, 30000\]"),
        "target": (base + 'default_target = "tcp://x:1"\n', "default_target"),
    }
    for name, (text, words) in cases.items():
        path = tmp_path / f"{name.replace(' ', '_')}.toml"
        path.write_text(text)
        with pytest.raises(ConfigError, match=words):
            load_controller(path)


def test_frame_struct_matches_the_table_widths():
    # Line L, Time L, n x L, BaseDout 2, DAC1/2 2 + 2, ExtDout 2 (4.2.6-4.2.9)
    assert struct.calcsize(">IIiiiHHHH") == 28 and mbox.frame_size(3) == 12 + 28
