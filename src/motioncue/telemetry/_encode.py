"""Game packets from vehicle motion: the inverse of the decoders, for trying without a game.

:func:`encode_motion` turns one sample of vehicle motion (specific force ``f`` in m/s^2 and
angular velocity ``w`` in rad/s, ISO 8855 body axes, see :mod:`motioncue.telemetry`) into the
datagrams a game would send, in the layouts the decoders read: the encoder each game's
module registers with its decoder (:attr:`~motioncue.telemetry.GameInfo.encoder`). The car
or aircraft is kept level (zero attitude) and the whole specific force is carried by the
game's acceleration or g-force fields, so each decoder gives back ``f`` and ``w`` to the
precision of its float32 fields; the round trip is tested for every game
(``tests/test_new_user.py``).

Bundled encoders: ``f1`` (Motion Ex, then Motion, F1 24 layout), ``forza`` (Sled, 232 bytes),
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
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._errors import ConfigError, TransportError
from ._registry import GAMES, encodable_games

__all__ = ["SendSummary", "encode_motion", "send_recording"]


def __getattr__(name: str) -> tuple[str, ...]:
    # ENCODABLE_GAMES, the games encode_motion writes, follows the registry (a game
    # registered later, from a plugin, is in it)
    if name == "ENCODABLE_GAMES":
        return encodable_games()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
        A registered game with an encoder (:func:`~motioncue.telemetry._registry.
        encodable_games`).
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
    info = GAMES.get(game)
    if info is None or info.encoder is None:
        raise ConfigError(
            f"game {game!r} cannot be encoded; allowed: {', '.join(encodable_games())}"
        )
    if k < 0 or not math.isfinite(t_s):
        raise ConfigError(f"sample {k}, t = {t_s!r}: allowed k >= 0 and a finite time")
    return info.encoder(k, t_s, _vec(f, "f"), _vec(w, "w"))


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
        A registered game with an encoder (:func:`~motioncue.telemetry._registry.
        encodable_games`).
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
