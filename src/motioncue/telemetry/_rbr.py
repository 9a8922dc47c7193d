"""Richard Burns Rally (RallySimFans / NGP physics) UDP telemetry, port 6776.

Layout
------
The RSF launcher's "UDP telemetry" sends, once per physics step, the NGP plugin's
``rbr::telemetry::data::TelemetryData`` (header ``rbr.telemetry.data.TelemetryData.h`` of the
NGP plugin; ported field by field in lennartb-/RBR2G29 ``src/common/telemetry.rs``, which
receives 664-byte datagrams on 127.0.0.1:6776). Little-endian, 4-byte fields, 664 bytes::

      0 u32 totalSteps
      4 stage:   s32 index, f32 progress, raceTime (s), driveLineLocation, distanceToEnd
     24 control: f32 steering, throttle, brake, handbrake, clutch, s32 gear,
                 f32 footbrakePressure, handbrakePressure
     56 car:     s32 index, f32 speed (km/h), positionX, Y, Z (m), roll, pitch, yaw (deg)
     88          velocities    f32 surge, sway, heave (m/s), roll, pitch, yaw (deg/s)
    112          accelerations f32 surge, sway, heave (m/s^2), roll, pitch, yaw (deg/s^2)
    136          engine        f32 rpm, radiator/engine coolant and engine temperatures
    152 suspension LF, RF, LB, RB: 128 bytes each (spring, damper, brake disk, tyre)

Axes and signs (taken as; unverified)
-------------------------------------
``surge``, ``sway`` and ``heave`` are taken as the car's forward, left and up axes (sway
positive to the left, as GenericTelemetryProvider's RBR reader implies by mapping
``lateral = -sway`` in its x-right frame), i.e. ISO 8855 as they are, and the rates as
right-handed about those axes (roll positive right side down, pitch positive nose down, yaw
positive nose left), in deg/s; the accelerations as kinematic (gravity excluded), gravity
being added from ``pitch`` and ``roll`` (deg) with the same senses::

    f = (surge, sway, heave) + G0 * up_body(pitch, roll)      w = rad(roll, pitch, yaw rates)

No captured datagram was available to pin these signs against real driving: treat them as
unverified until a capture confirms them (``motioncue record rbr`` makes one).

Pause: ``totalSteps`` stands still while the game is paused or in a menu (the same step is
sent again); such a datagram is a ``paused`` sample. ``gear`` is passed on (0 reverse,
1 neutral, n + 1 the n-th gear, as NGP counts), and the engine rpm.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3, up_in_body_from_angles, wrong_size

__all__ = ["HEAD", "PACKET_SIZE", "RBRCar", "RBRDecoder"]

DEFAULT_PORT = 6776  # the RSF launcher's default
PACKET_SIZE = 664

HEAD = struct.Struct("<I i4f 5fi2f i7f 6f 6f 4f")
"""totalSteps, stage (5), control (8), car (8), velocities (6), accelerations (6), engine
(4): the first 152 bytes."""
_SUSPENSION_SIZE = 128
_DEG = math.pi / 180.0


@dataclass(frozen=True, slots=True)
class RBRCar:
    """The fields of a TelemetryData datagram this reader uses, in NGP's units."""

    total_steps: int
    race_time_s: float
    gear: int
    speed_km_h: float
    attitude_deg: tuple[float, float, float]  # roll, pitch, yaw
    velocities: tuple[float, float, float, float, float, float]  # m/s, deg/s
    accelerations: tuple[float, float, float, float, float, float]  # m/s^2, deg/s^2
    rpm: float

    @classmethod
    def unpack(cls, data: bytes) -> RBRCar:
        v = HEAD.unpack_from(data)
        return cls(v[0], v[3], v[11], v[15], (v[19], v[20], v[21]),
                   tuple(v[22:28]), tuple(v[28:34]), v[34])  # fmt: skip

    def pack(self) -> bytes:
        """A 664-byte datagram with these fields and zeros elsewhere."""
        out = bytearray(PACKET_SIZE)
        HEAD.pack_into(out, 0, self.total_steps, 0, 0.0, self.race_time_s, 0.0, 0.0,
                       0.0, 0.0, 0.0, 0.0, 0.0, self.gear, 0.0, 0.0,
                       0, self.speed_km_h, 0.0, 0.0, 0.0, *self.attitude_deg,
                       *self.velocities, *self.accelerations, self.rpm, 0.0, 0.0, 0.0)  # fmt: skip
        return bytes(out)


assert HEAD.size + 4 * _SUSPENSION_SIZE == PACKET_SIZE


class RBRDecoder(Decoder):
    """Decoder of RSF / NGP telemetry datagrams.

    Outcome reasons: ``sample``, ``skipped: truncated`` / ``skipped: wrong size`` (not 664
    bytes), ``skipped: foreign`` (attitude angles beyond +-360 deg, a speed beyond
    2000 km/h, or a gear outside 0..10), ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "rbr"
    default_port = DEFAULT_PORT
    title = "Richard Burns Rally (RSF / NGP UDP telemetry; signs unverified)"

    def __init__(self) -> None:
        super().__init__()
        self._last_step: int | None = None

    def reset(self) -> None:
        self._last_step = None

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        if n != PACKET_SIZE:
            return wrong_size(n, PACKET_SIZE)
        v = HEAD.unpack_from(datagram)
        steps, gear, speed, roll, pitch = v[0], v[11], v[15], v[19], v[20]
        if not (math.isfinite(roll) and math.isfinite(pitch) and math.isfinite(speed)):
            return DecodeResult("skipped", "skipped: non-finite")
        if abs(roll) > 360.0 or abs(pitch) > 360.0 or abs(speed) > 2000.0 or not 0 <= gear <= 10:
            return DecodeResult("skipped", "skipped: foreign")
        paused = steps == self._last_step
        self._last_step = steps
        _vs, _vw, _vh, wr, wp, wy = v[22:28]
        a_s, a_w, a_h = v[28], v[29], v[30]
        ux, uy, uz = up_in_body_from_angles(pitch * _DEG, roll * _DEG)
        f = (a_s + G0_M_S2 * ux, a_w + G0_M_S2 * uy, a_h + G0_M_S2 * uz)
        extras: dict[str, object] = {"rpm": v[34], "gear": gear - 1 if gear else -1}
        return self._make(t_s, f, (wr * _DEG, wp * _DEG, wy * _DEG), paused, extras)


def encode_rbr(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
    """An NGP TelemetryData datagram of a level car with specific force ``f`` (m/s^2) and
    angular velocity ``w`` (rad/s), ISO 8855 body axes, stamped ``t_s`` (s), step ``k``."""
    # decoder, level: f = (surge, sway, heave + g), w = radians of the (roll, pitch, yaw)
    # rates in deg/s
    fx, fy, fz = f
    wx, wy, wz = w
    deg = 180.0 / math.pi
    car = RBRCar(k & 0xFFFFFFFF, t_s, 2, 0.0, (0.0, 0.0, 0.0),
                 (0.0, 0.0, 0.0, wx * deg, wy * deg, wz * deg),
                 (fx, fy, fz - G0_M_S2, 0.0, 0.0, 0.0), 3000.0)  # fmt: skip
    return [car.pack()]


INFO = register_game(GameInfo.of(RBRDecoder, encode_rbr))
