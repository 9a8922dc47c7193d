"""Gran Turismo 7 "Simulator Interface" UDP telemetry (PlayStation 4 / 5).

Protocol
--------
Polyphony Digital's packets as documented by the community: Nenkai/PDTools
(``PDTools.SimulatorInterface``: ``SimulatorPacket.cs``, ``SimulatorInterfaceCryptorGT7.cs``)
and, for the extended packets of update 1.42, PDTools issues #14 and #18 and SimHub issue
#2254. Decryption: :mod:`._gt7_cipher` (libsodium through PyNaCl, else pycryptodome).

* The receiver sends a one-byte *heartbeat* to the console's UDP port 33739 at least every
  ~1.6 s (the console stops after ~100 packets without one); the console sends 60 packets a
  second to the heartbeat's source address, port 33740. The heartbeat byte picks the layout:
  ``A`` 296 bytes, ``B`` 316, ``~`` 344, ``C`` 368; the first heartbeat the console hears
  wins until the stream lapses.
* Every packet is Salsa20-encrypted (20 rounds) with the published 32-byte key
  ``b"Simulator Interface Packet GT7 v"`` (the first 32 bytes of "Simulator Interface Packet
  GT7 ver 0.0"); the 8-byte nonce is ``(iv ^ X, iv)`` (two little-endian u32) where ``iv``
  is the u32 at byte 0x40 of the encrypted packet and ``X`` is 0xDEADBEAF for ``A``,
  0xDEADBEEF for ``B`` and ``C``, 0x55FABB4F for ``~``. The decrypted packet starts with
  the magic 0x47375330 (``"0S7G"``); anything else is foreign.

Fields read (little-endian, byte offsets)::

    0x04 f32 position[3] (m, world)          0x10 f32 velocity[3] (m/s, world)
    0x1C f32 orientation quaternion x, y, z  0x28 f32 its w ("relative orientation to north")
    0x2C f32 angular velocity[3] (rad/s, car frame)
    0x3C f32 engine rpm   0x4C f32 speed (m/s)   0x70 s32 packet id (+1 per 1/60 s)
    0x8A u16 rpm of the rev-limit alert          0x8E u16 flags   0x90 u8 gears (low nibble)
    B and later: 0x128 f32 wheel rotation, filler, sway, heave, surge

Flags: 1 car on track, 2 paused, 4 loading or processing; ``paused`` is set unless the car
is on track and neither paused nor loading (menus, pause, loading screens).

Axes and signs (pinned on real captures)
----------------------------------------
The world frame is right-handed with y up; the quaternion rotates car axes into world axes,
and the car's axes are x right, y up, z backward. On three public captured laps
(profittlich/gt7speedboard, ``tests/fixtures/games/gt7``) the velocity expressed in car
axes is ``(0, 0, -|v|)`` within 1 % of the speed; the course angle of the world velocity
turns by +1.00 turn at Interlagos (driven anticlockwise) and -1.00 turn on the Nürburgring
GP circuit (clockwise), which fixes the handedness; the angular velocity's y component
equals that course rate (slope 0.98-0.99, correlation 0.99), and its x, z components match
the attitude change taken in car axes better than in world axes, so the angular velocity is
in car axes. ISO 8855 axes are ``forward = -z``, ``left = -x``, ``up = y``::

    w_iso = (-w_z, -w_x, w_y)

Acceleration: the ``A`` packet carries none; the decoder differences the world velocity of
consecutive packets over the game's own clock (packet id / 60 s), subtracts gravity
(``-9.80665`` m/s^2 along world y) and rotates the result into car axes. The first packet,
and any packet after a gap of more than :attr:`GT7Decoder.max_gap_frames` frames or a jump
(packet id backwards: a replay seek, a restart), only restarts the difference (``partial``,
no sample), so a seek never becomes an acceleration spike.

Sway, heave and surge (``B``, ``~``, ``C``): decoded (:class:`GT7Packet` ``extended``) but
not used for motion; the differenced velocity is used on every layout. What was found
(searched 2026-11; ``docs/games/gt7.md`` has the same):

* Layout: five f32 at 0x128 (wheel rotation, "FillerFloatFB", sway, heave, surge), read when
  the packet has at least 0x13C bytes: PDTools ``SimulatorPacket.cs``; found by SimHub's
  author (PDTools issue #14, 2025-03-18: "5 additional floats ... clearly an extra bundle of
  motion related fields"). PDTools issue #14 later (2025-07-04) identifies 0x128 as the
  steering-wheel angle (rad) and 0x12C as probably the force-feedback signal; nothing on the
  other three. SimHub issue #2254 (2026-04-24) asks for them to be exposed; no units.
* Units, axes, signs: published nowhere with evidence. PDTools documents none;
  gt7-datalogger (jbhoorasingh/gt7-datalogger, ``backend/app/telemetry/packet.py``) decodes
  them without units and its export contract keeps them as "raw GT7 units"; one community
  packet table asserts m/s^2 along car x, y, z, with no capture or test behind it.
* Captures: none public with extended packets found. The 82 ``.gt7track`` recordings in
  profittlich/gt7speedboard's history (where ``tests/fixtures/games/gt7`` comes from) are
  all 296-byte ``A`` packets (checked by size; the three whose size would also fit a longer
  layout, by decryption), and so are the three fixtures here.

Without a capture nothing can pin their units and signs against the velocity's derivative
(as the ``A`` fields are in ``tests/test_gt7.py``), and a wrong sign is a rig thrown the
wrong way; so they stay unused until a capture exists (``motioncue record
gt7@CONSOLE`` records the packets as they come, whichever heartbeat won).

Replays: the console streams replays like live driving (the flags cannot tell them apart),
so the rig moves with a replay as it would on track; a replay's jumps are handled above.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field

from .._errors import ConfigError
from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, wrong_size

__all__ = [
    "HEARTBEAT_PORT",
    "KEY",
    "MAGIC",
    "PACKET",
    "SIZES",
    "GT7Decoder",
    "GT7Packet",
    "decrypt",
    "encrypt",
]

HEARTBEAT_PORT = 33739  # the console's port, where heartbeats go
DEFAULT_PORT = 33740  # where the console sends, from the heartbeat's source address
KEY = b"Simulator Interface Packet GT7 ver 0.0"[:32]
MAGIC = 0x47375330
FRAME_HZ = 60.0

SIZES: dict[int, tuple[str, int]] = {
    296: ("A", 0xDEADBEAF),
    316: ("B", 0xDEADBEEF),
    344: ("~", 0x55FABB4F),
    368: ("C", 0xDEADBEEF),
}
"""Packet size -> (heartbeat byte, nonce XOR constant)."""
_XOR = {k: x for k, x in SIZES.values()}

PACKET = struct.Struct("<i3f3f4f3f2f")
"""magic, position[3], velocity[3], quaternion x, y, z, w, angular velocity[3], body height,
engine rpm: bytes 0x00-0x3F."""
_IV = struct.Struct("<I")  # 0x40
_SPEED = struct.Struct("<f")  # 0x4C
_PACKET_ID = struct.Struct("<i")  # 0x70
_STATE = struct.Struct("<HHhHB")  # 0x88 rpm alert min, max, max speed, flags, gears
_EXTENDED = struct.Struct("<5f")  # 0x128 wheel rotation, filler, sway, heave, surge
_NONCE = struct.Struct("<II")
_READ = struct.Struct("<i12x3f4f3f4xf48xi22xH2xH")
"""Everything the decoder reads, in one call: magic (0x00), velocity (0x10), quaternion
(0x1C), angular velocity (0x2C), engine rpm (0x3C), packet id (0x70), rev-limit alert rpm
(0x8A), flags (0x8E); the rest is skipped (pad bytes)."""

FLAG_ON_TRACK, FLAG_PAUSED, FLAG_LOADING = 1, 2, 4
_STATE_MASK = FLAG_ON_TRACK | FLAG_PAUSED | FLAG_LOADING
_INF = math.inf
_USED = 0x94  # the decoder reads bytes 0x00-0x93 (a stream cipher: only those are decrypted)
_NO_CRYPTO = "Gran Turismo 7 telemetry needs pycryptodome: pip install pycryptodome"


def _xor(data: bytes, iv_xor: int, n: int) -> bytes:
    # the cipher (pycryptodome through cffi, libsodium's checks) loads on first use: every
    # start that imports the games would pay for it otherwise
    from ._gt7_cipher import Salsa20Xor, available

    if not available():  # pragma: no cover
        raise ConfigError(_NO_CRYPTO)
    iv = _IV.unpack_from(data, 0x40)[0]
    return bytes(Salsa20Xor(KEY, n).xor(data, _NONCE.pack(iv ^ iv_xor, iv)))


def decrypt(datagram: bytes) -> bytes | None:
    """The plain packet, or None when the size is not a GT7 layout or the magic is wrong."""
    layout = SIZES.get(len(datagram))
    if layout is None:
        return None
    plain = _xor(datagram, layout[1], len(datagram))
    return plain if plain[:4] == b"0S7G" else None


def encrypt(plain: bytes, iv: int) -> bytes:
    """Encrypt a plain packet as the console does, with the nonce seed ``iv`` (u32) stored in
    clear at 0x40 (for tests and stand-in consoles)."""
    layout = SIZES.get(len(plain))
    if layout is None:
        raise ConfigError(f"a GT7 packet has {sorted(SIZES)} bytes, not {len(plain)}")
    iv &= 0xFFFFFFFF
    seeded = bytearray(plain)
    _IV.pack_into(seeded, 0x40, iv)  # _xor reads the seed there; the byte is overwritten
    out = bytearray(_xor(bytes(seeded), layout[1], len(plain)))
    _IV.pack_into(out, 0x40, iv)
    return bytes(out)


@dataclass(frozen=True, slots=True)
class GT7Packet:
    """The fields of a (decrypted) GT7 packet this reader uses, in the game's axes and units.

    ``quaternion`` is ``(x, y, z, w)``: car axes to world axes. ``extended`` holds wheel
    rotation, filler, sway, heave, surge (B and later layouts), else None.
    """

    packet_id: int
    position: tuple[float, float, float]
    velocity: tuple[float, float, float]
    quaternion: tuple[float, float, float, float]
    angular_velocity: tuple[float, float, float]
    speed_m_s: float = 0.0
    engine_rpm: float = 0.0
    rpm_alert_max: int = 0
    flags: int = FLAG_ON_TRACK
    gear: int = 1
    extended: tuple[float, float, float, float, float] | None = field(default=None)

    @classmethod
    def unpack(cls, plain: bytes) -> GT7Packet:
        v = PACKET.unpack_from(plain)
        _amin, amax, _vmax, flags, gears = _STATE.unpack_from(plain, 0x88)
        ext = _EXTENDED.unpack_from(plain, 0x128) if len(plain) >= 316 else None
        return cls(
            packet_id=_PACKET_ID.unpack_from(plain, 0x70)[0],
            position=(v[1], v[2], v[3]), velocity=(v[4], v[5], v[6]),
            quaternion=(v[7], v[8], v[9], v[10]), angular_velocity=(v[11], v[12], v[13]),
            speed_m_s=_SPEED.unpack_from(plain, 0x4C)[0], engine_rpm=v[15],
            rpm_alert_max=amax, flags=flags, gear=gears & 0x0F, extended=ext,
        )  # fmt: skip

    def pack(self, size: int = 296) -> bytes:
        """A plain packet of ``size`` bytes (296, 316, 344 or 368) with these fields and
        zeros elsewhere."""
        if size not in SIZES:
            raise ConfigError(f"a GT7 packet has {sorted(SIZES)} bytes, not {size}")
        out = bytearray(size)
        PACKET.pack_into(out, 0, MAGIC, *self.position, *self.velocity, *self.quaternion,
                         *self.angular_velocity, 0.0, self.engine_rpm)  # fmt: skip
        _SPEED.pack_into(out, 0x4C, self.speed_m_s)
        _PACKET_ID.pack_into(out, 0x70, self.packet_id)
        _STATE.pack_into(out, 0x88, 0, self.rpm_alert_max, 0, self.flags, self.gear & 0x0F)
        if size >= 316:
            _EXTENDED.pack_into(out, 0x128, *(self.extended or (0.0,) * 5))
        return bytes(out)


class GT7Decoder(Decoder):
    """Decoder of Gran Turismo 7 packets, and the heartbeat the console needs.

    Parameters
    ----------
    heartbeat : {"A", "B", "~", "C"}
        The layout to ask for. Every layout is decoded whichever was asked.
    max_gap_frames : int
        Largest packet-id step (1/60 s frames) the velocity is differenced over; a longer
        gap restarts the difference. Default 6 (0.1 s).

    Outcome reasons: ``sample``, ``partial`` (first packet, or after a gap or a jump: the
    difference restarts), ``ignored: repeated`` (same packet id again), ``skipped:
    truncated`` / ``skipped: wrong size`` (not 296/316/344/368 bytes), ``skipped: foreign``
    (wrong magic after decryption, or a quaternion that is not a unit one),
    ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "gt7"
    default_port = DEFAULT_PORT
    title = "Gran Turismo 7 Simulator Interface (encrypted; motioncue sends the heartbeat)"
    PEER_PORT = HEARTBEAT_PORT
    LISTEN_PORT = DEFAULT_PORT
    HEARTBEAT_PERIOD_S = 1.0

    def __init__(self, heartbeat: str = "A", max_gap_frames: int = 6) -> None:
        super().__init__()
        if heartbeat not in _XOR:
            raise ConfigError(f"GT7 heartbeat {heartbeat!r} is not one of {sorted(_XOR)}")
        if not 1 <= max_gap_frames <= 600:
            raise ConfigError(f"max_gap_frames = {max_gap_frames!r} is outside 1..600")
        self.heartbeat = heartbeat.encode("ascii")
        self.max_gap_frames = max_gap_frames
        self.layouts: dict[str, int] = {}
        self._next_heartbeat_s = -math.inf
        self._prev_id: int | None = None
        self._prev_v = (0.0, 0.0, 0.0)
        from ._gt7_cipher import Salsa20Xor, available  # on first use (see _xor)

        if not available():  # pragma: no cover
            raise ConfigError(_NO_CRYPTO)
        self._xor = Salsa20Xor(KEY, _USED).xor

    def reset(self) -> None:
        self._prev_id = None

    def requests(self, now_s: float) -> list[bytes]:
        """The heartbeat, once every :attr:`HEARTBEAT_PERIOD_S`."""
        if now_s < self._next_heartbeat_s:
            return []
        self._next_heartbeat_s = now_s + self.HEARTBEAT_PERIOD_S
        return [self.heartbeat]

    def farewell(self) -> list[bytes]:
        """Nothing: the console stops by itself ~1.6 s after the last heartbeat."""
        return []

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        layout = SIZES.get(n)
        if layout is None:
            return wrong_size(n, 296)
        iv = _IV.unpack_from(datagram, 0x40)[0]
        plain = self._xor(datagram, _NONCE.pack(iv ^ layout[1], iv))
        (magic, vx, vy, vz, qx, qy, qz, qw, wx, wy, wz, rpm, pid, amax, flags) = _READ.unpack_from(
            plain
        )
        if magic != MAGIC:
            return DecodeResult("skipped", "skipped: foreign")
        self.layouts[layout[0]] = self.layouts.get(layout[0], 0) + 1
        norm = qx * qx + qy * qy + qz * qz + qw * qw
        # one chained comparison each (False for nan, and for inf): the common case costs two
        if not (-1e-3 <= norm - 1.0 <= 1e-3 and -_INF < vx + vy + vz < _INF):
            if not (math.isfinite(norm) and math.isfinite(vx + vy + vz)):
                return DecodeResult("skipped", "skipped: non-finite")
            return DecodeResult("skipped", "skipped: foreign")
        prev, self._prev_id = self._prev_id, pid
        prev_v, self._prev_v = self._prev_v, (vx, vy, vz)
        if prev is not None and pid == prev:
            self._prev_id = prev
            return DecodeResult("ignored", "ignored: repeated")
        if prev is None or not 0 < pid - prev <= self.max_gap_frames:
            return DecodeResult("partial", "partial")
        k = FRAME_HZ / (pid - prev)
        # specific force in world axes: a - g, with g = (0, -G0, 0)
        ax = (vx - prev_v[0]) * k
        ay = (vy - prev_v[1]) * k + G0_M_S2
        az = (vz - prev_v[2]) * k
        # in car axes, R(q)^T a: the conjugate quaternion's rotation written out (this runs
        # for every packet): t = 2 (a x u), c = a + w t + t x u, with u = (qx, qy, qz)
        tx = 2.0 * (ay * qz - az * qy)
        ty = 2.0 * (az * qx - ax * qz)
        tz = 2.0 * (ax * qy - ay * qx)
        cx = ax + qw * tx + ty * qz - tz * qy
        cy = ay + qw * ty + tz * qx - tx * qz
        cz = az + qw * tz + tx * qy - ty * qx
        # ISO is (-car z, -car x, car y)
        paused = (flags & _STATE_MASK) != FLAG_ON_TRACK
        extras: dict[str, object] = {"rpm": rpm, "rpm_max": float(amax) if amax else math.nan}
        return self._make(t_s, (-cz, -cx, cy), (-wz, -wx, wy), paused, extras)


INFO = register_game(GameInfo.of(GT7Decoder, asked=True))
