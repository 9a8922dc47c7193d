"""``bridge --source replay:FILE`` ends with the recording: fade out, park at rest, exit 0.

The recordings are built from the real F1 captures (``test_bridge.F1Stream``: real Motion and
Motion Ex datagrams with rewritten times and motion) and written with ``RecordingWriter``,
as ``motioncue record`` would. Frames are judged on the emulator's trace (the controller's
view) with the independent finite-difference check, like the other bridge tests.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from motioncue.cli import main
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import imax, load_controller, mbox, open_transport
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import ReplaySource, TelemetrySource, open_source
from motioncue.telemetry._container import RecordingWriter
from motioncue.trajectory import ActuatorLimits
from test_bridge import DATA, GATE, F1Stream, _all_received, _check_trace, _wait_for, lap_motion

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="real F1 captures not on this machine")

RECORDED_S = 1.5  # seconds of 60 Hz telemetry in each recording


def write_f1_recording(path: Path, seconds: float = RECORDED_S, year: int = 2024) -> float:
    """A ``motioncue record`` file of a moving car; returns its span (first to last, s)."""
    stream = F1Stream(year)
    n = round(seconds * 60)
    with RecordingWriter(path, "f1", 20777) as w:
        for k in range(1, n + 1):
            g_lat, g_lon, g_vert, rates = lap_motion(k / 60.0)
            ex, motion = stream.frame(k, g_lat, g_lon, g_vert, rates)
            w.write(k / 60.0, ex)
            w.write(k / 60.0 + 0.001, motion)
    return (n - 1) / 60.0 + 0.001


def test_sources_report_finished_only_at_the_end_of_a_replay(tmp_path: Path) -> None:
    path = tmp_path / "short.mctr"
    write_f1_recording(path, 0.3)
    live = open_source("f1:127.0.0.1:0")
    assert isinstance(live, TelemetrySource)
    try:
        assert live.finished is False
    finally:
        live.close()
    src = open_source(f"replay:{path}?speed=1")
    assert isinstance(src, ReplaySource)
    try:
        assert src.finished is False  # 0.3 s of telemetry, not begun before it is asked for
        assert src.latest() is None  # the consumer's first call starts the file's clock
        assert src.finished is False
        assert _wait_for(lambda: src.finished, 3.0)
        assert src.stats["samples"] == 18  # every Motion packet was delivered first
    finally:
        src.close()


def test_replay_bridge_ends_by_itself_parked_and_at_rest(tmp_path: Path) -> None:
    path = tmp_path / "lap.mctr"
    span_s = write_f1_recording(path)
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    rate_hz = 250.0
    with mbox.MboxEmulator(ctrl) as emu:
        transport = open_transport(f"udp://127.0.0.1:{emu.port}")
        t0 = time.perf_counter()  # the replay starts when the source is opened
        source = open_source(f"replay:{path}?speed=1")
        try:
            bridge = Bridge(
                platform, ctrl, load_cueing("racing"), source, transport, lim,
                BridgeConfig(rate_hz=rate_hz, gate=GATE),
            )  # fmt: skip
            bound_s = span_s + GATE.fade_out_s + bridge.stage.park_frames_bound() / rate_hz + 0.5
            bridge.start()
            # a bound for a bridge that never ends, not a timing check: bound_s is what the
            # replay, the fade-out and the park take on an idle machine, + 10 s for a busy one
            ended = bridge.wait(bound_s + 10.0)
            took_s = time.perf_counter() - t0
            final = bridge.stats  # not stop(): the loop ended on its own
        finally:
            if bridge.running:
                bridge.stop()
            transport.close()
            source.close()
        assert ended, ("the bridge kept running after the recording", took_s, bound_s)
        assert took_s >= span_s  # not before the recording was over (load only lengthens it)
        _all_received(emu, bridge)
    assert final.state == "stopped" and final.error is None and final.park_q_error == 0.0
    assert final.fade_ins == 1 and final.fade_outs == 1
    assert any("end of the replay" in n for n in final.notes)
    tr = _check_trace(emu, platform, lim)  # within the limits; last frames at park, at rest
    park = platform.drives.to_pulses(platform.q_park)
    assert np.abs(tr.positions - park).max() > 1000  # the recording did move the platform


def test_bridge_verb_exits_0_at_the_end_of_a_replay(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "lap.mctr"
    span_s = write_f1_recording(path)
    ctrl = load_controller("imax3")
    with imax.ImaxEmulator(ctrl) as emu:
        t0 = time.perf_counter()
        code = main(
            [
                "bridge", "--source", f"replay:{path}?speed=1", "--platform", "seat3",
                "--controller", "imax3", "--target", f"udp://127.0.0.1:{emu.port}",
                "--rate", "200", "--fade", "0.3", "--rt-priority", "0",
                "--duration", "20",  # a safety net only: the replay must end long before
            ]
        )  # fmt: skip
        took_s = time.perf_counter() - t0
        # every datagram traced but the one position read at the start (udp:// targets)
        assert _wait_for(lambda: len(emu.trace) > 0 and emu.frames_received == len(emu.trace))
        assert emu.received >= emu.frames_received + 1  # + the start-up query (and any probe)
    err = capsys.readouterr().err
    assert code == 0, err
    # never before the recording was over (load only lengthens it); that it ended at the end
    # of the replay and not at the --duration safety net is told by the message below, not
    # by a wall-clock bound a busy machine could break
    assert took_s > span_s, took_s
    assert "bridge stopped:" in err and "parked error 0" in err
    assert "end of the replay" in err
    platform = load_platform("seat3")
    lim = ActuatorLimits.from_platform(platform, ctrl)
    tr = emu.trace
    chk = check_frames(tr.t_s, tr.positions, lim.to_pulses_table(platform), start_at_rest=True)
    assert chk.ok, chk.summary()
    assert emu.violations == []
    park = platform.drives.to_pulses(platform.q_park)
    np.testing.assert_array_equal(tr.positions[-1], park)
    np.testing.assert_array_equal(tr.positions[-2], park)
    assert np.abs(tr.positions - park).max() > 1000
