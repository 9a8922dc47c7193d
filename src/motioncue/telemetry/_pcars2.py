"""Project CARS 2 / Project CARS 3 / Automobilista 2 UDP ("Project CARS 2" protocol).

Layout
------
Slightly Mad Studios' ``SMS_UDP_Definitions.hpp`` (Project CARS 2 patch 5 UDP API, the
format Automobilista 2 also sends when its UDP protocol is set to "Project CARS 2"), packed,
little-endian. Every packet starts with a 12-byte header::

    u32 mPacketNumber, u32 mCategoryPacketNumber,
    u8 mPartialPacketIndex, u8 mPartialPacketNumber, u8 mPacketType, u8 mPacketVersion

Packet type 0 (``eCarPhysics``, ``sTelemetryData``) is 559 bytes; the fields read here
(byte offsets)::

     36 f32 sSpeed (m/s)          40 u16 sRpm      42 u16 sMaxRpm
     45 u8  sGearNumGears         # low nibble gear (0 neutral, 15 reverse), high nibble count
     52 f32 sOrientation[3]       # Euler angles (rad)
     64 f32 sLocalVelocity[3]     # m/s
     88 f32 sAngularVelocity[3]   # rad/s
    100 f32 sLocalAcceleration[3] # m/s^2
    328 f32 sSuspensionVelocity[4]  # m/s, wheels FL, FR, RL, RR (sign: not documented)

Packet type 4 (``eGameState``, 24 bytes) carries ``sGameState`` at byte 14: its low 3 bits
are the game state (2 = playing; 3 paused, 4 in a menu with time ticking, 1 front end,
0 exited, 5 restarting, 6/7 replays), which sets ``paused`` for the samples that follow.
The other packet types carry no motion: they are ``ignored`` when they have their documented
size (``sPacketSize`` comments of the header: 1 race 308, 2 participants 1136, 3 timings
1063, 7 time stats 1024, 8 vehicle names 1164 or class names 1452 bytes), else skipped.

Axes and signs
--------------
Pinned on two real captures (``tests/fixtures/games/pcars2/README.md``: Automobilista 2 and
Project CARS 2, both at the Nürburgring GP). The car's local frame is x to the LEFT, y up,
z backward (a left-handed frame: DirectX's x right, y up, z forward with the car facing -z):
a car driving forward reports a negative ``sLocalVelocity[2]``; the left wheels' ride height
(``sRideHeight[0]``, ``[2]``: FL, FR, RL, RR) rises when ``sLocalAcceleration[0]`` is
positive (the car rolls outward, away from +x: +x is the inside of the turn, the left in a
left turn). ``sAngularVelocity`` holds the components of the physical (right-hand rule)
angular velocity in that frame: the local acceleration equals ``d(v)/dt - w x v`` (the
cross product's component formula changes sign in a left-handed frame), correlations 0.93
(x) and 0.96 (z) on the whole Automobilista 2 capture. The ISO 8855 axes are
``forward = -z``, ``left = x``, ``up = y`` (a reflection, determinant -1, which the
pseudovector ``w`` follows like a vector because the game's components already are the
physical ones)::

    a_iso = (-a_z, a_x, a_y)        w_iso = (-w_z, w_x, w_y)

The local acceleration is kinematic (gravity excluded; the Automobilista 2 capture's mean of
``sLocalAcceleration[1]`` is 0.1 m/s^2); gravity is added back from the attitude.
``sOrientation = (theta, psi, phi)`` rotates local vectors into the world (y up) as the
component matrices ``Ry(psi) Rx(theta) Rz(phi)``: ``sWorldVelocity`` equals that rotation of
``sLocalVelocity`` to 0.05 % of the speed (median) in the captures. World up in the local frame is
therefore ``(sin(phi) cos(theta), cos(phi) cos(theta), -sin(theta))``, in ISO axes
``(sin(theta), sin(phi) cos(theta), cos(phi) cos(theta))``: ISO pitch (nose down +) is
``-theta`` and ISO roll (right side down +) is ``phi``. On the captures f_x follows the
derivative of the speed, the yaw rate the heading's rate and f_y the speed times the yaw
rate, with the slopes and correlations the tests pin (``tests/test_pcars2_capture.py``).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3, up_in_body_from_angles, wrong_size

__all__ = [
    "GAME_STATE_SIZE",
    "HEADER",
    "TELEMETRY_SIZE",
    "PCars2Decoder",
    "PCars2Telemetry",
]

DEFAULT_PORT = 5606  # fixed by the games

HEADER = struct.Struct("<IIBBBB")
"""Packet number, category packet number, partial index, partial count, type, version."""

TELEMETRY_SIZE = 559
GAME_STATE_SIZE = 24
TYPE_TELEMETRY = 0
TYPE_GAME_STATE = 4
MAX_TYPE = 8  # eParticipantVehicleNames; anything above is not this format
OTHER_SIZES: dict[int, tuple[int, ...]] = {1: (308,), 2: (1136,), 3: (1063,), 7: (1024,),
                                           8: (1164, 1452)}  # fmt: skip
"""Documented sizes of the packet types without motion."""
GAME_PLAYING = 2

_ENGINE = struct.Struct("<fHH")  # @36 speed, rpm, max rpm
_KINEMATICS = struct.Struct("<15f")  # @52 orientation, local vel, world vel, angular vel, local acc
_SUSPENSION = struct.Struct("<4f")  # @328


@dataclass(frozen=True, slots=True)
class PCars2Telemetry:
    """The motion fields of a type-0 packet, in the game's own axes and units."""

    packet_number: int
    speed_m_s: float
    rpm: int
    max_rpm: int
    gear_num_gears: int
    orientation: tuple[float, float, float]
    local_velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]
    local_acceleration: tuple[float, float, float]
    suspension_velocity: tuple[float, float, float, float]

    @classmethod
    def unpack(cls, data: bytes) -> PCars2Telemetry:
        head = HEADER.unpack_from(data)
        speed, rpm, max_rpm = _ENGINE.unpack_from(data, 36)
        k = _KINEMATICS.unpack_from(data, 52)
        s = _SUSPENSION.unpack_from(data, 328)
        return cls(
            packet_number=head[0],
            speed_m_s=speed,
            rpm=rpm,
            max_rpm=max_rpm,
            gear_num_gears=data[45],
            orientation=(k[0], k[1], k[2]),
            local_velocity=(k[3], k[4], k[5]),
            angular_velocity=(k[9], k[10], k[11]),
            local_acceleration=(k[12], k[13], k[14]),
            suspension_velocity=(s[0], s[1], s[2], s[3]),
        )

    def pack(self) -> bytes:
        """A 559-byte type-0 packet with these fields and zeros elsewhere."""
        out = bytearray(TELEMETRY_SIZE)
        HEADER.pack_into(out, 0, self.packet_number, self.packet_number, 1, 1, TYPE_TELEMETRY, 2)
        _ENGINE.pack_into(out, 36, self.speed_m_s, self.rpm, self.max_rpm)
        out[45] = self.gear_num_gears
        _KINEMATICS.pack_into(
            out, 52, *self.orientation, *self.local_velocity, 0.0, 0.0, 0.0,
            *self.angular_velocity, *self.local_acceleration,
        )  # fmt: skip
        _SUSPENSION.pack_into(out, 328, *self.suspension_velocity)
        return bytes(out)


def game_state_packet(state: int, number: int = 0) -> bytes:
    """A 24-byte type-4 packet with ``sGameState = state`` (low 3 bits)."""
    out = bytearray(GAME_STATE_SIZE)
    HEADER.pack_into(out, 0, number, number, 1, 1, TYPE_GAME_STATE, 2)
    out[14] = state & 0x07
    return bytes(out)


class PCars2Decoder(Decoder):
    """Decoder of Project CARS 2 / Automobilista 2 UDP packets (stateful: the pause flag).

    Outcome reasons: ``sample``, ``state`` (game-state packet), ``ignored`` (other valid
    packet types), ``skipped: truncated`` (shorter than its type's size), ``skipped: wrong
    size`` (longer), ``skipped: foreign`` (unknown packet type, or a partial-packet index
    beyond the count), ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "pcars2"
    default_port = DEFAULT_PORT
    title = "Project CARS 2 / 3 and Automobilista 2 UDP (Project CARS 2 protocol)"

    def __init__(self) -> None:
        super().__init__()
        self.paused = False

    def reset(self) -> None:
        self.paused = False

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        if n < HEADER.size:
            return DecodeResult("skipped", "skipped: truncated")
        _num, _cat, part, parts, ptype, _version = HEADER.unpack_from(datagram)
        if ptype > MAX_TYPE or part > parts or parts == 0:
            return DecodeResult("skipped", "skipped: foreign")
        if ptype == TYPE_GAME_STATE:
            if n != GAME_STATE_SIZE:
                return wrong_size(n, GAME_STATE_SIZE)
            self.paused = (datagram[14] & 0x07) != GAME_PLAYING
            return DecodeResult("state", "state")
        if ptype != TYPE_TELEMETRY:
            if n in OTHER_SIZES.get(ptype, ()):
                return DecodeResult("ignored", "ignored")
            return DecodeResult("skipped", "skipped: wrong size")
        if n != TELEMETRY_SIZE:
            return wrong_size(n, TELEMETRY_SIZE)
        (pitch_x, _yaw, roll_z, _lvx, _lvy, _lvz, _wvx, _wvy, _wvz, wx, wy, wz, ax, ay, az) = (
            _KINEMATICS.unpack_from(datagram, 52)
        )
        if not (math.isfinite(pitch_x) and math.isfinite(roll_z)):
            return DecodeResult("skipped", "skipped: non-finite")
        # local frame x left, y up, z back (module docstring): ISO = (-z, x, y)
        ux, uy, uz = up_in_body_from_angles(-pitch_x, roll_z)
        f = (-az + G0_M_S2 * ux, ax + G0_M_S2 * uy, ay + G0_M_S2 * uz)
        w = (-wz, wx, wy)
        _speed, rpm, max_rpm = _ENGINE.unpack_from(datagram, 36)
        gear_code = datagram[45] & 0x0F
        extras: dict[str, object] = {
            "rpm": float(rpm),
            "rpm_max": float(max_rpm),
            "gear": -1 if gear_code == 15 else gear_code,
            "suspension_velocity_m_s": _SUSPENSION.unpack_from(datagram, 328),
        }
        return self._make(t_s, f, w, self.paused, extras)


def encode_pcars2(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
    """A type-0 telemetry datagram (packet number ``k``) of a level car with specific force
    ``f`` (m/s^2) and angular velocity ``w`` (rad/s), ISO 8855 body axes."""
    # decoder, level: f = (-az, ax, ay + g), w = (-wz, wx, wy)
    fx, fy, fz = f
    wx, wy, wz = w
    pc = PCars2Telemetry(k & 0xFF, 0.0, 3000, 8000, 0x63, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                         (wy, wz, -wx), (fy, fz - G0_M_S2, -fx),
                         (0.0, 0.0, 0.0, 0.0))  # fmt: skip
    return [pc.pack()]


INFO = register_game(GameInfo.of(PCars2Decoder, encode_pcars2))
