"""Interface-string controllers (kind ``iface``): golden byte streams, round trips through
each board's firmware parser, garbage counted, the baud budget, and every exit parked as the
board reads it.

The golden streams are written by hand from each board's documented string; the parsers
(``_boards``) share no code with the encoder (``_format``). Where a ride is played, safety is
judged here on the decoded values, one frame per period of the send clock, with a checker of
this file's own against the limits table ``motioncue limits`` prints.
"""

from __future__ import annotations

import errno
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _ports import free_port
from motioncue import ConfigError, ProtocolError
from motioncue._config import ConfigReader, config_dir
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import controller_kind, load_controller
from motioncue.output.iface import (
    IfaceController,
    IfaceEmulator,
    InterfaceFormat,
    board_parser,
    controller_from_config,
)
from motioncue.pipeline import generate_ride, play_ride, save_ride
from motioncue.pipeline._stream import ParkFailed, PlayAborted
from motioncue.telemetry._recording import Recording, read_recording_csv
from motioncue.trajectory import ActuatorLimits

SRC = Path(__file__).resolve().parents[1] / "src"
CONFIGS = ["smc3", "eh-msc-4dof", "odrive-hexapod", "decimal6"]

# (config, axis values, the bytes its documentation's string gives, written by hand)
GOLDEN = [
    ("smc3", (512, 0, 1023), b"[A\x02\x00][B\x00\x00][C\x03\xff]"),
    ("smc3", (0x5B, 0x15D, 0x15B), b"[A\x00[][B\x01]][C\x01[]"),  # values that look like [ ]
    ("eh-msc-4dof", (0, 65535, 0x1234, 0x0100), b"P4\x00\x00\xff\xff\x12\x34\x01\x00!!"),
    ("odrive-hexapod", (0, 1, 0xABCD, 0xFFFF, 0x0F00, 42), b"H00000001ABCDFFFF0F00002A\n"),
    ("decimal6", (0, 7, 40, 2048, 4095, 100), b"0,7,40,2048,4095,100X"),
]


def _values_to_pulses(ctrl: IfaceController, values: tuple[int, ...]) -> list[int]:
    """Pulses that map exactly onto ``values`` (the bundled configs map one pulse per value)."""
    assert ctrl.pulses_hi - ctrl.pulses_lo == ctrl.fmt.full_scale
    return [ctrl.pulses_lo + v for v in values]


@pytest.mark.parametrize(("name", "values", "wire"), GOLDEN)
def test_golden_streams_both_ways(name: str, values: tuple[int, ...], wire: bytes) -> None:
    ctrl = load_controller(name)
    assert isinstance(ctrl, IfaceController)
    enc = ctrl.run_encoder(ctrl.frame_rate_hz)
    first = b"".join(enc.encode(0.0, _values_to_pulses(ctrl, values)))
    assert first == ctrl.start_bytes + wire
    assert b"".join(enc.encode(0.01, _values_to_pulses(ctrl, values))) == wire  # start once
    parser = board_parser(ctrl.firmware)
    assert parser.feed(ctrl.start_bytes + wire) == [values]
    assert parser.malformed == 0


def test_smc3_start_string_and_firmware_commands() -> None:
    ctrl = load_controller("smc3")
    assert ctrl.start_bytes == b"[ena]" and ctrl.fmt.bits == 10 and ctrl.baud == 500000
    parser = board_parser("smc3")
    assert parser.feed(b"[ena][sav][A\x01\x00]") == []  # targets complete a frame at C
    assert parser.commands == {"ena": 1, "sav": 1} and parser.enabled
    assert parser.feed(b"[B\x00\x01][C\x00\x02]") == [(256, 1, 2)]
    # a 5th byte that is not ']' drops the command; a value above 10 bits is refused
    assert parser.feed(b"[A\x00\x01X[A\x04\x00][C\x00\x00]") == [(256, 1, 0)]
    assert parser.malformed == 2


@pytest.mark.parametrize("name", CONFIGS)
@settings(max_examples=60)
@given(data=st.data())
def test_round_trip_through_the_firmware_parser(name: str, data: st.DataObject) -> None:
    ctrl = load_controller(name)
    full = ctrl.fmt.full_scale
    frames = data.draw(
        st.lists(st.tuples(*[st.integers(0, full)] * ctrl.n_axes), min_size=1, max_size=5)
    )
    cuts = data.draw(st.lists(st.integers(0, 200), max_size=4))
    enc = ctrl.run_encoder(ctrl.frame_rate_hz)
    stream = b"".join(b"".join(enc.encode(0.0, _values_to_pulses(ctrl, f))) for f in frames)
    assert all(len(stream) <= len(frames) * ctrl.frame_bytes + len(ctrl.start_bytes) for _ in [0])
    parser = board_parser(ctrl.firmware)
    got: list[tuple[int, ...]] = []
    pos = 0
    for cut in sorted(c % (len(stream) + 1) for c in cuts):  # any split of the stream
        got += parser.feed(stream[pos:cut])
        pos = max(pos, cut)
    got += parser.feed(stream[pos:])
    assert got == frames and parser.malformed == 0


@pytest.mark.parametrize("name", CONFIGS)
@settings(max_examples=80)
@given(blob=st.binary(max_size=300))
def test_random_bytes_are_only_counted(name: str, blob: bytes) -> None:
    ctrl = load_controller(name)
    parser = board_parser(ctrl.firmware)
    frames = parser.feed(blob)  # never raises
    assert all(len(f) == ctrl.n_axes for f in frames)
    assert all(0 <= v <= ctrl.fmt.full_scale for f in frames for v in f)


@pytest.mark.parametrize("name", ["smc3", "eh-msc-4dof", "odrive-hexapod"])
def test_garbage_then_a_good_frame_resynchronises(name: str) -> None:
    ctrl = load_controller(name)
    parser = board_parser(ctrl.firmware)
    good = b"".join(
        ctrl.run_encoder(ctrl.frame_rate_hz).encode(0.0, [ctrl.pulses_lo] * ctrl.n_axes)
    )
    assert parser.feed(b"\x00\x01\x02" + good) == [(0,) * ctrl.n_axes]
    assert parser.malformed == 3
    emu = IfaceEmulator(ctrl)
    emu.feed(good + b"\x00\x01" + good)
    assert emu.received == 2 and [(v.kind, v.detail) for v in emu.violations] == [
        ("malformed", "2 bytes or frames dropped")
    ]


def test_format_syntax_and_encodings() -> None:
    f = InterfaceFormat("<255><Axis2b>%<1>x<Axis1a>", ("Axis1a", "Axis2b"), 12, "hex")
    assert f.encoder().format([0xABC, 0x00F]) == b"\xff00F%\x01xABC"
    assert f.max_frame_bytes() == 1 + 3 + 1 + 1 + 1 + 3
    d = InterfaceFormat("<Axis1a>;<Axis2a>", ("Axis1a", "Axis2a"), 8, "decimal")
    assert d.encoder().format([255, 3]) == b"255;3" and d.max_frame_bytes() == 7
    b8 = InterfaceFormat("<Axis1a><Axis1b>", ("Axis1a", "Axis1b"), 8, "binary")
    assert b8.encoder().format([1, 254]) == b"\x01\xfe"
    with pytest.raises(ProtocolError, match="bit range"):
        b8.encoder().format([256, 0])
    for template, axes, bits, enc, match in [
        ("<Axis1a><Foo>", ("Axis1a",), 10, "binary", "token <Foo>"),
        ("<Axis1a><256>", ("Axis1a",), 10, "binary", "token <256>"),
        ("<Axis1a", ("Axis1a",), 10, "binary", "unmatched"),
        ("<Axis1a>", ("Axis1a", "Axis2a"), 10, "binary", "never sent"),
        ("<Axis2a>", ("Axis1a",), 10, "binary", "not among"),
        ("<Axis1a>", ("Axis1a",), 17, "binary", r"bits = 17"),
        ("<Axis1a>", ("Axis1a",), 10, "octal", "encoding"),
    ]:
        with pytest.raises(ConfigError, match=match):
            InterfaceFormat(template, axes, bits, enc)


def _smc3_config(**over: object) -> dict[str, object]:
    import tomllib

    data = tomllib.loads((config_dir("controllers") / "smc3.toml").read_text())
    data.pop("kind")
    data.update(over)
    return data


def test_a_rate_the_baud_cannot_carry_is_refused_with_the_maximum() -> None:
    # 15 bytes a frame x 10 bits at 9600 baud: at most 64 frames a second
    with pytest.raises(ConfigError, match=r"15 bytes a frame at 9600 baud .* at most 64 Hz"):
        controller_from_config(ConfigReader(_smc3_config(baud=9600), "t"), "slow")
    ok = controller_from_config(
        ConfigReader(_smc3_config(baud=9600, frame_rate_hz=50.0), "t"), "slow"
    )
    assert ok.max_frame_rate_hz == pytest.approx(64.0)
    with pytest.raises(ConfigError, match="at most 64 Hz"):
        ok.check_rate(100.0)
    ok.check_rate(64.0)
    ok.check_rate(40.0)
    with pytest.raises(ConfigError, match=r"at most 3333\.33 Hz"):
        load_controller("smc3").run_encoder(4000.0)
    with pytest.raises(ConfigError, match="at most 64 Hz"):
        IfaceEmulator(ok, rate_hz=65.0)


def test_encoder_refuses_a_position_outside_the_range() -> None:
    ctrl = load_controller("smc3")
    enc = ctrl.run_encoder(100.0)
    with pytest.raises(ProtocolError, match="pulses_range"):
        enc.encode(0.0, [0, 0, ctrl.pulses_hi + 1])


def test_the_emulator_catches_a_jump_and_passes_a_ramp() -> None:
    ctrl = load_controller("smc3")
    rate = ctrl.frame_rate_hz
    enc = ctrl.run_encoder(rate)
    emu = IfaceEmulator(ctrl)
    # a gentle ramp: 5 values a frame (500/s) with a 2-frame speed-up: within 2600/s
    pos = [0, 0, 1, 3, 6, 10, 15, 20, 25, 30]
    for p in pos:
        emu.feed(b"".join(enc.encode(0.0, [p, p, p])))
    assert emu.received == len(pos) and not emu.violations
    emu.feed(b"".join(enc.encode(0.0, [30, 30, 90])))  # 60 values in 10 ms: 6000/s
    kinds = {(v.kind, v.axis) for v in emu.violations}
    assert ("speed", 2) in kinds and ("accel", 2) in kinds and ("speed", 0) not in kinds
    trace = emu.trace
    np.testing.assert_allclose(trace.t_s[:3], [0.0, 0.01, 0.02])
    assert trace.positions[-1].tolist() == [30, 30, 90]


def test_registry_declares_the_kind() -> None:
    kind = controller_kind("iface")
    assert kind.emulator is not None and "udp" in kind.emulator_schemes
    assert "serial" in kind.links and "udp" in kind.links


# -- every exit parks, as the board reads it ---------------------------------------------
PLATFORM, CONTROLLER, RATE_HZ = "seat3-pot", "smc3", 100.0


@pytest.fixture(scope="module")
def rig() -> tuple[Any, Any, ActuatorLimits, np.ndarray]:
    platform = load_platform(PLATFORM)
    ctrl = load_controller(CONTROLLER)
    lim = ActuatorLimits.from_platform(platform, ctrl, rate_hz=RATE_HZ)
    return platform, ctrl, lim, platform.drives.to_pulses(platform.q_park)


@pytest.fixture(scope="module")
def ride(rig: Any) -> Any:
    platform, ctrl, lim, _ = rig
    rec = read_recording_csv(config_dir("recordings") / "lap.csv")
    keep = rec.t_s <= 1.0  # a short excerpt: the ride still ramps in and parks
    made, _ = generate_ride(
        Recording(rec.t_s[keep], rec.f[keep], rec.w[keep]), platform, ctrl,
        load_cueing(platform.default_preset), rate_hz=RATE_HZ, limits=lim,
    )  # fmt: skip
    return made


def check_board(stream: bytes, rig: Any, *, ends_parked: bool = True) -> float:
    """Decode ``stream`` as the SMC3 reads it and judge every frame against the limits
    table, one period apart, at rest at park first; returns the largest distance from park
    (values) reached."""
    platform, ctrl, lim, park = rig
    frames = np.array(board_parser("smc3").feed(stream), dtype=float)
    assert len(frames), "no frame on the wire"
    table = lim.to_pulses_table(platform)
    rows = table["actuators"] if isinstance(table, dict) else table
    lo = np.array([r["stroke_pulses"][0] for r in rows]) - ctrl.pulses_lo
    hi = np.array([r["stroke_pulses"][1] for r in rows]) - ctrl.pulses_lo
    v_max = np.array([r["max_speed_pulses_s"] for r in rows], dtype=float)
    a_max = np.array([r["max_accel_pulses_s2"] for r in rows], dtype=float)
    park_v = np.asarray(park) - ctrl.pulses_lo
    assert np.all(frames >= lo) and np.all(frames <= hi), "a frame leaves the stroke"
    p = np.vstack([park_v, park_v, frames])
    v = np.diff(p, axis=0) * RATE_HZ
    a = np.diff(v, axis=0) * RATE_HZ
    assert np.max(np.abs(v) / v_max) <= 1.0 + 1e-9, "speed over the limit"
    assert np.max(np.abs(a) / a_max) <= 1.0 + 1e-9, "acceleration over the limit"
    if ends_parked:
        np.testing.assert_array_equal(frames[-1], park_v, "the last frame is not at park")
        np.testing.assert_array_equal(frames[-2], park_v, "not at rest at the end")
    return float(np.max(np.abs(frames - park_v)))


class Sink:
    """Keeps what it sends; from send ``fail_at`` on, ``times`` sends raise ENOBUFS; an
    encoder failure is injected by ``bad_at`` (a position outside the range)."""

    def __init__(self, fail_at: int | None = None, times: int = 0) -> None:
        self.sent: list[bytes] = []
        self.calls = 0
        self.fail_at = fail_at
        self.times = times
        self.failures = 0

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self.calls += 1
        if self.fail_at is not None and self.calls >= self.fail_at and self.failures < self.times:
            self.failures += 1
            raise OSError(errno.ENOBUFS, "No buffer space available (injected)")
        self.sent.append(data)


class FaultyController:
    """The real controller whose encoder raises once, at its ``fail_at``-th frame."""

    def __init__(self, inner: Any, fail_at: int) -> None:
        self._inner, self.fail_at, self.calls = inner, fail_at, 0

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def run_encoder(self, *args: Any, **kwargs: Any) -> Any:
        inner = self._inner.run_encoder(*args, **kwargs)
        owner = self

        class Enc:
            clock = inner.clock  # the FrameEncoder protocol declares it (None for iface)

            def encode(self, *a: Any, **k: Any) -> list[bytes]:
                owner.calls += 1
                if owner.calls == owner.fail_at:
                    raise RuntimeError("encoder bug (injected)")
                return list(inner.encode(*a, **k))

        return Enc()


def test_a_whole_ride_stays_within_the_limits_and_ends_parked(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink()
    rep = play_ride(ride, platform, ctrl, lim, sink, paced=False)
    assert rep.ride_frames_sent == ride.n_frames
    stream = b"".join(sink.sent)
    assert stream.startswith(b"[ena][A")
    assert check_board(stream, rig) > 100  # it moved (values; 10 a mm)


def test_encoder_exception_parks(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink()
    with pytest.raises(PlayAborted, match="encoder bug") as info:
        play_ride(
            ride, platform, FaultyController(ctrl, ride.n_frames // 2), lim, sink, paced=False
        )
    rep = info.value.report
    assert (
        rep is not None and rep.ride_frames_sent == ride.n_frames // 2 - 1 and rep.park_frames > 0
    )
    assert check_board(b"".join(sink.sent), rig) > 50


def test_repeated_send_errors_park(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink(fail_at=ride.n_frames // 2, times=12)
    with pytest.raises(PlayAborted, match=r"ENOBUFS|No buffer space"):
        play_ride(ride, platform, ctrl, lim, sink, paced=False)
    assert check_board(b"".join(sink.sent), rig) > 50


def test_a_dead_link_says_the_park_failed(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink(fail_at=ride.n_frames // 2, times=10**9)
    with pytest.raises(ParkFailed, match="PARK FAILED"):
        play_ride(ride, platform, ctrl, lim, sink, paced=False)
    check_board(b"".join(sink.sent), rig, ends_parked=False)


def test_checker_catches_a_jump(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink()
    play_ride(ride, platform, ctrl, lim, sink, paced=False)
    frames = bytearray(b"".join(sink.sent))
    i = frames.index(b"[C", 5 + 15 * (ride.n_frames // 2))  # motor C mid-ride
    frames[i + 2] ^= 0x01  # 256 values away
    with pytest.raises(AssertionError, match=r"speed|acceleration"):
        check_board(bytes(frames), rig)


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_play_cli_signal_parks_on_the_emulator(
    sig: int, rig: Any, ride: Any, tmp_path: Path
) -> None:
    """``motioncue play`` to the SMC3 emulator on UDP, stopped by a signal mid-ride."""
    _, ctrl, _, park = rig
    path = save_ride(tmp_path / "lap.ride", ride)
    emu = IfaceEmulator(ctrl).start()
    rc, out, err = signal_when_moving(["play", str(path), "--target", emu.where], emu, park,
                                      50, sig)  # fmt: skip
    assert "Traceback" not in err, err
    assert rc == 130, err
    assert f"interrupted and parked ({signal.Signals(sig).name})" in out + err
    assert emu.malformed == 0
    assert_moved_then_parked(emu, np.asarray(park) - ctrl.pulses_lo, 50)


def test_bridge_sigint_parks_on_the_emulator(rig: Any) -> None:
    """``motioncue bridge`` (live F1 stream) to the SMC3 emulator, stopped by SIGINT."""
    from test_bridge import Sender

    _, ctrl, _, park = rig
    port = free_port()
    emu = IfaceEmulator(ctrl).start()
    cmd = ["bridge", "--source", f"f1:{port}", "--platform", PLATFORM, "--controller",
           CONTROLLER, "--rate", "100", "--fade", "0.3", "--quiet",
           "--target", emu.where]  # fmt: skip
    with Sender(port, 2024):
        rc, out, err = signal_when_moving(cmd, emu, park, 20, signal.SIGINT)
    assert "Traceback" not in err, err
    assert rc == 130, err
    assert "stopped by SIGINT; parked at rest" in out + err
    assert_moved_then_parked(emu, np.asarray(park) - ctrl.pulses_lo, 20)


def test_socket_free() -> None:
    """The emulator's UDP socket is released on stop (the port can be bound again)."""
    emu = IfaceEmulator(load_controller("smc3")).start()
    port = int(emu.where.rsplit(":", 1)[1])
    emu.stop()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", port))


def test_demo_picks_a_bundled_platform_the_controller_can_drive() -> None:
    """Issue 22: ``motioncue demo --controller smc3`` needs no --platform: the 3-axis SMC3,
    whose 10-bit values imply the pot drive, gets the platform that drive agrees with; a
    6-axis controller keeps the default hexapod, and one nothing fits is a clear error."""
    from motioncue._errors import ConfigError
    from motioncue.kinematics import load_platform
    from motioncue.output import load_controller
    from motioncue.pipeline._demo import _platform_for
    from motioncue.trajectory import ActuatorLimits

    smc3 = load_controller("smc3")
    name = _platform_for(smc3, 100.0)
    platform = load_platform(name)
    assert platform.n_actuators == smc3.n_axes == 3
    ActuatorLimits.from_platform(platform, smc3, rate_hz=100.0)  # agrees: no ConfigError
    with pytest.raises(ConfigError):  # the plain seat3's drive disagrees with the SMC3's values
        ActuatorLimits.from_platform(load_platform("seat3"), smc3, rate_hz=100.0)
    assert _platform_for(load_controller("mbox6"), 100.0) == "stewart6-linear"
    from types import SimpleNamespace

    five = SimpleNamespace(name="five", n_axes=5)  # no bundled platform has 5 actuators
    with pytest.raises(ConfigError, match="no bundled platform fits controller 'five'"):
        _platform_for(five, 100.0)  # type: ignore[arg-type]


def signal_when_moving(
    cmd: list[str], emu: Any, park: Any, away: int, sig: int
) -> tuple[int, str, str]:
    """Run ``motioncue`` ``cmd`` against the started ``emu``; once the board is ``away``
    pulses from ``park``, send ``sig``; returns (exit status, stdout, stderr). Stops the
    emulator."""
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    proc = subprocess.Popen([sys.executable, "-m", "motioncue", *cmd], env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        end = time.monotonic() + 90  # a bound for a process that never moves, not a timing check
        while time.monotonic() < end and proc.poll() is None:
            tr = emu.trace
            if len(tr.positions) and np.abs(tr.positions[-1] - park).max() > away:
                break
            time.sleep(0.01)
        proc.send_signal(sig)
        out, err = proc.communicate(timeout=90)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        time.sleep(0.1)
        emu.stop()
    return proc.returncode, out, err


def assert_moved_then_parked(emu: Any, park_v: Any, away: int) -> None:
    """The board's frames left park by more than ``away`` pulses and end on two park frames."""
    assert not emu.violations, emu.violations[:3]
    frames = np.array(emu.frames)
    assert np.abs(frames - park_v).max() > away  # it was moving when stopped
    np.testing.assert_array_equal(frames[-1], park_v)
    np.testing.assert_array_equal(frames[-2], park_v)


def test_never_skipping_late_frames_is_refused_for_a_board_without_a_buffer(
    rig: Any, ride: Any
) -> None:
    """resync_after_s=None sends late frames back to back: a buffered controller plays them
    on its own clock, the SMC3 would move as fast as they arrive. Refused before a send."""
    from motioncue.output import open_transport

    platform, ctrl, lim, _ = rig
    assert ctrl.buffer_frames <= 1
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as listener:
        listener.bind(("127.0.0.1", 0))
        listener.settimeout(0.2)
        port = listener.getsockname()[1]
        with open_transport(f"udp://127.0.0.1:{port}") as tr:
            with pytest.raises(ConfigError, match="has no buffer to play them on its own clock"):
                play_ride(ride, platform, ctrl, lim, tr, resync_after_s=None)
        with pytest.raises(TimeoutError):
            listener.recv(1024)  # nothing was sent
