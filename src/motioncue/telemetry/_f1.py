"""EA SPORTS F1 23 / F1 24 / F1 25 UDP telemetry (Motion, Motion Ex and Session packets).

Layouts
-------
From EA's public "Data Output from F1 23 / F1 24 / F1 25 Game" UDP specifications (the F1 25
C++ structure file, ``(c) 2025 Electronic Arts``, and the F1 23/24 specification texts). All
little-endian, packed:

* Header, 29 bytes, the same in F1 23, 24 and 25: ``uint16 packetFormat`` (2023/2024/2025),
  ``uint8 gameYear, gameMajorVersion, gameMinorVersion, packetVersion, packetId``,
  ``uint64 sessionUID``, ``float sessionTime``, ``uint32 frameIdentifier,
  overallFrameIdentifier``, ``uint8 playerCarIndex, secondaryPlayerCarIndex``.
* Motion (id 0), 1349 bytes: header + 22 x CarMotionData (60 bytes): ``float
  worldPosition[3], worldVelocity[3]``, ``int16 worldForwardDir[3], worldRightDir[3]``
  (normalised, divide by 32767), ``float gForceLateral, gForceLongitudinal, gForceVertical,
  yaw, pitch, roll``.
* Motion Ex (id 13), player car only: 8 x ``float[4]`` wheel arrays (suspension position,
  velocity, acceleration, wheel speed, slip ratio, slip angle, lateral force, longitudinal
  force), ``float heightOfCOGAboveGround, localVelocity[3], angularVelocity[3],
  angularAcceleration[3], frontWheelsAngle``, ``float wheelVertForce[4]`` = 188 bytes common
  to all three years; F1 24 appends 5 floats (aero heights, roll angles, chassis yaw) -> 237
  bytes; F1 25 also ``chassisPitch, wheelCamber[4], wheelCamberGain[4]`` -> 273 bytes.
* Car Telemetry (id 6), 1352 bytes: header + 22 x 60 bytes (``uint16 speed, float throttle,
  steer, brake, uint8 clutch, int8 gear, uint16 engineRPM``, ...) + 3 bytes; only the player
  car's ``gear`` (byte 15: -1 reverse, 0 neutral) and ``engineRPM`` (byte 16) are read, for the
  effect layer. Motion Ex's ``suspensionVelocity`` (floats 4..7, wheels RL, RR, FL, FR) is in
  mm/s on the captures (positions ~50 mm, velocities ~100): it is passed on in m/s, reordered
  FL, FR, RL, RR.
* Session (id 1): after the header ``uint8 weather, int8 trackTemperature, int8
  airTemperature, uint8 totalLaps, uint16 trackLength, uint8 sessionType, int8 trackId, uint8
  formula, uint16 sessionTimeLeft, uint16 sessionDuration, uint8 pitSpeedLimit, uint8
  gamePaused, uint8 isSpectating, uint8 spectatorCarIndex`` (17 bytes read; the rest unused).

Axes (derived from the specification's field names and checked on real captured packets)
--------------------------------------------------------------------------------------
The world frame has +Y up (``worldPositionY`` is height). The car's local frame, in which
Motion Ex gives ``localVelocity`` and ``angularVelocity``, is **x left, y up, z forward**:

* ``localVelocity`` equals the world velocity projected on ``(-worldRightDir,
  worldRightDir x worldForwardDir, worldForwardDir)``; on the F1 23 capture (Motion and Motion
  Ex of the same frame) the three components agree to 1e-3 m/s, the x sign being opposite to
  the right direction. So local x is *left*, local z forward, local y = right x forward = up.
* (left, up, forward) is right-handed (left x up = forward), so ISO 8855 is a cyclic
  relabelling, a proper rotation: ``x_iso = z_local, y_iso = x_local, z_iso = y_local``.
  Angular velocity (a pseudovector) maps the same way: ``w_iso = (w_z, w_x, w_y)``.
* On the F1 24 capture (a fast left-hand corner) ``angularVelocity.y = +0.378 rad/s`` with
  ``localVelocity.z = 29 m/s`` gives a centripetal ``w x v`` of +11 m/s^2 along local +x,
  the wheels' lateral forces are all positive along local x, and ``gForceLateral = +1.35``:
  the lateral g-force is positive toward the car's **left** (ISO +y).
* ``gForceLongitudinal`` is positive forward (it is negative together with the summed
  longitudinal tyre forces when lifting at 73 m/s in the F1 23 capture).
* The g-forces are kinematic acceleration in g **without gravity**: ``gForceVertical`` is
  0.03 at 73 m/s on a level straight (F1 23 capture), not ~1.

Conversion
----------
With ``G0 = 9.80665``, ``F = worldForwardDir / 32767``, ``R = worldRightDir / 32767`` and
``U = R x F`` (the car's up axis in world coordinates), the body components of world up are
``(F_y, -R_y, U_y)`` (forward, left, up), so::

    f = G0 * (gForceLongitudinal + F_y,  gForceLateral - R_y,  gForceVertical + U_y)
    w = (angularVelocity.z, angularVelocity.x, angularVelocity.y)     # Motion Ex

A car at rest on level ground (g-forces 0, F_y = R_y = 0, U_y = 1) gives ``(0, 0, G0)``.

Orientation (``yaw``, ``pitch``, ``roll`` of CarMotionData, rad)
-----------------------------------------------------------------
With the car's local axes (left, up, forward) equal to the world axes (X, Y, Z) at zero
angles, the orientation is the intrinsic yaw-pitch-roll rotation

    R = Ry(yaw) Rx(pitch) Rz(roll)        (world <- local; Rx, Ry, Rz right-handed)

so ``forward = (cos p sin y, -sin p, cos p cos y)`` and ``right = -R (1, 0, 0) = -(cos r cos y
+ sin r sin p sin y, sin r cos p, -cos r sin y + sin r sin p cos y)``. Relabelled to ISO 8855
(x forward, y left, z up) these are exactly the ISO yaw (about up, nose left positive), pitch
(about the left axis, nose down positive) and roll (about forward, right side down positive)
of a Z-Y-X sequence, and the world up in body axes is ``up_in_body_from_angles(pitch, roll)``.
Checked on every car of both real Motion captures: the float angles give the packed int16
``worldForwardDir`` and ``worldRightDir`` (normalised: they are up to 1.7e-4 short) to one
int16 step, 1/32767, signs included (e.g.
pitch -0.0193 with forward Y +0.0193, roll +0.0241 with right Y -0.0241). Those cars are all
nearly level, so the order of pitch and roll (a second-order effect, ~1e-6 here) is not
seen in the data; yaw-pitch-roll is the order the names and ISO imply.

Angular velocity without Motion Ex
----------------------------------
Motion Ex is sent for the player's car only and can be switched off; an older packet mix or a
game set up that way sends Motion alone. Then the body rates come from the orientation of two
consecutive Motion packets of the same session and player car, ``dt`` of session time apart
(``0 < dt <=`` :data:`F1Decoder.max_orientation_dt_s`): the angle differences (yaw and roll
wrapped into [-pi, pi)) over ``dt`` are the Euler-angle rates, turned into body rates by the
Z-Y-X kinematic matrix evaluated at the mid-point angles::

    w_x = roll' - yaw' sin(pitch)
    w_y = pitch' cos(roll) + yaw' sin(roll) cos(pitch)
    w_z = yaw' cos(roll) cos(pitch) - pitch' sin(roll)

It is the mean rate over the last interval, so it lags the Motion Ex value by about
``dt / 2``; the session time is a float32, so at 700 s of session ``dt`` is known to 61 us
(0.4 % of a 60 Hz period). The first Motion packet after a gap (or of a session) has no
predecessor and stays ``partial: no motion ex``. Each sample made this way is also counted
under :data:`NOTE_W_FROM_ORIENTATION`, which the bridge, ``record`` and ``generate`` report.
Near pitch +-90 deg (a car on its nose) the Euler angles are degenerate and the derived rate
is unreliable; such values are caught by the range check or held by the washout.

Pairing and pause
-----------------
A sample is emitted for each Motion packet, combined with the latest Motion Ex of the same
session within :data:`F1Decoder.max_ex_age_s` of session time (the game sends both every
frame; the Motion Ex may be a frame older); without one, with the angular velocity derived
from the orientation (above). A Motion Ex always takes precedence. ``paused`` follows the
Session packet's ``gamePaused`` ("network game only" per EA) or ``isSpectating``, and is also
set when Motion packets keep coming with a frozen ``sessionTime`` (:data:`FROZEN_REPEATS`
repeats in a row, so one duplicated datagram does not pause). In single-player the game stops
sending Motion packets when not in control (pause menu, replays): sources detect that as
missing packets (``latest(max_age_s=...)``).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from .._errors import ConfigError
from ._packed import flat_values
from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3, wrong_size

__all__ = [
    "CAR_MOTION",
    "F1_FORMATS",
    "HEADER",
    "MOTION_EX_CORE",
    "MOTION_EX_SIZES",
    "MOTION_SIZE",
    "NOTE_W_FROM_ORIENTATION",
    "SESSION_HEAD",
    "F1Decoder",
    "F1Header",
]

DEFAULT_PORT = 20777

HEADER = struct.Struct("<HBBBBBQfIIBB")
"""Packet header, 29 bytes (F1 23, 24, 25)."""

CAR_MOTION = struct.Struct("<6f6h6f")
"""CarMotionData, 60 bytes: position[3], velocity[3], forward[3] i16, right[3] i16,
gForceLateral, gForceLongitudinal, gForceVertical, yaw, pitch, roll."""

MOTION_EX_CORE = struct.Struct("<32f" + "f3f3f3ff" + "4f")
"""Motion Ex body common to F1 23/24/25, 188 bytes (see module docstring)."""

SESSION_HEAD = struct.Struct("<BbbBHBbBHHBBBB")
"""First 17 bytes of the Session body, up to spectatorCarIndex."""

NUM_CARS = 22
MOTION_SIZE = HEADER.size + NUM_CARS * CAR_MOTION.size  # 1349
MOTION_EX_SIZES: dict[int, int] = {
    2023: HEADER.size + MOTION_EX_CORE.size,  # 217
    2024: HEADER.size + MOTION_EX_CORE.size + 5 * 4,  # 237
    2025: HEADER.size + MOTION_EX_CORE.size + 14 * 4,  # 273
}
F1_FORMATS = frozenset(MOTION_EX_SIZES)
"""``packetFormat`` values decoded (F1 23, F1 24, F1 25)."""

FROZEN_REPEATS = 2
"""Motion packets repeating the previous one's session time this many times in a row mean the
game is paused while still sending (time frozen): the samples are flagged ``paused``."""

NOTE_W_FROM_ORIENTATION = (
    "note: angular velocity derived from the Motion orientation (no Motion Ex packets)"
)
"""Counter key of the samples whose angular velocity was derived from the orientation."""

_PLAUSIBLE_F1_FORMATS = range(2017, 2036)  # older/newer F1 games: "unsupported format"
_ID_MOTION, _ID_SESSION, _ID_MOTION_EX, _ID_CAR_TELEMETRY = 0, 1, 13, 6
CAR_TELEMETRY_SIZE = HEADER.size + NUM_CARS * 60 + 3  # 1352
_CAR_GEAR_RPM = struct.Struct("<bH")  # at +15 of a car's 60-byte block
_MAX_PACKET_ID = 15
_EX_LOCAL_VELOCITY = 33  # float index in MOTION_EX_CORE
_EX_ANGULAR_VELOCITY = 36
_INV_NORM = 1.0 / 32767.0
_VEC3 = struct.Struct("<3f")


def _wrap_pi(angle_rad: float) -> float:
    """``angle_rad`` wrapped into [-pi, pi) (rad)."""
    return (angle_rad + math.pi) % (2.0 * math.pi) - math.pi


@dataclass(frozen=True, slots=True)
class F1Header:
    """The decoded 29-byte packet header."""

    packet_format: int
    game_year: int
    game_major_version: int
    game_minor_version: int
    packet_version: int
    packet_id: int
    session_uid: int
    session_time: float
    frame_identifier: int
    overall_frame_identifier: int
    player_car_index: int
    secondary_player_car_index: int

    @classmethod
    def unpack(cls, data: bytes) -> F1Header:
        return cls(*HEADER.unpack_from(data))

    def pack(self) -> bytes:
        return HEADER.pack(*flat_values(self))


class F1Decoder(Decoder):
    """Stateful decoder of F1 23/24/25 datagrams (Motion + Motion Ex + Session).

    Outcome reasons counted in ``stats``: ``sample``, ``partial: no motion ex``,
    ``partial: motion ex stored``, ``state: session``, ``ignored: other packet id``,
    ``skipped: truncated``, ``skipped: wrong size``, ``skipped: foreign``,
    ``skipped: unsupported format``, ``skipped: bad player index``, ``skipped: non-finite``,
    ``skipped: out of range``. Samples whose angular velocity was derived from the
    orientation (no Motion Ex) are counted under ``sample`` and also under
    :data:`NOTE_W_FROM_ORIENTATION`.

    Parameters
    ----------
    max_ex_age_s : float
        Largest session-time difference (s) between a Motion packet and the Motion Ex whose
        angular velocity it is paired with.
    max_orientation_dt_s : float
        Largest session-time difference (s) between two Motion packets whose orientations
        are differentiated when there is no Motion Ex (the games send 10 to 60 Hz).
    """

    game = "f1"
    default_port = DEFAULT_PORT
    title = "EA SPORTS F1 23 / F1 24 / F1 25 (Motion, Motion Ex, Session)"

    def __init__(self, max_ex_age_s: float = 0.1, max_orientation_dt_s: float = 0.25) -> None:
        super().__init__()
        if not (math.isfinite(max_ex_age_s) and max_ex_age_s > 0):
            raise ConfigError(f"max_ex_age_s = {max_ex_age_s!r} must be a finite number > 0")
        if not (math.isfinite(max_orientation_dt_s) and 0 < max_orientation_dt_s <= 1.0):
            raise ConfigError(
                f"max_orientation_dt_s = {max_orientation_dt_s!r} is invalid; allowed: (0, 1] s"
            )
        self.max_ex_age_s = float(max_ex_age_s)
        self.max_orientation_dt_s = float(max_orientation_dt_s)
        self.reset()

    def reset(self) -> None:
        self._ex_uid: int | None = None
        self._ex_time = 0.0
        self._ex_w = (0.0, 0.0, 0.0)
        self._paused_uid: int | None = None
        self._paused = False
        self._last_motion: tuple[int, float] | None = None
        self._frozen_repeats = 0
        # previous player orientation: (session uid, player index, session time, yaw, pitch,
        # roll), and the body rate last derived from it
        self._att: tuple[int, int, float, float, float, float] | None = None
        # player car's suspension velocity from the last Motion Ex (m/s, FL, FR, RL, RR) and
        # (session uid, rpm, gear) from the last Car Telemetry, for the effect layer
        self._ex_sv: tuple[float, float, float, float] | None = None
        self._engine: tuple[int, int, int] | None = None
        self._att_w: Vec3 | None = None

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        if n < HEADER.size:
            return DecodeResult("skipped", "skipped: truncated")
        (fmt, _year, _maj, _min, _ver, pid, uid, stime, _frame, _oframe, player, _sec) = (
            HEADER.unpack_from(datagram)
        )
        if fmt not in F1_FORMATS:
            if fmt in _PLAUSIBLE_F1_FORMATS and pid <= _MAX_PACKET_ID:
                return DecodeResult("skipped", "skipped: unsupported format")
            return DecodeResult("skipped", "skipped: foreign")
        if pid > _MAX_PACKET_ID:
            return DecodeResult("skipped", "skipped: foreign")
        if pid == _ID_MOTION:
            return self._motion(datagram, n, uid, stime, player, t_s)
        if pid == _ID_MOTION_EX:
            return self._motion_ex(datagram, n, fmt, uid, stime)
        if pid == _ID_SESSION:
            return self._session(datagram, n, uid)
        if pid == _ID_CAR_TELEMETRY and n == CAR_TELEMETRY_SIZE and player < NUM_CARS:
            gear, rpm = _CAR_GEAR_RPM.unpack_from(datagram, HEADER.size + 60 * player + 15)
            self._engine = (uid, rpm, gear)
            return DecodeResult("state", "state: car telemetry")
        return DecodeResult("ignored", "ignored: other packet id")

    def _motion(
        self, data: bytes, n: int, uid: int, stime: float, player: int, t_s: float
    ) -> DecodeResult:
        if n != MOTION_SIZE:
            return wrong_size(n, MOTION_SIZE)
        if player >= NUM_CARS:
            return DecodeResult("skipped", "skipped: bad player index")
        (_px, _py, _pz, _vx, _vy, _vz, fx, fy, fz, rx, ry, rz, g_lat, g_lon, g_vert, yaw, pitch,
         roll) = CAR_MOTION.unpack_from(data, HEADER.size + player * CAR_MOTION.size)  # fmt: skip
        w_att = self._orientation_rate(uid, player, stime, yaw, pitch, roll)
        extras: dict[str, object] = {}
        if self._ex_uid == uid and abs(stime - self._ex_time) <= self.max_ex_age_s:
            w, derived = self._ex_w, False
            extras["suspension_velocity_m_s"] = self._ex_sv
        elif w_att is not None:
            w, derived = w_att, True
        elif not (math.isfinite(yaw) and math.isfinite(pitch) and math.isfinite(roll)):
            return DecodeResult("skipped", "skipped: non-finite")
        else:
            return DecodeResult("partial", "partial: no motion ex")
        if self._last_motion is not None and self._last_motion == (uid, stime):
            self._frozen_repeats += 1
        else:
            self._frozen_repeats = 0
        self._last_motion = (uid, stime)
        up_y = (rz * fx - rx * fz) * (_INV_NORM * _INV_NORM)  # (R x F)_y
        f = (
            G0_M_S2 * (g_lon + fy * _INV_NORM),
            G0_M_S2 * (g_lat - ry * _INV_NORM),
            G0_M_S2 * (g_vert + up_y),
        )
        paused = (self._paused and self._paused_uid == uid) or (
            self._frozen_repeats >= FROZEN_REPEATS
        )
        engine = self._engine
        if engine is not None and engine[0] == uid:
            extras["rpm"], extras["gear"] = float(engine[1]), engine[2]
        result = self._make(t_s, f, w, paused, extras or None)
        if derived and result.status == "sample":
            self._count(NOTE_W_FROM_ORIENTATION)
        return result

    def _orientation_rate(
        self, uid: int, player: int, stime: float, yaw: float, pitch: float, roll: float
    ) -> Vec3 | None:
        """Body rate (ISO, rad/s) from this and the previous player orientation, or None.

        Always keeps the newest orientation, so the rate is ready when a Motion Ex goes
        missing. A repeated session time (a duplicate or a frozen game) repeats the last rate.
        """
        if not (math.isfinite(yaw) and math.isfinite(pitch) and math.isfinite(roll)):
            return None  # keep the previous orientation; this packet gives no rate
        prev = self._att
        self._att = (uid, player, stime, yaw, pitch, roll)
        if prev is None or prev[0] != uid or prev[1] != player:
            self._att_w = None
            return None
        dt = stime - prev[2]
        if dt == 0.0:
            self._att = prev
            return self._att_w
        if not 0.0 < dt <= self.max_orientation_dt_s:  # after a gap, or time went back
            self._att_w = None
            return None
        d_yaw = _wrap_pi(yaw - prev[3])
        d_pitch = _wrap_pi(pitch - prev[4])
        d_roll = _wrap_pi(roll - prev[5])
        pitch_m = prev[4] + 0.5 * d_pitch  # mid-point angles
        roll_m = prev[5] + 0.5 * d_roll
        inv = 1.0 / dt
        yaw_dot, pitch_dot, roll_dot = d_yaw * inv, d_pitch * inv, d_roll * inv
        sp, cp = math.sin(pitch_m), math.cos(pitch_m)
        sr, cr = math.sin(roll_m), math.cos(roll_m)
        w = (
            roll_dot - yaw_dot * sp,
            pitch_dot * cr + yaw_dot * sr * cp,
            yaw_dot * cr * cp - pitch_dot * sr,
        )
        self._att_w = w
        return w

    def _motion_ex(self, data: bytes, n: int, fmt: int, uid: int, stime: float) -> DecodeResult:
        size = MOTION_EX_SIZES[fmt]
        if n != size:
            return wrong_size(n, size)
        wx, wy, wz = _VEC3.unpack_from(data, HEADER.size + 4 * _EX_ANGULAR_VELOCITY)
        w = (wz, wx, wy)
        for v in w:  # reject here so a bad Motion Ex never pairs with later Motion packets
            if not math.isfinite(v):
                return DecodeResult("skipped", "skipped: non-finite")
        self._ex_uid, self._ex_time, self._ex_w = uid, stime, w
        rl, rr, fl, fr = struct.unpack_from("<4f", data, HEADER.size + 16)  # mm/s
        self._ex_sv = (fl / 1e3, fr / 1e3, rl / 1e3, rr / 1e3)
        return DecodeResult("partial", "partial: motion ex stored")

    def _session(self, data: bytes, n: int, uid: int) -> DecodeResult:
        if n < HEADER.size + SESSION_HEAD.size:
            return DecodeResult("skipped", "skipped: truncated")
        head = SESSION_HEAD.unpack_from(data, HEADER.size)
        game_paused, spectating = head[11], head[12]
        if game_paused > 1 or spectating > 1:
            return DecodeResult("skipped", "skipped: foreign")
        self._paused_uid = uid
        self._paused = bool(game_paused or spectating)
        return DecodeResult("state", "state: session")


_ENCODE_FORMAT = 2024
_ENCODE_SESSION_UID = 0x4D6F74696F6E6375  # "Motioncu": any fixed value names one session


def encode_f1(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
    """Motion Ex and Motion of a level car (F1 24 layout, player car 0).

    Decoder: ``f = G0 (gForceLongitudinal + F_y, gForceLateral - R_y, gForceVertical +
    U_y)`` with ``F = (0, 0, 1)``, ``R = (-1, 0, 0)`` (level, heading 0: ``U_y = 1``), and
    ``w_iso = (w_z, w_x, w_y)`` of Motion Ex's local (left, up, forward) rates.
    """
    g = G0_M_S2
    frame = k & 0xFFFFFFFF

    def header(packet_id: int) -> bytes:
        return HEADER.pack(_ENCODE_FORMAT, 24, 1, 0, 1, packet_id, _ENCODE_SESSION_UID, t_s, frame,
                           frame, 0, 255)  # fmt: skip

    ex = bytearray(MOTION_EX_SIZES[_ENCODE_FORMAT])
    ex[: HEADER.size] = header(13)
    core = [0.0] * (MOTION_EX_CORE.size // 4)
    core[33:36] = [0.0, 0.0, 0.0]  # localVelocity (left, up, forward)
    core[36:39] = [w[1], w[2], w[0]]  # angularVelocity (left, up, forward)
    MOTION_EX_CORE.pack_into(ex, HEADER.size, *core)
    motion = bytearray(MOTION_SIZE)
    motion[: HEADER.size] = header(0)
    n = 32767
    for car in range(22):
        g_lat, g_lon, g_vert = (f[1] / g, f[0] / g, f[2] / g - 1.0) if car == 0 else (0, 0, 0)
        CAR_MOTION.pack_into(
            motion, HEADER.size + car * CAR_MOTION.size,
            0.0, 0.0, 0.0, 0.0, 0.0, 0.0,  # world position, velocity
            0, 0, n, -n, 0, 0,  # forward (world Z), right (world -X): level, heading 0
            g_lat, g_lon, g_vert, 0.0, 0.0, 0.0,  # g-forces; yaw, pitch, roll
        )  # fmt: skip
    return [bytes(ex), bytes(motion)]


INFO = register_game(GameInfo.of(F1Decoder, encode_f1))
