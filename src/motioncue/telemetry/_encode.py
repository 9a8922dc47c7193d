"""Game packets from vehicle motion: the inverse of the decoders, for trying without a game.

:func:`encode_motion` turns one sample of vehicle motion (specific force ``f`` in m/s^2 and
angular velocity ``w`` in rad/s, ISO 8855 body axes, see :mod:`motioncue.telemetry`) into the
datagrams a game would send, in the layouts the decoders read (the structures and ``pack``
functions of each game's module). The car or aircraft is kept level (zero attitude) and the
whole specific force is carried by the game's acceleration or g-force fields, so each
decoder gives back ``f`` and ``w`` to the precision of its float32 fields; the round trip is
tested for every game (``tests/test_new_user.py``).

Games: ``f1`` (Motion Ex, then Motion, F1 24 layout), ``forza`` (Sled, 232 bytes),
``beamng`` (BNG1), ``xplane`` and ``xplane11`` (DATA rows 4 and 16), ``pcars2`` (type-0
telemetry), ``lfs`` (OutSim2, options 1ff), ``rbr`` (NGP TelemetryData). ``dirt`` is not
encodable: its decoder derives the angular velocity from the orientation of consecutive
packets, which a level car does not change (nor are ``wrc``, ``ac`` and ``gt7``, whose
decoders derive rates or forces from consecutive packets too, and ``dcs``, a text format
with 5 decimals).

:func:`send_recording` paces such datagrams to a UDP address on the recording's clock
(``motioncue send-telemetry``).
"""

from __future__ import annotations

import math
import socket
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._errors import ConfigError, TransportError
from ._sample import G0_M_S2

__all__ = ["ENCODABLE_GAMES", "SendSummary", "encode_motion", "send_recording"]

ENCODABLE_GAMES = ("f1", "forza", "beamng", "xplane", "xplane11", "pcars2", "lfs", "rbr")
"""Games :func:`encode_motion` writes (``dirt``: see the module docstring)."""

_F1_FORMAT = 2024
_F1_SESSION_UID = 0x4D6F74696F6E6375  # "Motioncu": any fixed value names one session


def _vec(x: ArrayLike, name: str) -> tuple[float, float, float]:
    a = np.asarray(x, dtype=float).reshape(-1)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ConfigError(f"{name} = {a.tolist()!r} is invalid; allowed: 3 finite numbers")
    return float(a[0]), float(a[1]), float(a[2])


def encode_motion(game: str, k: int, t_s: float, f: ArrayLike, w: ArrayLike) -> list[bytes]:
    """The datagrams of sample ``k`` at ``t_s`` (s) of ``game``, in sending order.

    Parameters
    ----------
    game : str
        One of :data:`ENCODABLE_GAMES`.
    k : int
        Sample number (packet counters, frame identifiers), >= 0.
    t_s : float
        Game time of the sample (s): F1's session time, Forza's time stamp.
    f : (3,) array_like
        Specific force ``a - g`` in the body frame (m/s^2; ``[0, 0, 9.80665]`` at rest).
    w : (3,) array_like
        Angular velocity in the body frame (rad/s).

    Returns
    -------
    list of bytes
        One or two datagrams (F1: Motion Ex, then Motion).

    Raises
    ------
    ConfigError
        An unknown game, non-finite values or a negative ``k``.
    """
    if game not in ENCODABLE_GAMES:
        raise ConfigError(f"game {game!r} cannot be encoded; allowed: {', '.join(ENCODABLE_GAMES)}")
    if k < 0 or not math.isfinite(t_s):
        raise ConfigError(f"sample {k}, t = {t_s!r}: allowed k >= 0 and a finite time")
    fx, fy, fz = _vec(f, "f")
    wx, wy, wz = _vec(w, "w")
    g = G0_M_S2
    if game == "f1":
        return _f1(k, t_s, (fx, fy, fz), (wx, wy, wz))
    if game == "forza":
        from ._forza import SLED_HEAD, ForzaMotion

        # decoder, level: f = (az, -ax, ay + g), w = (-wz, wx, -wy)
        stamp_ms = round(t_s * 1e3) & 0xFFFFFFFF
        m = ForzaMotion(1, stamp_ms, 8000.0, 800.0, 3000.0, (-fy, fz - g, fx),
                        (0.0, 0.0, 0.0), (wy, -wz, -wx), 0.0, 0.0, 0.0)  # fmt: skip
        return [m.pack() + bytes(232 - SLED_HEAD.size)]
    if game == "beamng":
        from ._beamng import BeamNGMotion

        # decoder, level: f = (ay, -ax, g - az), w = (roll_rate, -pitch_rate, -yaw_rate)
        b = BeamNGMotion(
            pos=(0.0, 0.0, 0.0), vel=(0.0, 0.0, 0.0), acc=(-fy, fx, g - fz),
            up_vec=(0.0, 0.0, 1.0), roll_pos=0.0, pitch_pos=0.0, yaw_pos=0.0,
            roll_rate=wx, pitch_rate=-wy, yaw_rate=-wz, roll_acc=0.0, pitch_acc=0.0,
            yaw_acc=0.0,
        )  # fmt: skip
        return [b.pack()]
    if game in ("xplane", "xplane11"):
        from ._xplane import UNUSED, pack_data

        # decoder: f = g (axial, -side, normal), w = (P, -Q, -R); X-Plane 12 row 16 holds
        # P, Q, R in deg/s, X-Plane 11 holds Q, P, R in rad/s
        p, q, r = wx, -wy, -wz
        rates = (q, p, r) if game == "xplane11" else tuple(math.degrees(v) for v in (p, q, r))
        u = UNUSED
        gload = (0.0, u, 0.0, u, fz / g, fx / g, -fy / g, u)
        return [pack_data({4: gload, 16: rates})]
    if game == "lfs":
        from ._lfs import OutSimMain

        # decoder, level, heading 0: car (right, forward, up) = world; f = (f_y, -f_x, f_z)
        stamp_ms = round(t_s * 1e3) & 0xFFFFFFFF
        outsim = OutSimMain((-wy, wx, wz), 0.0, 0.0, 0.0, (-fy, fx, fz - g), (0.0, 0.0, 0.0))
        return [outsim.outsim2(time_ms=stamp_ms)]
    if game == "rbr":
        from ._rbr import RBRCar

        # decoder, level: f = (surge, sway, heave + g), w = radians of the (roll, pitch, yaw)
        # rates in deg/s
        deg = 180.0 / math.pi
        car = RBRCar(k & 0xFFFFFFFF, t_s, 2, 0.0, (0.0, 0.0, 0.0),
                     (0.0, 0.0, 0.0, wx * deg, wy * deg, wz * deg),
                     (fx, fy, fz - g, 0.0, 0.0, 0.0), 3000.0)  # fmt: skip
        return [car.pack()]
    from ._pcars2 import PCars2Telemetry

    # decoder, level: f = (-az, -ax, ay + g), w = (-wz, -wx, wy)
    pc = PCars2Telemetry(k & 0xFF, 0.0, 3000, 8000, 0x63, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0),
                         (-wy, wz, -wx), (-fy, fz - g, -fx), (0.0, 0.0, 0.0, 0.0))  # fmt: skip
    return [pc.pack()]


def _f1(k: int, t_s: float, f: Sequence[float], w: Sequence[float]) -> list[bytes]:
    """Motion Ex and Motion of a level car (F1 24 layout, player car 0).

    Decoder: ``f = G0 (gForceLongitudinal + F_y, gForceLateral - R_y, gForceVertical +
    U_y)`` with ``F = (0, 0, 1)``, ``R = (-1, 0, 0)`` (level, heading 0: ``U_y = 1``), and
    ``w_iso = (w_z, w_x, w_y)`` of Motion Ex's local (left, up, forward) rates.
    """
    from ._f1 import CAR_MOTION, HEADER, MOTION_EX_CORE, MOTION_EX_SIZES, MOTION_SIZE

    g = G0_M_S2
    frame = k & 0xFFFFFFFF

    def header(packet_id: int) -> bytes:
        return HEADER.pack(_F1_FORMAT, 24, 1, 0, 1, packet_id, _F1_SESSION_UID, t_s, frame,
                           frame, 0, 255)  # fmt: skip

    ex = bytearray(MOTION_EX_SIZES[_F1_FORMAT])
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


@dataclass(frozen=True)
class SendSummary:
    """What :func:`send_recording` sent.

    Attributes
    ----------
    samples : int
        Samples sent.
    datagrams : int
        Datagrams sent.
    duration_s : float
        Recording time covered (s).
    late : int
        Samples sent more than one period after their time (a busy machine).
    stopped : bool
        True when ``stop()`` ended the run before the recording's end.
    """

    samples: int
    datagrams: int
    duration_s: float
    late: int
    stopped: bool


def send_recording(
    game: str,
    t_s: ArrayLike,
    f: ArrayLike,
    w: ArrayLike,
    host: str,
    port: int,
    *,
    stop: Callable[[], bool] | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> SendSummary:
    """Send every sample of a uniformly sampled recording on its own clock.

    Parameters
    ----------
    game : str
        One of :data:`ENCODABLE_GAMES`.
    t_s : (N,) array_like
        Sample times (s), strictly increasing.
    f, w : (N, 3) array_like
        Specific force (m/s^2) and angular velocity (rad/s), body frame.
    host, port : str, int
        UDP destination.
    stop : callable, optional
        Polled before each sample; True ends the run.
    progress : callable, optional
        ``progress(samples_sent, total)`` about once a second.

    Raises
    ------
    ConfigError
        Bad shapes, times or values.
    TransportError
        The socket cannot send.
    """
    t = np.asarray(t_s, dtype=float).reshape(-1)
    fa = np.asarray(f, dtype=float)
    wa = np.asarray(w, dtype=float)
    n = t.size
    if n < 1 or fa.shape != (n, 3) or wa.shape != (n, 3):
        raise ConfigError(f"t_s, f, w must have shapes (N,), (N, 3), (N, 3); got "
                          f"{t.shape}, {fa.shape}, {wa.shape}")  # fmt: skip
    if not (np.all(np.isfinite(t)) and np.all(np.diff(t) > 0)):
        raise ConfigError("t_s must be finite and strictly increasing")
    period = float(np.median(np.diff(t))) if n > 1 else 0.0
    sent = late = 0
    stopped = False
    try:
        sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET,
                             socket.SOCK_DGRAM)  # fmt: skip
    except OSError as exc:
        raise TransportError(f"cannot open a UDP socket: {exc}") from exc
    with sock:
        t0 = time.perf_counter()
        next_report = t0 + 1.0
        k = 0
        for k in range(n):
            if stop is not None and stop():
                stopped = True
                break
            due = t0 + (t[k] - t[0])
            left = due - time.perf_counter()
            if left > 0:
                time.sleep(left)
            elif period > 0 and -left > period:
                late += 1
            for data in encode_motion(game, k, float(t[k] - t[0]), fa[k], wa[k]):
                try:
                    sock.sendto(data, (host, port))
                except OSError as exc:
                    raise TransportError(f"udp://{host}:{port}: cannot send: {exc}") from exc
                sent += 1
            now = time.perf_counter()
            if progress is not None and now >= next_report:
                progress(k + 1, n)
                next_report = now + 1.0
        samples = k if stopped else n
    return SendSummary(samples, sent, float(t[max(samples - 1, 0)] - t[0]), late, stopped)
