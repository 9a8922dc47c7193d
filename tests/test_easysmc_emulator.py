"""EasySmc emulator (manual state machine and replies), send/inspect hooks, USB adapter
against a fake DLL, and the end-to-end stream over a real pseudo-terminal with pyserial."""

from __future__ import annotations

import ctypes
import itertools
import math

import pytest

from motioncue import ProtocolError, TransportError
from motioncue.output._controllers import load_controller
from motioncue.output._transport_serial import SerialTransport, open_serial
from motioncue.output.easysmc import (
    BUFFER_DEPTH,
    Command,
    ControllerModel,
    EasySmcEmulator,
    EasySmcLink,
    EasySmcStreamer,
    ErrorCode,
    ErrorReply,
    ExecStatus,
    ReadReply,
    Start,
    UsbCommandLink,
    UsbDllLink,
    UsbReadReply,
    UsbReadRequest,
    UsbWriteReply,
    WriteReply,
    decode_reply,
    decode_usb_write,
    encode_command,
    encode_usb_read_reply,
    encode_usb_write_reply,
    inspect_bytes,
    move_duration_s,
    run_send,
    send_commands,
    signed_from_word,
    word_from_signed,
)

SEQ = Start.SEQUENCE
OOB = Start.OUT_OF_BAND


def ask(emu: EasySmcEmulator, cmd: Command, t: float):  # type: ignore[no-untyped-def]
    out = emu.feed(encode_command(cmd), now_s=t)
    return decode_reply(out)


def homed_emulator() -> EasySmcEmulator:
    emu = EasySmcEmulator((0,), clock=lambda: 0.0)
    for code in (0x41, 0x42, 0x43, 0x47):
        assert isinstance(ask(emu, Command(code, (2,), SEQ), 0.0), WriteReply)
    return emu


def position(emu: EasySmcEmulator, t: float) -> list[int]:
    r = ask(emu, Command(0x31, (4,), Start.IMMEDIATE), t)
    assert isinstance(r, ReadReply)
    return [signed_from_word(w) for w in r.words]


def status(emu: EasySmcEmulator, t: float) -> ExecStatus:
    r = ask(emu, Command(0x38, (0,), Start.IMMEDIATE), t)
    assert isinstance(r, ReadReply)
    return ExecStatus.from_reply(r)


# -- replies as the manual says -------------------------------------------------------------


def test_error_replies() -> None:
    emu = EasySmcEmulator((0,), clock=lambda: 0.0)
    good = encode_command(Command(0x01, (2000,)))
    assert decode_reply(emu.feed(good[:-2] + b"00", 0.0)) == ErrorReply(ErrorCode.CHECKSUM)
    body = b"000A0000000" + b"0\x03"
    unknown = b"\x02" + body + (b"%02X" % (sum(body) & 0xFF))
    assert decode_reply(emu.feed(unknown, 0.0)) == ErrorReply(ErrorCode.NO_SUCH_COMMAND)
    emu.set_manual(True)
    assert ask(emu, Command(0x01, (2000,)), 0.0) == ErrorReply(ErrorCode.MANUAL_MODE)
    r = ask(emu, Command(0x37, (0,)), 0.0)  # queries still answered: 0 = manual
    assert isinstance(r, ReadReply) and r.words == (0,)
    emu.set_manual(False)
    assert ask(emu, Command(0x19, (0x5000000,), OOB), 0.0) == WriteReply(0x19, 8, 0)  # loop
    assert emu.stats["checksum_errors"] == 1 and emu.stats["unknown"] == 1
    # another address on the bus: silence
    assert emu.feed(encode_command(Command(0x01, (2000,), addr=2)), 0.0) == b""


def test_buffer_full_after_63_commands() -> None:
    emu = homed_emulator()  # 4 homing commands (instant: at the home switch already)
    for i in range(BUFFER_DEPTH):
        r = ask(emu, Command(0x19, (0x1000000 | 1000,), SEQ), 0.001)
        assert isinstance(r, WriteReply), i
    assert ask(emu, Command(0x19, (0x1000000 | 1000,), SEQ), 0.001) == ErrorReply(
        ErrorCode.BUFFER_FULL, 4
    )
    st = status(emu, 0.001)
    assert st.received == 4 + BUFFER_DEPTH and st.executing == 5
    # after one wait of 1 s has run there is room for one more
    assert isinstance(ask(emu, Command(0x19, (0x1000000 | 1000,), SEQ), 1.0011), WriteReply)
    assert emu.models[0].stats["buffer_full"] == 1


def test_queries_reply_state_and_parameters() -> None:
    emu = homed_emulator()
    ask(emu, Command(0xA3, (1000, 3000, 2000), SEQ), 0.0)
    r = ask(emu, Command(0x34, (0xA,)), 0.0)
    assert isinstance(r, ReadReply) and r.words == (1000, 3000, 2000)
    ask(emu, Command(0x27, (word_from_signed(-500),), SEQ), 0.0)
    r = ask(emu, Command(0x37, (0xB,)), 0.0)
    assert isinstance(r, ReadReply) and signed_from_word(r.words[0]) == -500
    assert ask(emu, Command(0x31, (0x77,)), 0.0) == ErrorReply(ErrorCode.NO_SUCH_COMMAND)
    ask(emu, Command(0x19, (0x9010064,), SEQ), 0.0)  # counter 1 = 100 (5.8.1.1)
    ask(emu, Command(0x19, (0xA010001,), SEQ), 0.0)  # counter 1 - 1
    r = ask(emu, Command(0x38, (0x3010000,)), 0.0)
    assert isinstance(r, ReadReply) and r.words == (0x3010063,)


def test_move_timing_follows_feed_and_accelerations() -> None:
    emu = homed_emulator()
    ask(emu, Command(0xA3, (20000, 5000, 20000), SEQ), 0.0)
    ask(emu, Command.move(0x57, [3000, -1500, 10]), 0.0)
    duration = move_duration_s(3000, 5000, 2000, 20000, 20000)
    assert position(emu, duration / 2)[0] not in (0, 3000)
    st = status(emu, duration / 2)
    assert st.executing == st.received == 6
    assert ask(emu, Command(0x31, (3,)), duration / 2) == ReadReply(0x31, (0x0111,))  # X Y Z busy
    assert position(emu, duration + 1e-6) == [3000, -1500, 10]
    entry = emu.models[0].trace[-1]
    assert entry.t_s == pytest.approx(duration) and entry.positions == (3000, -1500, 10, 0)
    assert emu.violations == []


def test_estop_freezes_and_release_resumes() -> None:
    emu = homed_emulator()
    ask(emu, Command(0xA3, (20000, 1000, 20000), SEQ), 0.0)
    ask(emu, Command.move(0x57, [1000, 0, 0]), 0.0)  # 1 s at 1000 Hz
    ask(emu, Command.move(0x57, [-200, 0, 0]), 0.0)
    assert ask(emu, Command(0x18, (0,), OOB), 0.3) == WriteReply(0x18, 8, 0)
    frozen = position(emu, 0.3)
    assert frozen[0] == pytest.approx(300, abs=1)
    assert position(emu, 5.0) == frozen  # nothing moves while braked
    assert status(emu, 5.0).state == 7  # e-stop state digit (8.8.0)
    ask(emu, Command(0x18, (1,), OOB), 5.0)  # release: the rest of the buffer continues
    assert position(emu, 5.0 + 0.7 + 0.2 + 1e-3) == [800, 0, 0]
    assert status(emu, 7.0).state == 0


def test_clear_buffer_stops_and_drops_the_queue() -> None:
    emu = homed_emulator()
    ask(emu, Command(0xA3, (20000, 1000, 20000), SEQ), 0.0)
    ask(emu, Command.move(0x57, [1000, 0, 0]), 0.0)
    ask(emu, Command.move(0x57, [1000, 0, 0]), 0.0)
    ask(emu, Command(0x19, (0x4000000,), OOB), 0.5)
    stopped = position(emu, 0.5)
    assert position(emu, 10.0) == stopped and abs(stopped[0] - 500) <= 1
    ask(emu, Command.move(0x57, [10, 0, 0]), 10.0)  # new moves start from where it stopped
    assert position(emu, 11.0) == [stopped[0] + 10, 0, 0]


def test_violations_are_flagged() -> None:
    emu = EasySmcEmulator((0,), clock=lambda: 0.0)
    ask(emu, Command.move(0x57, [10, 0, 0]), 0.0)  # never homed
    ask(emu, Command(0x21, (100,), SEQ), 0.0)
    ask(emu, Command.move(0x44, [500]), 0.0)  # beyond the X positive soft limit
    ask(emu, Command.move(0x5B, [1, 1]), 0.0)
    ask(emu, Command.move(0x57, [0, 0, 1]), 0.0)  # 5B without its 5C
    v = " | ".join(str(x) for x in emu.violations)
    assert "before homing" in v and "soft limits" in v and "5B" in v
    kinds = {(x.kind, x.axis) for x in emu.violations}
    assert {("homing", "X"), ("soft-limit", "X"), ("pairing", None)} <= kinds


def test_controller_model_is_usable_alone() -> None:
    m = ControllerModel(1)
    r = m.handle(Command(0x38, (0x1000000,), addr=1), 0.0)
    assert r == ReadReply(0x38, (0,), 0, 1)


# -- send / inspect hooks ------------------------------------------------------------------


class EmulatorLink:
    """A byte link straight into an emulator (no pty)."""

    def __init__(self, emu: EasySmcEmulator) -> None:
        self.emu = emu
        self.pending = b""
        self.sent: list[bytes] = []

    def send(self, data: bytes) -> None:
        self.sent.append(data)
        self.pending += self.emu.feed(data)

    def recv(self, timeout_s: float) -> bytes | None:
        data, self.pending = self.pending, b""
        return data or None


def test_send_words() -> None:
    ctrl = load_controller("easysmc")
    assert send_commands(ctrl, ["estop", "on"]) == [Command(0x18, (0,), OOB)]
    assert send_commands(ctrl, ["estop", "off"]) == [Command(0x18, (1,), OOB)]
    raw = send_commands(ctrl, ["raw", "44", "00003E8", "--start", "4"])
    assert raw == [Command(0x44, (1000,), SEQ)]
    outs = send_commands(ctrl, ["outputs", "0x3"])
    assert [c.words[0] for c in outs[:3]] == [0xD000000, 0xD000001, 0xC000002]
    reset = send_commands(ctrl, ["reset"])
    assert [c.words[0] for c in reset] == [0x4000000, 1, 0xC, 0x3000000]
    with pytest.raises(ProtocolError):
        send_commands(ctrl, ["raw", "0A", "0000000"])
    dual = load_controller("easysmc-dual")
    (c,) = send_commands(dual, ["raw", "57", "0000001", "0000000", "0000000", "--addr", "1"])
    assert c.addr == 1
    with pytest.raises(Exception, match="not on this bus"):
        send_commands(dual, ["raw", "57", "0", "0", "0", "--addr", "2"])

    clock = [0.0]
    emu = EasySmcEmulator((0,), clock=lambda: clock[0])
    link = EmulatorLink(emu)
    lines = run_send(ctrl, ["home"], link)
    assert len(lines) == 6 and all(line.endswith("ok") for line in lines)
    assert run_send(ctrl, ["write", "A3_feed_hz", "4000"], link)[0].endswith("ok")
    assert run_send(ctrl, ["read", "A3_feed_hz"], link) == ["A3_feed_hz = 4000"]
    assert run_send(ctrl, ["read", "A3_acc_a_hz_s"], link) == ["A3_acc_a_hz_s = 20000"]
    run_send(ctrl, ["write", "27_XFMAX", "-1234"], link)
    assert run_send(ctrl, ["read", "27_XFMAX"], link) == ["27_XFMAX = -1234"]
    run_send(ctrl, ["raw", "57", "0000064", "1000032", "0000000", "--start", "4"], link)
    clock[0] = 1.0
    run_send(ctrl, ["park"], link)
    clock[0] = 3.0
    assert position(emu, 3.0) == [0, 0, 0]
    assert run_send(ctrl, ["estop", "on"], link)[0].endswith("ok")
    assert status(emu, 3.0).state == 7
    run_send(ctrl, ["reset"], link)
    assert status(emu, 3.0).state == 0
    assert emu.violations == []
    text = inspect_bytes(b"".join(link.sent) + b"junk")
    assert any("xyz_linear" in line for line in text)
    assert text[-1].startswith("4 byte(s) outside frames")


# -- USB adapter against a fake DLL ---------------------------------------------------------


class FakeDll:
    """The two DLL functions, backed by a controller model speaking the USB formats."""

    def __init__(self) -> None:
        self.model = ControllerModel(0)
        self.t = 0.0

    def senddata(self, buf, addr: int, length: int) -> int:  # type: ignore[no-untyped-def]
        assert addr == 0 and length == 16
        cmd = decode_usb_write(bytes(buf[:16]))
        r = self.model.handle(cmd, self.t)
        st = self.model.exec_status(self.t)
        pos = self.model.position_at(self.t)
        if isinstance(r, ErrorReply):
            reply = UsbWriteReply(0x99, int(r.error), 0, st.state, st.executing, pos[:3])
        else:
            reply = UsbWriteReply(cmd.code, 0, 0, st.state, st.executing, pos[:3])
        ctypes.memmove(buf, encode_usb_write_reply(reply), 20)
        return 1

    def recdata(self, buf, addr: int, cmd: int, rdat1: int, rdat2: int) -> int:  # type: ignore[no-untyped-def]
        req = UsbReadRequest(cmd, rdat1, rdat2)
        words = self.model.query_words(cmd, req.serial_word(), self.t) or (0,)
        padded = (*words, 0, 0, 0)[:3]
        data = encode_usb_read_reply(UsbReadReply(cmd, padded, 0, len(words)))  # type: ignore[arg-type]
        ctypes.memmove(buf, data, 16)
        return 1


def test_usb_dll_adapter_against_fake() -> None:
    fake = FakeDll()
    usb = UsbDllLink(fake)
    assert usb.write(Command(0x41, (2,))).code == 0x41
    r = usb.write(Command.move(0x44, [1000], SEQ))
    assert r.code == 0x44 and r.executing == 2
    fake.t = 1.0
    rr = usb.read(UsbReadRequest(0x31, 0x04))
    assert signed_from_word(rr.words[0]) == 1000 and rr.n_valid == 3
    assert usb.read(UsbReadRequest(0x34, 0x01)).words[0] == 2000  # 6.2.1 example 2
    fake.model.manual_mode = True
    err = usb.write(Command(0x01, (100,)))
    assert err.code == 0x99 and err.error == 2
    with pytest.raises(ProtocolError, match="query"):
        usb.write(Command(0x31, (1,)))
    with pytest.raises(TransportError, match="Windows"):
        UsbDllLink()


def test_streamer_learns_the_numbering_and_waits_for_room() -> None:
    clock = [0.0]
    emu = EasySmcEmulator((0,), clock=lambda: clock[0])
    link = EasySmcLink(EmulatorLink(emu))
    for _ in range(5):  # someone else used the controller before
        link.request(Command(0x19, (0x1000000,), SEQ))
    slept: list[float] = []

    def sleep(dt: float) -> None:
        slept.append(dt)
        clock[0] += dt

    streamer = EasySmcStreamer(link, {0: 10}, poll_interval_s=0.1, sleep=sleep)
    for _ in range(30):  # 1 s waits: only 10 may be queued at a time
        streamer.send(Command(0x19, (0x1000000 | 1000,), SEQ))
    assert streamer.sent[0] == 35
    assert emu.models[0].stats["buffer_full"] == 0
    assert emu.models[0].stats["max_depth"] <= 11
    assert sum(slept) == pytest.approx(20.0, abs=1.0)  # 30 s of waits, 10 still queued


def test_usb_stream_and_send_through_fake_dll() -> None:
    ctrl = load_controller("easysmc")
    fake = FakeDll()
    link = UsbCommandLink(UsbDllLink(fake))
    assert all(line.endswith("ok") for line in run_send(ctrl, ["home"], link))
    assert run_send(ctrl, ["read", "A3_feed_hz"], link) == ["A3_feed_hz = 20000"]
    streamer = EasySmcStreamer.for_controller(ctrl, link, 20.0)
    streamer.lead_s = 0.0
    enc = ctrl.frame_encoder(20.0)
    fake_clock = [0.0]

    def sleep(dt: float) -> None:
        fake_clock[0] += dt
        fake.t = fake_clock[0]

    streamer._sleep = sleep
    frames = [(k / 20, [3 * k, -2 * k, k]) for k in range(40)]
    assert streamer.stream(enc, frames, clock=lambda: fake_clock[0]) == 40
    fake.t = 10.0
    assert fake.model.position_at(10.0)[:3] == (117, -78, 39)
    assert link.last_write is not None and link.last_write.code == 0x57
    assert fake.model.violations == []


# -- serial transport --------------------------------------------------------------------------


def test_serial_transport_errors_are_wrapped() -> None:
    with pytest.raises(TransportError) as info:
        open_serial("serial:///dev/does-not-exist-easysmc?baud=19200")
    assert info.value.__cause__ is not None
    with pytest.raises(Exception, match="unknown option"):
        open_serial("serial:///dev/ttyS0?speed=1")
    emu = EasySmcEmulator((0,)).start()
    other = SerialTransport.from_url(f"serial://{emu.path}?baud=9600&parity=n", baud=4800)
    assert other.baud == 4800  # open_transport's options override the URL's
    other.close()
    with pytest.raises(Exception, match="not a serial target"):
        SerialTransport.from_url("udp://127.0.0.1:7408")
    port = open_serial(f"serial://{emu.path}")
    assert port.baud == 19200
    emu.stop()  # the other end goes away: writing fails with an OS error, wrapped
    with pytest.raises(TransportError) as info:
        for _ in range(100):
            port.send(b"x" * 4096)
    assert isinstance(info.value.__cause__, OSError)
    port.close()


def test_end_to_end_stream_over_a_pty() -> None:
    """10 s trajectory at 20 Hz, 19200 baud, XYZ: pyserial on the emulator's pty.

    The emulator holds every byte for its time on a 19200-baud line, so the stream only
    keeps up if the link budget (82.6 bytes per frame, max 23.2 Hz) is right.
    """
    ctrl = load_controller("easysmc")
    rate = 20.0  # the link budget allows 23.2 Hz at 19200 baud
    emu = EasySmcEmulator((0,), line_baud=ctrl.baud).start()
    try:
        port = open_serial(f"serial://{emu.path}?baud={ctrl.baud}")
        assert isinstance(port, SerialTransport)
        link = EasySmcLink(port, timeout_s=1.0)
        streamer = EasySmcStreamer.for_controller(ctrl, link, rate)
        streamer.send_all(ctrl.setup_commands())
        streamer.send_all(send_commands(ctrl, ["home"]))
        enc = ctrl.frame_encoder(rate)
        frames = []
        for k in range(int(10 * rate)):
            t = k / rate
            frames.append(
                (
                    t,
                    [
                        400 * math.sin(2 * math.pi * 0.4 * t),
                        250 * math.sin(2 * math.pi * 0.25 * t) * (t < 6),  # then holds still
                        150 * (1 - math.cos(2 * math.pi * 0.1 * t)),
                    ],
                )
            )
        streamer.stream(enc, frames)
        streamer.drain(timeout_s=5.0)
        stream_depth = emu.models[0].stats["max_depth"]
        stream_full = link.stats.buffer_full + emu.models[0].stats["buffer_full"]
        # e-stop, buffer-full and reset over the same link
        r = link.request(Command(0x18, (0,), OOB))
        assert r == WriteReply(0x18, 8, 0)
        assert link.status(0).state == 7
        for _ in range(BUFFER_DEPTH):
            link.request(Command(0x19, (0x1000000 | 10,), SEQ))
        assert link.request(Command(0x19, (0x1000000 | 10,), SEQ)) == ErrorReply(
            ErrorCode.BUFFER_FULL, 4
        )
        for c in send_commands(ctrl, ["reset"]):
            assert isinstance(link.request(c), WriteReply)
        st = link.status(0)
        assert st.state == 0 and st.executing == 1  # cleared, renumbered
        port.close()
    finally:
        emu.stop()
    assert emu.violations == []
    # never beyond the 63-command buffer while streaming (the 63 waits of the buffer-full
    # check come after); the paced streamer queues at most about lead_frames x 2 commands.
    # That the buffer never runs dry (and stays about that full) is a real-time figure a busy
    # machine misses (the sender is late): benchmarks/bench_easysmc.py checks it.
    assert 0 < stream_depth <= 40
    assert stream_full == 0
    # the trace: one entry per frame (move or wait), in order
    n_before = len(ctrl.setup_commands()) + len(send_commands(ctrl, ["home"]))
    moves = [e for e in emu.trace if e.number > n_before][: len(frames)]
    assert len(moves) == len(frames)
    for (t, target), entry in zip(frames, moves, strict=True):
        assert [abs(p - round(v)) <= 1 for p, v in zip(entry.positions, target, strict=False)] == [
            True
        ] * 3, (t, entry)
    # on the controller's clock each move lasts its period (its feed): consecutive moves are
    # never closer than one period, so no move is played faster than planned whatever the
    # load; a late sender only opens gaps (the buffer ran dry), which bench_easysmc.py times
    gaps = [b.t_s - a.t_s for a, b in itertools.pairwise(moves)]
    assert min(gaps) >= 1 / rate - 1e-6, min(gaps)
    assert moves[-1].positions[:3] == enc.last_pulses
    assert emu.models[0].stats["buffer_full"] == 1 and link.stats.garbled_replies == 0


@pytest.mark.parametrize(("name", "rate"), [("easysmc-xyzu", 15.0), ("easysmc-dual", 10.0)])
def test_frames_play_on_time_in_the_emulator(name: str, rate: float) -> None:
    """Simulated time (no pty): every frame's target is reached at its time on every unit."""
    ctrl = load_controller(name)
    emu = EasySmcEmulator(tuple(u.address for u in ctrl.units), clock=lambda: 0.0)
    for c in ctrl.setup_commands() + send_commands(ctrl, ["home"]):
        assert isinstance(decode_reply(emu.feed(encode_command(c), 0.0)), WriteReply)
    n_before = {u.address: emu.models[u.address].received for u in ctrl.units}
    enc = ctrl.frame_encoder(rate)
    frames = []
    for k in range(int(8 * rate)):
        t = k / rate
        frames.append((t, [(150 + 30 * i) * math.sin(1.3 * t) for i in range(ctrl.n_axes)]))
    for t, target in frames:
        # the host sends each frame half a period before its time: queue never runs dry
        for c in enc.encode_commands(t, target):
            reply = decode_reply(emu.feed(encode_command(c), max(t - 0.5 / rate, 0.0)))
            assert isinstance(reply, WriteReply), reply
    emu.feed(b"", 100.0)
    for m in emu.models.values():
        m.advance(100.0)
    assert emu.violations == []
    i = 0
    for u in ctrl.units:
        model = emu.models[u.address]
        assert model.stats["underflows"] == 0
        moves = [e for e in model.trace if e.number > n_before[u.address]]
        assert len(moves) == len(frames)
        for (t, target), entry in zip(frames, moves, strict=True):
            want = [round(v) for v in target[i : i + len(u.axes)]]
            assert list(entry.positions[: len(u.axes)]) == want
            assert entry.t_s == pytest.approx(t + 1 / rate, abs=2e-3)
        i += len(u.axes)


def test_smooth_brake_decelerates_then_holds() -> None:
    emu = homed_emulator()
    ask(emu, Command(0x02, (100, 100, 100), SEQ), 0.0)
    ask(emu, Command(0xA3, (1000, 1000, 1000), SEQ), 0.0)  # slow ramps: 0.9 s each
    ask(emu, Command.move(0x57, [5000, 0, 0]), 0.0)
    ask(emu, Command(0x18, (0x08,), OOB), 1.0)  # smooth brake all axes at full feed
    p_brake = position(emu, 1.0)[0]
    held = position(emu, 10.0)[0]
    # it keeps going while slowing from 1000 Hz to 100 Hz at 1000 Hz/s: ~0.9 s more
    assert 300 < held - p_brake < 600
    assert position(emu, 20.0)[0] == held
    ask(emu, Command(0x18, (0x0C,), OOB), 20.0)  # release the smooth brake
    assert position(emu, 40.0)[0] == 5000


def test_run_emulator_prints_its_path_and_inspect_reads_replies(tmp_path) -> None:  # type: ignore[no-untyped-def]
    from motioncue.output.easysmc import run_emulator

    ctrl = load_controller("easysmc-dual")

    def drive(emu: EasySmcEmulator) -> None:  # a client on the printed path
        port = open_serial(f"serial://{emu.path}?baud=19200")
        link = EasySmcLink(port)
        for c in [Command(0x41, (2,), SEQ, 1), Command.move(0x57, [5, 6, 7], SEQ, 1)]:
            assert isinstance(link.request(c), WriteReply)
        port.close()

    lines: list[str] = []
    csv = tmp_path / "trace.csv"
    status_ = run_emulator(ctrl, 0.3, lines.append, trace_csv=csv, ready=drive)
    assert status_ == 1  # Y and Z of controller 01 moved without homing: flagged
    assert lines[0].startswith("EasySmc emulator (easysmc-dual, addresses 00, 01) on /dev/")
    assert lines[1].startswith("connect with: serial:///dev/") and lines[1].endswith("baud=19200")
    assert lines[2].startswith("received 2 frames, 1 trace points, 2 violation(s)")
    assert csv.read_text().splitlines()[1].endswith(",1,2,5,6,7,0")
    emu = EasySmcEmulator((0,), clock=lambda: 0.0)
    replies = emu.feed(encode_command(Command(0x38, (0,))), 0.0)
    replies += emu.feed(encode_command(Command(0x01, (1,)))[:-1] + b"0", 0.0)  # bad checksum
    text = inspect_bytes(replies + b"xx")
    assert text[0].startswith("reply ReadReply(code=56")
    assert text[1].startswith("reply ErrorReply(error=<ErrorCode.CHECKSUM")
    assert text[2] == "2 byte(s) outside frames, 0 trailing byte(s)"


class WriteOnly:
    def __init__(self) -> None:
        self.data = b""

    def send(self, data: bytes) -> None:
        self.data += data

    def recv(self, timeout_s: float) -> None:
        return None


def test_verb_hooks() -> None:
    import io

    from motioncue import ConfigError
    from motioncue.output.easysmc import emulator, inspect_decode, send_verb, split_stream

    ctrl = load_controller("easysmc")
    emu = EasySmcEmulator((0,), clock=lambda: 0.0)
    link = EasySmcLink(EmulatorLink(emu))
    out = io.StringIO()
    assert send_verb(ctrl, link, "home", [], out=out) == 0
    assert send_verb(ctrl, link, "write", ["A3_feed_hz", "5000"], save=True, out=out) == 0
    assert "defaults" in out.getvalue().splitlines()[-1]  # 17 0000002: save to EEPROM
    emu.set_manual(True)  # A/M jumper closed: serial commands are refused (4.3.1)
    assert send_verb(ctrl, link, "estop", ["on"], out=out) == 1
    assert "error 99/2 MANUAL_MODE" in out.getvalue().splitlines()[-1]
    # write-only target (file:): frames written, reading verbs refused
    sink = WriteOnly()
    assert send_verb(ctrl, sink, "estop", ["on"], out=io.StringIO()) == 0
    assert sink.data == encode_command(Command(0x18, (0,), OOB))
    with pytest.raises(ConfigError, match="serial"):
        send_verb(ctrl, sink, "read", ["A3_feed_hz"], out=io.StringIO())
    # inspect: frames and the junk between them, in order
    capture = b"zz" + sink.data + encode_reply_bytes() + b"\x02\x03"
    parts = split_stream(capture)
    assert parts[0] == b"zz" and parts[1] == sink.data
    assert inspect_decode(parts[1]).startswith("cmd addr 00 cmd 18 brake")
    assert inspect_decode(parts[2]).startswith("reply WriteReply(code=24")
    with pytest.raises(ProtocolError):
        inspect_decode(parts[0])
    with pytest.raises(ProtocolError, match="no EasySmc frame"):
        split_stream(b"\x00\x01 not a capture")
    with pytest.raises(ConfigError, match="pseudo-terminal"):
        emulator(ctrl, "127.0.0.1", 7408)
    assert emulator(ctrl).models.keys() == {0}


def encode_reply_bytes() -> bytes:
    from motioncue.output.easysmc import encode_reply

    return encode_reply(WriteReply(0x18, 8, 0))


def test_a_slower_line_than_budgeted_starves_the_controller() -> None:
    """The other side of the budget: 20 Hz over a 9600-baud line (max 11.6 Hz) falls behind."""
    ctrl = load_controller("easysmc")
    assert ctrl.link_budget().bytes_per_frame * 10 / 9600 > 1 / 20
    emu = EasySmcEmulator((0,), line_baud=9600).start()
    try:
        port = open_serial(f"serial://{emu.path}?baud=9600")
        link = EasySmcLink(port, timeout_s=1.0)
        streamer = EasySmcStreamer.for_controller(ctrl, link, 20.0)
        streamer.lead_s = 0.1
        streamer.send_all(send_commands(ctrl, ["home"]))
        enc = ctrl.frame_encoder(20.0)  # checked against 19200 baud, the config's rate
        frames = [(k / 20, [2 * k, k, 0]) for k in range(30)]
        streamer.stream(enc, frames)
        port.close()
    finally:
        emu.stop()
    assert emu.models[0].stats["underflows"] > 5


class StalledHost:
    """A link whose reader is held up: its first read finds nothing, then the host stops for
    ``stall_s`` (a busy machine, a stopped process) while the controller's reply arrives in
    the port's buffer, so the link next looks after its reply deadline (the clock is the link
    module's, moved here)."""

    def __init__(self, emu: EasySmcEmulator | None, clock: list[float], stall_s: float) -> None:
        self.emu, self.clock, self.stall_s = emu, clock, stall_s
        self.later = self.pending = b""

    def send(self, data: bytes) -> None:
        if self.emu is not None:
            self.later += self.emu.feed(data)  # on its way, not there yet

    def recv(self, timeout_s: float) -> bytes | None:
        if self.later or (self.emu is None and self.clock[0] < self.stall_s):
            self.clock[0] += self.stall_s  # nothing yet; the host is held up after the read
            self.pending, self.later = self.pending + self.later, b""
            return None
        self.clock[0] += timeout_s
        data, self.pending = self.pending, b""
        return data or None


def test_a_held_up_host_is_not_a_silent_controller(monkeypatch: pytest.MonkeyPatch) -> None:
    """The reply that came while the host was held up is read before the link gives up;
    a controller that sent nothing is still reported silent (ControllerSilent)."""
    from motioncue._errors import ControllerSilent
    from motioncue.output.easysmc import _link

    clock = [0.0]
    monkeypatch.setattr(_link.time, "monotonic", lambda: clock[0])
    emu = EasySmcEmulator((0,), clock=lambda: 0.0)
    link = EasySmcLink(StalledHost(emu, clock, stall_s=2.0), timeout_s=0.5)
    reply = link.request(Command(0x19, (0x1000000,), SEQ))  # answered, read 1.5 s late
    assert reply.addr == 0 and link.stats.commands == 1
    dead = EasySmcLink(StalledHost(None, clock, stall_s=2.0), timeout_s=0.5)
    with pytest.raises(ControllerSilent, match="controller silent for 500 ms"):
        dead.request(Command(0x19, (0x1000000,), SEQ))
