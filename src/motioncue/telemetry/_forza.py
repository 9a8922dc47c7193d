"""Forza Motorsport 7 / Forza Motorsport (2023) / Forza Horizon 4, 5, 6 "Data Out".

Layouts
-------
From Turn 10's "Forza Motorsport Data Out Documentation" (support.forzamotorsport.net, also
the FM7 "Data Out feature details" forum post) and Playground's "Forza Horizon 6 Data Out
Documentation" (support.forza.net). Little-endian, packed. The first 232 bytes ("Sled") are
the same in every variant; this decoder reads only its head::

    s32 IsRaceOn          # 1 when racing, 0 in menus / race stopped
    u32 TimestampMS
    f32 EngineMaxRpm, EngineIdleRpm, CurrentEngineRpm
    f32 AccelerationX, Y, Z      # car's local space, X = right, Y = up, Z = forward (m/s^2)
    f32 VelocityX, Y, Z          # same axes (m/s)
    f32 AngularVelocityX, Y, Z   # same axes (rad/s): X = pitch, Y = yaw, Z = roll
    f32 Yaw, Pitch, Roll         # rad

Datagram sizes identify the variant: 232 "Sled"; 311 "Dash" (FM7); 331 "Dash" (FM 2023:
+ TireWear[4] and TrackOrdinal); 324 Horizon 4/5/6 (12 extra bytes inserted after
NumCylinders, before PositionX: FH6 documents them as CarGroup, SmashableVelDiff,
SmashableMass). Any other size is skipped.

Axes and conversion
-------------------
Forza's local frame (right, up, forward) is left-handed (DirectX convention): positive
rotations follow the left-hand rule, so a positive rate about +X (right) tips the nose down,
about +Y (up) turns the car to the right and about +Z (forward) raises the right side. The
map to ISO 8855 ``M = [[0,0,1],[-1,0,0],[0,1,0]]`` (forward, -right, up) has determinant -1,
so the pseudovector ``w`` picks up a further sign: ``w_iso = -M w``::

    a_iso = ( AccelerationZ, -AccelerationX, AccelerationY)
    w_iso = (-AngularVelocityZ, AngularVelocityX, -AngularVelocityY)

Forza's acceleration excludes gravity: a car parked on a slope (pitch -0.25 rad, roll
-0.23 rad, all velocities ~1e-5) reports accelerations of ~1e-7 m/s^2 (public Forza Horizon
sample capture in richstokes/Forza-data-tools). Gravity is added back from the attitude with
the same left-handed rule: ISO pitch (nose down +) = ``Pitch``, ISO roll (right side down +)
= ``-Roll``; ``f = a_iso + G0 * up_body(pitch, roll)``.

The sign conventions of ``w`` and of the Pitch/Roll angles follow from the documented
left-handed axes; no captured Forza datagram was available to pin them against real motion.

``CurrentEngineRpm`` and ``EngineMaxRpm`` are passed on for the effect layer (engine).

Pause: ``IsRaceOn == 0`` (menus, race stopped) -> ``paused``. Horizon 6 documents that no
data is sent in menus, pauses, replays or rewinds: sources see that as missing packets.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from ._packed import flat_values, from_flat
from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3, up_in_body_from_angles, wrong_size

__all__ = ["FORZA_LAYOUTS", "SLED_HEAD", "SLED_SIZE", "ForzaDecoder", "ForzaMotion"]

# Forza has no default port. Tools often use 5300, but the Forza Horizon 6 documentation asks
# to avoid 5200-5300 (the game binds its own outgoing socket there), so: the first one above.
DEFAULT_PORT = 5301

SLED_HEAD = struct.Struct("<iI3f3f3f3f3f")
"""IsRaceOn, TimestampMS, 3 rpm, acceleration[3], velocity[3], angular velocity[3],
yaw, pitch, roll: the first 68 bytes of every Forza Data Out datagram."""

SLED_SIZE = 232

FORZA_LAYOUTS: dict[int, str] = {
    232: "sled",
    311: "dash (FM7)",
    324: "horizon (FH4/FH5/FH6)",
    331: "dash (FM 2023)",
}
"""Datagram size -> layout name."""


@dataclass(frozen=True, slots=True)
class ForzaMotion:
    """The head of a Forza Data Out datagram, in the game's own axes and units."""

    is_race_on: int
    timestamp_ms: int
    engine_max_rpm: float
    engine_idle_rpm: float
    current_engine_rpm: float
    acceleration: tuple[float, float, float]
    velocity: tuple[float, float, float]
    angular_velocity: tuple[float, float, float]
    yaw: float
    pitch: float
    roll: float

    @classmethod
    def unpack(cls, data: bytes) -> ForzaMotion:
        return from_flat(cls, SLED_HEAD.unpack_from(data))

    def pack(self) -> bytes:
        return SLED_HEAD.pack(*flat_values(self))


class ForzaDecoder(Decoder):
    """Decoder of Forza Data Out datagrams (Sled, Dash, Horizon).

    Outcome reasons: ``sample``, ``skipped: truncated`` (shorter than a Sled),
    ``skipped: wrong size`` (not one of :data:`FORZA_LAYOUTS`), ``skipped: foreign``
    (``IsRaceOn`` not 0 or 1), ``skipped: non-finite``, ``skipped: out of range``.
    ``layouts`` counts the variants seen.
    """

    game = "forza"
    default_port = DEFAULT_PORT
    title = "Forza Motorsport 7 / 2023 (Sled, Dash), Forza Horizon 4/5/6 Data Out"

    def __init__(self) -> None:
        super().__init__()
        self.layouts: dict[str, int] = {}

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        layout = FORZA_LAYOUTS.get(n)
        if layout is None:
            return wrong_size(n, SLED_SIZE)
        (race_on, _ts, rpm_max, _idle, rpm, ax, ay, az, _vx, _vy, _vz, wx, wy, wz, _yaw, pitch,
         roll) = SLED_HEAD.unpack_from(datagram)  # fmt: skip
        if race_on not in (0, 1):
            return DecodeResult("skipped", "skipped: foreign")
        self.layouts[layout] = self.layouts.get(layout, 0) + 1
        if not (math.isfinite(pitch) and math.isfinite(roll)):
            return DecodeResult("skipped", "skipped: non-finite")
        ux, uy, uz = up_in_body_from_angles(pitch, -roll)
        f = (az + G0_M_S2 * ux, -ax + G0_M_S2 * uy, ay + G0_M_S2 * uz)
        w = (-wz, wx, -wy)
        return self._make(t_s, f, w, race_on == 0, {"rpm": rpm, "rpm_max": rpm_max})


def encode_forza(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
    """A Sled datagram (232 bytes) of a level car with specific force ``f`` (m/s^2) and
    angular velocity ``w`` (rad/s), ISO 8855 body axes, stamped ``t_s`` (s)."""
    # decoder, level: f = (az, -ax, ay + g), w = (-wz, wx, -wy)
    fx, fy, fz = f
    wx, wy, wz = w
    stamp_ms = round(t_s * 1e3) & 0xFFFFFFFF
    m = ForzaMotion(1, stamp_ms, 8000.0, 800.0, 3000.0, (-fy, fz - G0_M_S2, fx),
                    (0.0, 0.0, 0.0), (wy, -wz, -wx), 0.0, 0.0, 0.0)  # fmt: skip
    return [m.pack() + bytes(232 - SLED_HEAD.size)]


INFO = register_game(GameInfo.of(ForzaDecoder, encode_forza))
