"""The interface-string stop string: sent once, after the park, by the player and the bridge
on every way out where the park went out (the ride's end, an error, SIGINT, a stop), never
before the park, not after a park that could not be sent; other kinds send nothing.

Judged on the bytes as the SMC3 firmware reads them (the board parser's command log says how
many frames had arrived when each command word came)."""

from __future__ import annotations

import dataclasses
import signal
import time
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motioncue._config import config_dir
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.output._registry import end_of_run_messages
from motioncue.output.iface import IfaceController, IfaceEmulator, board_parser
from motioncue.pipeline import generate_ride, play_ride, save_ride
from motioncue.pipeline._stream import ParkFailed, PlayAborted
from motioncue.telemetry._recording import Recording, read_recording_csv
from motioncue.trajectory import ActuatorLimits
from test_iface import (
    CONTROLLER,
    PLATFORM,
    RATE_HZ,
    FaultyController,
    Sink,
    assert_moved_then_parked,
    check_board,
    signal_when_moving,
)

STOP = b"[end]"  # a test word: the SMC3 parser logs any 3-letter command


@pytest.fixture(scope="module")
def rig() -> tuple[Any, Any, ActuatorLimits, np.ndarray]:
    """As ``test_iface``'s: the seat3-pot on the bundled SMC3 (no stop string)."""
    platform = load_platform(PLATFORM)
    ctrl = load_controller(CONTROLLER)
    lim = ActuatorLimits.from_platform(platform, ctrl, rate_hz=RATE_HZ)
    return platform, ctrl, lim, platform.drives.to_pulses(platform.q_park)


@pytest.fixture(scope="module")
def ride(rig: Any) -> Any:
    """One second of the bundled lap, ramped in from park and parked."""
    platform, ctrl, lim, _ = rig
    rec = read_recording_csv(config_dir("recordings") / "lap.csv")
    keep = rec.t_s <= 1.0
    made, _ = generate_ride(
        Recording(rec.t_s[keep], rec.f[keep], rec.w[keep]), platform, ctrl,
        load_cueing(platform.default_preset), rate_hz=RATE_HZ, limits=lim,
    )  # fmt: skip
    return made


def _with_stop(ctrl: IfaceController) -> IfaceController:
    return dataclasses.replace(ctrl, stop_bytes=STOP)


def _ends_with_stop_after_park(stream: bytes, rig: Any) -> None:
    """One stop string, the last bytes; before it a whole ride within the limits, at rest at
    park; the firmware saw every frame before the stop word."""
    assert stream.count(STOP) == 1 and stream.endswith(STOP), stream[-40:]
    check_board(stream[: -len(STOP)], rig)  # ends at park, at rest
    parser = board_parser("smc3")
    frames = parser.feed(stream)
    assert parser.command_log == [("ena", 0), ("end", len(frames))]


def test_only_interface_strings_with_a_stop_string_end_with_one() -> None:
    smc3 = load_controller("smc3")
    assert isinstance(smc3, IfaceController) and smc3.stop_bytes == b""
    assert end_of_run_messages(smc3) == []
    assert end_of_run_messages(_with_stop(smc3)) == [STOP]
    assert end_of_run_messages(load_controller("mbox6")) == []
    assert end_of_run_messages(load_controller("imax6")) == []


def test_the_stop_string_follows_the_park_at_the_end_of_a_ride(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink()
    rep = play_ride(ride, platform, _with_stop(ctrl), lim, sink, paced=False)
    assert rep.ride_frames_sent == ride.n_frames and not rep.interrupted
    assert sink.sent[-1] == STOP  # its own write, after the last park frame
    _ends_with_stop_after_park(b"".join(sink.sent), rig)


def test_without_a_stop_string_the_stream_ends_with_the_park(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink()
    play_ride(ride, platform, ctrl, lim, sink, paced=False)
    parser = board_parser("smc3")
    frames = parser.feed(b"".join(sink.sent))
    assert parser.command_log == [("ena", 0)] and sink.sent[-1].startswith(b"[A")
    assert len(frames) == len(sink.sent)


def test_an_error_exit_parks_then_sends_the_stop_string(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink()
    faulty = FaultyController(_with_stop(ctrl), ride.n_frames // 2)
    with pytest.raises(PlayAborted, match="encoder bug"):
        play_ride(ride, platform, faulty, lim, sink, paced=False)
    _ends_with_stop_after_park(b"".join(sink.sent), rig)


def test_a_park_that_could_not_be_sent_is_not_followed_by_the_stop_string(
    rig: Any, ride: Any
) -> None:
    platform, ctrl, lim, _ = rig
    sink = Sink(fail_at=ride.n_frames // 2, times=10**9)  # the link dies mid-ride
    with pytest.raises(ParkFailed):
        play_ride(ride, platform, _with_stop(ctrl), lim, sink, paced=False)
    assert STOP not in b"".join(sink.sent)


class _RefusesStop(Sink):
    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        if data == STOP:
            raise OSError(5, "Input/output error (injected)")
        super().send(data, t_s=t_s)


def test_a_refused_stop_string_is_noted_and_the_ride_still_ends_parked(rig: Any, ride: Any) -> None:
    platform, ctrl, lim, _ = rig
    sink = _RefusesStop()
    rep = play_ride(ride, platform, _with_stop(ctrl), lim, sink, paced=False)
    assert any("stop string could not be sent" in n for n in rep.notes), rep.notes
    check_board(b"".join(sink.sent), rig)


def test_play_cli_sigint_parks_then_sends_the_stop_string(
    rig: Any, ride: Any, tmp_path: Path
) -> None:
    """``motioncue play`` to the SMC3 emulator on UDP with a config that has a stop string,
    stopped by SIGINT mid-ride: the board reads the park, then the stop word, last."""
    _, ctrl, _, park = rig
    toml = tmp_path / "smc3-stop.toml"
    toml.write_text((config_dir("controllers") / "smc3.toml").read_text() + 'stop = "[end]"\n')
    stop_ctrl = load_controller(toml)
    assert isinstance(stop_ctrl, IfaceController) and stop_ctrl.stop_bytes == STOP
    path = save_ride(tmp_path / "lap.ride", ride)
    emu = IfaceEmulator(stop_ctrl).start()
    rc, out, err = signal_when_moving(["play", str(path), "--controller", str(toml), "--target",
                                       emu.where], emu, park, 50, signal.SIGINT)  # fmt: skip
    assert "Traceback" not in err, err
    assert rc == 130, err
    assert "interrupted and parked (SIGINT)" in out + err
    assert emu.malformed == 0
    assert_moved_then_parked(emu, np.asarray(park) - ctrl.pulses_lo, 50)
    assert emu.parser.command_log == [("ena", 0), ("end", len(emu.frames))]


def test_the_bridge_parks_then_sends_the_stop_string(rig: Any) -> None:
    """The live bridge (F1 stream) to the SMC3 emulator with a stop string, stopped as
    SIGINT stops ``motioncue bridge`` (``Bridge.stop``): park, then the stop word."""
    from motioncue.output import open_transport
    from motioncue.pipeline._bridge import Bridge, BridgeConfig
    from motioncue.pipeline._realtime import GateConfig
    from motioncue.telemetry import TelemetrySource
    from test_bridge import Sender

    platform, ctrl, lim, park = rig
    stop_ctrl = _with_stop(ctrl)
    source = TelemetrySource("f1", 0, "127.0.0.1")
    emu = IfaceEmulator(stop_ctrl).start()
    transport = open_transport(emu.where)
    gate = GateConfig(timeout_s=0.25, fade_out_s=0.3, fade_in_s=0.3)
    try:
        with Sender(source.port, 2024):
            bridge = Bridge(platform, stop_ctrl, load_cueing(platform.default_preset), source,
                            transport, lim, BridgeConfig(rate_hz=100.0, gate=gate))  # fmt: skip
            bridge.start()
            try:
                end = time.monotonic() + 30
                while time.monotonic() < end and not (
                    len(emu.frames) and np.abs(emu.trace.positions[-1] - park).max() > 20
                ):
                    time.sleep(0.01)
            finally:
                final = bridge.stop()
        assert final.state == "stopped" and final.error is None, final
        time.sleep(0.1)
    finally:
        transport.close()
        source.close()
        emu.stop()
    frames = np.array(emu.frames)
    park_v = np.asarray(park) - ctrl.pulses_lo
    assert np.abs(frames - park_v).max() > 20 and not emu.violations, emu.violations[:3]
    np.testing.assert_array_equal(frames[-1], park_v)
    assert emu.parser.command_log == [("ena", 0), ("end", len(emu.frames))]
