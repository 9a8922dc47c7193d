"""Codemasters "extradata" UDP telemetry: DiRT Rally, DiRT Rally 2.0, DiRT 4 and relatives.

The format is the motion-platform output of Codemasters' EGO-engine games, switched on in
``hardware_settings_config.xml`` (``<udp enabled="true" extradata="3" port="20777" .../>``).
With ``extradata="3"`` every datagram is 66 little-endian f32 (264 bytes); other extradata
levels are not read (the sizes differ and the rotation vectors are missing).

Layout
------
Field list of the community sheet the DiRT Rally tools cite ("DiRT Rally telemetry",
docs.google.com/spreadsheets/d/1UTgeE7vbnGIzDz-URRk2eBIPc_LR1vWcZklp7xD9N0Y, as used by
ErlerPhilipp/dr2_logger and soong-construction/dirt-rally-time-recorder); index = f32 slot::

     0 run time (s, game clock)        7 speed (m/s)
     4.. 6 position (world, m)         8..10 velocity (world, m/s)
    11..13 "roll vector"  (world)     14..16 "pitch vector" (world)
    17..20 suspension position RL, RR, FL, FR (mm)
    21..24 suspension velocity RL, RR, FL, FR (mm/s)
    25..28 wheel speed RL, RR, FL, FR (m/s)
    33 gear   34 g-force lateral (g)   35 g-force longitudinal (g)
    37 engine rate (rpm / 10)          63 max rpm (/ 10)    64 idle rpm (/ 10)

Axes and signs, pinned on a real DiRT Rally 2.0 capture
-------------------------------------------------------
The fixture ``tests/data/dirt/`` (from ErlerPhilipp/dr2_logger, see its README) settles what
the sheet leaves open; every statement below is checked again by ``tests/test_dirt.py``:

* the world is right-handed with y up; the "pitch vector" is the car's forward axis and the
  "roll vector" its **right** axis (unit, orthogonal): in corners the free-rolling front
  wheel on the +roll-vector side turns faster when the acceleration points to -roll-vector,
  i.e. it is the outer wheel; so the body axes of ISO 8855 are ``fwd = pitch vector``,
  ``left = -roll vector``, ``up = roll vector x pitch vector``;
* g-force longitudinal is ``a . fwd / G0`` and lateral is ``a . left / G0`` (a = the
  derivative of the world velocity; regression slopes 1.01 and -1.00 on the roll vector,
  correlations 0.97 and 0.99): kinematic accelerations, gravity excluded;
* suspension position grows as the spring compresses (outer side larger in corners), so
  suspension velocity is positive compressing.

Conversion
----------
``f = a_kin + G0 * up_in_body`` with ``a_kin = G0 * (g_lon, g_lat, a . up)`` and
``up_in_body = (fwd_y, -right_y, up_y)``. The game sends no vertical acceleration and no
angular velocity: both come from the previous datagram (backward differences over the game's
own clock, field 0): ``a . up`` from the world velocity, ``w`` from the rotation between the
two body frames (``w = log(B_prev^T B) / dt``, body axes). The first datagram, and any after
the game clock stood still, went back or jumped by more than :data:`MAX_GAP_S`, is
``partial``. The format has no pause flag: a paused game stops the clock (partial datagrams)
or the stream, and the source then reports the sample as paused by its age.
"""

from __future__ import annotations

import math
import struct

from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, wrong_size

__all__ = ["EXTRADATA3", "MAX_GAP_S", "DirtDecoder", "pack_extradata"]

DEFAULT_PORT = 20777  # the games' default in hardware_settings_config.xml

EXTRADATA3 = struct.Struct("<66f")
"""The ``extradata="3"`` datagram: 66 f32, 264 bytes."""

MAX_GAP_S = 0.25
"""Longest game-clock step over which accelerations and rates are differenced (s)."""

UNIT_TOL = 1e-2  # |v| and v.w tolerance on the rotation vectors (f32 rounding is 1e-7)

Mat = tuple[tuple[float, float, float], tuple[float, float, float], tuple[float, float, float]]


def pack_extradata(values: list[float] | tuple[float, ...]) -> bytes:
    """A 264-byte datagram from its 66 values (the fixture and tests use it)."""
    return EXTRADATA3.pack(*values)


def _cross(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float]:
    return (
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    )


def _dot(a: tuple[float, ...], b: tuple[float, ...]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def _rates(prev: Mat, cur: Mat, dt: float) -> tuple[float, float, float]:
    """Body angular velocity from two body frames (rows: fwd, left, up in world axes)."""
    # M = B_prev^T B_cur in body axes: M[i][j] = e_i(prev) . e_j(cur); only the trace and
    # the skew part are needed
    p0, p1, p2 = prev
    c0, c1, c2 = cur
    trace = _dot(p0, c0) + _dot(p1, c1) + _dot(p2, c2)
    c = max(-1.0, min(1.0, (trace - 1.0) / 2.0))
    theta = math.acos(c)
    k = (0.5 if theta < 1e-6 else theta / (2.0 * math.sin(theta))) / dt
    return (
        k * (_dot(p2, c1) - _dot(p1, c2)),
        k * (_dot(p0, c2) - _dot(p2, c0)),
        k * (_dot(p1, c0) - _dot(p0, c1)),
    )


class DirtDecoder(Decoder):
    """Decoder of the Codemasters ``extradata="3"`` datagrams (stateful: it differences).

    Outcome reasons: ``sample``, ``partial: no previous datagram`` (first datagram, or the
    game clock stood still, went back or jumped), ``skipped: truncated`` / ``skipped: wrong
    size`` (not 264 bytes), ``skipped: foreign`` (rotation vectors not orthonormal),
    ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "dirt"
    default_port = DEFAULT_PORT
    title = 'Codemasters extradata="3" UDP: DiRT Rally, DiRT Rally 2.0, DiRT 4 and relatives'

    def __init__(self) -> None:
        super().__init__()
        self._prev: tuple[float, tuple[float, float, float], Mat] | None = None

    def reset(self) -> None:
        self._prev = None

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        if n != EXTRADATA3.size:
            return wrong_size(n, EXTRADATA3.size)
        v = EXTRADATA3.unpack(datagram)
        # one finiteness test for the 16 fields used: a float64 sum of f32 values cannot
        # overflow, and a nan or inf anywhere makes it non-finite
        if not math.isfinite(sum(v[8:17]) + sum(v[21:25]) + v[0] + v[34] + v[35]):
            return DecodeResult("skipped", "skipped: non-finite")
        right = (v[11], v[12], v[13])
        fwd = (v[14], v[15], v[16])
        if (
            abs(_dot(right, right) - 1.0) > UNIT_TOL
            or abs(_dot(fwd, fwd) - 1.0) > UNIT_TOL
            or abs(_dot(right, fwd)) > UNIT_TOL
        ):
            return DecodeResult("skipped", "skipped: foreign")
        up = _cross(right, fwd)
        left = (-right[0], -right[1], -right[2])
        frame: Mat = (fwd, left, up)
        t_game = v[0]
        vel = (v[8], v[9], v[10])
        prev = self._prev
        self._prev = (t_game, vel, frame)
        if prev is None:
            return DecodeResult("partial", "partial: no previous datagram")
        dt = t_game - prev[0]
        if not 0.0 < dt <= MAX_GAP_S:
            return DecodeResult("partial", "partial: no previous datagram")
        pv = prev[1]
        a_world = ((vel[0] - pv[0]) / dt, (vel[1] - pv[1]) / dt, (vel[2] - pv[2]) / dt)
        a_up = _dot(a_world, up)
        f = (
            G0_M_S2 * (v[35] + fwd[1]),
            G0_M_S2 * (v[34] + left[1]),
            a_up + G0_M_S2 * up[1],
        )
        w = _rates(prev[2], frame, dt)
        gear = v[33]
        extras: dict[str, object] = {
            "rpm": 10.0 * v[37],
            "rpm_max": 10.0 * v[63],
            "gear": int(gear) if gear.is_integer() and 0 <= gear <= 12 else None,
            # FL, FR, RL, RR from the game's RL, RR, FL, FR (mm/s -> m/s)
            "suspension_velocity_m_s": (v[23] / 1e3, v[24] / 1e3, v[21] / 1e3, v[22] / 1e3),
        }
        return self._make(t_s, f, w, False, extras)


INFO = register_game(GameInfo.of(DirtDecoder))
