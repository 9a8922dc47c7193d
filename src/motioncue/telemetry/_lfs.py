"""Live for Speed OutSim UDP (OutSim2 with its options word, and the classic OutSimPack).

Layout
------
Live for Speed's ``docs/InSim.txt`` (the ``OutSimPack`` / ``OutSimPack2`` definitions shipped
with the game, also transcribed by theangryangel/insim.rs and simbroadcasts/node-insim).
Little-endian. ``OutSim Opts`` in ``cfg.txt`` (hexadecimal) chooses the blocks, in this
order::

    0x01 OSO_HEADER   char[4] "LFST"
    0x02 OSO_ID       s32 OutSim ID
    0x04 OSO_TIME     u32 time (ms)
    0x08 OSO_MAIN     OutSimMain (60 bytes):
                          f32 AngVel[3]               (rad/s, world axes)
                          f32 Heading, Pitch, Roll    (rad: anticlockwise from above about Z,
                                                       from the right about X, from the front
                                                       about Y)
                          f32 Accel[3], f32 Vel[3]    (m/s^2, m/s, world axes)
                          s32 Pos[3]                  (1 m = 65536)
    0x10 OSO_INPUTS   f32 throttle, brake, steer, clutch, handbrake
    0x20 OSO_DRIVE    u8 gear (0 reverse, 1 neutral, 2 first...), u8 spare[3],
                      f32 engine angular velocity (rad/s), f32 max torque at velocity
    0x40 OSO_DISTANCE f32 current lap distance, indexed distance
    0x80 OSO_WHEELS   OutSimWheel[4] (40 bytes each)
    0x100 OSO_EXTRA_1 f32 steer torque, spare

With ``OutSim Opts 0`` the game sends the classic ``OutSimPack``: u32 time, then OutSimMain,
then an optional s32 ID (64 or 68 bytes). The options word is not in the packet, so the
decoder is told it (:class:`LFSDecoder`, default ``0x1ff``: everything, 280 bytes); the
classic 64/68-byte packet is recognised by its size and the absence of the header.

Axes and conversion
-------------------
World axes: X and Y on the ground, Z up (right-handed); the car's axes are x right, y
forward, z up, and its attitude is ``R = Rz(Heading) Rx(Pitch) Ry(Roll)`` (the order the
angles are listed in, each anticlockwise about its axis). ``AngVel``, ``Accel`` and ``Vel``
are world vectors; they are rotated into car axes with ``R^T``. ``Accel`` is taken as the
kinematic acceleration (it reads 0 at rest), so the specific force is ``R^T (Accel + G0
e_z)``. The car's (right, forward, up) map to ISO 8855 as ``forward = y``, ``left = -x``,
``up = z``::

    f_iso = (f_y, -f_x, f_z)        w_iso = (w_y, -w_x, w_z)

No captured OutSim datagram was available to pin these signs against real motion; they
follow the documented axes and angle senses (``motioncue record lfs`` makes a capture).

LFS sends OutSim only while the player's car is shown in cockpit or custom view; pausing
stops the stream (the source sees missing packets).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from .._errors import ConfigError
from ._packed import flat_values, from_flat
from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3, wrong_size

__all__ = [
    "MAIN",
    "OSO_ALL",
    "LFSDecoder",
    "OutSimMain",
    "outsim2_size",
]

DEFAULT_PORT = 4123  # LFS has none ("OutSim Port 0" = off); the port its community uses

OSO_HEADER, OSO_ID, OSO_TIME, OSO_MAIN = 0x01, 0x02, 0x04, 0x08
OSO_INPUTS, OSO_DRIVE, OSO_DISTANCE, OSO_WHEELS, OSO_EXTRA_1 = 0x10, 0x20, 0x40, 0x80, 0x100
OSO_ALL = 0x1FF
_BLOCKS = ((OSO_HEADER, 4), (OSO_ID, 4), (OSO_TIME, 4), (OSO_MAIN, 60), (OSO_INPUTS, 20),
           (OSO_DRIVE, 12), (OSO_DISTANCE, 8), (OSO_WHEELS, 160), (OSO_EXTRA_1, 8))  # fmt: skip

MAIN = struct.Struct("<3f3f3f3f3i")
"""OutSimMain: AngVel[3], Heading, Pitch, Roll, Accel[3], Vel[3], Pos[3] (60 bytes)."""
_DRIVE = struct.Struct("<B3xf")
CLASSIC_SIZES = (64, 68)


def outsim2_size(options: int) -> int:
    """Datagram size for an ``OutSim Opts`` word."""
    return sum(size for bit, size in _BLOCKS if options & bit)


def _offset(options: int, block: int) -> int:
    off = 0
    for bit, size in _BLOCKS:
        if bit == block:
            return off
        if options & bit:
            off += size
    raise AssertionError(block)  # pragma: no cover


@dataclass(frozen=True, slots=True)
class OutSimMain:
    """OutSimMain in the game's axes and units (world vectors, attitude angles in rad)."""

    ang_vel: tuple[float, float, float]
    heading: float
    pitch: float
    roll: float
    accel: tuple[float, float, float]
    vel: tuple[float, float, float]
    pos: tuple[int, int, int] = (0, 0, 0)

    @classmethod
    def unpack(cls, data: bytes, offset: int = 0) -> OutSimMain:
        return from_flat(cls, MAIN.unpack_from(data, offset))

    def pack(self) -> bytes:
        return MAIN.pack(*flat_values(self))

    def outsim2(self, options: int = OSO_ALL, time_ms: int = 0, gear: int = 3,
                engine_rad_s: float = 500.0) -> bytes:  # fmt: skip
        """An OutSim2 datagram with these fields (zeros in the other blocks)."""
        if not options & OSO_MAIN:
            raise ConfigError(f"OutSim options 0x{options:x} lack OSO_MAIN (0x8)")
        out = bytearray(outsim2_size(options))
        if options & OSO_HEADER:
            out[0:4] = b"LFST"
        if options & OSO_TIME:
            struct.pack_into("<I", out, _offset(options, OSO_TIME), time_ms & 0xFFFFFFFF)
        MAIN.pack_into(out, _offset(options, OSO_MAIN), *flat_values(self))
        if options & OSO_DRIVE:
            _DRIVE.pack_into(out, _offset(options, OSO_DRIVE), gear, engine_rad_s)
        return bytes(out)

    def classic(self, time_ms: int = 0, outsim_id: int | None = None) -> bytes:
        """The classic OutSimPack (``OutSim Opts 0``): 64 bytes, 68 with an ID."""
        tail = b"" if outsim_id is None else struct.pack("<i", outsim_id)
        return struct.pack("<I", time_ms & 0xFFFFFFFF) + self.pack() + tail


def _rotation_t(h: float, p: float, r: float) -> tuple[float, ...]:
    """The 9 entries (row-major) of ``R^T`` with ``R = Rz(h) Rx(p) Ry(r)``: world vectors
    into car axes (x right, y forward, z up)."""
    ch, sh, cp, sp = math.cos(h), math.sin(h), math.cos(p), math.sin(p)
    cr, sr = math.cos(r), math.sin(r)
    # R^T = Ry(r)^T Rx(p)^T Rz(h)^T, multiplied out
    return (
        cr * ch - sr * sp * sh, cr * sh + sr * sp * ch, -sr * cp,
        -cp * sh, cp * ch, sp,
        sr * ch + cr * sp * sh, sr * sh - cr * sp * ch, cr * cp,
    )  # fmt: skip


def _to_car(m: tuple[float, ...], v: tuple[float, float, float]) -> tuple[float, float, float]:
    x, y, z = v
    return (m[0] * x + m[1] * y + m[2] * z, m[3] * x + m[4] * y + m[5] * z,
            m[6] * x + m[7] * y + m[8] * z)  # fmt: skip


class LFSDecoder(Decoder):
    """Decoder of Live for Speed OutSim datagrams.

    Parameters
    ----------
    options : int
        The ``OutSim Opts`` word of the game's ``cfg.txt`` (default 0x1ff); it must include
        OSO_MAIN (0x8).

    Outcome reasons: ``sample``, ``skipped: truncated`` / ``skipped: wrong size`` (neither
    the configured OutSim2 size nor a classic 64/68-byte packet), ``skipped: other options``
    (an OutSim2 header with another size: the game's ``OutSim Opts`` differ from
    ``options``), ``skipped: foreign`` (the configured size without the ``LFST`` header, or
    attitude angles beyond +-2 pi), ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "lfs"
    default_port = DEFAULT_PORT
    title = "Live for Speed OutSim (OutSim2, OutSim Opts 1ff; or the classic OutSimPack)"

    def __init__(self, options: int = OSO_ALL) -> None:
        super().__init__()
        if not 0 <= options <= OSO_ALL or not options & OSO_MAIN:
            raise ConfigError(
                f"OutSim options = 0x{options:x} must be within 0x0-0x1ff and include "
                "OSO_MAIN (0x8)"
            )
        self.options = options
        self.size = outsim2_size(options)
        self._main = _offset(options, OSO_MAIN)
        self._drive = _offset(options, OSO_DRIVE) if options & OSO_DRIVE else -1
        self._header = bool(options & OSO_HEADER)

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        drive = -1
        if n == self.size and (not self._header or datagram[:4] == b"LFST"):
            main, drive = self._main, self._drive
        elif n in CLASSIC_SIZES and datagram[:4] != b"LFST":
            main = 4
        elif datagram[:4] == b"LFST":
            return DecodeResult("skipped", "skipped: other options")
        elif n == self.size:
            return DecodeResult("skipped", "skipped: foreign")
        else:
            return wrong_size(n, self.size)
        (wx, wy, wz, h, p, r, ax, ay, az, _vx, _vy, _vz, _px, _py, _pz) = MAIN.unpack_from(
            datagram, main
        )
        if not (math.isfinite(h) and math.isfinite(p) and math.isfinite(r)):
            return DecodeResult("skipped", "skipped: non-finite")
        lim = 2 * math.pi + 1e-3
        if abs(h) > lim or abs(p) > lim or abs(r) > lim:
            return DecodeResult("skipped", "skipped: foreign")
        rt = _rotation_t(h, p, r)
        fx, fy, fz = _to_car(rt, (ax, ay, az + G0_M_S2))
        cx, cy, cz = _to_car(rt, (wx, wy, wz))
        extras: dict[str, object] | None = None
        if drive >= 0:
            gear, engine = _DRIVE.unpack_from(datagram, drive)
            extras = {"rpm": engine * 30.0 / math.pi, "gear": gear - 1 if gear else -1}
        return self._make(t_s, (fy, -fx, fz), (cy, -cx, cz), False, extras)


def encode_lfs(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
    """An OutSim2 datagram (options 1ff) of a level car heading 0 with specific force ``f``
    (m/s^2) and angular velocity ``w`` (rad/s), ISO 8855 body axes, stamped ``t_s`` (s)."""
    # decoder, level, heading 0: car (right, forward, up) = world; f = (f_y, -f_x, f_z)
    fx, fy, fz = f
    wx, wy, wz = w
    stamp_ms = round(t_s * 1e3) & 0xFFFFFFFF
    outsim = OutSimMain((-wy, wx, wz), 0.0, 0.0, 0.0, (-fy, fx, fz - G0_M_S2), (0.0, 0.0, 0.0))
    return [outsim.outsim2(time_ms=stamp_ms)]


INFO = register_game(GameInfo.of(LFSDecoder, encode_lfs))
