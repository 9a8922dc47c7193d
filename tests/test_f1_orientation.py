"""F1 without Motion Ex: the angular velocity derived from the Motion packets' orientation.

The orientation convention is pinned on the real captures (every car's float yaw/pitch/roll
against its packed int16 forward and right vectors). The derivation is then checked against
Motion Ex: the real captures hold one Motion and one Motion Ex per game year (single
datagrams), so the second orientation cannot come from the game; each test starts from the
real player orientation and turns it by the real Motion Ex angular velocity with rotation
matrices (Rodrigues' formula, no Euler-angle rates), packs the resulting angles as the game
does (float32, like the session time), and asks the decoder, fed Motion packets only, for
the rate. A loopback test shows a Motion-only stream moving the bridge.
"""

from __future__ import annotations

import math
import socket
import struct
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from _ports import free_port
from motioncue import ConfigError
from motioncue.cli import main
from motioncue.cueing import load_cueing
from motioncue.kinematics import load_platform
from motioncue.output import load_controller, mbox, open_transport
from motioncue.pipeline._bridge import Bridge, BridgeConfig
from motioncue.telemetry import TelemetrySource, open_source
from motioncue.telemetry._f1 import CAR_MOTION, HEADER, NOTE_W_FROM_ORIENTATION, F1Decoder
from motioncue.telemetry._sample import up_in_body_from_angles
from motioncue.trajectory import ActuatorLimits
from test_bridge import (
    DATA,
    GATE,
    F1Stream,
    ThreadedSender,
    _all_received,
    _check_trace,
    _wait_for,
    lap_motion,
)

pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason="real F1 captures not on this machine")

YEARS = (2023, 2024)
ANGLES = 48  # yaw, pitch, roll: float32 at +48 in CarMotionData (EA specification)
FWD_RIGHT = 24  # worldForwardDir[3], worldRightDir[3]: int16 at +24


# -- rotations, written here from the definitions (world X, Y up, Z; local left, up, fwd) ---
def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def world_from_local(yaw: float, pitch: float, roll: float) -> np.ndarray:
    """Columns: the car's left, up and forward axes in world coordinates."""
    return _ry(yaw) @ _rx(pitch) @ _rz(roll)


def angles_of(r: np.ndarray) -> tuple[float, float, float]:
    """(yaw, pitch, roll) of a world <- local rotation (inverse of ``world_from_local``)."""
    left, up, fwd = r[:, 0], r[:, 1], r[:, 2]
    return (
        math.atan2(fwd[0], fwd[2]),
        -math.asin(max(-1.0, min(1.0, fwd[1]))),
        math.atan2(left[1], up[1]),
    )


def turn(r: np.ndarray, w_local: np.ndarray, dt: float) -> np.ndarray:
    """``r`` after ``dt`` s of the constant body rate ``w_local`` (rad/s, local axes):
    ``R(t + dt) = R(t) exp([w] dt)`` by Rodrigues' formula."""
    th = float(np.linalg.norm(w_local)) * dt
    if th == 0.0:
        return r
    k = w_local / np.linalg.norm(w_local)
    kx = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return r @ (np.eye(3) + math.sin(th) * kx + (1 - math.cos(th)) * kx @ kx)


def _f32(x: float) -> float:
    return float(struct.unpack("<f", struct.pack("<f", x))[0])


# -- packets --------------------------------------------------------------------------------
def _real(year: int) -> tuple[bytes, bytes]:
    d = DATA / str(year)
    return (d / "packet-0.bin").read_bytes(), (d / "packet-13.bin").read_bytes()


def _cars(motion: bytes) -> Iterator[tuple[np.ndarray, np.ndarray, tuple[float, ...]]]:
    """(forward, right, (yaw, pitch, roll)) of every car slot that holds a car; the int16
    direction vectors normalised to unit length."""
    for i in range(22):
        base = HEADER.size + CAR_MOTION.size * i
        v = struct.unpack_from("<3h3h", motion, base + FWD_RIGHT)
        if not any(v):
            continue  # an empty slot (15 cars in both captures)
        fwd = np.array(v[:3]) / np.linalg.norm(v[:3])
        right = np.array(v[3:]) / np.linalg.norm(v[3:])
        yield fwd, right, struct.unpack_from("<3f", motion, base + ANGLES)


def motion_at(motion: bytes, stime: float, r: np.ndarray) -> bytes:
    """The real Motion packet at session time ``stime`` with the player car's orientation
    ``r`` (angles as float32, forward/right vectors as int16, both as the game packs them)."""
    out = bytearray(motion)
    struct.pack_into("<f", out, 15, stime)
    base = HEADER.size + CAR_MOTION.size * motion[27]
    fwd, right = r[:, 2], -r[:, 0]
    struct.pack_into(
        "<3h3h", out, base + FWD_RIGHT, *(round(32767 * float(x)) for x in (*fwd, *right))
    )
    struct.pack_into("<3f", out, base + ANGLES, *angles_of(r))
    return bytes(out)


def ex_w_iso(ex: bytes) -> np.ndarray:
    """The Motion Ex angular velocity as the decoder reports it (ISO: forward, left, up)."""
    dec = F1Decoder()
    dec.feed(ex, 0.0)
    return np.array(dec._ex_w)


def ex_w_local(ex: bytes) -> np.ndarray:
    """angularVelocity as packed: local (left, up, forward), float32 at 29 + 4 * 36."""
    return np.array(struct.unpack_from("<3f", ex, HEADER.size + 4 * 36))


# -- the convention --------------------------------------------------------------------------
@pytest.mark.parametrize("year", YEARS)
def test_orientation_convention_is_pinned_by_the_real_direction_vectors(year: int) -> None:
    """forward = R e_z and right = -R e_x with R = Ry(yaw) Rx(pitch) Rz(roll), for every car
    of the capture, to one int16 step (1 / 32767 = 3.05e-5; the packed vectors are up to
    1.7e-4 short of unit length, so they are normalised first; 5e-5 leaves room for the
    float32 angles). A flipped sign of pitch (forward Y up to 0.019), roll (right Y up to
    0.025) or yaw fails by two orders of magnitude more."""
    motion, _ = _real(year)
    cars = list(_cars(motion))
    assert len(cars) == 15
    pitches, rolls = [], []
    for fwd, right, (yaw, pitch, roll) in cars:
        r = world_from_local(yaw, pitch, roll)
        np.testing.assert_allclose(r[:, 2], fwd, atol=5e-5)
        np.testing.assert_allclose(-r[:, 0], right, atol=5e-5)
        # the decoder's gravity from the vectors, (F_y, -R_y, (R x F)_y), is the ISO "up"
        # of these angles taken as ISO pitch and roll
        up_vectors = (fwd[1], -right[1], float(np.cross(right, fwd)[1]))
        np.testing.assert_allclose(up_in_body_from_angles(pitch, roll), up_vectors, atol=5e-5)
        pitches.append(abs(pitch))
        rolls.append(abs(roll))
    assert max(pitches) > 0.01 and max(rolls) > 0.01  # the signs are really exercised


# -- derived against Motion Ex ---------------------------------------------------------------
def derived_rates(
    motion: bytes, r0: np.ndarray, w_local: np.ndarray, frames: int, rate_hz: float = 60.0
) -> list[np.ndarray]:
    """Feed ``frames + 1`` Motion packets (no Motion Ex) of a car turning at ``w_local``;
    return the angular velocities of the samples the decoder made."""
    stime0 = struct.unpack_from("<f", motion, 15)[0]
    dec = F1Decoder()
    out = []
    r = r0
    for k in range(frames + 1):
        stime = _f32(stime0 + k / rate_hz)
        result = dec.decode(motion_at(motion, stime, r), 0.0)
        if k == 0:
            assert result.reason == "partial: no motion ex"  # nothing to differentiate yet
        else:
            assert result.sample is not None, result.reason
            out.append(np.array(result.sample.w))
        r = turn(r, w_local, 1.0 / rate_hz)
    assert dec.stats[NOTE_W_FROM_ORIENTATION] == frames == dec.stats["sample"]
    return out


def _tolerance(w: np.ndarray) -> float:
    """|derived - Motion Ex| allowed per component (rad/s), with its reasons:

    * session time float32 near 700 s: steps of 2**-14 s = 61 us, so each 1/60 s interval
      is known to 61 us: 0.37 % of the rate;
    * angles float32: about 2.4e-7 rad at yaw 2.6, over 1/60 s: 1.5e-5 rad/s;
    * mid-point differentiation of a constant body rate: ~|w|^3 dt^2 / 24, below 1e-4 rad/s
      for |w| < 2 rad/s at 60 Hz.
    Total: 0.5 % of |w| plus 1e-4 rad/s.
    """
    return 0.005 * float(np.linalg.norm(w)) + 1e-4


@pytest.mark.parametrize("year", YEARS)
def test_derived_rate_agrees_with_motion_ex_on_the_real_capture(year: int) -> None:
    motion, ex = _real(year)
    (yaw, pitch, roll) = struct.unpack_from("<3f", motion, HEADER.size + ANGLES)  # player 0
    assert motion[27] == 0
    w_iso = ex_w_iso(ex)
    rates = derived_rates(motion, world_from_local(yaw, pitch, roll), ex_w_local(ex), 12)
    tol = _tolerance(w_iso)
    for w in rates:
        np.testing.assert_allclose(w, w_iso, rtol=0, atol=tol)
    if year == 2024:  # the fast left-hand corner: yawing left at 0.38 rad/s
        assert rates[-1][2] == pytest.approx(0.378, abs=0.003)


@pytest.mark.parametrize(
    ("yaw0", "pitch0", "roll0", "w_local"),
    [
        # crossing yaw = +-pi at 1.5 rad/s while banked and pitched: the kinematic matrix's
        # cross terms (sin pitch, sin roll ~ 0.3, 0.5) are large here, unlike on the captures
        (math.pi - 0.05, 0.3, -0.5, (-0.8, 1.5, 1.0)),
        # on its roof and rolling through roll = +-pi (a crash), yawing the other way
        (-math.pi + 0.03, -0.2, math.pi - 0.04, (0.4, -1.2, 1.8)),
    ],
)
def test_derived_rate_is_right_across_wrap_around_and_large_angles(
    yaw0: float, pitch0: float, roll0: float, w_local: tuple[float, float, float]
) -> None:
    motion, _ = _real(2024)
    wl = np.array(w_local)
    w_iso = np.array([wl[2], wl[0], wl[1]])  # (forward, left, up)
    rates = derived_rates(motion, world_from_local(yaw0, pitch0, roll0), wl, 30)
    for w in rates:  # no 2 pi / dt spike where an angle wraps
        np.testing.assert_allclose(w, w_iso, rtol=0, atol=_tolerance(w_iso))
    # the same differences without the kinematic matrix (Euler rates taken as body rates)
    # are far off here: the check has teeth
    r0 = world_from_local(yaw0, pitch0, roll0)
    a0, a1 = np.array(angles_of(r0)), np.array(angles_of(turn(r0, wl, 1 / 60)))
    d = (a1 - a0 + math.pi) % (2 * math.pi) - math.pi
    naive = np.array([d[2], d[1], d[0]]) * 60
    assert np.abs(naive - w_iso).max() > 20 * _tolerance(w_iso)


def test_motion_ex_takes_precedence_and_the_switch_is_seamless() -> None:
    motion, ex = _real(2024)
    stime0 = struct.unpack_from("<f", motion, 15)[0]
    ex_iso = ex_w_iso(ex)
    r = world_from_local(*struct.unpack_from("<3f", motion, HEADER.size + ANGLES))
    other = np.array([0.0, -0.9, 0.4])  # the orientation turns differently from Motion Ex
    dec = F1Decoder(max_ex_age_s=0.09)
    got = []
    for k in range(20):
        stime = _f32(stime0 + k / 60)
        if k < 10:  # Motion Ex of the same frame, then the Motion
            e = bytearray(ex)
            struct.pack_into("<f", e, 15, stime)
            dec.feed(bytes(e), 0.0)
        s = dec.feed(motion_at(motion, stime, r), 0.0)
        got.append(None if s is None else np.array(s.w))
        r = turn(r, other, 1 / 60)
    for w in got[:10]:
        assert w is not None
        np.testing.assert_array_equal(w, ex_iso)  # Motion Ex wins while it comes
    # Motion Ex stops (last one at k = 9): once it is older than max_ex_age_s (k >= 15)
    # the orientation takes over, with no partial packet in between (it was tracked all
    # along)
    other_iso = np.array([other[2], other[0], other[1]])
    for k in range(10, 20):
        w = got[k]
        assert w is not None
        if k >= 15:
            np.testing.assert_allclose(w, other_iso, atol=_tolerance(other_iso))
        else:
            np.testing.assert_array_equal(w, ex_iso)
    assert dec.stats["sample"] == 20
    assert dec.stats[NOTE_W_FROM_ORIENTATION] == 5


def test_gaps_other_sessions_time_going_back_and_bad_angles_are_handled() -> None:
    motion, _ = _real(2023)
    stime0 = struct.unpack_from("<f", motion, 15)[0]
    r = world_from_local(1.0, 0.02, -0.01)
    dec = F1Decoder(max_orientation_dt_s=0.25)

    def feed(dt: float, uid: int | None = None, angles: tuple[float, ...] | None = None) -> str:
        pkt = bytearray(motion_at(motion, _f32(stime0 + dt), r))
        if uid is not None:
            struct.pack_into("<Q", pkt, 7, uid)
        if angles is not None:
            struct.pack_into("<3f", pkt, HEADER.size + ANGLES, *angles)
        return dec.decode(bytes(pkt), 0.0).reason

    assert feed(0.0) == "partial: no motion ex"
    assert feed(1 / 60) == "sample"
    assert feed(1 / 60) == "sample"  # a duplicate repeats the last rate
    assert feed(0.5) == "partial: no motion ex"  # 0.48 s gap: not differentiated
    assert feed(0.5 + 1 / 60) == "sample"
    assert feed(0.2) == "partial: no motion ex"  # session time went back (a flashback)
    assert feed(0.2 + 1 / 60, uid=7) == "partial: no motion ex"  # another session
    assert feed(0.2 + 2 / 60, uid=7) == "sample"
    assert feed(0.2 + 3 / 60, uid=7, angles=(math.nan, 0.0, 0.0)) == "skipped: non-finite"
    assert feed(0.2 + 4 / 60, uid=7) == "sample"  # differentiated over the bad packet
    # an absurd jump (garbage angles) is out of range, never a sample
    assert feed(0.2 + 5 / 60, uid=7, angles=(1.0 + 3.0, 0.02, -0.01)) == "skipped: out of range"
    with pytest.raises(ConfigError, match="max_orientation_dt_s"):
        F1Decoder(max_orientation_dt_s=0.0)
    with pytest.raises(ConfigError, match="max_orientation_dt_s"):
        F1Decoder(max_orientation_dt_s=math.inf)


# -- the bridge on a Motion-only stream ------------------------------------------------------
class MotionOnlySender(ThreadedSender):
    """The moving F1 stream of ``test_bridge`` at 60 Hz, Motion packets only: no Motion Ex.
    The player's orientation follows the stream's body rates (integrated with ``turn``)."""

    def __init__(self, port: int, year: int = 2024) -> None:
        super().__init__(port)
        self.stream = F1Stream(year)

    def _run(self) -> None:
        s = self.stream
        r = world_from_local(*struct.unpack_from("<3f", s.motion, s.car + ANGLES))
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            t0 = time.perf_counter()
            k = 0
            while not self._stop.is_set():
                k += 1
                left = t0 + k / 60.0 - time.perf_counter()
                if left > 0:
                    time.sleep(left)
                g_lat, g_lon, g_vert, w = lap_motion(k / 60.0)
                _, motion = s.frame(k, g_lat, g_lon, g_vert, w)
                r = turn(r, np.array([w[1], w[2], w[0]]), 1 / 60)  # ISO -> (left, up, fwd)
                pkt = bytearray(motion)
                struct.pack_into("<3f", pkt, s.car + ANGLES, *angles_of(r))
                tx.sendto(bytes(pkt), self.dest)
                self.sent += 1


@contextmanager
def _rig() -> Iterator[tuple[Bridge, object, object, ActuatorLimits]]:
    platform = load_platform("stewart6-linear")
    ctrl = load_controller("mbox6")
    lim = ActuatorLimits.from_platform(platform, ctrl, a_max=5.0)
    with mbox.MboxEmulator(ctrl) as emu:
        source = open_source("f1:127.0.0.1:0")
        assert isinstance(source, TelemetrySource)
        transport = open_transport(f"udp://127.0.0.1:{emu.port}")
        try:
            bridge = Bridge(
                platform, ctrl, load_cueing("racing"), source, transport, lim,
                BridgeConfig(rate_hz=250.0, gate=GATE),
            )  # fmt: skip
            with MotionOnlySender(source.port):
                bridge.start()
                try:
                    yield bridge, emu, platform, lim
                finally:
                    bridge.stop()
        finally:
            transport.close()
            source.close()


def test_a_stream_without_motion_ex_moves_the_bridge_and_says_so() -> None:
    with _rig() as (bridge, emu, platform, lim):
        assert _wait_for(lambda: bridge.stats.state == "live", 3.0), bridge.stats.status_line()
        time.sleep(0.8)
        live = bridge.stats
        final = bridge.stop()
    assert live.gain == 1.0 and live.bad_packets == 0
    r = live.packet_reasons
    assert "partial: motion ex stored" not in r  # really no Motion Ex
    assert r[NOTE_W_FROM_ORIENTATION] == r["sample"] > 30
    assert NOTE_W_FROM_ORIENTATION in live.status_line()
    assert any("derived from the Motion orientation" in n for n in final.notes)
    assert final.state == "stopped" and final.error is None
    _all_received(emu, bridge)
    tr = _check_trace(emu, platform, lim)  # within the limits, ends parked at rest
    park = platform.drives.to_pulses(platform.q_park)
    moved = np.abs(tr.positions - park).max(axis=0) / platform.drives.pulses_per_unit
    assert np.all(moved > 0.005)  # frames left park: every actuator moved at least 5 mm


# -- record and generate say so --------------------------------------------------------------
def test_record_and_generate_report_the_derived_angular_velocity(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    port = free_port()
    rec = tmp_path / "motion-only.mctr"
    with MotionOnlySender(port) as sender:
        assert (
            main(["record", "--source", f"f1:{port}", "--out", str(rec), "--duration", "1.5"]) == 0
        )
    out = capsys.readouterr().out
    assert sender.sent > 30
    assert f"{NOTE_W_FROM_ORIENTATION}: " in out
    assert "partial: motion ex stored" not in out

    ride = tmp_path / "r.ride"
    rc = main(["generate", "--input", str(rec), "--platform", "seat3", "--controller", "mbox3",
               "--preset", "cinema-seat-3dof", "--out", str(ride), "--quiet"])  # fmt: skip
    err = capsys.readouterr().err
    assert rc == 0, err
    samples = int(err.split("telemetry: ")[1].split(" samples used")[0])
    assert samples > 30
    assert f"telemetry: {NOTE_W_FROM_ORIENTATION} ({samples} samples)" in err
