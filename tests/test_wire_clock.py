"""Limits on the controller's own clock, at every common frame rate.

MBOX and IMAX frames carry whole milliseconds, and the MBOX plays them Fn012/1000 times as
fast as stamped. Every frame ``generate`` writes (its pcap) and ``bridge`` sends is decoded
here by a decoder written from the manuals' frame tables (not the package's), its time taken
as the controller reads it (``stamp_ms / 1000 / catch_up``), and checked against the motor's
own limits: the platform's drive and [limits] with the controller's parameters, derived with
the catch-up switched off (Fn012 = 1000), so the catch-up division itself is under test.
A rate a controller cannot carry must be refused with a clear message instead.
"""

from __future__ import annotations

import math
import struct
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from motioncue import ConfigError
from motioncue.cli import main
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.pipeline._realtime import GateConfig
from motioncue.telemetry import TelemetrySample
from motioncue.trajectory import ActuatorLimits

RATES = (30, 50, 60, 90, 100, 120, 144, 200, 250, 300, 500, 1000)
CONTROLLERS = {"mbox3": "seat3", "mbox6": "stewart6-linear", "imax3": "seat3",
               "imax6": "stewart6-linear"}  # fmt: skip
G = 9.80665


# -- the manuals' frame layouts (MBOX 4.2.7-4.2.9; IMAX 2.2.2.5) ----------------------------
def decode_frame(data: bytes, kind: str) -> tuple[int, int, tuple[int, ...]]:
    """``(frame number, absolute ms, positions)`` of a 0x1301 frame."""
    confirm, passcode, function, channel, _accept, _reply = struct.unpack_from(">6H", data)
    assert (confirm, passcode, function) == (0x55AA, 0, 0x1301)
    n = {0: 3, 1: 6}[channel]
    tail = 8 if kind == "mbox" else 6  # MBOX: BaseDout, DAC1, DAC2, ExtDout; IMAX: PortOut, Extend
    assert len(data) == 12 + 8 + 4 * n + tail
    frame, ms = struct.unpack_from(">II", data, 12)
    positions = struct.unpack_from(f">{n}i", data, 20)
    return frame, ms, positions


def read_pcap_payloads(path: Path) -> list[bytes]:
    import dpkt

    out = []
    with path.open("rb") as fh:
        for _ts, buf in dpkt.pcap.Reader(fh):
            ip = dpkt.ethernet.Ethernet(buf).data
            out.append(bytes(ip.data.data))
    return out


def motor_limits(platform: Any, controller: Any) -> tuple[np.ndarray, ...]:
    """Stroke ends, speed and acceleration limits in pulses, as the motors must keep them:
    derived with the controller playing exactly as stamped."""
    plain = controller
    if controller.kind == "mbox":
        plain = controller.with_parameters(Fn012=1000)
    table = ActuatorLimits.from_platform(platform, plain).to_pulses_table(platform)
    lo = np.array([r["stroke_pulses"][0] for r in table], dtype=float)
    hi = np.array([r["stroke_pulses"][1] for r in table], dtype=float)
    v = np.array([r["max_speed_pulses_s"] for r in table])
    a = np.array([r["max_accel_pulses_s2"] for r in table])
    return lo, hi, v, a


def catch_up(controller: Any) -> float:
    """MBOX 5.3.3: Fn012 >= 1000 plays frames Fn012/1000 times as fast as stamped."""
    return controller.parameters["Fn012"] / 1000.0 if controller.kind == "mbox" else 1.0


def check_on_controller_clock(
    frames: list[bytes], platform: Any, controller: Any, park: np.ndarray
) -> dict[str, float]:
    """Worst use of each limit (1.0 = at the limit) over frames as the controller plays them,
    starting from rest at park and (checked by the caller) ending at rest at park."""
    decoded = [decode_frame(d, controller.kind) for d in frames]
    numbers = [f for f, _, _ in decoded]
    assert numbers == list(range(len(numbers))), "frames lost or reordered"
    ms = np.array([m for _, m, _ in decoded], dtype=float)
    p = np.array([q for _, _, q in decoded], dtype=float)
    assert np.all(np.diff(ms) > 0), "two frames with the same ms stamp (a jog)"
    t = ms / 1000.0 / catch_up(controller)
    lo, hi, vmax, amax = motor_limits(platform, controller)
    # at rest at park before the first frame, one frame period earlier
    t = np.concatenate([[t[0] - (t[1] - t[0])], t])
    p = np.vstack([park, p])
    h = np.diff(t)[:, None]
    v = np.diff(p, axis=0) / h
    a = 2.0 * np.diff(v, axis=0) / (h[1:] + h[:-1])
    return {
        "stroke": float(np.max(np.maximum((lo - p) / (hi - lo), (p - hi) / (hi - lo)))) + 1.0,
        "speed": float(np.max(np.abs(v) / vmax)),
        "accel": float(np.max(np.abs(a) / amax)),
    }


def square_wave_csv(path: Path, seconds: float = 2.0) -> Path:
    """The issue's reproduction: a 1 Hz, 1 g square wave in fx and fy.

    Two periods: every accepted rate and controller uses each limit as much as on four
    (measured, session 28: the worst stroke, speed and acceleration use of the 24 cases equal
    to 1e-4, but the acceleration at 50 Hz on the 3-axis seat, 0.903 / 0.627 against 0.908 /
    0.630, and the stroke at 1000 Hz on mbox6, 1.000 against 0.982), for 30 % less CPU:
    the frames after the wave (fade-out and park) are the same."""
    t = np.arange(0.0, seconds, 0.01)
    sq = np.where(np.sin(2 * np.pi * 1.0 * t) >= 0, G, -G)
    rows = np.column_stack([t, sq, sq, np.full_like(t, G), 0 * t, 0 * t, 0 * t])
    np.savetxt(path, rows, delimiter=",", header="t,fx,fy,fz,wx,wy,wz", comments="")
    return path


def expect_refusal(rate: float, controller: Any) -> bool:
    period_ms = 1000.0 / rate
    return abs(period_ms - round(period_ms)) > 1e-9 or rate > 1000.0


@pytest.fixture(scope="module")
def square(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return square_wave_csv(tmp_path_factory.mktemp("wire") / "square.csv")


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
@pytest.mark.parametrize("rate", RATES)
def test_generate_on_the_wire_clock(
    name: str, rate: float, square: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    pname = CONTROLLERS[name]
    ride, pcap = tmp_path / "s.ride", tmp_path / "s.pcap"
    args = ["generate", "--input", str(square), "--platform", pname, "--controller", name,
            "--preset", "racing", "--rate", str(rate), "--out", str(ride), "--pcap", str(pcap),
            "--quiet"]  # fmt: skip
    rc = main(args)
    err = capsys.readouterr().err
    controller = load_controller(name)
    if expect_refusal(rate, controller):
        assert rc == 2
        assert "whole milli" in err and "Hz" in err, err
        assert not ride.exists() and not pcap.exists()
        return
    assert rc == 0, err
    platform = load_platform(pname)
    park = np.asarray(platform.drives.to_pulses(platform.q_park), dtype=float)
    frames = read_pcap_payloads(pcap)
    use = check_on_controller_clock(frames, platform, controller, park)
    assert use["stroke"] <= 1.0 and use["speed"] <= 1.0 and use["accel"] <= 1.0, use
    last = np.array(decode_frame(frames[-1], controller.kind)[2], dtype=float)
    prev = np.array(decode_frame(frames[-2], controller.kind)[2], dtype=float)
    assert np.array_equal(last, park) and np.array_equal(prev, park)  # parked, at rest


class SquareSource:
    """A telemetry source for Bridge.step by hand: the square wave, sampled on demand."""

    def __init__(self) -> None:
        self.now = 0.0

    def latest(self) -> TelemetrySample:
        s = G if math.sin(2 * math.pi * self.now) >= 0 else -G
        return TelemetrySample(self.now, (s, s, G), (0.0, 0.0, 0.0), False, "test")

    @property
    def stats(self) -> dict[str, int]:
        return {"samples": 0, "datagrams": 0}


class Recorder:
    def __init__(self) -> None:
        self.sent: list[bytes] = []

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        self.sent.append(bytes(data))


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
@pytest.mark.parametrize("rate", RATES)
def test_bridge_on_the_wire_clock(name: str, rate: float) -> None:
    pname = CONTROLLERS[name]
    platform = load_platform(pname)
    controller = load_controller(name)
    config = BridgeConfig(rate_hz=rate, gate=GateConfig(0.25, 0.3, 0.3))
    limits = ActuatorLimits.from_platform(platform, controller, rate_hz=rate)
    source, link = SquareSource(), Recorder()
    if expect_refusal(rate, controller):
        with pytest.raises(ConfigError, match="whole milli"):
            Bridge(platform, controller, load_cueing("racing"), source, link, limits, config)
        assert link.sent == []
        return
    bridge = Bridge(platform, controller, load_cueing("racing"), source, link, limits, config)
    period = 1.0 / rate
    k = 0
    for _ in range(int(2.5 * rate)):  # fade in, then the square wave
        source.now = k * period
        bridge.step(k * period)
        k += 1
    for _ in range(int(20 * rate)):  # stop: fade out and park
        source.now = k * period
        bridge.step(k * period, stopping=True)
        k += 1
        if bridge.gate.parked and bridge.stage.parked:
            break
    assert bridge.stage.parked
    park = np.asarray(platform.drives.to_pulses(platform.q_park), dtype=float)
    use = check_on_controller_clock(link.sent, platform, controller, park)
    assert use["stroke"] <= 1.0 and use["speed"] <= 1.0 and use["accel"] <= 1.0, use
    moved = [decode_frame(d, controller.kind)[2] for d in link.sent]
    assert any(np.any(np.array(m) != park) for m in moved)  # it did move
    assert np.array_equal(np.array(moved[-1], dtype=float), park)


def test_catch_up_is_what_keeps_the_mbox_inside() -> None:
    """The checker is sharp: frames planned without the catch-up division break the speed
    limit on the MBOX's clock (Fn012 = 1200)."""
    platform = load_platform("stewart6-linear")
    controller = load_controller("mbox6")
    plain = controller.with_parameters(Fn012=1000)
    rate = 100.0
    limits = ActuatorLimits.from_platform(platform, plain, rate_hz=rate)
    source, link = SquareSource(), Recorder()
    bridge = Bridge(platform, controller, load_cueing("racing"), source, link, limits,
                    BridgeConfig(rate_hz=rate, gate=GateConfig(0.25, 0.3, 0.3)))  # fmt: skip
    for k in range(300):
        source.now = k / rate
        bridge.step(k / rate)
    park = np.asarray(platform.drives.to_pulses(platform.q_park), dtype=float)
    use = check_on_controller_clock(link.sent, platform, controller, park)
    assert use["speed"] > 1.0 or use["accel"] > 1.0, use
