"""Fault injection: every way out of ``play`` and ``bridge`` parks within the limits.

For both verbs: an exception in the encoder, one and repeated send errors, SIGINT, SIGINT
twice and three times (the later ones during the park), SIGTERM, SIGHUP, SIGQUIT, garbage
telemetry (bridge), a bad output value mid-ride (play: a DAC above Fn078; bridge: a position
the controller's own stroke refuses). Each run must end with the last frame at the park
position and at rest, with every frame inside the limits table.

Safety is judged on the datagrams as the controller reads them, by a decoder and a checker
written here from the SC-MBOX manual (section 4.2.8, function 0x1301): a 12-byte header of six
big-endian u16 (confirm 0x55AA, pass 0, function, channel 0 = 3 axes / 1 = 6 axes, who
accept, who reply), the frame number u32, the time u32 in whole milliseconds since the run's
first frame, n x i32 motor positions in encoder pulses, then BaseDout, DAC1, DAC2, ExtDout u16.
Speed and acceleration are taken on those millisecond stamps (the controller's clock), with
the second divided difference for non-uniform steps, against the numbers of
``ActuatorLimits.to_pulses_table`` (the table ``motioncue limits`` prints). Nothing here
uses the planner's, the limiter's or the package's decoders.
"""

from __future__ import annotations

import dataclasses
import errno
import math
import os
import signal
import socket
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import _loopback as lb
from _ports import free_port
from motioncue import LimitError
from motioncue._config import config_dir
from motioncue.cli import main
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, open_transport
from motioncue.output._transports_udp import UdpTransport
from motioncue.output.mbox import MboxEmulator
from motioncue.pipeline import generate_ride, play_ride, save_ride
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.pipeline._stream import OutputStage, ParkFailed, PlayAborted
from motioncue.telemetry import TelemetrySample, open_source
from motioncue.telemetry._recording import Recording, read_recording_csv
from motioncue.trajectory import ActuatorLimits
from test_bridge import Sender

SRC = Path(__file__).resolve().parents[1] / "src"
PLATFORM, CONTROLLER = "stewart6-linear", "mbox6"
RATE_HZ = 100.0
GATE = GateConfig(timeout_s=0.25, fade_out_s=0.3, fade_in_s=0.3)


# -- the controller's view: decoder and checker from the manual ------------------------------
HEAD = struct.Struct(">6H")
NUMBER_TIME = struct.Struct(">II")


@dataclasses.dataclass
class Wire:
    """Frames as the controller reads them."""

    number: np.ndarray  # (N,) frame numbers
    t_ms: np.ndarray  # (N,) whole-ms time stamps
    pulses: np.ndarray  # (N, n) motor positions
    outputs: np.ndarray  # (N, 4) BaseDout, DAC1, DAC2, ExtDout


def decode_wire(datagrams: list[bytes]) -> Wire:
    """The 0x1301 frames among ``datagrams`` (register reads and anything else skipped)."""
    numbers, times, pulses, outputs = [], [], [], []
    for d in datagrams:
        if len(d) < HEAD.size:
            continue
        confirm, passcode, function, channel, _who_a, _who_r = HEAD.unpack_from(d)
        if confirm != 0x55AA or passcode != 0 or function != 0x1301:
            continue
        assert channel in (0, 1), f"frame channel {channel}"
        n = 3 if channel == 0 else 6
        assert len(d) == HEAD.size + NUMBER_TIME.size + 4 * n + 8, "frame of the wrong size"
        number, t_ms = NUMBER_TIME.unpack_from(d, HEAD.size)
        off = HEAD.size + NUMBER_TIME.size
        pulses.append(struct.unpack_from(f">{n}i", d, off))
        outputs.append(struct.unpack_from(">4H", d, off + 4 * n))
        numbers.append(number)
        times.append(t_ms)
    assert numbers, "no frame on the wire"
    return Wire(
        np.asarray(numbers, dtype=np.int64),
        np.asarray(times, dtype=np.int64),
        np.asarray(pulses, dtype=np.int64),
        np.asarray(outputs, dtype=np.int64),
    )


def split_file(blob: bytes, n_axes: int) -> list[bytes]:
    """A ``file:`` target's bytes: MBOX frames back to back."""
    size = HEAD.size + NUMBER_TIME.size + 4 * n_axes + 8
    assert len(blob) % size == 0
    return [blob[i : i + size] for i in range(0, len(blob), size)]


def limits_table(platform_name: str = PLATFORM, controller_name: str = CONTROLLER) -> Any:
    platform = load_platform(platform_name)
    ctrl = load_controller(controller_name)
    return ActuatorLimits.from_platform(platform, ctrl).to_pulses_table(platform)


def check_wire(
    wire: Wire, table: Any, start: np.ndarray, park: np.ndarray, *, ends_parked: bool = True
) -> float:
    """Assert the frames keep every limit on the controller's clock, starting at rest at
    ``start`` and (``ends_parked``) ending at rest at ``park``; returns the largest
    distance from park (pulses) the frames reached."""
    rows = table["actuators"] if isinstance(table, dict) else table
    lo = np.array([r["stroke_pulses"][0] for r in rows], dtype=float)
    hi = np.array([r["stroke_pulses"][1] for r in rows], dtype=float)
    v_max = np.array([r["max_speed_pulses_s"] for r in rows], dtype=float)
    a_max = np.array([r["max_accel_pulses_s2"] for r in rows], dtype=float)
    # one run: numbered 0, 1, 2 ... (no frame lost or skipped), time never going back
    np.testing.assert_array_equal(wire.number, np.arange(len(wire.number)))
    t = wire.t_ms.astype(float) / 1000.0
    assert t[0] == 0.0 and np.all(np.diff(t) > 0), "time stamps must increase"
    p = wire.pulses.astype(float)
    assert np.all(p >= lo) and np.all(p <= hi), "a frame leaves the stroke"
    # at rest at the start: two earlier samples at the start position, one period apart
    h0 = t[1] - t[0] if len(t) > 1 else 1.0 / RATE_HZ
    tt = np.concatenate([[t[0] - 2 * h0, t[0] - h0], t])
    pp = np.vstack([start, start, p]).astype(float)
    h = np.diff(tt)[:, None]
    v = np.diff(pp, axis=0) / h
    a = 2.0 * (v[1:] - v[:-1]) / (h[1:] + h[:-1])
    worst_v = float(np.max(np.abs(v) / v_max))
    worst_a = float(np.max(np.abs(a) / a_max))
    assert worst_v <= 1.0 + 1e-9, f"speed {worst_v:.4f} of the limit"
    assert worst_a <= 1.0 + 1e-9, f"acceleration {worst_a:.4f} of the limit"
    if ends_parked:
        np.testing.assert_array_equal(wire.pulses[-1], park, "the last frame is not at park")
        np.testing.assert_array_equal(wire.pulses[-2], park, "not at rest at the end")
        np.testing.assert_array_equal(wire.outputs[-1], 0, "effect outputs not zero at park")
    return float(np.max(np.abs(p - park)))


# -- set-ups -------------------------------------------------------------------------------
def _lap(seconds: float) -> Recording:
    rec = read_recording_csv(config_dir("recordings") / "lap.csv")
    keep = rec.t_s <= seconds
    return Recording(rec.t_s[keep], rec.f[keep], rec.w[keep])


@pytest.fixture(scope="module")
def rig() -> tuple[Any, Any, ActuatorLimits, np.ndarray]:
    platform = load_platform(PLATFORM)
    ctrl = load_controller(CONTROLLER)
    lim = ActuatorLimits.from_platform(platform, ctrl)
    return platform, ctrl, lim, platform.drives.to_pulses(platform.q_park)


@pytest.fixture(scope="module")
def ride(rig: Any) -> Any:
    platform, ctrl, lim, _ = rig
    made, _ = generate_ride(_lap(5.0), platform, ctrl, load_cueing("racing-hexapod"),
                            rate_hz=RATE_HZ, limits=lim)  # fmt: skip
    return made


@pytest.fixture(scope="module")
def ride_path(ride: Any, tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("fault") / "lap.ride"
    save_ride(path, ride)
    return path


class FaultyController:
    """A real controller whose frame encoder raises once, at its ``fail_at``-th frame."""

    def __init__(self, inner: Any, fail_at: int) -> None:
        self._inner = inner
        self.fail_at = fail_at
        self.calls = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def frame_encoder(self, *args: Any, **kwargs: Any) -> Any:
        return FaultyEncoder(self._inner.frame_encoder(*args, **kwargs), self)

    def run_encoder(self, *args: Any, **kwargs: Any) -> Any:  # what the output stage calls
        return FaultyEncoder(self._inner.run_encoder(*args, **kwargs), self)


class FaultyEncoder:
    def __init__(self, inner: Any, owner: FaultyController) -> None:
        self._inner = inner
        self._owner = owner

    def __getattr__(self, name: str) -> Any:
        return getattr(self._inner, name)

    def encode(self, *args: Any, **kwargs: Any) -> list[bytes]:
        owner = self._owner
        owner.calls += 1
        if owner.calls == owner.fail_at:
            raise RuntimeError("encoder bug (injected)")
        return list(self._inner.encode(*args, **kwargs))


class FlakyTransport:
    """Keeps what it sends; from send call ``fail_at`` on, ``times`` calls raise ENOBUFS."""

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


# -- play, in process ---------------------------------------------------------------------
def test_play_encoder_exception_parks(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, park = rig
    tr = FlakyTransport()
    with pytest.raises(PlayAborted, match="encoder bug") as info:
        play_ride(ride, platform, FaultyController(ctrl, 300), lim, tr, paced=False)
    rep = info.value.report
    assert rep is not None and rep.ride_frames_sent == 299 and rep.park_frames > 0
    wire = decode_wire(tr.sent)
    assert len(wire.number) == rep.frames_sent
    assert check_wire(wire, limits_table(), park, park) > 5000  # it was moving


def test_play_one_send_error_is_retried_and_the_ride_finishes(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, park = rig
    tr = FlakyTransport(fail_at=300, times=1)
    rep = play_ride(ride, platform, ctrl, lim, tr, paced=False)
    assert not rep.interrupted and rep.ride_frames_sent == ride.n_frames
    assert rep.send_errors == 1 and tr.failures == 1
    wire = decode_wire(tr.sent)
    check_wire(wire, limits_table(), park, park)
    np.testing.assert_array_equal(wire.pulses[: ride.n_frames], ride.pulses)  # nothing lost


def test_play_repeated_send_errors_stop_the_ride_and_park(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, park = rig
    tr = FlakyTransport(fail_at=300, times=12)  # more than the retries of one frame
    with pytest.raises(PlayAborted, match=r"ENOBUFS|No buffer space") as info:
        play_ride(ride, platform, ctrl, lim, tr, paced=False)
    rep = info.value.report
    assert rep is not None and rep.ride_frames_sent == 299 and rep.send_errors == 12
    assert check_wire(decode_wire(tr.sent), limits_table(), park, park) > 5000


def test_play_dead_link_says_the_park_failed(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, park = rig
    tr = FlakyTransport(fail_at=300, times=10**9)
    t0 = time.monotonic()
    with pytest.raises(ParkFailed, match="PARK FAILED"):
        play_ride(ride, platform, ctrl, lim, tr, paced=False)
    # gives up instead of retrying for ever; not a timing check (it takes well under a second
    # on an idle machine): only a park that keeps retrying trips 60 s
    assert time.monotonic() - t0 < 60.0
    # what did go out is still within the limits (it cannot end parked)
    check_wire(decode_wire(tr.sent), limits_table(), park, park, ends_parked=False)


def test_play_bad_output_value_mid_ride_parks_with_outputs_at_zero(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, park = rig
    dacs = np.zeros_like(ride.dacs)
    dacs[100:400] = 5000
    dacs[350, 0] = ctrl.parameters["Fn078"] + 1  # DAC1 above full scale
    bad = dataclasses.replace(ride, dacs=dacs)
    tr = FlakyTransport()
    with pytest.raises(PlayAborted, match="Fn078") as info:
        play_ride(bad, platform, ctrl, lim, tr, paced=False)
    assert info.value.report is not None and info.value.report.ride_frames_sent == 350
    wire = decode_wire(tr.sent)
    assert check_wire(wire, limits_table(), park, park) > 5000
    assert np.all(wire.outputs[100:350, 1] == 5000)  # the ride's DAC until the bad value
    assert np.all(wire.outputs[350:] == 0)  # parking: effect outputs zero


def test_play_cli_encoder_exception_is_one_line_and_parks(
    ride_path: Path, tmp_path: Path, rig: Any, monkeypatch: pytest.MonkeyPatch,
    capsys: pytest.CaptureFixture[str],
) -> None:  # fmt: skip
    import motioncue.output

    _, ctrl, _, park = rig
    monkeypatch.setattr(
        motioncue.output, "load_controller", lambda name: FaultyController(ctrl, 250)
    )
    out = tmp_path / "raw.bin"
    assert main(["play", str(ride_path), "--target", f"file:{out}"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    errors = [ln for ln in err.splitlines() if "error" in ln]
    assert len(errors) == 1 and errors[0].startswith("motioncue play: error: ride stopped at")
    assert "parked" in errors[0]
    wire = decode_wire(split_file(out.read_bytes(), 6))
    assert check_wire(wire, limits_table(), park, park) > 2000


def test_play_refuses_speed_on_a_live_link(
    ride_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.bind(("127.0.0.1", 0))
        sink.settimeout(0.3)
        target = f"udp://127.0.0.1:{sink.getsockname()[1]}"
        assert main(["play", str(ride_path), "--speed", "10", "--target", target]) == 2
        with pytest.raises(TimeoutError):
            sink.recv(100)  # nothing was sent
    assert "--speed 10 is only for pcap: and file:" in capsys.readouterr().err


def test_refused_frames_are_counted_and_the_final_park_frame_confirmed(rig: Any, ride: Any) -> None:
    """A controller whose buffer overflows (frames sent 3x faster than it plays them, as
    ``--speed 3`` did): the refusals are counted from its replies, and the final park frame
    is sent again until it is taken, so the platform still ends at park."""
    platform, ctrl, lim, park = rig
    emu = MboxEmulator(dataclasses.replace(ctrl, buffer_frames=64))
    with emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        rep = play_ride(ride, platform, ctrl, lim, tr, speed=3.0, spin_s=0.0,
                        throttle=lambda sent: None)  # fmt: skip
        deadline = time.monotonic() + 5
        while emu.received < rep.frames_sent and time.monotonic() < deadline:
            time.sleep(0.01)
        refused = emu.refused_frames
        last = emu.trace.positions[-1]
    assert refused > 100 and rep.refused_frames == refused
    assert rep.frame_replies == rep.frames_sent
    np.testing.assert_array_equal(last, park)


# -- bridge, in process -------------------------------------------------------------------
class HeldSource:
    """A telemetry source whose newest sample is a strong, steady cue (re-stamped on read)."""

    def __init__(self) -> None:
        self.stats = {"samples": 0, "datagrams": 0}
        self.k = 0

    def latest(self) -> TelemetrySample:
        self.k += 1
        t = self.k / RATE_HZ
        f = (4.0 * math.sin(2 * math.pi * 0.5 * t), 3.0, 9.80665)
        w = (0.0, 0.0, 0.6 * math.sin(2 * math.pi * 0.5 * t))
        self.stats["samples"] += 1
        return TelemetrySample(time.perf_counter(), f, w, False, "test")


def _run_bridge(
    rig: Any, controller: Any, transport: Any, *, until: Callable[[Bridge], bool], live_s: float
) -> Any:
    platform, _, lim, _ = rig
    bridge = Bridge(platform, controller, load_cueing("racing"), HeldSource(), transport, lim,
                    BridgeConfig(RATE_HZ, GATE, switch_interval_s=None))  # fmt: skip
    bridge.start()
    end = time.monotonic() + live_s
    while time.monotonic() < end and bridge.running and not until(bridge):
        time.sleep(0.01)
    bridge.stop()
    # as the CLI does: the park takes as long as it takes (a loaded machine may need longer
    # than stop()'s own wait); the frames are judged once the loop has ended
    assert bridge.wait(60.0), "the bridge loop did not end"
    return bridge.stats


def test_bridge_encoder_exception_parks(rig: Any) -> None:
    _, ctrl, _, park = rig
    tr = FlakyTransport()
    st = _run_bridge(rig, FaultyController(ctrl, 120), tr, until=lambda b: False, live_s=3.0)
    assert st.state == "failed" and st.error is not None and "encoder bug" in st.error
    assert "PARK FAILED" not in st.error
    assert check_wire(decode_wire(tr.sent), limits_table(), park, park) > 5000


def test_bridge_one_send_error_is_retried(rig: Any) -> None:
    _, ctrl, _, park = rig
    tr = FlakyTransport(fail_at=100, times=1)
    st = _run_bridge(rig, ctrl, tr, until=lambda b: b.stats.frames_sent > 130, live_s=3.0)
    assert st.state == "stopped" and st.error is None and st.send_errors == 1
    assert check_wire(decode_wire(tr.sent), limits_table(), park, park) > 5000


def test_bridge_repeated_send_errors_park(rig: Any) -> None:
    _, ctrl, _, park = rig
    tr = FlakyTransport(fail_at=100, times=12)
    st = _run_bridge(rig, ctrl, tr, until=lambda b: False, live_s=3.0)
    assert st.state == "failed" and st.error is not None and "No buffer space" in st.error
    assert "PARK FAILED" not in st.error
    assert check_wire(decode_wire(tr.sent), limits_table(), park, park) > 5000


def test_bridge_dead_link_says_the_park_failed(rig: Any) -> None:
    _, ctrl, _, park = rig
    tr = FlakyTransport(fail_at=100, times=10**9)
    st = _run_bridge(rig, ctrl, tr, until=lambda b: False, live_s=4.0)
    assert st.state == "failed" and st.error is not None and st.error.startswith("PARK FAILED")
    check_wire(decode_wire(tr.sent), limits_table(), park, park, ends_parked=False)


@pytest.mark.parametrize("live_s", [0.4, 0.8, 1.2, 1.8])
def test_bridge_within_the_controllers_own_stroke_parks(rig: Any, live_s: float) -> None:
    """The controller's own stroke (Fn0C0 = 60 mm) is narrower than the limits table's: the
    stage plans within it from the start, so no frame is refused, and the park, whenever
    the bridge is stopped (toward that stroke end or not), is accepted. Before, a frame
    beyond Fn0C0 was refused while the platform moved outward, and it could not brake
    within Fn0C0: the park frames were refused too ("PARK FAILED after 0 park frames")."""
    _, ctrl, _, park = rig
    narrow = ctrl.with_parameters(Fn0C0=600)
    tr = FlakyTransport()
    # stopped after live_s of frames on the bridge's own clock, not of the test's wall clock:
    # a fresh clone's quiet run (four workers on two cores) stopped it after 0.4 s of wall
    # time with the platform at 57384 of its 120000 pulses, short of the stroke end
    n_live = round(live_s * RATE_HZ)
    st = _run_bridge(rig, narrow, tr, until=lambda b: b.stats.frames_sent >= n_live,
                     live_s=120.0)  # fmt: skip
    assert st.state == "stopped" and st.error is None, st.error
    assert any("Fn0C0" in n for n in st.notes), st.notes
    # judged against the controller's own stroke, read from its parameters, not the planner
    lo, hi = narrow.stroke_pulses
    table = [dict(r, stroke_pulses=[max(r["stroke_pulses"][0], lo), min(r["stroke_pulses"][1], hi)])
             for r in limits_table()]  # fmt: skip
    wire = decode_wire(tr.sent)
    assert check_wire(wire, table, park, park) > 5000
    assert int(wire.pulses.max()) > 0.9 * hi  # it did drive toward that stroke end


def test_bridge_garbage_telemetry_keeps_the_limits(rig: Any) -> None:
    """Random bytes, NaN and infinite values between real F1 packets, into the real source."""
    platform, ctrl, lim, park = rig
    port = free_port()
    rng = np.random.default_rng(11)

    def random_bytes(ex: bytes, motion: bytes) -> bytes:
        return rng.bytes(int(rng.integers(1, 1500)))

    def nan_motion(ex: bytes, motion: bytes) -> bytes:
        out = bytearray(motion)
        car = 29 + 60 * motion[27]
        struct.pack_into("<3f", out, car + 36, math.nan, math.inf, -math.nan)
        return bytes(out)

    def nan_ex(ex: bytes, motion: bytes) -> bytes:
        out = bytearray(ex)
        struct.pack_into("<3f", out, 29 + 4 * 36, math.nan, math.nan, math.inf)
        return bytes(out)

    tr = FlakyTransport()
    source = open_source(f"f1:{port}")
    try:
        with Sender(port, 2024) as sender:
            sender.extra = [random_bytes, nan_motion, nan_ex] * 40
            bridge = Bridge(platform, ctrl, load_cueing("racing"), source, tr, lim,
                            BridgeConfig(RATE_HZ, GATE, switch_interval_s=None))  # fmt: skip
            bridge.start()
            end = time.monotonic() + 4.0
            while sender.extra and time.monotonic() < end:
                time.sleep(0.02)
            st = bridge.stop()
    finally:
        source.close()
    assert not sender.extra and st.error is None and st.state == "stopped"
    assert st.bad_packets > 0 or st.cueing_bad_samples > 0
    assert check_wire(decode_wire(tr.sent), limits_table(), park, park) > 5000


# -- start from the position the controller reports -----------------------------------------
class RecordingUdp(UdpTransport):
    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.sent: list[bytes] = []

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self.sent.append(data)
        super().send(data, t_s=t_s)


def _leave_platform_up(rig: Any, emu: MboxEmulator) -> np.ndarray:
    """Drive the emulator's platform to a pose away from park and stop there (at rest)."""
    platform, ctrl, lim, _ = rig
    with open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        stage = OutputStage(platform, ctrl, lim, RATE_HZ, tr)
        target = np.asarray(platform.q_park) + 0.03
        t0 = time.perf_counter()
        for k in range(300):
            while time.perf_counter() < t0 + k / RATE_HZ:
                time.sleep(0.001)
            stage.emit(target)
            if stage.at_rest and np.allclose(stage.q, target):
                break
    deadline = time.monotonic() + 3
    while emu.playback.depth and time.monotonic() < deadline:
        time.sleep(0.02)
    return stage.last_pulses


def test_play_starts_from_the_reported_position(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, park = rig
    with MboxEmulator(ctrl) as emu:
        up = _leave_platform_up(rig, emu)
        assert np.all(up - park > 50000)
        tr = RecordingUdp("127.0.0.1", emu.port)
        k = 150  # the first 1.5 s of the ride, then the park
        cut = dataclasses.replace(ride, t_s=ride.t_s[:k], pulses=ride.pulses[:k],
                                  dout=ride.dout[:k], dacs=ride.dacs[:k])  # fmt: skip
        try:
            rep = play_ride(cut, platform, ctrl, lim, tr, q_start="auto")
        finally:
            tr.close()
        violations = emu.violations
    assert any("starting there" in n for n in rep.notes), rep.notes
    wire = decode_wire(tr.sent)
    table = limits_table()
    check_wire(wire, table, up, park)  # from `up` at rest: no jump
    a_max = min(r["max_accel_pulses_s2"] for r in table)
    assert np.abs(wire.pulses[0] - up).max() <= a_max / RATE_HZ**2  # one step from rest
    assert violations == []


def test_bridge_starts_from_the_reported_position(rig: Any) -> None:
    platform, ctrl, lim, park = rig
    with MboxEmulator(ctrl) as emu:
        up = _leave_platform_up(rig, emu)
        tr = RecordingUdp("127.0.0.1", emu.port)
        try:
            bridge = Bridge(platform, ctrl, load_cueing("racing"), HeldSource(), tr, lim,
                            BridgeConfig(RATE_HZ, GATE, switch_interval_s=None),
                            q_start="auto")  # fmt: skip
            assert any("starting there" in n for n in bridge.stats.notes)
            bridge.start()
            time.sleep(1.0)
            st = bridge.stop()
        finally:
            tr.close()
        violations = emu.violations
    assert st.error is None
    check_wire(decode_wire(tr.sent), limits_table(), up, park)
    assert violations == []


def test_no_position_reply_assumes_park_and_says_so(rig: Any) -> None:
    platform, ctrl, lim, _ = rig
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sink:
        sink.bind(("127.0.0.1", 0))
        with open_transport(f"udp://127.0.0.1:{sink.getsockname()[1]}") as tr:
            stage = OutputStage(platform, ctrl, lim, RATE_HZ, tr, q_start="auto")
    assert stage.parked and "assuming parked" in stage.notes[0]


def test_a_platform_still_moving_is_refused(rig: Any) -> None:
    platform, ctrl, lim, _ = rig
    with MboxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        stage = OutputStage(platform, ctrl, lim, RATE_HZ, tr)
        for _ in range(200):  # 2 s of frames queued at once: the box plays them for 2 s
            stage.emit(np.asarray(platform.q_park) + 0.02)
        with pytest.raises(LimitError, match="still playing"):
            OutputStage(platform, ctrl, lim, RATE_HZ, tr, q_start="auto")


# -- the real CLI in a process, stopped by signals --------------------------------------------
class Sink(lb.UdpPeer):
    """A UDP socket standing for the controller: keeps every datagram and its arrival time,
    and answers each frame 0x1301 with 0x1302 as an SC-MBOX does (manual 4.2.8: the header
    with the reply's function code and Who fields 0, then the frame's data), so that the
    player knows the controller is there (issue 23: a silent controller stops the job).
    Register reads (the position query) go unanswered."""

    def __init__(self) -> None:
        self.got: list[tuple[float, bytes]] = []
        super().__init__(bufsize=2048)

    def on_datagram(self, now: float, data: bytes, peer: Any) -> bool:
        self.got.append((now, data))
        if len(data) > 12 and data[:2] == b"\x55\xaa" and data[4:6] == b"\x13\x01":
            reply = data[:4] + b"\x13\x02" + data[6:8] + bytes(4) + data[12:]
            try:
                self.sock.sendto(reply, peer)
            except OSError:
                return False
        return True

    def moved(self, park: np.ndarray, pulses: int) -> bool:
        for _, d in self.got[-5:]:
            if len(d) == 52 and d[4:6] == b"\x13\x01":
                p = np.asarray(struct.unpack_from(">6i", d, 20))
                if np.abs(p - park).max() > pulses:
                    return True
        return False


@contextmanager
def _cli(args: list[str]) -> Iterator[tuple[subprocess.Popen[str], Sink]]:
    sink = Sink()
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    cmd = [sys.executable, "-m", "motioncue", *args, "--target", f"udp://127.0.0.1:{sink.port}"]
    proc = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)  # fmt: skip
    try:
        yield proc, sink
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        sink.close()


SIGNAL_CASES = {
    "SIGINT": [signal.SIGINT],
    "SIGINT twice": [signal.SIGINT, signal.SIGINT],
    "SIGTERM": [signal.SIGTERM],
    "SIGHUP": [signal.SIGHUP],
    "SIGQUIT, then SIGINT twice": [signal.SIGQUIT, signal.SIGINT, signal.SIGINT],
}


def _wait_delivered(pid: int, sig: int, timeout_s: float = 10.0) -> None:
    """Wait until ``sig`` is no longer pending for process ``pid`` (Linux ``/proc``; elsewhere
    returns at once)."""
    status = Path(f"/proc/{pid}/status")
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        try:
            lines = status.read_text().splitlines()
        except OSError:
            return  # gone or no /proc
        masks = [int(ln.split()[1], 16) for ln in lines if ln.startswith(("SigPnd:", "ShdPnd:"))]
        if not masks or not any(m >> (sig - 1) & 1 for m in masks):
            return
        time.sleep(0.001)


def _signal_run(args: list[str], signals: list[int], park: np.ndarray) -> tuple[Any, str, Sink]:
    with _cli(args) as (proc, sink):
        # a bound for a process that never moves the platform, not a timing check: the CLI's
        # start (imports, the ride, the unpark) takes seconds on a busy machine
        end = time.monotonic() + 90
        while not sink.moved(park, 20000) and time.monotonic() < end and proc.poll() is None:
            time.sleep(0.01)
        assert sink.moved(park, 20000), "the platform never moved"
        sent_at = []
        for i, sig in enumerate(signals):
            if i:
                # the later ones arrive during the park, after the first was delivered: two
                # signals pending together are delivered lowest number first (SIGINT before
                # SIGQUIT), whatever order they were sent in (a quiet fresh clone's run
                # reported 'stopped by SIGINT' for SIGQUIT then SIGINT 20 ms later)
                _wait_delivered(proc.pid, signals[i - 1])
                time.sleep(0.02)
            proc.send_signal(sig)
            sent_at.append(time.monotonic())
        out, err = proc.communicate(timeout=90)
    assert "Traceback" not in err, err
    assert proc.returncode == 130, err
    # frames still went out after the second signal: it came during the park, and the
    # park went on to its end (checked by the caller)
    assert any(t > sent_at[min(1, len(sent_at) - 1)] for t, _ in sink.got)
    return proc, out + err, sink


@pytest.mark.parametrize("case", list(SIGNAL_CASES))
def test_play_signals_park(case: str, ride_path: Path, rig: Any) -> None:
    _, _, _, park = rig
    _, err, sink = _signal_run(["play", str(ride_path)], SIGNAL_CASES[case], park)
    name = signal.Signals(SIGNAL_CASES[case][0]).name
    assert "assuming parked" in err  # the sink does not answer the position read
    wire = decode_wire([d for _, d in sink.got])
    assert check_wire(wire, limits_table(), park, park) > 5000
    assert f"interrupted and parked ({name})" in err


@pytest.mark.parametrize("case", list(SIGNAL_CASES))
def test_bridge_signals_park(case: str, rig: Any) -> None:
    _, _, _, park = rig
    port = free_port()
    args = ["bridge", "--source", f"f1:{port}", "--platform", PLATFORM, "--controller",
            CONTROLLER, "--rate", str(int(RATE_HZ)), "--fade", "0.3", "--quiet"]  # fmt: skip
    with Sender(port, 2024):
        _, err, sink = _signal_run(args, SIGNAL_CASES[case], park)
    name = signal.Signals(SIGNAL_CASES[case][0]).name
    assert f"stopped by {name}; parked at rest" in err
    wire = decode_wire([d for _, d in sink.got])
    assert check_wire(wire, limits_table(), park, park) > 5000


def test_checker_catches_a_jump(rig: Any) -> None:
    """The checker is not blind: one frame moved by a few pulses too many fails it."""
    _, _, _, park = rig
    tr = FlakyTransport()
    platform, ctrl, lim, _ = rig
    stage = OutputStage(platform, ctrl, lim, RATE_HZ, tr)
    for _ in range(100):
        stage.emit(np.asarray(platform.q_park) + 0.05)
    for _ in range(stage.park_frames_bound()):
        if stage.park_step():
            break
    wire = decode_wire(tr.sent)
    check_wire(wire, limits_table(), park, park)
    bad = dataclasses.replace(wire, pulses=wire.pulses.copy())
    bad.pulses[40] += 3000
    with pytest.raises(AssertionError, match=r"acceleration|speed"):
        check_wire(bad, limits_table(), park, park)
    lost = dataclasses.replace(wire, number=np.delete(wire.number, 40),
                               t_ms=np.delete(wire.t_ms, 40),
                               pulses=np.delete(wire.pulses, 40, axis=0),
                               outputs=np.delete(wire.outputs, 40, axis=0))  # fmt: skip
    with pytest.raises(AssertionError):
        check_wire(lost, limits_table(), park, park)
    with pytest.raises(AssertionError, match="channel"):
        decode_wire([b"\x55\xaa\x00\x00\x13\x01\x00\x07" + bytes(44)])


def test_imax_reports_its_position_too() -> None:
    from motioncue.output._feedback import read_position
    from motioncue.output.imax import ImaxEmulator

    platform = load_platform(PLATFORM)
    ctrl = load_controller("imax6")
    lim = ActuatorLimits.from_platform(platform, ctrl)
    with ImaxEmulator(ctrl) as emu, open_transport(f"udp://127.0.0.1:{emu.port}") as tr:
        assert read_position(ctrl, tr) is not None
        stage = OutputStage(platform, ctrl, lim, RATE_HZ, tr)
        for _ in range(60):
            stage.emit(np.asarray(platform.q_park) + 0.01)
        rep = read_position(ctrl, tr, settle_s=3.0)
        assert rep is not None and not rep.moving
        np.testing.assert_array_equal(rep.pulses, stage.last_pulses)
        assert not emu.violations
    with open_transport("file:/dev/null") as tr:
        assert read_position(ctrl, tr) is None  # a file cannot answer
