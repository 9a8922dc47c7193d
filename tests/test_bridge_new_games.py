"""The live bridge on the games of issue 22 (Assetto Corsa, Gran Turismo 7, Live for Speed,
EA Sports WRC, Richard Burns Rally, DCS World): a stand-in game over UDP loopback (asked by
the source where the game needs it) -> Bridge at 250 Hz -> SC-MBOX emulator, frames checked
against the limits table by the independent finite-difference check of ``_verify``."""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Callable

import numpy as np
import pytest

from _games import Answer, StandInGame
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox, open_transport
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.pipeline._verify import check_frames
from motioncue.telemetry import TelemetrySource
from motioncue.telemetry._ac import ACCarInfo, handshake_response
from motioncue.telemetry._dcs import DCSFrame
from motioncue.telemetry._gt7 import GT7Packet, encrypt
from motioncue.telemetry._lfs import OutSimMain
from motioncue.telemetry._rbr import RBRCar
from motioncue.telemetry._wrc import WRCDecoder
from motioncue.trajectory import ActuatorLimits

GATE = GateConfig(timeout_s=0.25, fade_out_s=0.3, fade_in_s=0.3)


def _ac(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    return ACCarInfo(30.0, (0.3 * s, 0.05 * s, 0.25 * s), int(t * 1e3), 6000.0, 4,
                     (t, 0.0, 0.0)).pack()  # fmt: skip


def _ac_answer(req: bytes) -> tuple[list[bytes], bool]:
    op = struct.unpack("<iii", req)[2] if len(req) == 12 else -1
    if op == 0:
        return [handshake_response("ks_audi_r8_lms", "Tester", "monza")], False
    return [], op == 1


def _gt7(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    psi = 0.3 * s  # yawing left and right; the car faces world -z at psi = 0
    q = (0.0, math.sin(psi / 2), 0.0, math.cos(psi / 2))
    speed = 30.0 + 4.0 * s
    v = (-speed * math.sin(psi), 0.0, -speed * math.cos(psi))
    w = (0.0, 0.3 * 2 * math.pi * 0.7 * math.cos(2 * math.pi * 0.7 * t), 0.0)
    pid = round(t * 60.0)
    return encrypt(GT7Packet(pid, (0.0, 0.0, 0.0), v, q, w, speed, 6000.0).pack(), pid * 7919)


def _gt7_answer(req: bytes) -> tuple[list[bytes], bool]:
    return [], req in (b"A", b"B", b"~", b"C")


def _lfs(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    m = OutSimMain((0.0, 0.0, 0.3 * s), 0.2 * s, 0.02 * s, 0.03 * s,
                   (2.0 * s, 3.0 * s, 0.5 * s), (0.0, 30.0, 0.0))  # fmt: skip
    return m.outsim2(time_ms=int(t * 1e3))


_WRC = WRCDecoder().layout


def _wrc(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    psi = 0.3 * s  # yawing; world y up, the car faces +z, its left is +x at psi = 0
    ch = {"game_total_time": t, "stage_current_time": t, "vehicle_acceleration_x": 3.0 * s,
          "vehicle_acceleration_z": 2.0 * s, "vehicle_engine_rpm_current": 6000.0,
          "vehicle_up_direction_y": 1.0}  # fmt: skip
    for name, vec in (("forward", (math.sin(psi), 0.0, math.cos(psi))),
                      ("left", (math.cos(psi), 0.0, -math.sin(psi)))):  # fmt: skip
        for axis, c in zip("xyz", vec, strict=True):
            ch[f"vehicle_{name}_direction_{axis}"] = c
    return _WRC.pack(ch)


def _dcs(t: float) -> bytes:
    """Loops: pitching through 360 deg every 6 s at 150 m/s (through 90 deg of pitch)."""
    q = 2 * math.pi / 6.0
    th = q * t
    return DCSFrame(t, (math.sin(th), (150.0 * q + 9.80665 * math.cos(th)) / 9.80665, 0.0),
                    (0.0, 0.0, q)).pack()  # fmt: skip


def _rbr(t: float) -> bytes:
    s = math.sin(2 * math.pi * 0.7 * t)
    return RBRCar(int(t * 400), t, 4, 90.0, (2.0 * s, 1.0 * s, 0.0),
                  (25.0, 0.0, 0.0, 5.0 * s, 3.0 * s, 15.0 * s),
                  (3.0 * s, 2.0 * s, 0.5 * s, 0.0, 0.0, 0.0), 6000.0).pack()  # fmt: skip


GAMES: dict[str, tuple[Callable[[float], bytes], Answer | None]] = {
    "ac": (_ac, _ac_answer),
    "gt7": (_gt7, _gt7_answer),
    "lfs": (_lfs, None),
    "wrc": (_wrc, None),
    "dcs": (_dcs, None),
    "rbr": (_rbr, None),
}


def _wait_for(cond: Callable[[], bool], timeout_s: float = 3.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return bool(cond())


@pytest.mark.parametrize("game", sorted(GAMES))
def test_the_bridge_moves_a_rig_on_the_game_within_the_limits(game: str) -> None:
    make, answer = GAMES[game]
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    with mbox.MboxEmulator(ctrl) as emu, StandInGame(make, answer) as stand_in:
        if answer is None:
            source = TelemetrySource(game, 0, "127.0.0.1")
            stand_in.client = ("127.0.0.1", source.port)
            stand_in.streaming = True
        else:  # the source asks the stand-in, which answers to the source's port
            source = TelemetrySource(game, 0, "127.0.0.1", peer="127.0.0.1",
                                     peer_port=stand_in.port)  # fmt: skip
        transport = open_transport(f"udp://127.0.0.1:{emu.port}")
        try:
            bridge = Bridge(platform, ctrl, load_cueing("racing"), source, transport, lim,
                            BridgeConfig(rate_hz=250.0, gate=GATE))  # fmt: skip
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
    if answer is not None:
        assert stand_in.requests and source.requests_sent >= len(stand_in.requests)
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
