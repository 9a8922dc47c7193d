"""EasySmc 2300 wire formats: golden bytes from the manual, round-trips, random bytes."""

from __future__ import annotations

import functools
import random

import pytest
from hypothesis import given
from hypothesis import strategies as st

from motioncue import ProtocolError
from motioncue.output.easysmc import (
    COMMANDS,
    MANUAL_DECISIONS,
    Command,
    ErrorCode,
    ErrorReply,
    ExecStatus,
    ReadReply,
    Start,
    UsbReadReply,
    UsbReadRequest,
    UsbWriteReply,
    WordKind,
    WriteReply,
    checksum,
    decode_command,
    decode_reply,
    decode_usb_read_reply,
    decode_usb_write,
    decode_usb_write_reply,
    encode_command,
    encode_reply,
    encode_usb_read_reply,
    encode_usb_write,
    encode_usb_write_reply,
    serial_frame_size,
    signed_from_word,
    split_serial_frames,
    usb_read_request,
    word_from_signed,
)


def manual_frame(addr: str, cmd: str, data: list[str], start: str) -> bytes:
    """A frame built the way the manual describes it, with an independent checksum."""
    body = (addr + cmd + "".join(data) + start).encode("ascii") + b"\x03"
    total = 0
    for b in body:
        total += b
    return b"\x02" + body + ("%02X" % (total % 256)).encode("ascii")


# -- golden: serial ------------------------------------------------------------------------


def test_checksum_example_5_1_1_1() -> None:
    # addr 00, cmd 01 (X home speed), data 00007D0 (2000 Hz), start 0 -> 0x25F -> "5F"
    body = b"00" + b"01" + b"00007D0" + b"0" + b"\x03"
    assert sum(body) == 0x25F
    assert checksum(body) == b"5F" == bytes((0x35, 0x46))
    golden = b"\x02" + body + b"5F"
    cmd = Command(0x01, (2000,), Start.IMMEDIATE, 0)
    assert encode_command(cmd) == golden
    assert decode_command(golden) == cmd


APPENDIX_PROGRAM = [
    # (manual text of appendix 2, the Command it means)
    (("00", "19", ["3000000"], "0"), Command(0x19, (0x3000000,), Start.IMMEDIATE, 0)),
    (("00", "41", ["0000001"], "0"), Command(0x41, (1,), Start.IMMEDIATE, 0)),
    (("00", "42", ["0000002"], "0"), Command(0x42, (2,), Start.IMMEDIATE, 0)),
    (("00", "24", ["0000000"], "0"), Command(0x24, (0,), Start.IMMEDIATE, 0)),
    (("00", "25", ["0000000"], "0"), Command(0x25, (0,), Start.IMMEDIATE, 0)),
    (("00", "02", ["00007D0", "00007D0", "00007D0"], "0"), Command(0x02, (2000,) * 3)),
    (("00", "03", ["0004E20", "0004E20", "0004E20"], "0"), Command(0x03, (20000,) * 3)),
    (("00", "44", ["0002710"], "0"), Command.move(0x44, [10000], Start.IMMEDIATE)),
]


@pytest.mark.parametrize(("text", "cmd"), APPENDIX_PROGRAM)
def test_programming_example_of_the_appendix(text: tuple, cmd: Command) -> None:
    golden = manual_frame(*text)
    assert encode_command(cmd) == golden
    assert decode_command(golden) == cmd


def test_worked_examples_of_chapter_5() -> None:
    # 5.5.1: XY linear, DAT1 = 1000190 (X -400), DAT2 = 000012C (Y +300)
    g = manual_frame("00", "51", ["1000190", "000012C"], "4")
    c = decode_command(g)
    assert c.fields() == {"x_pulses": -400, "y_pulses": 300}
    assert encode_command(Command.move(0x51, [-400, 300])) == g
    # 5.1.8.1: wait 1000 ms = (31H 30H 30H 30H 33H 45H 38H)
    g = manual_frame("00", "19", ["10003E8"], "4")
    assert decode_command(g).describe().endswith("[wait 1000 ms] start 4")
    # 5.8.1.1: counter 1 = 100 -> 9010064
    assert (
        "set counter 1 = 100"
        in decode_command(manual_frame("00", "19", ["9010064"], "0")).describe()
    )
    # 5.1.8.4 clear buffer, 5.1.7 brake all, start condition 8
    assert decode_command(manual_frame("00", "19", ["4000000"], "8")).start == Start.OUT_OF_BAND
    assert decode_command(manual_frame("00", "18", ["0000000"], "8")).words == (0,)
    # 5.6.1 arc: angle 30.67 deg = 3067 = BFB
    arc = decode_command(manual_frame("00", "61", ["1000190", "000012C", "0000BFB"], "4"))
    assert arc.words[2] == 3067


def test_error_replies_of_chapter_5() -> None:
    for code, digit in (
        (ErrorCode.NO_SUCH_COMMAND, "1"),
        (ErrorCode.MANUAL_MODE, "2"),
        (ErrorCode.BUFFER_FULL, "3"),
        (ErrorCode.CHECKSUM, "4"),
    ):
        g = manual_frame("00", "99", ["000000" + digit], "0")
        assert decode_reply(g) == ErrorReply(code, 0, 0)
        assert encode_reply(ErrorReply(code, 0, 0)) == g
    g = manual_frame("01", "57", [], "4")  # write reply: STX addr cmd start ETX checksum
    assert decode_reply(g) == WriteReply(0x57, 4, 1)
    assert len(g) == serial_frame_size(0) == 9


def test_exec_status_layout() -> None:
    st_ = ExecStatus(7, 0x123, 0x130, (1, 2, 4, 8))
    reply = ReadReply(0x38, st_.words())
    assert reply.words[0] == 0x7000123
    assert f"{reply.words[2]:07X}" == "0124800"  # digits 2..5 = X Y Z U faults (5.3.8.0)
    assert ExecStatus.from_reply(decode_reply(encode_reply(reply))) == st_  # type: ignore[arg-type]


# -- golden: USB ----------------------------------------------------------------------------


def test_usb_example_x_plus_1000() -> None:
    # manual 6.2.1 example 1: psend = 01 00 44 00 00 03 E8 ... [15] = 00
    golden = bytes([0x01, 0x00, 0x44, 0x00, 0x00, 0x03, 0xE8] + [0] * 8 + [0x00])
    cmd = Command.move(0x44, [1000], Start.IMMEDIATE)
    assert encode_usb_write(cmd) == golden
    assert decode_usb_write(golden) == cmd


def test_usb_words_match_serial_words() -> None:
    # 7.1.8.6: 6000001 -> 06 00 00 01 ; 7.3.5: X -1000 -> 01 00 03 E8 ; 7.4.1 XY -400/+300
    usb = encode_usb_write(Command(0x19, (0x6000001,)))
    assert usb[3:7] == bytes([0x06, 0x00, 0x00, 0x01])
    assert encode_usb_write(Command.move(0x44, [-1000]))[3:7] == bytes([1, 0, 3, 0xE8])
    xy = encode_usb_write(Command.move(0x51, [-400, 300]))
    assert xy[3:11] == bytes([1, 0, 1, 0x90, 0, 0, 1, 0x2C])
    # 7.5.1 arc angle DAT3 = 00 00 0B B8 (30.00 deg)
    arc = Command(0x61, (word_from_signed(-400), 300, 3000))
    assert encode_usb_write(arc)[11:15] == bytes([0, 0, 0x0B, 0xB8])


def test_usb_replies() -> None:
    # 6.2.4.2: addr, cmd, error, busy, executing (4), X, Y, Z (sign byte + 3 bytes)
    raw = bytes([0, 0x57, 0, 0b1010, 0, 0, 0, 42, 1, 0, 3, 0xE8, 0, 0, 0, 5, 0, 0, 0, 0])
    r = decode_usb_write_reply(raw)
    assert r == UsbWriteReply(0x57, 0, 0b1010, 0, 42, (-1000, 5, 0), 0)
    assert encode_usb_write_reply(r) == raw
    err = bytes([0, 0x99, 3]) + bytes(17)
    assert decode_usb_write_reply(err).error == 3
    # 6.2.4.3: addr, cmd, DAT1..3, start, number of valid DATs
    raw = bytes([0, 0x34, 0, 0, 0x07, 0xD0] + [0] * 8 + [0, 1])
    rr = decode_usb_read_reply(raw)
    assert rr == UsbReadReply(0x34, (2000, 0, 0), 0, 1, 0)
    assert encode_usb_read_reply(rr) == raw


def test_usb_read_request_serial_equivalent() -> None:
    assert UsbReadRequest(0x34, 0x01).serial_word() == 0x0000001  # 6.2.1 example 2
    assert UsbReadRequest(0x38, 0x01).serial_word() == 0x1000000  # 5.3.8.1 vs 8.8.1
    assert UsbReadRequest(0x38, 0x03, 2).serial_word() == 0x3020000  # counter 2
    assert UsbReadRequest(0x31, 0x06).serial_word() == 0x42  # decision on 5.3.1.6
    with pytest.raises(ProtocolError):
        UsbReadRequest(0x57, 1)


def test_decisions_are_documented() -> None:
    topics = {d.topic for d in MANUAL_DECISIONS}
    assert {"USB start code byte", "brake code 7", "small-segment mode word"} <= topics


# -- decoder errors ----------------------------------------------------------------------------


def test_decoders_name_what_is_wrong() -> None:
    good = encode_command(Command(0x01, (2000,)))
    bad_sum = good[:-2] + b"00"
    with pytest.raises(ProtocolError, match="checksum"):
        decode_command(bad_sum)
    with pytest.raises(ProtocolError, match="bytes"):
        decode_command(good[:-1])
    with pytest.raises(ProtocolError, match="unknown command"):
        decode_command(manual_frame("00", "0A", ["0000000"], "0"))
    with pytest.raises(ProtocolError, match="takes 3 data words"):
        decode_command(manual_frame("00", "57", ["0000001"], "4"))
    with pytest.raises(ProtocolError, match="sign"):
        decode_command(manual_frame("00", "44", ["2000001"], "4"))
    with pytest.raises(ProtocolError, match="hex digit"):
        decode_command(manual_frame("00", "01", ["00007d0"], "0"))
    with pytest.raises(ProtocolError, match="start condition"):
        decode_command(manual_frame("00", "01", ["00007D0"], "9"))
    with pytest.raises(ProtocolError, match="brake code"):
        decode_command(manual_frame("00", "18", ["0000011"], "8"))
    with pytest.raises(ProtocolError, match="15 bytes, expected 16"):
        decode_usb_write(bytes(15))
    with pytest.raises(ProtocolError, match="one hex digit"):
        decode_usb_write(bytes([1, 0, 0x44, 0x10, 0, 0, 0] + [0] * 9))
    with pytest.raises(ProtocolError, match="range"):
        word_from_signed(1 << 24)


def test_split_frames_counts_noise() -> None:
    a = encode_command(Command(0x01, (2000,)))
    b = encode_command(Command.move(0x57, [1, -2, 3]))
    frames, rest, skipped = split_serial_frames(b"xy" + a + b + b[:5])
    assert frames == [a, b]
    assert rest == b[:5]
    assert skipped == 2


# -- hypothesis round-trips ---------------------------------------------------------------------

_VALID_CODE_WORDS = {
    0x19: [
        0x1000000 | 50,
        0x3000000,
        0x3000001,
        0x3000002,
        0x4000000,
        0x5000000,
        0x6000001,
        0x6000038,
        0x7000018,
        0x8000001,
        0x9010064,
        0xA020001,
        0xB000000,
        0xC00000F,
        0xD000000,
        0xE010203,
    ],
    0x18: [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 0xA, 0xB, 0xC, 0xD, 0xE, 0xF, 0x12, 0x13, 0x19, 0x1D],
    0x17: [1, 2],
    0x2A: [0],
    0x2B: [0],
    0x2C: [0],
    0x2D: [0],
    0x41: list(range(1, 8)),
    0x42: list(range(1, 8)),
    0x43: list(range(1, 8)),
    0x47: list(range(1, 8)),
}


@st.composite
def commands(draw: st.DrawFn) -> Command:
    code = draw(st.sampled_from(sorted(COMMANDS)))
    spec = COMMANDS[code]
    words = []
    for _, kind in spec.words:
        if kind in (WordKind.SIGNED, WordKind.ANGLE):
            words.append((draw(st.integers(0, 1)) << 24) | draw(st.integers(0, 0xFFFFFF)))
        elif kind is WordKind.CODE and code in _VALID_CODE_WORDS:
            words.append(draw(st.sampled_from(_VALID_CODE_WORDS[code])))
        elif kind is WordKind.CODE and code == 0x16:
            words.append((draw(st.integers(1, 9)) << 24) | draw(st.integers(0, 0xFFFFFF)))
        else:
            words.append(draw(st.integers(0, 0x0FFFFFFF)))
    return Command(code, tuple(words), Start(draw(st.integers(0, 8))), draw(st.integers(0, 255)))


@given(commands())
def test_serial_command_round_trip(cmd: Command) -> None:
    frame = encode_command(cmd)
    assert len(frame) == serial_frame_size(cmd.spec.n_words)
    assert decode_command(frame) == cmd
    assert cmd.describe().startswith(f"addr {cmd.addr:02X} cmd {cmd.code:02X}")


@given(commands())
def test_usb_command_round_trip(cmd: Command) -> None:
    if cmd.spec.kind == "query":
        with pytest.raises(ProtocolError, match="query"):
            decode_usb_write(encode_usb_write(cmd))
        return
    data = encode_usb_write(cmd)
    assert len(data) == 16
    assert decode_usb_write(data) == cmd


_codes = st.sampled_from(sorted(COMMANDS))
_word = st.integers(0, 0x0FFFFFFF)
_signed = st.integers(-0xFFFFFF, 0xFFFFFF)


@given(
    st.one_of(
        st.builds(WriteReply, _codes, st.integers(0, 8), st.integers(0, 255)),
        st.builds(
            ReadReply,
            _codes,
            st.lists(_word, min_size=1, max_size=3).map(tuple),
            st.integers(0, 8),
            st.integers(0, 255),
        ),
        st.builds(
            ErrorReply, st.sampled_from(list(ErrorCode)), st.integers(0, 8), st.integers(0, 255)
        ),
    )
)
def test_serial_reply_round_trip(reply: object) -> None:
    assert decode_reply(encode_reply(reply)) == reply  # type: ignore[arg-type]


@given(
    st.builds(
        UsbWriteReply,
        st.integers(0, 255).filter(lambda c: c != 0x99),
        st.just(0),
        st.integers(0, 15),
        st.integers(0, 7),
        st.integers(0, 0xFFFFFF),
        st.tuples(_signed, _signed, _signed),
        st.integers(0, 255),
    ),
    st.builds(
        UsbReadReply,
        _codes,
        st.tuples(_word, _word, _word),
        st.integers(0, 8),
        st.integers(0, 3),
        st.integers(0, 255),
    ),
)
def test_usb_reply_round_trip(wr: UsbWriteReply, rr: UsbReadReply) -> None:
    assert decode_usb_write_reply(encode_usb_write_reply(wr)) == wr
    assert decode_usb_read_reply(encode_usb_read_reply(rr)) == rr


@given(_signed)
def test_sign_magnitude_round_trip(v: int) -> None:
    w = word_from_signed(v)
    assert signed_from_word(w) == v
    assert (w >> 24) == (1 if v < 0 else 0)


# -- random bytes -----------------------------------------------------------------------------

_DECODERS = [
    decode_command,
    decode_reply,
    decode_usb_write,
    decode_usb_write_reply,
    decode_usb_read_reply,
]


@functools.cache
def _random_frames() -> tuple[bytes, ...]:
    """The 100 000 inputs every decoder is fed: the same for each (one seed), so made once
    for the module (making them costs about 0.35 s of CPU, decoding them 0.06-0.14 s)."""
    rng = random.Random(20260121)
    alphabet = b"0123456789ABCDEF\x02\x03Gg-"
    sizes = [9, 16, 20, 23, 30]
    frames = []
    for i in range(100_000):
        kind = i % 4
        if kind == 0:  # arbitrary bytes of arbitrary length
            data = rng.randbytes(rng.randrange(0, 40))
        elif kind == 1:  # right sizes, arbitrary or small bytes (reaches the USB checks)
            size = rng.choice(sizes)
            if i % 8 == 1:
                data = rng.randbytes(size)
            else:
                data = bytes(
                    [1, 0, rng.randrange(256)] + [rng.randrange(3) for _ in range(size - 3)]
                )
        else:  # plausible serial frames with a valid checksum (reaches the payload checks)
            n = rng.choice((0, 7, 14, 21, rng.randrange(0, 25)))
            body = bytes(rng.choice(alphabet) for _ in range(4 + n)) + b"0\x03"
            if kind == 3:
                body = body[:-2] + bytes((rng.randrange(0x2F, 0x3B), 3))
            data = b"\x02" + body + checksum(body)
        frames.append(data)
    return tuple(frames)


@pytest.mark.parametrize("decoder", _DECODERS, ids=lambda d: d.__name__)
def test_random_bytes_raise_only_protocol_error(decoder: object) -> None:
    frames = _random_frames()
    assert len(frames) == 100_000
    ok = 0
    for data in frames:
        try:
            decoder(data)  # type: ignore[operator]
            ok += 1
        except ProtocolError:
            pass
    # some random frames must decode, or the fuzzing never reached the payload checks
    assert ok > 0


@given(
    st.sampled_from([0x31, 0x32, 0x33, 0x34, 0x35, 0x36, 0x37, 0x38]),
    st.integers(0, 255),
    st.integers(1, 2),
)
def test_usb_read_request_round_trip(code: int, rdat1: int, counter: int) -> None:
    if code == 0x38:
        rdat1 %= 16
    if code == 0x31 and rdat1 == 0x42:
        rdat1 = 0x41  # 0x42 is the serial spelling of USB item 6 (decision)
    req = UsbReadRequest(code, rdat1, counter if (code, rdat1) == (0x38, 3) else 0)
    query = Command(code, (req.serial_word(),))
    assert usb_read_request(query) == req


@given(st.lists(st.one_of(commands(), st.binary(max_size=40)), max_size=40), st.randoms())
def test_emulator_answers_anything_without_crashing(items: list, rnd: random.Random) -> None:
    """Any mix of valid commands (all codes, all words) and noise: every answer decodes."""
    from motioncue.output.easysmc import EasySmcEmulator

    emu = EasySmcEmulator((0, 1), clock=lambda: 0.0)
    t = 0.0
    for item in items:
        t += rnd.uniform(0.0, 0.5)
        data = encode_command(item) if isinstance(item, Command) else item
        out = emu.feed(data, t)
        frames, rest, skipped = split_serial_frames(out)
        assert rest == b"" and skipped == 0
        for f in frames:
            decode_reply(f)
        if isinstance(item, Command) and item.addr in (0, 1) and not emu._buffer:
            assert len(frames) == 1
    emu.sync()
    assert isinstance(emu.trace, list)
