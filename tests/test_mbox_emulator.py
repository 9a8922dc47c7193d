"""SC-MBOX emulator: manual behaviour (deterministic clock) and end-to-end over UDP."""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np
import pytest

from motioncue.output import load_controller, mbox, open_transport

ESTOP_ON = bytes.fromhex("55AA000012010000FFFFFFFF009000010001")
ESTOP_OFF = bytes.fromhex("55AA000012010000FFFFFFFF009000010000")


def _ctrl(**params):
    ctrl = load_controller("mbox6")
    return ctrl.with_parameters(**params) if params else ctrl


def _function(raw: bytes) -> int:
    return int.from_bytes(raw[4:6], "big")


def _stream(emu, enc, n, *, t0=0.0, dt=0.02, wall0=0.0, pos=lambda k: [k * 100] * 6):
    replies = []
    for k in range(n):
        (raw,) = enc.encode(t0 + k * dt, pos(k))
        replies += emu.handle(raw, wall0 + k * dt)
    return replies


def test_frames_are_played_on_their_time_and_acknowledged():
    emu = mbox.MboxEmulator(_ctrl())
    enc = emu.controller.frame_encoder()
    replies = _stream(emu, enc, 10)
    assert [_function(r) for r in replies] == [0x1302] * 10
    tr = emu.trace
    assert np.allclose(tr.t_s, 0.02 * np.arange(10))
    assert (tr.positions[:, 0] == 100 * np.arange(10)).all() and list(tr.frames) == list(range(10))
    assert emu.violations == []


def test_who_addressing():
    emu = mbox.MboxEmulator(_ctrl())  # node 0F.C9 (Fn022.Fn023 = 15.201)
    enc = lambda a, r: emu.controller.frame_encoder(who_accept=a, who_reply=r)  # noqa: E731
    assert emu.handle(enc(0x0F01, 0xFFFF).encode(0, [0] * 6)[0], 0) == []  # another node
    assert len(emu.trace) == 0
    assert emu.handle(enc(0xFFC9, 0).encode(0, [0] * 6)[0], 0) == []  # row match, no reply
    assert len(emu.trace) == 1
    assert len(emu.handle(enc(0x0FC9, 0x0FFF).encode(0, [0] * 6)[0], 0)) == 1


def test_jog_rewind_and_fast_forward_times_from_fn013_to_fn016():
    emu = mbox.MboxEmulator(_ctrl())
    frames = [(0, 0), (1, 0), (2, -20), (3, 5000), (4, 20)]  # (line, delta ms)
    for line, delta in frames:
        emu.handle(mbox.MotionFrame(False, line, delta, (0,) * 6).encode(), 0.0)
    # first frame t = 0; jog 100 ms (Fn013); rewind 1.0 s (Fn014); ff 1.0 s (Fn016); 20 ms
    assert np.allclose(emu.trace.t_s, [0.0, 0.1, 1.1, 2.1, 2.12])


def test_speed_and_stroke_violations_are_flagged():
    emu = mbox.MboxEmulator(_ctrl(Fn0C0=3000))  # 300 mm stroke = 600000 pulses
    enc = emu.controller.frame_encoder()
    emu.handle(enc.encode(0.0, [0] * 6)[0], 0.0)
    emu.handle(enc.encode(0.02, [20_000] + [0] * 5)[0], 0.02)  # 1e6 pulses/s > 5e5
    emu.handle(mbox.MotionFrame(True, 2, 40, (20_000, 0, 0, 0, 0, 600_001)).encode(), 0.04)
    kinds = {(v.kind, v.axis) for v in emu.violations}
    assert kinds == {("speed", 0), ("stroke", 5), ("speed", 5)}  # 600001 in 20 ms is fast too


def test_estop_capture_holds_ignores_frames_and_release_uses_fn018():
    emu = mbox.MboxEmulator(_ctrl())
    enc = emu.controller.frame_encoder()
    _stream(emu, enc, 10, pos=lambda k: [1000 * k] * 6)
    # frame 9 arrived at wall 0.18 when frame 8 (t = 0.16) had been reached; the box plays
    # Fn012 / 1000 = 1.2x as fast as stamped (5.3.3), so 10 ms later it is 12 ms, 60 %, of
    # the way from frame 8 (8000) to frame 9 (9000)
    (rep,) = emu.handle(ESTOP_ON, 0.19)
    assert mbox.decode(rep) == mbox.RegisterWriteReply(0, 0x90, (1,))
    assert emu.estop
    tr = emu.trace
    assert tr.frames[-1] == -1 and tr.t_s[-1] == pytest.approx(0.172 + 1.0)  # Fn017 = 1.0 s
    assert (tr.positions[-1] == 8600).all()
    dx = mbox.decode(emu.handle(mbox.RegisterRead(0, 0x3E, 1).encode(), 0.2)[0])
    assert dx.values == (2,)  # state: e-stop
    n = len(emu.trace)
    replies = _stream(emu, enc, 5, t0=0.2, wall0=0.2)
    assert [_function(r) for r in replies] == [0x1302] * 5
    assert len(emu.trace) == n and emu.ignored_frames == 5
    emu.handle(ESTOP_OFF, 0.4)
    assert not emu.estop
    emu.handle(enc.encode(0.4, [0] * 6)[0], 0.4)
    assert emu.trace.t_s[-1] - emu.trace.t_s[-2] == pytest.approx(1.0)  # Fn018 = 10 x 0.1 s


def test_estop_method_fn091_0_returns_to_origin():
    emu = mbox.MboxEmulator(_ctrl(Fn091=0))
    _stream(emu, emu.controller.frame_encoder(), 5)
    emu.handle(ESTOP_ON, 0.1)
    assert (emu.trace.positions[-1] == 0).all()


def test_fault_reset_and_home_through_cx0():
    emu = mbox.MboxEmulator(_ctrl(), homing_time_s=0.5)
    enc = emu.controller.frame_encoder()
    _stream(emu, enc, 3)
    emu.inject_fault(2520)
    assert _stream(emu, enc, 2, t0=0.06, wall0=0.06) and emu.ignored_frames == 2
    fault = mbox.decode(emu.handle(mbox.RegisterRead(0, 0x38, 1).encode(), 0.1)[0])
    assert fault.values == (2520,)
    reset = mbox.RegisterWrite(mbox.CHANNEL_CX, 0, (0x0001,))  # RST = 1, SON = 0 -> re-home
    assert mbox.decode(emu.handle(reset.encode(), 0.2)[0]) == mbox.RegisterWriteReply(2, 0, (1,))
    assert emu.fault_code == 0 and emu.state == 0  # homing
    assert (emu.trace.positions[-1] == 0).all()
    emu.handle(mbox.RegisterRead(0, 0, 1).encode(), 0.71)
    assert emu.state == 1  # ready again after 0.5 s
    # the manual's reset capture, as actually sent (channel 2), re-homes too
    emu.handle(bytes.fromhex("55AA000012010002FFFFFFFF000000010000"), 1.0)
    assert emu.state == 0


def test_buffer_full_reply_and_recovery():
    ctrl = dataclasses.replace(_ctrl(), buffer_frames=4)
    emu = mbox.MboxEmulator(ctrl)
    enc = ctrl.frame_encoder()
    replies = [emu.handle(enc.encode(0.02 * k, [0] * 6)[0], 0.0)[0] for k in range(7)]
    assert [_function(r) for r in replies] == [0x1302] * 5 + [0x1303] * 2
    assert emu.refused_frames == 2 and {v.kind for v in emu.violations} == {"buffer"}
    full = mbox.decode(replies[-1])
    assert full.status == mbox.FrameStatus.BUFFER_FULL and full.frame.line == 6
    later = emu.handle(mbox.MotionFrame(True, 7, 140, (0,) * 6).encode(), 0.05)
    assert _function(later[0]) == 0x1302


def test_latest_frame_mode_keeps_only_the_newest():
    emu = mbox.MboxEmulator(_ctrl(Fn01C=0))
    enc = emu.controller.frame_encoder()
    for k in range(5):
        emu.handle(enc.encode(0.02 * k, [k] * 6)[0], 0.0)
    # frame 0 played at once, frame 1 was under way when 2, 3, 4 came: 2 and 3 replaced
    assert list(emu.trace.frames) == [0, 1, 4] and emu.playback.frames_dropped == 2
    assert np.allclose(emu.trace.t_s, [0.0, 0.02, 0.08])


def test_short_frame_gets_0x1304_and_is_flagged():
    emu = mbox.MboxEmulator(_ctrl())
    raw = emu.controller.frame_encoder(absolute_time=False).encode(0.0, [1] * 6)[0]
    (rep,) = emu.handle(raw[:30], 0.0)
    assert _function(rep) == 0x1404 and len(rep) == 52
    assert [v.kind for v in emu.violations] == ["malformed"] and len(emu.trace) == 0


def test_garbage_is_flagged_not_fatal():
    emu = mbox.MboxEmulator(_ctrl())
    for junk in (b"", b"\x00" * 40, bytes.fromhex("55AA00007777 0000 FFFFFFFF") + bytes(8)):
        assert emu.handle(junk, 0.0) == []
    assert [v.kind for v in emu.violations] == ["malformed"] * 3


def test_register_access_and_outputs():
    emu = mbox.MboxEmulator(_ctrl(Fn010=0, Fn011=0))
    rep = mbox.decode(emu.handle(mbox.RegisterRead(1, 0x0C0, 3).encode(), 0)[0])
    assert rep.values == (0, 2000, 50)
    err = mbox.decode(emu.handle(mbox.RegisterWrite(0, 0x0C1, (0,)).encode(), 0)[0])
    assert isinstance(err, mbox.RegisterError) and err.error_code == 2  # Fn0C1 >= 1
    emu.handle(mbox.RegisterWrite(2, 1, (0x00F, 5000, 10000, 0x0A0)).encode(), 0)
    assert emu.outputs == (0x00F, 0x0A0, (5000, 10000))
    neg = mbox.RegisterWrite(0, 0x091, (0xFFFE,))  # Fn091 = -2 (signed parameter)
    emu.handle(neg.encode(), 0)
    assert emu.params["Fn091"] == -2


def test_periodic_status_reports_fn040_fn041():
    emu = mbox.MboxEmulator(_ctrl(Fn040=1, Fn041=-100, Fn042=0x3E, Fn043=2))
    assert emu.periodic(0.0) and emu.periodic(0.05) == [] and emu.periodic(0.1)
    rep = mbox.decode(emu.periodic(0.2)[0])
    assert isinstance(rep, mbox.StatusReport) and rep.start == 0x3E and rep.values == (1, 0)


# -- end to end over UDP -----------------------------------------------------------------------
AMP = np.array([40_000, 50_000, 60_000, 70_000, 80_000, 90_000])
FREQ = np.array([0.30, 0.35, 0.40, 0.45, 0.50, 0.55])


def intended(t):
    """Intended positions (pulses) at times t: starts at the homed origin."""
    return AMP * (1 - np.cos(2 * np.pi * FREQ * np.asarray(t)[..., None]))


def check_trace(trace, t_frames, dt):
    assert len(trace) == len(t_frames)
    assert np.all(np.abs(trace.t_s - t_frames) <= dt)
    vmax = float(np.max(AMP * 2 * np.pi * FREQ))
    err = np.abs(trace.positions - intended(trace.t_s))
    assert np.all(err <= 1 + vmax * np.abs(trace.t_s - t_frames)[:, None])


@pytest.mark.parametrize("absolute", [True, False])
def test_ten_second_trajectory_over_udp_matches_within_a_frame_and_a_pulse(absolute):
    dt = 0.02
    ctrl = dataclasses.replace(_ctrl(Fn0C0=3000), buffer_frames=1024)
    t = np.arange(0, 10.0 + dt / 2, dt)
    q = np.rint(intended(t)).astype(np.int64)
    with mbox.MboxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder(absolute_time=absolute, t0_s=0.0)
        for tk, qk in zip(t, q, strict=True):
            for msg in enc.encode(float(tk), qk):
                tr.send(msg)
        deadline = time.monotonic() + 5
        while emu.received < len(t) and time.monotonic() < deadline:
            time.sleep(0.01)
    assert emu.received == len(t) and emu.internal_errors == []
    assert emu.violations == []
    check_trace(emu.trace, t, dt)
    assert list(emu.trace.frames) == list(range(len(t)))


def test_realtime_stream_at_1khz_loses_and_reorders_nothing():
    ctrl = _ctrl()
    n = 1000  # 1 s here; benchmarks/bench_output.py runs 10 s
    with mbox.MboxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder(who_reply=0)
        start = time.monotonic()
        for k in range(n):
            delay = start + k * 0.001 - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            tr.send(enc.encode(k * 0.001, [k] * 6)[0])
        deadline = time.monotonic() + 5
        while emu.received < n and time.monotonic() < deadline:
            time.sleep(0.01)
    assert emu.received == n and emu.refused_frames == 0
    assert list(emu.trace.frames) == list(range(n))
    assert not [v for v in emu.violations if v.kind in ("sequence", "buffer", "malformed")]


@pytest.mark.skipif(sys.platform != "linux", reason="kernel receive stamps: Linux SO_TIMESTAMPNS")
def test_a_stalled_emulator_thread_still_sees_real_arrival_times():
    # 400 frames at 1 kHz while the emulator thread cannot run: they queue in the socket.
    # Judged by the time they are read, 400 frames would arrive at once and overflow the
    # 256-frame FIFO; judged by the kernel's arrival stamps they came 1 ms apart.
    ctrl = _ctrl()
    with mbox.MboxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder(who_reply=0)
        with emu.lock:
            start = time.monotonic()
            for k in range(400):
                delay = start + k * 0.001 - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
                tr.send(enc.encode(k * 0.001, [k] * 6)[0])
        deadline = time.monotonic() + 5
        while emu.received < 400 and time.monotonic() < deadline:
            time.sleep(0.01)
    assert emu.received == 400 and emu.refused_frames == 0
