"""EasySmc end to end.

* The per-frame bound of ``pulse_limits(rate)`` is exact: any frame sequence within it (random,
  at the bound, full reversals, after waits) is accepted by the encoder and every move ends
  within its frame's period on the controller's motion model; one pulse more is refused.
* ``generate`` refuses a rate the serial link cannot carry, before any work, naming the
  highest rate that works.
* The bundled lap -> ``generate`` -> ``play`` -> the EasySmc emulator: zero violations, every
  frame executed, every move inside its period, for the factory and the servo configs.

The wire bytes are read by a parser written here from the manual (ch. 5: frame layout and
checksum; 5.5.1: sign digit + 6-digit magnitude) and each move's duration by a profile written
here from 5.1.1 (start frequency, acceleration A, constant feed, deceleration B), checked
against a numerical integration; neither shares code with the encoder.
"""

from __future__ import annotations

import io
import math
import time
from collections.abc import Sequence
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st

from motioncue import ConfigError, LimitError
from motioncue._config import config_dir
from motioncue.cli import main
from motioncue.output import load_controller
from motioncue.output.easysmc import (
    Command,
    EasySmcController,
    EasySmcEmulator,
    Start,
    Unit,
    encode_command,
    send_commands,
)
from motioncue.pipeline import load_ride

STX, ETX = 0x02, 0x03

# -- an independent reading of the manual ------------------------------------------------------


def parse_serial(data: bytes) -> list[tuple[int, int, tuple[int, ...], bytes]]:
    """Split host bytes into ``(address, code, DAT words, raw frame)``.

    Manual ch. 5: STX + address (2 ASCII hex) + command code (2) + DATs (7 ASCII hex each) +
    start condition (1 ASCII digit) + ETX + checksum (2 ASCII hex: the low byte of the sum of
    the bytes from the address to ETX). Every byte but STX/ETX is ASCII, so ETX ends a frame.
    """
    out = []
    i = 0
    while i < len(data):
        assert data[i] == STX, f"byte {i} is {data[i]:#04x}, not STX"
        j = data.index(ETX, i)
        body = data[i + 1 : j + 1]
        assert int(data[j + 1 : j + 3], 16) == sum(body) & 0xFF, "checksum"
        text = body[:-1].decode("ascii")
        dats = text[4:-1]
        assert len(dats) % 7 == 0 and text[-1].isdigit()
        words = tuple(int(dats[k : k + 7], 16) for k in range(0, len(dats), 7))
        out.append((int(text[:2], 16), int(text[2:4], 16), words, data[i : j + 3]))
        i = j + 3
    return out


def signed(word: int) -> int:
    """5.5.1: the first of the 7 digits is the direction (0 positive, 1 negative), the other
    six the magnitude."""
    assert word >> 24 in (0, 1)
    return -(word & 0xFFFFFF) if word >> 24 else word & 0xFFFFFF


def move_time(dist: int, feed: float, f0: float, a: float, b: float) -> float:
    """5.1.1: a move starts at the start frequency f0, accelerates at A up to the feed, runs
    at the feed and decelerates at B so as to end at f0; a feed at or below f0 is run as a
    constant rate throughout; a move too short to reach the feed turns back at a lower peak."""
    if dist == 0:
        return 0.0
    if feed <= f0:
        return dist / feed
    t_up, t_down = (feed - f0) / a, (feed - f0) / b
    d_ramps = (f0 + feed) / 2 * (t_up + t_down)
    if d_ramps <= dist:
        return t_up + t_down + (dist - d_ramps) / feed
    peak = math.sqrt(f0 * f0 + 2 * dist / (1 / a + 1 / b))
    return (peak - f0) / a + (peak - f0) / b


def integrate(dist: float, feed: float, f0: float, a: float, b: float, dt: float = 1e-6) -> float:
    """Step the pulse rate: up at A towards the feed until the rest of the distance is what a
    deceleration at B to f0 takes."""
    if feed <= f0:
        return dist / feed
    done, rate, t = 0.0, f0, 0.0
    while done < dist:
        if dist - done <= (rate * rate - f0 * f0) / (2 * b):
            rate = max(rate - b * dt, f0)
        else:
            rate = min(rate + a * dt, feed)
        done += rate * dt
        t += dt
    return t


@pytest.mark.parametrize(
    ("d", "feed", "f0", "a", "b"),
    [
        (100, 1500, 2000, 20000, 20000),  # constant
        (112, 20000, 2000, 20000, 20000),  # triangle (factory settings, one 20 Hz frame)
        (3000, 40000, 2000, 2e6, 5e5),  # trapezoid, unequal ramps
        (20000, 400000, 400000, 2e7, 2e7),  # servo config: constant
    ],
)
def test_independent_move_time_matches_integration(
    d: int, feed: float, f0: float, a: float, b: float
) -> None:
    assert move_time(d, feed, f0, a, b) == pytest.approx(integrate(d, feed, f0, a, b), abs=3e-6)


def capacity(period_s: float, cap: float, f0: float, a: float, b: float) -> int:
    """Most whole pulses a move can cover within one period (the feed at most ``cap``; a
    higher feed is never slower, so the cap is the best), with a 1e-9 relative allowance
    for rounding: one pulse more is beyond doubt."""
    lo, hi = 0, 1
    t = period_s * (1 + 1e-9)
    while move_time(hi, cap, f0, a, b) <= t:
        hi *= 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if move_time(mid, cap, f0, a, b) <= t else (lo, mid)
    return lo


# -- playing frames on the controller's motion model --------------------------------------------


def unit_frames(
    data: bytes, axes: Sequence[str]
) -> list[list[tuple[int, int, tuple[int, ...], bytes]]]:
    """Group the commands of timed frames: per frame, each unit ends with its move (57, or
    5B + 5C) or its wait (19 with leading digit 1)."""
    frames: list[list[tuple[int, int, tuple[int, ...], bytes]]] = []
    current: list[tuple[int, int, tuple[int, ...], bytes]] = []
    ends = 0
    for cmd in parse_serial(data):
        current.append(cmd)
        _, code, words, _ = cmd
        if code in (0x57, 0x5C) or (code == 0x19 and words[0] >> 24 == 1):
            ends += 1
            if ends == len(axes):
                frames.append(current)
                current, ends = [], 0
    assert not current, "bytes after the last complete frame"
    return frames


def play_on_model(
    ctrl: EasySmcController, rate_hz: float, frames: list[bytes], lead: int = 3
) -> EasySmcEmulator:
    """Feed the emulator (with the controller description's frame checks on) the setup,
    homing and frames as a host keeping ``lead`` frames queued would; time is simulated."""
    emu = EasySmcEmulator(
        tuple(u.address for u in ctrl.units),
        clock=lambda: 0.0,
        controller=ctrl,
        frame_rate_hz=rate_hz,
    )
    setup = b"".join(encode_command(c) for c in ctrl.setup_commands())
    setup += b"".join(encode_command(c) for c in send_commands(ctrl, ["home"]))
    emu.feed(setup, 0.0)
    period = 1.0 / rate_hz
    for k, chunk in enumerate(frames):
        emu.feed(chunk, max(0, k - lead) * period)
    for m in emu.models.values():
        m.advance(1e9)
    return emu


def check_played(
    ctrl: EasySmcController,
    rate_hz: float,
    frames: list[bytes],
    targets: np.ndarray,
    start: Sequence[int],
) -> None:
    """Zero violations; each unit executes every frame to its target; by the independent
    profile every frame ends within its period (the k-th by (k + 1) periods) and the
    emulator's clock agrees."""
    emu = play_on_model(ctrl, rate_hz, frames)
    assert emu.violations == [], [str(v) for v in emu.violations[:5]]
    period = 1.0 / rate_hz
    data = b"".join(frames)
    f0 = ctrl.parameters["02_x_linear_start_hz"]
    i = 0
    for u in ctrl.units:
        n = len(u.axes)
        model = emu.models[u.address]
        trace = [e for e in model.trace if e.number > 0][-len(frames) :]
        assert len(trace) == len(frames)
        got = np.array([e.positions[:n] for e in trace])
        want = targets[:, i : i + n] - np.asarray(start[i : i + n])
        np.testing.assert_array_equal(got, want)
        # independent timing of this unit's commands
        clock = 0.0
        feed: tuple[int, ...] = (1, 1, 1)
        pending: list[int] = []
        k = 0
        for addr, code, words, _ in parse_serial(data):
            if addr != u.address:
                continue
            if code in (0xA3, 0xA6):
                feed = words  # A, feed, B
                assert feed[1] <= (ctrl.parameters["A3_feed_hz" if code == 0xA3 else "A6_feed_hz"])
                continue
            if code == 0x5B:
                pending = [signed(w) for w in words]
                continue
            if code in (0x57, 0x5C):
                deltas = pending + [signed(w) for w in words]
                pending = []
                clock += move_time(max(map(abs, deltas)), feed[1], f0, feed[0], feed[2])
            elif code == 0x19 and words[0] >> 24 == 1:
                clock += (words[0] & 0xFFFFFF) / 1e3
            else:
                continue
            assert clock <= (k + 1) * period + 1e-9, f"unit {addr}: frame {k} ends late"
            assert trace[k].t_s == pytest.approx(clock, abs=1e-6)
            k += 1
        assert k == len(frames)
        i += n


# -- the bound is exact -------------------------------------------------------------------------


def _controller(layout: str, f0: int, acc_a: int, acc_b: int, cap: int) -> EasySmcController:
    units = {
        "XYZ": (Unit(0, "XYZ"),),
        "XYZU": (Unit(0, "XYZU"),),
        "dual": (Unit(0, "XYZ"), Unit(1, "XYZ")),
    }[layout]
    params = {"02_x_linear_start_hz": f0, "09_y_linear_start_hz": f0, "14_z_linear_start_hz": f0}
    for prefix in ("A3", "A6"):
        params |= {f"{prefix}_acc_a_hz_s": acc_a, f"{prefix}_feed_hz": cap}
        params |= {f"{prefix}_acc_b_hz_s": acc_b}
    return EasySmcController("t", units, parameters=params)


def _encode(
    ctrl: EasySmcController, rate_hz: float, steps: np.ndarray, start: list[int]
) -> tuple[list[bytes], np.ndarray]:
    enc = ctrl.run_encoder(rate_hz, start)
    targets = np.asarray(start) + np.cumsum(steps, axis=0)
    frames = [b"".join(enc.encode(k / rate_hz, list(row))) for k, row in enumerate(targets)]
    return frames, targets


_FRACTION = st.one_of(st.sampled_from([-1.0, 1.0, 0.0, 1.0, -1.0]), st.floats(-1.0, 1.0))


@settings(max_examples=120)
@given(
    layout=st.sampled_from(["XYZ", "XYZU", "dual"]),
    f0=st.one_of(st.integers(1, 5000), st.integers(5000, 500000)),
    acc_a=st.one_of(st.integers(1000, 100000), st.integers(100000, 10**8)),
    acc_b=st.one_of(st.integers(1000, 100000), st.integers(100000, 10**8)),
    cap=st.one_of(st.integers(1000, 50000), st.integers(50000, 2_000_000)),
    rate_frac=st.one_of(st.just(1.0), st.floats(0.05, 1.0)),
    random_steps=st.lists(st.lists(_FRACTION, min_size=6, max_size=6), min_size=1, max_size=12),
    start_pulses=st.integers(-5000, 5000),
)
def test_frames_within_pulse_limits_are_accepted_and_on_time(
    layout: str,
    f0: int,
    acc_a: int,
    acc_b: int,
    cap: int,
    rate_frac: float,
    random_steps: list[list[float]],
    start_pulses: int,
) -> None:
    ctrl = _controller(layout, f0, acc_a, acc_b, cap)
    rate = ctrl.max_frame_rate_hz * rate_frac
    n = ctrl.n_axes
    try:
        per_frame = ctrl.pulse_limits(rate).max_speed_pulses_s / rate
    except ConfigError as exc:  # less than one pulse per frame: refused, and rightly so
        event("less than one pulse per frame")
        assert "less than one pulse" in str(exc)
        assert capacity(1 / rate, cap, f0, acc_a, acc_b) < 1 + 1e-9
        return
    d = round(float(per_frame[0]))
    event("bound " + ("< 10" if d < 10 else "< 1000" if d < 1000 else ">= 1000") + " pulses")
    assert np.allclose(per_frame, d) and ctrl.max_frame_pulses(rate) == (d,) * n
    # exact within one pulse: the true capacity of a period, by the independent profile
    assert capacity(1 / rate, cap, f0, acc_a, acc_b) in (d, d + 1)
    # rate-independent bound: the feed cap
    assert np.all(ctrl.pulse_limits(None).max_speed_pulses_s == cap)
    start = [start_pulses * (j + 1) % 7919 for j in range(n)]
    phase = np.array([1 if j % 2 else -1 for j in range(n)])
    sequences = {
        "random": np.array([[math.trunc(f * d) for f in row[:n]] for row in random_steps]),
        "at the bound": np.tile(np.full(n, d), (6, 1)),
        "full reversals": np.array([phase * d * (-1) ** k for k in range(8)]),
        "one pulse, a wait, then the bound": np.array(
            [np.full(n, 1), np.zeros(n, int), np.full(n, d), phase, np.full(n, -d)]
        ),
    }
    for name, steps in sequences.items():
        try:
            frames, targets = _encode(ctrl, rate, steps, start)
        except LimitError as exc:  # pragma: no cover - the claim under test
            raise AssertionError(f"{name}: frame refused within pulse_limits: {exc}") from exc
        check_played(ctrl, rate, frames, targets, start)
    # beyond what a period holds, from rest: refused (the bound is at most one pulse under)
    beyond = capacity(1 / rate, cap, f0, acc_a, acc_b) + 1
    assert beyond <= d + 2
    with pytest.raises(LimitError):
        _encode(ctrl, rate, np.array([np.eye(n, dtype=int)[0] * beyond]), start)


@pytest.mark.parametrize("rate", [5.0, 10.0, 20.0])
def test_factory_bound_figures_and_one_pulse_more_is_refused(rate: float) -> None:
    ctrl = load_controller("easysmc")
    d = ctrl.max_frame_pulses(rate)[0]
    # F0 T + T^2 / (2 (1/A + 1/B)) with F0 = 2 kHz, A = B = 20 kHz/s (the cap is not reached):
    # 5 Hz 600 (exactly, so 599 kept), 10 Hz 250 (249), 20 Hz 112.5 (112)
    t = 1 / rate
    assert d == math.ceil(2000 * t + t * t / (2 * 1e-4)) - 1
    lim = ctrl.pulse_limits(rate)
    assert np.all(lim.max_speed_pulses_s == d * rate) and not lim.has_accel
    assert f"{d} pulses per frame" in lim.sources["v_max"]
    over = math.floor(2000 * t + t * t / (2 * 1e-4)) + 1
    for steps in ([over, 0, 0], [0, -over, 0]):
        enc = ctrl.run_encoder(rate, [0, 0, 0])
        with pytest.raises(LimitError, match="accelerations"):
            enc.encode(0.0, steps)
    # a steady run one pulse over is refused too, however the previous frames ended
    enc = ctrl.run_encoder(rate, [0, 0, 0])
    with pytest.raises(LimitError):
        for k in range(5):
            enc.encode(k * t, [over * (k + 1), 0, 0])


def test_emulator_checks_frames_with_the_descriptions_numbers() -> None:
    """Frames one pulse over the bound, or at a feed over the cap, are flagged by the
    emulator given the description and the rate; the same bytes pass a bare emulator."""
    ctrl = load_controller("easysmc")
    rate = 20.0
    d = ctrl.max_frame_pulses(rate)[0]

    def frame(feed: int, dx: int) -> bytes:
        return encode_command(Command(0xA3, (20000, feed, 20000), Start.SEQUENCE, 0)) + (
            encode_command(Command.move(0x57, [dx, 0, 0], Start.SEQUENCE, 0))
        )

    setup = b"".join(
        encode_command(c) for c in ctrl.setup_commands() + send_commands(ctrl, ["home"])
    )
    for checked in (True, False):
        opts = {"controller": ctrl, "frame_rate_hz": rate} if checked else {}
        emu = EasySmcEmulator((0,), clock=lambda: 0.0, **opts)
        emu.feed(setup, 0.0)
        emu.feed(frame(2500, d), 0.0)  # at the bound: fine
        emu.feed(frame(2500, d + 1), 0.0)  # one pulse over (as early as the last was late)
        emu.feed(frame(2500, d + 5), 0.0)  # five over: 2 ms longer than the period
        emu.feed(frame(30000, 5), 0.0)  # feed above the 20 kHz cap
        kinds = sorted({v.kind for v in emu.violations})
        assert kinds == (["feed", "late", "speed"] if checked else [])
    with pytest.raises(ConfigError, match="needs the controller"):
        EasySmcEmulator((0,), frame_rate_hz=rate)


# -- generate refuses what the link cannot carry --------------------------------------------------


def _cli(*argv: str) -> tuple[int, str, str]:
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            code = main(list(argv))
        except SystemExit as exc:
            code = int(exc.code or 0)
    return code, out.getvalue(), err.getvalue()


@pytest.mark.parametrize(
    ("controller", "rate", "top"), [("easysmc", 100, "23.2"), ("easysmc-dual", 20, "11.6")]
)
def test_generate_refuses_a_rate_the_link_cannot_carry(
    tmp_path: Path, controller: str, rate: int, top: str
) -> None:
    out = tmp_path / "r.ride"
    platform = "seat3" if controller == "easysmc" else "stewart6-linear"
    # the input does not exist: the rate is refused before anything is read
    code, _, err = _cli(
        "generate", "--input", str(tmp_path / "missing.csv"), "--platform", platform,
        "--controller", controller, "--rate", str(rate), "--out", str(out),
    )  # fmt: skip
    assert code == 2
    (line,) = [ln for ln in err.splitlines() if "error" in ln]
    assert line.startswith("motioncue generate: error: EasySmc link cannot carry")
    assert f"highest rate this link carries is {top} Hz" in line
    assert "Traceback" not in err and not out.exists()
    ctrl = load_controller(controller)
    with pytest.raises(ConfigError, match=f"{top} Hz"):
        ctrl.check_rate(float(rate))
    ctrl.check_rate(math.floor(ctrl.max_frame_rate_hz))


# -- the bundled lap, end to end ----------------------------------------------------------------


def _generate_and_play(
    tmp_path: Path, platform: str, controller: str, rate: float, lap: Path
) -> tuple[Any, bytes]:
    ride_path = tmp_path / f"{controller}.ride"
    code, out, err = _cli(
        "generate", "--quiet", "--input", str(lap), "--platform", platform,
        "--controller", controller, "--rate", f"{rate:g}", "--out", str(ride_path),
    )  # fmt: skip
    assert code == 0, err
    # the frame check passed ("(OK)", or "(frames within the limits; WARNING: N % of the
    # poses clamped)" when the preset asks more than the seat gives: issue 14)
    assert "(OK)" in out or "(frames within the limits; WARNING: " in out
    assert "VIOLATED" not in out
    bin_path = tmp_path / f"{controller}.bin"
    code, out, err = _cli("play", str(ride_path), "--target", f"file:{bin_path}")
    assert code == 0, err
    return load_ride(ride_path), bin_path.read_bytes()


@pytest.mark.parametrize(
    ("controller", "platform", "rate"),
    [
        ("easysmc", "seat3", 20.0),
        ("easysmc-servo", "seat3", 20.0),
        ("easysmc-dual", "stewart6-linear", 10.0),
    ],
)
def test_bundled_lap_ride_plays_on_the_emulator(
    tmp_path: Path, controller: str, platform: str, rate: float
) -> None:
    ctrl = load_controller(controller)
    lap = config_dir("recordings") / "lap.csv"
    ride, data = _generate_and_play(tmp_path, platform, controller, rate, lap)
    assert ride.rate_hz == rate and ride.controller == controller
    frames = [b"".join(c[3] for c in f) for f in unit_frames(data, [u.axes for u in ctrl.units])]
    # every ride frame was sent (play parks nothing more: the ride ends parked)
    assert len(frames) == ride.n_frames
    start = [int(p) for p in ride.pulses[0]]
    check_played(ctrl, rate, frames, ride.pulses, start)
    d = ctrl.max_frame_pulses(rate)[0]
    steps = np.abs(np.diff(ride.pulses, axis=0))
    assert steps.max() <= d
    if controller == "easysmc-servo":  # a usable ride: well above the factory's 1 mm/s
        assert steps.max() * rate / 2000 > 20  # mm/s


def test_servo_ride_over_the_pty_emulator(tmp_path: Path) -> None:
    """``generate`` then ``send home`` and ``play`` through the CLI, real time, to the
    pseudo-terminal emulator on a 19200-baud line checking with the description's numbers."""
    lap = tmp_path / "lap.csv"
    lines = (config_dir("recordings") / "lap.csv").read_text().splitlines()
    lap.write_text("\n".join(lines[:101]) + "\n")  # the first second
    ctrl = load_controller("easysmc-servo")
    rate = 20.0
    ride_path = tmp_path / "s.ride"
    code, _, err = _cli(
        "generate", "--quiet", "--input", str(lap), "--platform", "seat3",
        "--controller", "easysmc-servo", "--rate", "20", "--out", str(ride_path),
    )  # fmt: skip
    assert code == 0, err
    ride = load_ride(ride_path)
    emu = EasySmcEmulator((0,), line_baud=ctrl.baud, controller=ctrl, frame_rate_hz=rate).start()
    try:
        target = f"serial://{emu.path}?baud={ctrl.baud}"
        code, out, err = _cli("send", "--controller", "easysmc-servo", "--target", target, "home")
        assert code == 0, err + out
        # every frame must reach the drive, which plays its buffer on its own clock: a
        # player held up by a busy machine sends late frames instead of skipping them
        code, out, err = _cli("play", str(ride_path), "--target", target,
                              "--resync-after-ms", "0")  # fmt: skip
        assert code == 0, err
        model = emu.models[0]
        deadline = time.monotonic() + 10.0
        while time.monotonic() < deadline:  # let the queued moves finish
            emu.sync()
            if model.last_done >= model.received:
                break
            time.sleep(0.05)
    finally:
        emu.stop()
    assert emu.violations == [], [str(v) for v in emu.violations[:5]]
    moves = [e for e in emu.trace if e.number > 0]
    got = np.array([e.positions[:3] for e in moves[-ride.n_frames :]])
    np.testing.assert_array_equal(got, ride.pulses)
