"""The MBOX and IMAX emulators judge frames with the controller's own numbers, on the clock
the controller plays them on.

The limits below are worked out here from the manuals' parameters, not taken from the
package, so a wrong derivation in the package shows up as a wrong verdict:

* mbox6: Fn0C1 = 2000 pulses/mm, Fn0C2 = 50 (5 mm lead), servo 3000 rpm:
  3000 / 60 x 5 x 2000 = 500 000 pulses/s; no acceleration parameter. Fn012 = 1200 plays
  every frame 1.2x as fast as stamped (MBOX manual 5.3.3).
* imax6 (counts_per_rev = 10000): min(PA07 = 3000, PAa0 x PAb0 = 2 x 1500) rpm
  = 50 turns/s = 500 000 pulses/s; PAb0 = 1500 rpm per 1 ms ramp step = 25 000 turns/s^2
  = 2.5e8 pulses/s^2.
"""

from __future__ import annotations

import dataclasses

import pytest

from motioncue.output import imax, load_controller, mbox

MBOX_V = 500_000.0  # pulses/s
IMAX_V = 500_000.0  # pulses/s at 10000 counts per turn
IMAX_A = 2.5e8  # pulses/s^2 at 10000 counts per turn


def _mbox(**params):
    ctrl = load_controller("mbox6")
    return ctrl.with_parameters(**params) if params else ctrl


def _imax(**params):
    ctrl = load_controller("imax6")
    return ctrl.with_parameters(**params) if params else ctrl


def _feed(emu, stamps_ms, positions, *, absolute=True):
    """Frames numbered 0.. with the given ms stamps and per-frame positions (all axes
    alike), each arriving at its own stamp time."""
    make = mbox.MotionFrame if isinstance(emu, mbox.MboxEmulator) else imax.MotionFrame
    for k, (ms, p) in enumerate(zip(stamps_ms, positions, strict=True)):
        if absolute:
            stamp = ms
        else:
            stamp = ms - (stamps_ms[k - 1] if k else ms)
        emu.handle(make(absolute, k, stamp, (p,) * emu.n_axes).encode(), ms / 1000.0)


def _kinds(emu, kind=None):
    return [(v.kind, v.axis) for v in emu.violations if kind is None or v.kind == kind]


def _ramp_then_cruise(step, n=20):
    """Positions rising by ``step`` pulses per frame after a first frame at rest at 0."""
    return [0] + [step * k for k in range(1, n)]


# -- speed on the controller's clock -----------------------------------------------------------
def test_mbox_limits_come_from_the_parameters():
    # the emulator checks with the numbers worked out above (and the catch-up of Fn012)
    emu = mbox.MboxEmulator(_mbox())
    pb = emu.playback
    assert pb.catch_up == pytest.approx(1.2)
    assert list(pb.limits.max_speed_pulses_s) == [MBOX_V] * 6


@pytest.mark.parametrize("absolute", [True, False])
def test_mbox_within_the_limit_on_its_clock_passes(absolute):
    # 10 ms stamps are played in 10 / 1.2 = 8.333 ms: 4166 pulses = 499 920 pulses/s
    emu = mbox.MboxEmulator(_mbox())
    _feed(emu, [10 * k for k in range(20)], _ramp_then_cruise(4166), absolute=absolute)
    assert emu.violations == [] and len(emu.trace) == 20


@pytest.mark.parametrize("absolute", [True, False])
def test_mbox_one_percent_over_at_fn012_1200_is_flagged(absolute):
    # 4209 pulses per 10 ms stamp: 420 900 pulses/s on the stamps (fine), 505 080 pulses/s
    # (1.0 % over) as the box plays them at Fn012 = 1200
    emu = mbox.MboxEmulator(_mbox())
    _feed(emu, [10 * k for k in range(20)], _ramp_then_cruise(4209), absolute=absolute)
    assert set(_kinds(emu)) == {("speed", i) for i in range(6)}
    assert len(_kinds(emu)) == 6 * 19  # every moving frame, not only queued ones
    assert "8.333 ms" in emu.violations[0].detail and "505080" in emu.violations[0].detail
    # as stamped (Fn012 = 1000) the same frames are within the limit
    plain = mbox.MboxEmulator(_mbox(Fn012=1000))
    _feed(plain, [10 * k for k in range(20)], _ramp_then_cruise(4209), absolute=absolute)
    assert plain.violations == []


def test_mbox_fn012_written_over_udp_changes_the_clock():
    emu = mbox.MboxEmulator(_mbox(Fn012=1000))
    emu.handle(mbox.RegisterWrite(1, 0x012, (1300,)).encode(), 0.0)  # FX Fn012 = 1300
    # 3847 pulses per 10 ms = 500 110 pulses/s at 1.3x: just over
    _feed(emu, [0, 10], [0, 3847])
    assert set(_kinds(emu)) == {("speed", i) for i in range(6)}
    emu2 = mbox.MboxEmulator(_mbox(Fn012=1000))
    emu2.handle(mbox.RegisterWrite(1, 0x012, (1300,)).encode(), 0.0)
    _feed(emu2, [0, 10], [0, 3846])  # 499 980 pulses/s
    assert emu2.violations == []


def test_mbox_plays_at_fn012_even_with_nothing_queued():
    # 5.3.3 states no buffer condition: a lone frame is played 1.2x as fast too, the box
    # then waits for the next one (the "staircase" the manual warns of)
    emu = mbox.MboxEmulator(_mbox())
    emu.handle(mbox.MotionFrame(True, 0, 0, (0,) * 6).encode(), 0.0)
    emu.handle(mbox.MotionFrame(True, 1, 100, (1000,) * 6).encode(), 0.1)
    emu.handle(mbox.RegisterRead(0, 0x3E, 1).encode(), 0.15)
    assert emu.playback.play_t == pytest.approx(0.06)  # 50 ms later: 60 ms of the frame
    assert emu.playback.depth == 1
    emu.handle(mbox.RegisterRead(0, 0x3E, 1).encode(), 0.19)
    assert emu.playback.play_t == pytest.approx(0.1)  # done after 100 / 1.2 = 83 ms
    assert emu.playback.depth == 0


def test_imax_one_percent_over_its_speed_is_flagged_and_at_the_limit_passes():
    # 10 ms frames (ramp from rest well inside 2.5e8 pulses/s^2)
    ok = imax.ImaxEmulator(_imax())
    _feed(ok, [10 * k for k in range(20)], _ramp_then_cruise(5000))  # 500 000 pulses/s
    assert ok.violations == []
    over = imax.ImaxEmulator(_imax())
    _feed(over, [10 * k for k in range(20)], _ramp_then_cruise(5050))  # 505 000 pulses/s
    assert set(_kinds(over)) == {("speed", i) for i in range(6)}


@pytest.mark.parametrize(("counts", "v_max"), [(10000, 500_000.0), (20000, 1_000_000.0)])
def test_imax_counts_per_rev_sets_the_speed_numbers(counts, v_max):
    # 3000 rpm = 50 turns/s: 500 000 pulses/s at 10000 counts per turn, 10^6 at 20000
    ctrl = dataclasses.replace(_imax(), counts_per_rev=counts)
    for step, flagged in ((round(v_max / 100) - 100, False), (round(v_max / 100) + 100, True)):
        emu = imax.ImaxEmulator(ctrl)
        _feed(emu, [10 * k for k in range(10)], _ramp_then_cruise(step, 10))
        assert bool(_kinds(emu, "speed")) is flagged, (counts, step, emu.violations[:1])
        assert _kinds(emu, "accel") == []


def test_imax_pa06_fast_forward_judges_frames_at_its_speed():
    # PA06 = 1 fast-forwards at 1.5x (the emulator's assumption): 4000 pulses per 10 ms
    # = 400 000 pulses/s on the stamps, 600 000 as possibly played
    emu = imax.ImaxEmulator(_imax(PA06=1))
    _feed(emu, [10 * k for k in range(5)], _ramp_then_cruise(4000, 5))
    assert set(_kinds(emu)) == {("speed", i) for i in range(6)}
    plain = imax.ImaxEmulator(_imax())
    _feed(plain, [10 * k for k in range(5)], _ramp_then_cruise(4000, 5))
    assert plain.violations == []


def test_imax_stroke_mm_above_the_lift_is_the_stroke():
    # stroke_mm = 100, PA40 lift 10 mm, 10000 counts per 5 mm turn = 2000 pulses/mm:
    # positions -20 000 .. 180 000
    ctrl = dataclasses.replace(_imax(), stroke_mm=100.0)
    emu = imax.ImaxEmulator(ctrl)
    frames = [(0, -20_000), (1000, 180_000), (2000, 180_001), (3000, -20_001)]
    emu.handle(imax.MotionFrame(True, 0, 0, (-20_000,) * 6).encode(), 0.0)
    for k, (ms, p) in enumerate(frames[1:], start=1):
        emu.handle(imax.MotionFrame(True, k, ms, (p,) * 6).encode(), ms / 1000)
    stroke = [v for v in emu.violations if v.kind == "stroke"]
    assert [(v.t_s, v.axis) for v in stroke] == [(2.0, i) for i in range(6)] + [
        (3.0, i) for i in range(6)
    ]
    assert "[-20000, 180000]" in stroke[0].detail


# -- acceleration ------------------------------------------------------------------------------
def test_imax_acceleration_step_is_flagged():
    # 1 ms frames from rest: speeds 240, 480 pulses/ms change by 2.4e8 pulses/s^2 (fine);
    # 240 -> 493 changes by 2.53e8 (1.2 % over)
    ok = imax.ImaxEmulator(_imax())
    _feed(ok, [0, 1, 2, 3, 4], [0, 0, 240, 720, 1200])
    assert ok.violations == []
    step = imax.ImaxEmulator(_imax())
    _feed(step, [0, 1, 2, 3], [0, 0, 240, 733])
    assert _kinds(step) == [("accel", i) for i in range(6)]
    assert step.violations[0].t_s == pytest.approx(0.003)
    assert "2.53e+08" in step.violations[0].detail
    # starting from rest is an acceleration too: 260 pulses in the first 1 ms
    jump = imax.ImaxEmulator(_imax())
    _feed(jump, [0, 1], [0, 260])
    assert _kinds(jump) == [("accel", i) for i in range(6)]


def test_acceleration_uses_the_mean_of_unequal_steps():
    # 2 ms at 100 000 pulses/s, then 1 ms: the change of speed counts over 1.5 ms
    # (twice the second divided difference). 200 + 460: 360 000 / 1.5 ms = 2.4e8 (fine);
    # 200 + 480: 380 000 / 1.5 ms = 2.53e8 (over). Judged over the last 1 ms only, both
    # would be over; over 2 ms, both within.
    ok = imax.ImaxEmulator(_imax())
    _feed(ok, [0, 2, 3], [0, 200, 660])
    assert ok.violations == []
    over = imax.ImaxEmulator(_imax())
    _feed(over, [0, 2, 3], [0, 200, 680])
    assert _kinds(over) == [("accel", i) for i in range(6)]


def test_deceleration_counts_too():
    emu = imax.ImaxEmulator(_imax())
    _feed(emu, [0, 1, 2, 3, 4], [0, 0, 240, 480, 480])  # 240 pulses/ms -> 0 in 1 ms: fine
    assert emu.violations == []
    emu = imax.ImaxEmulator(_imax())
    _feed(emu, [0, 1, 2, 3, 4, 5], [0, 0, 240, 480, 720, 720])  # fine
    assert emu.violations == []
    emu = imax.ImaxEmulator(_imax())
    _feed(emu, [0, 1, 2, 3, 4], [0, 0, 240, 490, 490])  # 250 -> 0 pulses/ms: 2.5e8, at it
    assert emu.violations == []
    emu = imax.ImaxEmulator(_imax())
    _feed(emu, [0, 1, 2, 3, 4], [0, 0, 240, 480, 460])  # 240 -> -20: 2.6e8
    assert _kinds(emu) == [("accel", i) for i in range(6)]


def test_mbox_sets_no_acceleration_limit():
    emu = mbox.MboxEmulator(_mbox(Fn012=1000))
    _feed(emu, [0, 1, 2, 3], [0, 0, 400, 0])  # 400 000 pulses/s reversed in 1 ms
    assert emu.violations == []


# -- frames with the same ms stamp -------------------------------------------------------------
@pytest.mark.parametrize("absolute", [True, False])
def test_mbox_moving_frames_with_the_same_stamp_are_flagged(absolute):
    emu = mbox.MboxEmulator(_mbox())
    _feed(emu, [0, 1, 1, 2, 2], [0, 10, 20, 30, 30], absolute=absolute)
    jogs = [v for v in emu.violations if v.kind == "jog"]
    assert len(jogs) == 1 and "frame 2" in jogs[0].detail and "Fn013 = 100 ms" in jogs[0].detail
    # frame 4 repeats frame 3's stamp without moving: nothing to flag
    assert {v.kind for v in emu.violations} == {"jog"}


@pytest.mark.parametrize("absolute", [True, False])
def test_imax_moving_frames_with_the_same_stamp_are_flagged(absolute):
    emu = imax.ImaxEmulator(_imax())
    _feed(emu, [0, 1, 1, 2], [0, 10, 20, 30], absolute=absolute)
    assert [(v.kind, v.detail.split(" ")[1]) for v in emu.violations] == [("jog", "2")]


def test_the_first_frame_of_a_run_is_no_same_stamp_jog():
    # time 0 of a run's first frame is its start, not a repeat of a stamp
    emu = mbox.MboxEmulator(_mbox())
    enc = emu.controller.frame_encoder(absolute_time=False)
    emu.handle(enc.encode(0.0, [0] * 6)[0], 0.0)
    emu.handle(enc.encode(0.01, [100] * 6)[0], 0.01)
    assert emu.violations == []


def test_a_stream_at_2khz_carries_same_ms_stamps_and_is_flagged():
    # 0.5 ms periods: every other frame repeats the previous frame's whole-ms stamp
    emu = mbox.MboxEmulator(_mbox())
    enc = emu.controller.frame_encoder()
    for k in range(10):
        emu.handle(enc.encode(k * 0.0005, [k] * 6)[0], k * 0.0005)
    assert sum(v.kind == "jog" for v in emu.violations) >= 4


# -- parameters written by the host ------------------------------------------------------------
def test_mbox_stroke_written_over_udp_is_checked_and_a_useless_one_is_reported():
    emu = mbox.MboxEmulator(_mbox(Fn012=1000))
    # Fn0C0 = 100 (10 mm) x Fn0C1 2000 pulses/mm: positions 0 .. 20 000
    emu.handle(mbox.RegisterWrite(1, 0x0C0, (100,)).encode(), 0.0)
    _feed(emu, [0, 100, 200], [0, 20_000, 20_001])
    assert _kinds(emu) == [("stroke", i) for i in range(6)]
    # Fn0C0 = 1 with Fn0C1 = 1: a stroke of 0.1 pulse, no usable limit: reported, no crash
    emu2 = mbox.MboxEmulator(_mbox(Fn012=1000))
    emu2.handle(mbox.RegisterWrite(1, 0x0C1, (1,)).encode(), 0.0)
    emu2.handle(mbox.RegisterWrite(1, 0x0C0, (1,)).encode(), 0.0)
    assert [v.kind for v in emu2.violations] == ["config"]


def test_imax_speed_written_over_udp_is_checked():
    emu = imax.ImaxEmulator(_imax())
    emu.handle(imax.RegisterWrite(imax.CHANNEL_PA, 0x07, (1500,)).encode(), 0.0)  # PA07
    _feed(emu, [10 * k for k in range(5)], _ramp_then_cruise(2600, 5))  # 260 000 > 250 000
    assert set(_kinds(emu)) == {("speed", i) for i in range(6)}
