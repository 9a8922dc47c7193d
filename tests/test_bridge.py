"""The live bridge end to end: real F1 packets over UDP -> Bridge -> controller emulators.

Every run checks the frames the emulator received against the limits table that
``motioncue limits`` prints (``ActuatorLimits.to_pulses_table``) with the independent
finite-difference check of :mod:`motioncue.pipeline._verify`. Runs are short (a few
seconds, fades of 0.3 s) and assert correctness only; timing figures are the benchmark's.
"""

from __future__ import annotations

import itertools
import math
import socket
import struct
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Self

import numpy as np
import pytest

from _emulator_process import EmulatorProcess
from motioncue import ConfigError, MotioncueError, TransportError
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, open_transport
from motioncue.output.mbox._messages import MotionFrame, decode
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import TelemetrySample, TelemetrySource, open_source
from motioncue.telemetry._f1 import CAR_MOTION, HEADER, SESSION_HEAD
from motioncue.trajectory import ActuatorLimits

DATA = Path("/work/shared/data/f1")
GATE = GateConfig(timeout_s=0.25, fade_out_s=0.3, fade_in_s=0.3)


# -- a moving F1 stream built from the real captures ---------------------------------------
class F1Stream:
    """Real Motion (id 0) and Motion Ex (id 13) captures with rewritten time and motion.

    Fields rewritten with struct at the offsets of EA's specification: header sessionTime
    (@15, f32), frameIdentifier (@19) and overallFrameIdentifier (@23, u32); the player car's
    gForceLateral / Longitudinal / Vertical (@29 + 60 i + 36/40/44, f32) in Motion; the
    angularVelocity (@29 + 4 * 36, 3 x f32) in Motion Ex.
    """

    def __init__(self, year: int) -> None:
        self.motion = bytearray((DATA / str(year) / "packet-0.bin").read_bytes())
        self.ex = bytearray((DATA / str(year) / "packet-13.bin").read_bytes())
        self.player = self.motion[27]
        self.car = HEADER.size + CAR_MOTION.size * self.player
        self.stime0 = struct.unpack_from("<f", self.motion, 15)[0]

    def frame(
        self,
        k: int,
        g_lat: float,
        g_lon: float,
        g_vert: float = 0.0,
        w: tuple[float, float, float] = (0.0, 0.0, 0.0),
    ) -> tuple[bytes, bytes]:
        """(Motion Ex, Motion) of frame ``k`` (60 Hz session clock)."""
        stime = self.stime0 + k / 60.0
        for pkt in (self.motion, self.ex):
            struct.pack_into("<fII", pkt, 15, stime, 1000 + k, 1000 + k)
        struct.pack_into("<3f", self.motion, self.car + 36, g_lat, g_lon, g_vert)
        struct.pack_into("<3f", self.ex, HEADER.size + 4 * 36, *w)
        return bytes(self.ex), bytes(self.motion)

    def session(self, paused: bool) -> bytes:
        head = bytearray(self.motion[: HEADER.size])
        head[6] = 1  # packetId = Session
        body = SESSION_HEAD.pack(0, 30, 20, 5, 5000, 10, 3, 0, 600, 900, 80, int(paused), 0, 255)
        return bytes(head) + body + bytes(600)


def lap_motion(t: float) -> tuple[float, float, float, tuple[float, float, float]]:
    """Cornering, braking and bumps in g (lat, long, vert) and yaw/roll rates (rad/s)."""
    g_lat = 2.5 * math.sin(2 * math.pi * 0.7 * t)
    g_lon = 1.5 * math.sin(2 * math.pi * 0.4 * t + 1.0) - 0.8 * (math.sin(5 * t) > 0.9)
    g_vert = 0.3 * math.sin(2 * math.pi * 6.0 * t)
    w = (0.4 * math.sin(3 * t), 0.2 * math.sin(2 * math.pi * 6.0 * t), 0.9 * math.sin(2 * t))
    return g_lat, g_lon, g_vert, w


class ThreadedSender:
    """A sender thread to ``127.0.0.1:port``, started and stopped by a ``with`` block;
    subclasses write ``_run``, which ends when ``self._stop`` is set, and count ``sent``."""

    def __init__(self, port: int) -> None:
        self.dest = ("127.0.0.1", port)
        self.sent = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def __enter__(self) -> Self:
        self._thread.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self._stop.set()
        self._thread.join(2.0)

    def _run(self) -> None:
        raise NotImplementedError


class Sender(ThreadedSender):
    """Sends the moving F1 stream at 60 Hz to a port from a thread; ``mode`` switches live."""

    def __init__(self, port: int, year: int = 2024) -> None:
        super().__init__(port)
        self.stream = F1Stream(year)
        self.mode = "drive"  # drive | silent | paused
        # bad datagrams to interleave, one per frame, made from that frame's (ex, motion)
        self.extra: list[Callable[[bytes, bytes], bytes]] = []
        self.motion: Callable[[float], Any] = lap_motion

    def _run(self) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            t0 = time.perf_counter()
            k = 0
            while not self._stop.is_set():
                k += 1
                due = t0 + k / 60.0
                left = due - time.perf_counter()
                if left > 0:
                    time.sleep(left)
                if self.mode == "silent":
                    continue
                g_lat, g_lon, g_vert, w = self.motion(k / 60.0)
                ex, motion = self.stream.frame(k, g_lat, g_lon, g_vert, w)
                if self.mode == "paused" or k % 30 == 0:
                    tx.sendto(self.stream.session(self.mode == "paused"), self.dest)
                tx.sendto(ex, self.dest)
                tx.sendto(motion, self.dest)
                if self.extra:
                    tx.sendto(self.extra.pop(0)(ex, motion), self.dest)
                self.sent += 1


# -- set-ups ------------------------------------------------------------------------------
def _mbox_setup() -> tuple[Any, Any, ActuatorLimits]:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    return platform, ctrl, ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)


def _imax_setup() -> tuple[Any, Any, ActuatorLimits]:
    platform = load_platform("seat3")
    ctrl = load_controller("imax3")
    return platform, ctrl, ActuatorLimits.from_platform(platform, ctrl)


@contextmanager
def live_rig(
    kind: str, rate_hz: float = 250.0, year: int = 2024, query: str = "", **config: Any
) -> Iterator[tuple[Bridge, Sender, Any, Any, ActuatorLimits]]:
    """Emulator on loopback, F1 receiver, bridge and sender, all started (``query``: the
    target URL's ``?...`` options, e.g. ``"?silence_ms=3000"``).

    The emulator runs in a process of its own (:mod:`_emulator_process`): a thread of this
    process was held up past the link watch's 0.2 s probe interval under load (a status
    request then joins the frames on the wire), and past the 0.5 s silence limit at load
    15-25 in other tests (the bridge then stops, "controller silent")."""
    platform, ctrl, lim = _mbox_setup() if kind == "mbox" else _imax_setup()
    with EmulatorProcess(ctrl.name) as emu:
        source = open_source("f1:127.0.0.1:0")
        assert isinstance(source, TelemetrySource)
        transport = open_transport(f"udp://127.0.0.1:{emu.port}{query}")
        try:
            bridge = Bridge(
                platform,
                ctrl,
                load_cueing("racing"),
                source,
                transport,
                lim,
                BridgeConfig(rate_hz=rate_hz, gate=GATE, **config),
            )
            with Sender(source.port, year) as sender:
                bridge.start()
                try:
                    yield bridge, sender, emu, platform, lim
                finally:
                    bridge.stop()
        finally:
            transport.close()
            source.close()


def _wait_for(cond: Callable[[], bool], timeout_s: float = 3.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return bool(cond())


def _all_received(emu: Any, bridge: Bridge) -> None:
    """Every frame the bridge counted reached the emulator, once, and nothing else did but
    the status requests its link watch counted (sent when the emulator, a thread of this
    process, was held up past the probe interval: 532 datagrams for 531 frames once)."""
    final = bridge.stats
    datagrams = final.frames_sent + final.status_requests
    assert _wait_for(lambda: emu.received >= datagrams)
    assert emu.frames_received == final.frames_sent
    assert emu.received == datagrams


def _check_trace(emu: Any, platform: Any, lim: ActuatorLimits) -> Any:
    tr = emu.trace
    table = lim.to_pulses_table(platform)
    chk = check_frames(tr.t_s, tr.positions, table, start_at_rest=True)
    assert chk.ok, chk.summary()
    assert emu.violations == []
    assert emu.internal_errors == []
    park = platform.drives.to_pulses(platform.q_park)
    np.testing.assert_array_equal(tr.positions[0], park)  # starts parked
    np.testing.assert_array_equal(tr.positions[-1], park)  # ends parked, at rest
    np.testing.assert_array_equal(tr.positions[-2], park)
    return tr


# -- end to end ---------------------------------------------------------------------------
@pytest.mark.parametrize(("kind", "year"), [("mbox", 2024), ("imax", 2023)])
def test_real_f1_packets_drive_the_emulator_within_the_limits(kind: str, year: int) -> None:
    with live_rig(kind, year=year) as (bridge, _sender, emu, platform, lim):
        assert _wait_for(lambda: bridge.stats.state == "live")
        time.sleep(1.5)
        live = bridge.stats
        assert live.gain == 1.0 and live.samples_in > 60 and live.bad_packets == 0
        assert live.packet_reasons["sample"] == live.samples_in
        final = bridge.stop()
    assert final.state == "stopped" and final.error is None and final.park_q_error == 0.0
    assert final.fade_ins == 1 and final.fade_outs == 1
    _all_received(emu, bridge)
    tr = _check_trace(emu, platform, lim)
    assert list(tr.frames) == list(range(final.frames_sent))  # none lost or reordered
    park = platform.drives.to_pulses(platform.q_park)
    moved = np.abs(tr.positions - park).max(axis=0)
    ppu = platform.drives.pulses_per_unit
    assert np.all(moved / ppu > 0.005)  # every actuator moved at least 5 mm (cues arrived)
    # frames are paced by the bridge: the emulator's timeline follows the frame period
    np.testing.assert_allclose(np.diff(tr.t_s[1:]), 1.0 / 250.0, atol=1e-9)


def test_a_held_up_emulator_is_probed_and_the_probes_are_no_frames() -> None:
    # the path that sent a datagram besides the counted frames, forced: the emulator's
    # process stopped for longer than the watch's 0.2 s probe interval, far less than the
    # link's silence limit (3 s here, so a busy machine cannot fail the job)
    with live_rig("imax", year=2023, query="?silence_ms=3000") as (
        bridge,
        _sender,
        emu,
        platform,
        lim,
    ):
        assert _wait_for(lambda: bridge.stats.state == "live")
        emu.pause()
        try:
            assert _wait_for(lambda: bridge.stats.status_requests >= 1, 2.5)
        finally:
            emu.resume()
        held = bridge.stats  # the emulator catches up with what waited in its socket
        assert _wait_for(lambda: emu.received >= held.frames_sent + held.status_requests)
        final = bridge.stop()
    assert final.state == "stopped" and final.error is None and final.status_requests >= 1
    _all_received(emu, bridge)
    assert emu.received > emu.frames_received  # the probes reached it: not frames
    tr = _check_trace(emu, platform, lim)
    assert list(tr.frames) == list(range(final.frames_sent))


def test_watchdog_parks_when_packets_stop_and_ramps_back_in() -> None:
    with live_rig("mbox") as (bridge, sender, emu, platform, lim):
        assert _wait_for(lambda: bridge.stats.state == "live")
        time.sleep(0.5)
        sender.mode = "silent"
        # timeout + fade (0.55 s), and the limiter may need a few more frames to reach park at
        # rest. Not a timing check (the gate's timeout and fade are checked to the tick on its
        # own clock in test_realtime.py): 10x that, so only a bridge that never parks trips it.
        assert _wait_for(
            lambda: bridge.stats.state == "parked", 10 * (GATE.timeout_s + GATE.fade_out_s)
        )
        parked = bridge.stats
        assert parked.park_q_error == 0.0 and parked.gain == 0.0
        time.sleep(0.2)
        assert bridge.cueing_state.samples == 0  # reset while parked: resume starts clean
        # the gain of every frame, recorded on the bridge's own thread (sampling it from
        # this thread saw one value inside the 0.3 s fade when four workers shared 2 cores)
        frame_gains: list[float] = []
        update = bridge.gate.update

        def recorded(now_s: float, last_packet_s: float | None, paused: bool) -> float:
            gain = update(now_s, last_packet_s, paused)
            frame_gains.append(gain)
            return gain

        bridge.gate.update = recorded  # type: ignore[method-assign]
        sender.mode = "drive"
        gains = []
        end = time.monotonic() + 1.0
        while time.monotonic() < end:
            gains.append(bridge.stats.gain)
            time.sleep(0.01)
        assert gains[-1] == 1.0
        ramp = [g for g in frame_gains if 0.0 < g < 1.0]
        assert len(ramp) >= 5, frame_gains  # fades in over 0.3 s (30 frames), not a step
        assert all(b >= a for a, b in itertools.pairwise(frame_gains))
        assert all(b >= a for a, b in itertools.pairwise(gains))
        resumed = bridge.stats
        assert resumed.fade_ins == 2 and resumed.fade_outs == 1
        bridge.stop()
    _all_received(emu, bridge)
    _check_trace(emu, platform, lim)


def test_pause_flag_parks_and_unpause_resumes() -> None:
    with live_rig("imax", year=2023) as (bridge, sender, emu, platform, lim):
        assert _wait_for(lambda: bridge.stats.state == "live")
        sender.mode = "paused"  # Session gamePaused = 1 while Motion keeps coming
        assert _wait_for(lambda: bridge.stats.state == "parked", 2.0)
        assert bridge.stats.park_q_error == 0.0
        sender.mode = "drive"
        assert _wait_for(lambda: bridge.stats.state == "live", 2.0)
        assert bridge.stats.fade_ins == 2
        bridge.stop()
    _all_received(emu, bridge)
    _check_trace(emu, platform, lim)


def test_truncated_foreign_and_nan_packets_are_counted_and_skipped() -> None:
    with live_rig("mbox") as (bridge, sender, emu, platform, lim):
        assert _wait_for(lambda: bridge.stats.state == "live")

        def nan_motion(ex: bytes, motion: bytes) -> bytes:  # same frame, NaN lateral g
            out = bytearray(motion)
            struct.pack_into("<f", out, HEADER.size + CAR_MOTION.size * motion[27] + 36, math.nan)
            return bytes(out)

        def inf_ex(ex: bytes, motion: bytes) -> bytes:  # same frame, infinite roll rate
            out = bytearray(ex)
            struct.pack_into("<f", out, HEADER.size + 4 * 38, math.inf)
            return bytes(out)

        bad: list[Callable[[bytes, bytes], bytes]] = [
            lambda ex, motion: motion[:100],  # truncated
            lambda ex, motion: b"\x00" * 40 + b"garbage",  # foreign
            nan_motion,
            inf_ex,
        ]
        sender.extra = bad * 5
        assert _wait_for(lambda: not sender.extra)
        time.sleep(0.2)
        st = bridge.stats
        assert st.state == "live"  # bad packets between good ones do not disturb the cue
        bridge.stop()
    r = st.packet_reasons
    assert r["skipped: truncated"] == 5
    assert r["skipped: foreign"] == 5
    assert r["skipped: non-finite"] == 10
    assert st.bad_packets == 20
    _all_received(emu, bridge)
    _check_trace(emu, platform, lim)


# -- in-process: injected source and transport --------------------------------------------
class FakeSource:
    """A telemetry source the test sets by hand (bypasses the decoders' checks)."""

    def __init__(self) -> None:
        self.sample: TelemetrySample | None = None
        self.stats = {"samples": 0, "datagrams": 0}

    def put(self, f: tuple[float, float, float], w: tuple[float, float, float]) -> None:
        self.sample = TelemetrySample(time.perf_counter(), f, w, False, "test")
        self.stats["samples"] += 1

    def latest(self) -> TelemetrySample | None:
        return self.sample


class ListTransport:
    def __init__(self) -> None:
        self.sent: list[bytes] = []
        self.fail_after: int | None = None

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        if self.fail_after is not None and len(self.sent) >= self.fail_after:
            raise TransportError("link down (test)")
        self.sent.append(data)


def _decode_frames(sent: list[bytes]) -> tuple[np.ndarray, np.ndarray]:
    frames = []
    for d in sent:
        msg = decode(d)
        assert isinstance(msg, MotionFrame)
        frames.append(msg)
    t = np.array([f.time_ms for f in frames], dtype=np.float64) / 1e3
    p = np.array([f.positions for f in frames], dtype=np.float64)
    assert [f.line for f in frames] == list(range(len(frames)))
    return t, p


def test_spikes_nan_and_inf_in_the_telemetry_never_break_the_limits() -> None:
    platform, ctrl, lim = _mbox_setup()
    src, tr = FakeSource(), ListTransport()
    bridge = Bridge(platform, ctrl, load_cueing("racing"), src, tr, lim, BridgeConfig(250.0, GATE))
    rng = np.random.default_rng(7)
    nan, inf = math.nan, math.inf
    with bridge:
        t0 = time.perf_counter()
        k = 0
        while time.perf_counter() - t0 < 2.0:
            k += 1
            f = tuple(float(v) for v in rng.normal(0.0, 30.0, 3) + np.array([0.0, 0.0, 9.8]))
            w = tuple(float(v) for v in rng.normal(0.0, 3.0, 3))
            if k % 7 == 0:
                f = (900.0 * rng.choice([-1, 1]), -900.0, 900.0)  # spikes
            if k % 11 == 0:
                f = (nan, 0.0, 9.8)
            if k % 13 == 0:
                w = (0.0, inf, -inf)
            src.put(f, w)  # type: ignore[arg-type]
            time.sleep(1 / 120)
        during = bridge.stats
    final = bridge.stats
    assert during.state == "live"
    assert final.state == "stopped" and final.error is None
    assert final.cueing_bad_samples > 0  # NaN/inf/spikes were held by the washout
    assert final.limiter_clamped_frames > 0 or final.pose_clamped > 0
    t, p = _decode_frames(tr.sent)
    assert np.all(np.isfinite(p))
    chk = check_frames(t, p, lim.to_pulses_table(platform), start_at_rest=True)
    assert chk.ok, chk.summary()
    assert np.abs(p - platform.drives.to_pulses(platform.q_park)).max() > 1000  # it moved


def test_a_source_that_forgets_its_sample_fades_out_instead_of_failing() -> None:
    platform, ctrl, lim = _imax_setup()
    src, tr = FakeSource(), ListTransport()
    bridge = Bridge(platform, ctrl, load_cueing("racing"), src, tr, lim, BridgeConfig(200.0, GATE))
    bridge.start()
    try:
        end = time.monotonic() + 0.6
        while time.monotonic() < end:
            src.put((3.0, -2.0, 9.8), (0.0, 0.0, 0.5))
            time.sleep(0.01)
        assert bridge.stats.state == "live"
        src.sample = None
        assert _wait_for(lambda: bridge.stats.state == "parked", 2.0)
        assert bridge.stats.error is None and bridge.stats.fade_outs == 1
    finally:
        final = bridge.stop()
    assert final.state == "stopped" and final.error is None


def test_no_telemetry_at_all_stays_parked_and_stop_is_quick() -> None:
    platform, ctrl, lim = _mbox_setup()
    src, tr = FakeSource(), ListTransport()
    bridge = Bridge(platform, ctrl, load_cueing("racing"), src, tr, lim, BridgeConfig(100.0))
    bridge.start()
    time.sleep(0.3)
    st = bridge.stop(timeout_s=2.0)
    assert st.state == "stopped" and st.gain == 0.0 and st.fade_ins == 0
    _, p = _decode_frames(tr.sent)
    assert len(p) >= 20
    assert np.all(p == platform.drives.to_pulses(platform.q_park))


def test_a_failing_transport_stops_the_loop_and_is_reported() -> None:
    platform, ctrl, lim = _mbox_setup()
    src, tr = FakeSource(), ListTransport()
    tr.fail_after = 10
    bridge = Bridge(platform, ctrl, load_cueing("racing"), src, tr, lim, BridgeConfig(200.0))
    bridge.start()
    assert bridge.wait(2.0)
    st = bridge.stats
    assert st.state == "failed" and st.error is not None and "link down" in st.error
    assert st.frames_sent == 10
    assert "failed" in st.status_line()


def test_configuration_errors_are_named() -> None:
    with pytest.raises(ConfigError, match="rate_hz"):
        BridgeConfig(rate_hz=0.0)
    with pytest.raises(ConfigError, match="rate_hz"):
        BridgeConfig(rate_hz=math.nan)
    with pytest.raises(ConfigError, match="spin_s"):
        BridgeConfig(spin_s=-1.0)
    with pytest.raises(ConfigError, match="rt_priority"):
        BridgeConfig(rt_priority=0)
    with pytest.raises(ConfigError, match="switch_interval_s"):
        BridgeConfig(switch_interval_s=0.0)
    platform, ctrl, lim = _mbox_setup()
    _, _, lim3 = _imax_setup()
    with pytest.raises(ConfigError, match="actuators"):
        Bridge(platform, ctrl, load_cueing("racing"), FakeSource(), ListTransport(), lim3)
    bridge = Bridge(platform, ctrl, load_cueing("racing"), FakeSource(), ListTransport(), lim)
    bridge.start()
    try:
        with pytest.raises(MotioncueError, match="already started"):
            bridge.start()
    finally:
        bridge.stop()


# -- deterministic stepping against an independent composition of the stages -------------
class TimelineSource:
    """Samples on a fake timeline; ``now`` picks the newest one that has arrived."""

    def __init__(self, samples: list[TelemetrySample]) -> None:
        self.samples = samples
        self.now = -math.inf
        self.stats = {"samples": 0}

    def latest(self) -> TelemetrySample | None:
        arrived = [s for s in self.samples if s.t_s <= self.now]
        return arrived[-1] if arrived else None


def test_stepping_equals_washout_blend_ik_and_limiter_composed_offline() -> None:
    """Oracle: the documented per-frame chain rebuilt from batch calls of each stage.

    Held input at each frame -> gate gain by its definition (raised cosine of a phase moving
    by dt / fade toward live or parked) -> ``ClassicalWashout.run`` over the open frames ->
    blend with the park pose -> ``platform.inverse`` in batch -> ``RealtimeLimiter.run``
    with the pulse-rounding limits -> pulses. Mild motion, so no pose needs limiting.
    """
    from motioncue.cueing import ClassicalWashout
    from motioncue.pipeline._generate import pulse_rounding_limits
    from motioncue.trajectory import RealtimeLimiter

    platform, ctrl, lim = _mbox_setup()
    rate, fs_in = 100.0, 60.0
    gate_cfg = GateConfig(timeout_s=0.25, fade_out_s=0.5, fade_in_s=0.4)
    t_end_samples = 3.0
    samples = []
    for k in range(int(t_end_samples * fs_in)):
        t = 0.123 + k / fs_in
        f = (2.0 * math.sin(1.3 * t), -1.5 * math.sin(0.9 * t), 9.80665 + 0.5 * math.sin(7 * t))
        w = (0.1 * math.sin(2 * t), 0.05 * math.cos(3 * t), 0.2 * math.sin(0.7 * t))
        samples.append(TelemetrySample(t, f, w, 110 <= k < 170, "test"))  # a 1 s pause
    src, tr = TimelineSource(samples), ListTransport()
    cueing = load_cueing("racing")
    bridge = Bridge(platform, ctrl, cueing, src, tr, lim, BridgeConfig(rate, gate_cfg))
    n = int(4.5 * rate)
    deadlines = [k / rate for k in range(1, n + 1)]
    for d in deadlines:
        src.now = d
        bridge.step(d)
    assert bridge.stats.pose_clamped == 0 and bridge.stats.pose_invalid == 0
    _, pulses = _decode_frames(tr.sent)

    # --- the oracle
    dt = 1.0 / rate
    phase, gains, held = 0.0, [], []
    for d in deadlines:
        arrived = [s for s in samples if s.t_s <= d]
        s = arrived[-1] if arrived else None
        live = s is not None and not s.paused and d - s.t_s <= gate_cfg.timeout_s
        phase = min(1.0, phase + dt / gate_cfg.fade_in_s) if live else phase
        phase = phase if live else max(0.0, phase - dt / gate_cfg.fade_out_s)
        gains.append(0.5 * (1 - math.cos(math.pi * phase)))
        held.append(s)
    gains_a = np.array(gains)
    open_ = gains_a > 0
    wash = ClassicalWashout(cueing, rate)
    poses = np.tile(platform.pose_park, (n, 1))
    k = 0
    while k < n:  # each run of open frames starts from a fresh washout state
        if not open_[k]:
            k += 1
            continue
        j = k
        while j < n and open_[j]:
            j += 1
        f = np.array([held[i].f for i in range(k, j)])
        w = np.array([held[i].w for i in range(k, j)])
        cue = wash.run(f, w).poses
        poses[k:j] = platform.pose_park + gains_a[k:j, None] * (cue - platform.pose_park)
        k = j
    assert np.count_nonzero(open_) > 200 and np.count_nonzero(~open_[50:]) > 20
    q_target = np.asarray(platform.inverse(poses), dtype=float)
    q_target[~open_] = platform.q_park
    rt = RealtimeLimiter(pulse_rounding_limits(lim, platform, dt), dt)
    q = rt.run(rt.initial_state(platform.q_park), q_target)
    expected = platform.drives.to_pulses(q)
    assert pulses.shape == expected.shape
    diff = np.abs(pulses - expected)
    assert diff.max() <= 1  # float rounding of batch vs streaming may flip a half pulse
    assert np.mean(diff == 0) > 0.99
    # the pause parked the platform in between, and the end is parked
    assert gains_a[int(2.7 * rate)] == 0.0 and gains_a[-1] == 0.0  # parked in the pause
    np.testing.assert_array_equal(pulses[-1], platform.drives.to_pulses(platform.q_park))
