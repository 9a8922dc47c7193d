"""The live bridge on the newer games: X-Plane, DiRT (Codemasters extradata) and Project CARS 2
packets over UDP loopback -> Bridge at 250 Hz -> SC-MBOX emulator, frames checked against the
limits table by the independent finite-difference check of ``_verify``.
"""

from __future__ import annotations

import math
import socket
import time
from collections.abc import Callable

import numpy as np
import pytest

from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox, open_transport
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import TelemetrySource, open_source
from motioncue.telemetry._dirt import pack_extradata
from motioncue.telemetry._pcars2 import PCars2Telemetry
from motioncue.telemetry._xplane import UNUSED, pack_data
from motioncue.trajectory import ActuatorLimits
from test_bridge import ThreadedSender

GATE = GateConfig(timeout_s=0.25, fade_out_s=0.3, fade_in_s=0.3)
U = UNUSED


def _xplane(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    # normal, axial, side g; P, Q, R in deg/s (X-Plane 12)
    return pack_data({4: (0.2, U, 0.0, U, 1.0 + 0.3 * s, 0.25 * s, 0.3 * s, U),
                      16: (20.0 * s, 10.0 * s, 5.0 * s)})  # fmt: skip


def _dirt(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    psi = 0.4 * s  # heading swinging left and right
    fwd = (math.cos(psi), 0.0, -math.sin(psi))
    right = (math.sin(psi), 0.0, math.cos(psi))  # fwd x up, world y up
    v = [0.0] * 66
    v[0] = 100.0 + t
    v[7] = 20.0
    v[8:11] = [20.0 * c for c in fwd]
    v[11:14] = right
    v[14:17] = fwd
    v[33], v[34], v[35], v[37], v[63] = 3.0, 0.6 * s, 0.3 * s, 500.0, 800.0
    return pack_extradata(v)


def _pcars2(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    return PCars2Telemetry(
        int(t * 60), 30.0, 5000, 8000, 0x63, (0.05 * s, 0.0, 0.05 * s), (0.0, 0.0, -30.0),
        (0.2 * s, 0.3 * s, 0.1 * s), (4.0 * s, 1.0 * s, -3.0 * s), (0.0, 0.0, 0.0, 0.0),
    ).pack()  # fmt: skip


PACKETS: dict[str, Callable[[float], bytes]] = {
    "xplane": _xplane,
    "dirt": _dirt,
    "pcars2": _pcars2,
}


class Sender(ThreadedSender):
    """Sends one game's packets at 60 Hz to a port from a thread."""

    def __init__(self, port: int, make: Callable[[float], bytes]) -> None:
        super().__init__(port)
        self.make = make

    def _run(self) -> None:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            t0 = time.perf_counter()
            k = 0
            while not self._stop.is_set():
                k += 1
                left = t0 + k / 60.0 - time.perf_counter()
                if left > 0:
                    time.sleep(left)
                tx.sendto(self.make(k / 60.0), self.dest)
                self.sent += 1


def _wait_for(cond: Callable[[], bool], timeout_s: float = 3.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return bool(cond())


@pytest.mark.parametrize("game", sorted(PACKETS))
def test_the_bridge_moves_a_rig_on_the_game_within_the_limits(game: str) -> None:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    with mbox.MboxEmulator(ctrl) as emu:
        source = open_source(f"{game}:127.0.0.1:0")
        assert isinstance(source, TelemetrySource)
        transport = open_transport(f"udp://127.0.0.1:{emu.port}")
        try:
            bridge = Bridge(platform, ctrl, load_cueing("racing"), source, transport, lim,
                            BridgeConfig(rate_hz=250.0, gate=GATE))  # fmt: skip
            with Sender(source.port, PACKETS[game]):
                bridge.start()
                try:
                    assert _wait_for(lambda: bridge.stats.state == "live"), bridge.stats
                    time.sleep(1.2)
                    live = bridge.stats
                    assert live.samples_in > 50 and live.bad_packets == 0
                    assert live.packet_reasons["sample"] == live.samples_in
                finally:
                    final = bridge.stop()
        finally:
            transport.close()
            source.close()
    assert final.state == "stopped" and final.error is None and final.park_q_error == 0.0
    assert _wait_for(lambda: emu.received >= final.frames_sent)
    tr = emu.trace
    chk = check_frames(tr.t_s, tr.positions, lim.to_pulses_table(platform), start_at_rest=True)
    assert chk.ok, chk.summary()
    assert emu.violations == [] and emu.internal_errors == []
    park = platform.drives.to_pulses(platform.q_park)
    np.testing.assert_array_equal(tr.positions[0], park)
    np.testing.assert_array_equal(tr.positions[-1], park)
    moved = np.abs(tr.positions - park).max(axis=0) / platform.drives.pulses_per_unit
    assert moved.max() > 0.005  # the game's motion reached the actuators (> 5 mm)
