"""Assetto Corsa (2014) UDP remote telemetry: handshake, subscribe, ``RTCarInfo``.

Protocol
--------
Kunos Simulazioni's "Assetto Corsa Remote Telemetry" document ("AC UDP Sockets", 2014; the
same facts are transcribed in vpicon/acudp ``UDP.md``). The game (the "server") listens on
UDP port 9996 of the PC it runs on; the client sends it 12-byte ``handshaker`` requests and
the game answers to the address they came from. Little-endian, C layout::

    handshaker (client -> game, 12 bytes): s32 identifier, s32 version, s32 operationId
        operationId 0 HANDSHAKE, 1 SUBSCRIBE_UPDATE, 2 SUBSCRIBE_SPOT, 3 DISMISS
    handshakerResponse (game -> client, 408 bytes):
        wchar carName[50], wchar driverName[50], s32 identifier, s32 version,
        wchar trackName[50], wchar trackConfig[50]          (UTF-16LE, NUL-padded)
    RTCarInfo (game -> client after SUBSCRIBE_UPDATE, 328 bytes, one per physics update):
          0 char identifier ('a') + 3 pad     4 s32 size (328)
          8 f32 speed_Kmh, speed_Mph, speed_Ms
         20 bool isAbsEnabled, isAbsInAction, isTcInAction, isTcEnabled, isInPit,
            isEngineLimiterOn + 2 pad
         28 f32 accG_vertical, accG_horizontal, accG_frontal   (g; see below)
         40 s32 lapTime, lastLap, bestLap (ms), lapCount
         56 f32 gas, brake, clutch, engineRPM, steer     76 s32 gear (0 R, 1 N, 2 first)
         80 f32 cgHeight; then 14 arrays f32[4] per wheel (wheelAngularSpeed, slipAngle, ...)
        308 f32 carPositionNormalized, carSlope          316 f32 carCoordinates[3] (m, world)
    RTLap (after SUBSCRIBE_SPOT, 212 bytes): s32 car, s32 lap, wchar driver[50], car[50], s32 ms

Axes and signs (pinned on a real capture)
-----------------------------------------
Whatever the document's field names say, the three ``accG`` values arrive as
(lateral, vertical, longitudinal), in g, gravity excluded (all three read 0 at rest in the
pits). On the public capture of an Audi R8 LMS lap of Monza (vthinsel/Python_UDP_Receiver,
``tests/fixtures/games/ac``) ``accG[2]`` equals the derivative of ``speed_Ms`` (slope 1.00,
correlation 0.99), and ``accG[0]`` equals ``speed x`` the rate of the course angle of
``carCoordinates`` measured from +z towards +x (slope 1.01, correlation 0.997); over the
lap that course angle turns by -1.00 turn, and Monza is driven clockwise (a net right turn,
-1 turn in ISO 8855), so a positive ``accG[0]`` is a *leftward* acceleration (and the world
frame is right-handed: x, y up, z). ``accG[1]`` correlates positively with the second
derivative of the height ``carCoordinates[1]`` (upward positive). Hence::

    f = G0 * (accG[2], accG[0], 1 + accG[1])

``RTCarInfo`` carries no angular velocity and no attitude. The yaw rate is taken as the
course rate of the car, ``w_z = a_y / v`` (exact while the sideslip angle is steady; the
decoder regularises it below a few m/s: ``a_y v / (v^2 + V0^2)``); roll and pitch rates are
reported as 0, and gravity is taken as vertical in the body frame (``carSlope`` is 0 in the
capture). The tests check ``w_z`` against the course change of ``carCoordinates``.

``engineRPM`` and ``gear`` are passed on (gear: 0 reverse -> -1, 1 neutral -> 0, n -> n-1).

Pause: the game keeps the subscription but stops sending while paused or in menus; the
source sees missing packets. The handshake answer and ``RTLap`` are counted ``state`` and
``ignored``.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, wrong_size

__all__ = [
    "CAR_INFO",
    "CAR_INFO_SIZE",
    "HANDSHAKE",
    "RESPONSE_SIZE",
    "ACCarInfo",
    "ACDecoder",
    "handshake_response",
    "request",
]

DEFAULT_PORT = 9996  # the game's own port: requests go there, answers come back from it

HANDSHAKE = struct.Struct("<iii")
"""identifier, version, operationId (client -> game)."""
OP_HANDSHAKE, OP_SUBSCRIBE_UPDATE, OP_SUBSCRIBE_SPOT, OP_DISMISS = 0, 1, 2, 3

CAR_INFO = struct.Struct("<c3xi3f6B2x3f4i5fif56f2f3f")
"""RTCarInfo: identifier, size, 3 speeds, 6 flags, accG[3], 4 lap ints, gas, brake, clutch,
rpm, steer, gear, cgHeight, 14 x 4 per-wheel floats, positionNormalized, slope, coords[3]."""
CAR_INFO_SIZE = 328
RESPONSE_SIZE = 408
RESPONSE = struct.Struct("<100s100sii100s100s")
LAP_SIZE = 212

V0_M_S = 3.0
"""Speed below which the course-rate yaw estimate ``a_y / v`` is faded out (m/s)."""

_HEAD = struct.Struct("<c3xi3f6B2x3f4i5fi")  # up to and including gear (80 bytes)
_COORDS = struct.Struct("<2f3f")  # @308
_MOTION = struct.Struct("<c3xi8xf8x3f28xf4xi")
"""What the decoder reads: identifier, size, speed_Ms, accG[3], engineRPM, gear (80 bytes)."""
assert CAR_INFO.size == CAR_INFO_SIZE and RESPONSE.size == RESPONSE_SIZE == 408
assert _MOTION.size == _HEAD.size == 80


def request(operation: int, identifier: int = 1, version: int = 1) -> bytes:
    """A 12-byte ``handshaker`` request (0 handshake, 1 subscribe, 2 spot, 3 dismiss)."""
    return HANDSHAKE.pack(identifier, version, operation)


def _wstr(text: str) -> bytes:
    return text.encode("utf-16-le")[:100].ljust(100, b"\0")


def handshake_response(car: str, driver: str, track: str, config: str = "") -> bytes:
    """The game's 408-byte answer to a handshake (for tests and stand-in games)."""
    return RESPONSE.pack(_wstr(car), _wstr(driver), 4242, 1, _wstr(track), _wstr(config))


@dataclass(frozen=True, slots=True)
class ACCarInfo:
    """The fields of ``RTCarInfo`` this reader uses, in the game's own units.

    ``acc_g`` is in arrival order (lateral left +, vertical up +, longitudinal forward +),
    ``coordinates`` in the world frame (m, y up).
    """

    speed_m_s: float
    acc_g: tuple[float, float, float]
    lap_time_ms: int
    engine_rpm: float
    gear: int
    coordinates: tuple[float, float, float]
    in_pit: bool = False

    @classmethod
    def unpack(cls, data: bytes) -> ACCarInfo:
        v = _HEAD.unpack_from(data)
        c = _COORDS.unpack_from(data, 308)
        return cls(
            speed_m_s=v[4], acc_g=(v[11], v[12], v[13]), lap_time_ms=v[14],
            engine_rpm=v[21], gear=v[23], coordinates=(c[2], c[3], c[4]), in_pit=bool(v[9]),
        )  # fmt: skip

    def pack(self) -> bytes:
        """A 328-byte ``RTCarInfo`` with these fields and zeros elsewhere."""
        out = bytearray(CAR_INFO_SIZE)
        _HEAD.pack_into(
            out, 0, b"a", CAR_INFO_SIZE, self.speed_m_s * 3.6, self.speed_m_s / 0.44704,
            self.speed_m_s, 0, 0, 0, 0, int(self.in_pit), 0, *self.acc_g, self.lap_time_ms,
            0, 0, 0, 0.0, 0.0, 0.0, self.engine_rpm, 0.0, self.gear,
        )  # fmt: skip
        _COORDS.pack_into(out, 308, 0.0, 0.0, *self.coordinates)
        return bytes(out)


class ACDecoder(Decoder):
    """Decoder of Assetto Corsa remote-telemetry datagrams, and the handshake it needs.

    Outcome reasons: ``sample`` (RTCarInfo), ``state`` (handshake answer), ``ignored``
    (RTLap), ``skipped: truncated`` / ``skipped: wrong size`` (any other size),
    ``skipped: foreign`` (a 328-byte datagram without identifier ``'a'`` and size 328),
    ``skipped: non-finite``, ``skipped: out of range``.

    Talking to the game (:meth:`requests`, called by a live source about every 50 ms):
    a handshake each second until the game answers, then one subscription; a fresh
    handshake when no car data came for :attr:`RESUBSCRIBE_S` (the game was restarted).
    """

    game = "ac"
    default_port = DEFAULT_PORT
    title = "Assetto Corsa UDP remote telemetry (RTCarInfo; motioncue sends the handshake)"
    PEER_PORT = DEFAULT_PORT
    """The game's port, where requests go."""
    LISTEN_PORT = 0
    """Local port to bind when none is given: any (the game answers to the sender)."""
    RESUBSCRIBE_S = 3.0

    def __init__(self) -> None:
        super().__init__()
        self.car = self.track = ""
        self._answered = False
        self._subscribed = False
        self._last_request_s = -math.inf
        self._last_data_s = -math.inf

    def reset(self) -> None:
        self._answered = self._subscribed = False

    # -- talking ---------------------------------------------------------------------------
    def requests(self, now_s: float) -> list[bytes]:
        """Datagrams to send to the game now (may be empty)."""
        if self._subscribed and now_s - max(self._last_data_s, self._last_request_s) > (
            self.RESUBSCRIBE_S
        ):
            self._answered = self._subscribed = False  # the game went away: start again
        if self._answered and not self._subscribed:
            self._subscribed = True
            self._last_request_s = now_s
            return [request(OP_SUBSCRIBE_UPDATE)]
        if not self._answered and now_s - self._last_request_s >= 1.0:
            self._last_request_s = now_s
            return [request(OP_HANDSHAKE)]
        return []

    def farewell(self) -> list[bytes]:
        """Datagrams to send when the source closes (dismiss the subscription)."""
        return [request(OP_DISMISS)] if self._subscribed else []

    # -- decoding --------------------------------------------------------------------------
    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        if n == RESPONSE_SIZE:
            car, _drv, _ident, _ver, track, _cfg = RESPONSE.unpack(datagram)
            self.car = car.decode("utf-16-le", "replace").split("\0", 1)[0]
            self.track = track.decode("utf-16-le", "replace").split("\0", 1)[0]
            self._answered = True
            return DecodeResult("state", "state")
        if n == LAP_SIZE:
            return DecodeResult("ignored", "ignored")
        if n != CAR_INFO_SIZE:
            return wrong_size(n, CAR_INFO_SIZE)
        ident, size, speed, a_lat, a_up, a_lon, rpm, gear = _MOTION.unpack_from(datagram)
        if ident != b"a" or size != CAR_INFO_SIZE:
            return DecodeResult("skipped", "skipped: foreign")
        self._last_data_s = t_s
        self._answered = True  # data flowing: the subscription stands
        g = G0_M_S2
        f = (g * a_lon, g * a_lat, g + g * a_up)
        yaw_rate = 0.0
        if math.isfinite(speed) and abs(speed) < 1e4:
            yaw_rate = g * a_lat * speed / (speed * speed + V0_M_S * V0_M_S)
        return self._make(t_s, f, (0.0, 0.0, yaw_rate), False,
                          {"rpm": rpm, "gear": gear - 1 if gear >= 1 else -1})  # fmt: skip


INFO = register_game(GameInfo.of(ACDecoder, asked=True))
