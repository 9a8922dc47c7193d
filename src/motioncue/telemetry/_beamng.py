"""BeamNG.drive / BeamNG.tech "MotionSim" UDP protocol (format ``BNG1``).

Layout
------
From BeamNG's protocol documentation (documentation.beamng.com/modding/protocols) and the
game's ``lua/vehicle/protocols/motionSim.lua`` (``motionSim_t``, bCDDL): 88 bytes,
little-endian::

    char  magic[4]                       # "BNG1"
    float posX, posY, posZ               # world position (m)
    float velX, velY, velZ               # world velocity (m/s)
    float accX, accY, accZ               # acceleration, "gravity not included" (m/s^2)
    float upVecX, upVecY, upVecZ         # the car's up vector, world coordinates
    float rollPos, pitchPos, yawPos      # rad
    float rollRate, pitchRate, yawRate   # rad/s
    float rollAcc, pitchAcc, yawAcc      # rad/s^2

Axes and conversion
-------------------
The Lua source fills ``acc = -ffiSensors.sensor{X,Y,Z}``, ``rollPos = -roll``, ``pitchPos =
pitch``, ``yawPos = -yaw`` (from ``obj:getRollPitchYaw()``) and the three rates straight from
``obj:getRollPitchYawAngularVelocity()``.

* Rates: the game's roll/pitch/yaw angular velocities follow the aerospace convention
  (x forward, y right, z down: roll right-side-down +, pitch nose-up +, yaw nose-right +).
  A public BeamNG research bridge that checked them against a node-based estimate builds
  ``omega_world = rollAV * forward + pitchAV * right - yawAV * up`` and notes "on FLU,
  p = +rollAV, q = -pitchAV, r = -yawAV". Hence ``w_iso = (rollRate, -pitchRate,
  -yawRate)``.
* Angles: taken in the same aerospace convention as their rates, ``rollPos = -roll`` is
  left-side-down positive and ``pitchPos`` nose-up positive, so ISO roll = ``-rollPos`` and
  ISO pitch = ``-pitchPos``.
* Acceleration: BeamNG vehicles are built facing -Y in a right-handed, Z-up frame, so the
  sensor frame is (x left, y rearward, z up); community code confirms ``sensorY`` is positive
  under braking and ``sensorX`` is the lateral acceleration. Hence ``acc = -sensor =
  (a_right, a_forward, a_down)``, which also matches motion-sim plugins that use ``accX`` as
  sway (+ in a right turn) and ``accY`` as surge (+ accelerating).

::

    a_iso = (accY, -accX, -accZ)
    f     = a_iso + G0 * up_body(pitch=-pitchPos, roll=-rollPos)
    w_iso = (rollRate, -pitchRate, -yawRate)

These signs rest on the game's source and third-party measurements; no captured BeamNG
datagram was available to pin them here (the F1 conversion is pinned on real packets).

Pause: the format has no flag. BeamNG sends nothing while the simulation is paused or no
player is seated (``updateV1`` returns early), which sources see as missing packets.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from .._errors import ProtocolError
from ._packed import flat_values, from_flat
from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3, up_in_body_from_angles, wrong_size

__all__ = ["BNG1", "MAGIC", "BeamNGDecoder", "BeamNGMotion"]

DEFAULT_PORT = 4444  # motionSim.lua: settings "motionSimPort" or 4444
MAGIC = b"BNG1"

BNG1 = struct.Struct("<4s21f")
"""The whole ``motionSim_t`` datagram, 88 bytes."""


@dataclass(frozen=True, slots=True)
class BeamNGMotion:
    """A decoded ``BNG1`` datagram, in the game's own axes and units."""

    pos: tuple[float, float, float]
    vel: tuple[float, float, float]
    acc: tuple[float, float, float]
    up_vec: tuple[float, float, float]
    roll_pos: float
    pitch_pos: float
    yaw_pos: float
    roll_rate: float
    pitch_rate: float
    yaw_rate: float
    roll_acc: float
    pitch_acc: float
    yaw_acc: float

    @classmethod
    def unpack(cls, data: bytes) -> BeamNGMotion:
        v = BNG1.unpack(data)
        if v[0] != MAGIC:
            raise ProtocolError(f"BeamNG MotionSim magic is {v[0]!r}, expected {MAGIC!r}")
        return from_flat(cls, v[1:])

    def pack(self) -> bytes:
        return BNG1.pack(MAGIC, *flat_values(self))


class BeamNGDecoder(Decoder):
    """Decoder of BeamNG MotionSim ``BNG1`` datagrams.

    Outcome reasons: ``sample``, ``skipped: truncated`` (magic right, too short),
    ``skipped: wrong size`` (magic right, too long), ``skipped: foreign`` (other magic,
    including other BeamNG protocols such as OutGauge on the same port),
    ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "beamng"
    default_port = DEFAULT_PORT
    title = "BeamNG.drive / BeamNG.tech MotionSim (BNG1)"

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        if datagram[:4] != MAGIC:
            return DecodeResult("skipped", "skipped: foreign")
        n = len(datagram)
        if n != BNG1.size:
            return wrong_size(n, BNG1.size)
        v = BNG1.unpack(datagram)
        ax, ay, az = v[7:10]
        roll, pitch = v[13], v[14]
        roll_rate, pitch_rate, yaw_rate = v[16:19]
        if not (math.isfinite(pitch) and math.isfinite(roll)):
            return DecodeResult("skipped", "skipped: non-finite")
        ux, uy, uz = up_in_body_from_angles(-pitch, -roll)
        f = (ay + G0_M_S2 * ux, -ax + G0_M_S2 * uy, -az + G0_M_S2 * uz)
        w = (roll_rate, -pitch_rate, -yaw_rate)
        return self._make(t_s, f, w, False)


def encode_beamng(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
    """A BNG1 datagram of a level car with specific force ``f`` (m/s^2) and angular
    velocity ``w`` (rad/s), ISO 8855 body axes."""
    # decoder, level: f = (ay, -ax, g - az), w = (roll_rate, -pitch_rate, -yaw_rate)
    fx, fy, fz = f
    wx, wy, wz = w
    b = BeamNGMotion(
        pos=(0.0, 0.0, 0.0), vel=(0.0, 0.0, 0.0), acc=(-fy, fx, G0_M_S2 - fz),
        up_vec=(0.0, 0.0, 1.0), roll_pos=0.0, pitch_pos=0.0, yaw_pos=0.0,
        roll_rate=wx, pitch_rate=-wy, yaw_rate=-wz, roll_acc=0.0, pitch_acc=0.0,
        yaw_acc=0.0,
    )  # fmt: skip
    return [b.pack()]


INFO = register_game(GameInfo.of(BeamNGDecoder, encode_beamng))
