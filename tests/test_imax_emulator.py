"""IMAX emulator: manual behaviour (deterministic clock) and end-to-end over UDP."""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest

from motioncue.output import imax, load_controller, open_transport

AMP = np.array([30_000, 40_000, 50_000, 60_000, 70_000, 80_000])
FREQ = np.array([0.5, 0.6, 0.7, 0.8, 0.9, 1.0])


def _ctrl(name="imax6", **params):
    ctrl = load_controller(name)
    return ctrl.with_parameters(**params) if params else ctrl


def _fn(raw: bytes) -> int:
    return int.from_bytes(raw[4:6], "big")


def _stream(emu, enc, n, *, t0=0.0, dt=0.01, wall0=0.0):
    out = []
    for k in range(n):
        out += emu.handle(enc.encode(t0 + k * dt, [100 * k] * emu.n_axes)[0], wall0 + k * dt)
    return out


def test_frames_replies_and_trace():
    emu = imax.ImaxEmulator(_ctrl())
    replies = _stream(emu, emu.controller.frame_encoder(), 5)
    assert [_fn(r) for r in replies] == [0x1302] * 5
    rep = imax.decode(replies[-1])
    assert rep.status == imax.ReplyStatus.OK and rep.channel == 1 and rep.frame == 4
    assert np.allclose(emu.trace.t_s, 0.01 * np.arange(5)) and emu.violations == []


def test_pa15_zero_disables_replies():
    emu = imax.ImaxEmulator(_ctrl(PA15=0))
    assert _stream(emu, emu.controller.frame_encoder(), 3) == [] and len(emu.trace) == 3


def test_estop_from_inputs_holds_and_answers_x4_then_goes_on():
    emu = imax.ImaxEmulator(_ctrl(PA90=1, PA92=0b11, PA91=0))
    enc = emu.controller.frame_encoder()
    _stream(emu, enc, 5)
    emu.set_inputs(0b01, now_s=0.05)  # one of the two selected inputs: no e-stop
    assert not emu.estop
    emu.set_inputs(0b11, now_s=0.05)
    assert emu.estop
    replies = _stream(emu, enc, 3, t0=0.05, wall0=0.05)
    assert [_fn(r) for r in replies] == [0x1304] * 3 and emu.ignored_frames == 3
    assert imax.decode(replies[0]).channel == 4
    emu.set_inputs(0, now_s=0.1)
    assert not emu.estop
    assert [_fn(r) for r in _stream(emu, enc, 1, t0=0.1, wall0=0.1)] == [0x1302]


def test_estop_pa91_1_goes_to_zero_and_pa91_2_waits_for_reset():
    emu = imax.ImaxEmulator(_ctrl(PA90=1, PA92=1, PA91=1))
    _stream(emu, emu.controller.frame_encoder(), 5)
    emu.set_inputs(1, now_s=0.05)
    assert (emu.trace.positions[-1] == 0).all()

    emu = imax.ImaxEmulator(_ctrl(PA90=1, PA92=1, PA91=2), homing_time_s=0.3)
    enc = emu.controller.frame_encoder()
    _stream(emu, enc, 5)
    emu.set_inputs(1, now_s=0.05)
    emu.set_inputs(0, now_s=0.06)
    assert emu.estop  # latched until a reset
    home = imax.RegisterWrite(imax.CHANNEL_DPF, 0, (0,)).encode()  # DPF0 = 0
    assert _fn(emu.handle(home, 0.1)[0]) == 0x1202
    dpf0 = imax.RegisterRead(imax.CHANNEL_DP, 0xF0, 1).encode()
    assert imax.decode(emu.handle(dpf0, 0.2)[0]).values == (0,)  # homing
    assert imax.decode(emu.handle(dpf0, 0.45)[0]).values == (2,)  # done
    assert not emu.estop


def test_pa08_manual_reset_homes_and_reads_back_zero():
    emu = imax.ImaxEmulator(_ctrl(), homing_time_s=0.2)
    emu.handle(imax.RegisterWrite(imax.CHANNEL_PA, 0x08, (1,)).encode(), 0.0)
    assert emu.state == 0
    replies = _stream(emu, emu.controller.frame_encoder(), 2, wall0=0.05)
    assert [_fn(r) for r in replies] == [0x1305] * 2  # frames while homing: command error
    rd = imax.RegisterRead(imax.CHANNEL_PA, 0x08, 1).encode()
    assert imax.decode(emu.handle(rd, 0.3)[0]).values == (0,) and emu.state == 1


def test_buffer_overflow_answers_err21_and_reports_it():
    ctrl = dataclasses.replace(_ctrl(PA1f=1, PA1e=0), buffer_frames=3)
    emu = imax.ImaxEmulator(ctrl)
    enc = ctrl.frame_encoder()
    replies = [emu.handle(enc.encode(0.01 * k, [0] * 6)[0], 0.0)[0] for k in range(6)]
    assert [_fn(r) for r in replies] == [0x1302] * 4 + [0x1303] * 2
    assert imax.decode(replies[-1]).channel == 21  # Err21
    (report,) = emu.periodic(0.0)
    rep = imax.decode(report)
    assert isinstance(rep, imax.StatusReport) and rep.control_alarm == 21
    assert rep.control_id == 0x0FC9 and len(rep.positions) == 6
    assert emu.periodic(0.1) == []  # PA1e = 0: only on a new alarm


def test_periodic_status_reports_pa1e():
    emu = imax.ImaxEmulator(_ctrl(PA1f=1, PA1e=50))
    assert emu.periodic(0.0) and emu.periodic(0.02) == [] and emu.periodic(0.05)


def test_pa95_takes_axes_from_a_longer_frame():
    ctrl = _ctrl("imax3", PA95=3)
    emu = imax.ImaxEmulator(ctrl)
    frame = imax.MotionFrame(True, 0, 0, (1, 2, 3, 4, 5, 6))
    assert _fn(emu.handle(frame.encode(), 0)[0]) == 0x1302
    assert list(emu.trace.positions[-1]) == [4, 5, 6]
    short = imax.MotionFrame(True, 1, 10, (1, 2, 3, 4, 5))
    assert _fn(emu.handle(short.encode(), 0)[0]) == 0x1305


def test_period_below_pa59_is_flagged_and_outputs_follow_portout():
    emu = imax.ImaxEmulator(_ctrl(PA59=5))
    enc = emu.controller.frame_encoder()
    emu.handle(enc.encode(0.0, [0] * 6, dout=0x5)[0], 0.0)
    emu.handle(enc.encode(0.002, [0] * 6, dout=0xA)[0], 0.002)
    assert [v.kind for v in emu.violations] == ["period"] and emu.outputs == 0xA
    masked = imax.ImaxEmulator(_ctrl(PA9d=1))
    masked.handle(masked.controller.frame_encoder().encode(0, [0] * 6, dout=0xF)[0], 0)
    assert masked.outputs == 0
    masked.handle(imax.RegisterWrite(imax.CHANNEL_DPF, 1, (0x3,)).encode(), 0)  # DPF1
    assert masked.outputs == 0x3


def test_vibration_frames_servo_parameters_and_errors():
    emu = imax.ImaxEmulator(_ctrl())
    enc = emu.controller.frame_encoder()
    (rep,) = emu.handle(enc.encode(0.0, [1] * 6, vibration=[(8, 10)] * 6)[0], 0.0)
    assert _fn(rep) == 0x1802 and emu.vibration == ((8, 10),) * 6
    emu.handle(imax.ServoWrite(2, 0x1FC, (42, 43)).encode(), 0)
    back = imax.decode(emu.handle(imax.ServoRead(2, 0x1FC, 2).encode(), 0)[0])
    assert back == imax.ServoReply(0x2102, 2, 0x1FC, (42, 43))
    bad = imax.decode(emu.handle(imax.ServoRead(9, 0, 1).encode(), 0)[0])
    assert bad.status == imax.ReplyStatus.ERROR
    err = imax.decode(emu.handle(imax.RegisterWrite(1, 0xA0, (0,)).encode(), 0)[0])
    assert err.function == 0x1203 and err.error_code == 2  # PAa0 range 1..3000
    junk = bytes.fromhex("55AA000013010001FFFFFFFF") + bytes(5)
    assert _fn(emu.handle(junk, 0)[0]) == 0x1305
    assert [v.kind for v in emu.violations] == ["malformed"]


def test_position_registers_read_back():
    emu = imax.ImaxEmulator(_ctrl())
    emu.handle(imax.MotionFrame(True, 0, 0, (-2, 70000, 3, 4, 5, 6)).encode(), 0.0)
    vals = imax.decode(emu.handle(imax.RegisterRead(0, 0x06, 4).encode(), 1.0)[0]).values
    assert vals == (0xFFFE, 0xFFFF, 70000 & 0xFFFF, 70000 >> 16)


def intended(t):
    return AMP * (1 - np.cos(2 * np.pi * FREQ * np.asarray(t)[..., None]))


@pytest.mark.parametrize("absolute", [True, False])
def test_ten_second_trajectory_over_udp(absolute):
    dt = 0.01
    # 4 x 5000 encoder lines per turn: the speed cap these amplitudes were chosen against
    ctrl = dataclasses.replace(_ctrl(), buffer_frames=2048, stroke_mm=100.0, counts_per_rev=20000)
    t = np.arange(0, 10.0 + dt / 2, dt)
    q = np.rint(intended(t)).astype(np.int64)
    with imax.ImaxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder(absolute_time=absolute, t0_s=0.0, who_reply=0)
        for tk, qk in zip(t, q, strict=True):
            tr.send(enc.encode(float(tk), qk)[0])
        deadline = time.monotonic() + 5
        while emu.received < len(t) and time.monotonic() < deadline:
            time.sleep(0.01)
    assert emu.received == len(t) and emu.violations == [] and emu.internal_errors == []
    trace = emu.trace
    assert len(trace) == len(t) and np.all(np.abs(trace.t_s - t) <= dt)
    vmax = float(np.max(AMP * 2 * np.pi * FREQ))
    err = np.abs(trace.positions - intended(trace.t_s))
    assert np.all(err <= 1 + vmax * np.abs(trace.t_s - t)[:, None])


def test_pa0b_flags_late_frames_and_pa0d_homes_when_frames_stop():
    emu = imax.ImaxEmulator(_ctrl(PA0b=50, PA0d=200), homing_time_s=0.1)
    enc = emu.controller.frame_encoder()
    emu.handle(enc.encode(0.0, [0] * 6)[0], 0.0)
    emu.handle(enc.encode(0.08, [10] * 6)[0], 0.08)  # 80 ms > PA0b = 50 ms
    assert [v.kind for v in emu.violations] == ["period"]
    emu.handle(imax.RegisterRead(0, 0xF0, 1).encode(), 0.25)
    assert emu.state == 1  # 170 ms without frames: still playing
    emu.handle(imax.RegisterRead(0, 0xF0, 1).encode(), 0.30)
    assert emu.state == 0 and (emu.trace.positions[-1] == 0).all()  # > 200 ms: homing


def test_realtime_stream_at_1khz_in_order_with_replies():
    ctrl = _ctrl()  # PA59 = 1 ms: 1 kHz is the fastest the controller takes
    n = 500
    with imax.ImaxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        enc = ctrl.frame_encoder()
        replies = []
        start = time.monotonic()
        for k in range(n):
            delay = start + k * 0.001 - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            tr.send(enc.encode(k * 0.001, [k] * 6)[0])
            while (r := tr.recv(0.0)) is not None:  # the host reads replies as they come
                replies.append(imax.decode(r))
        deadline = time.monotonic() + 5
        while len(replies) < n and time.monotonic() < deadline:
            r = tr.recv(0.2)
            if r is not None:
                replies.append(imax.decode(r))
    assert emu.received == n and list(emu.trace.frames) == list(range(n))
    assert [r.frame for r in replies] == list(range(n))  # every frame acknowledged, in order
    assert all(r.status == imax.ReplyStatus.OK for r in replies)
    assert emu.violations == [] and emu.internal_errors == []
