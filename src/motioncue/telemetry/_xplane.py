"""X-Plane 11 / 12 UDP ``DATA`` output (Settings > Data Output, "Network via UDP").

Layout
------
From Laminar Research's "Exchanging Data with X-Plane" (the ``Instructions/X-Plane SPECS from
Austin/Exchanging Data with X-Plane.rtfd`` document shipped with the simulator) and the Data
Output screen's row labels. Little-endian::

    char[4] "DATA"     then one byte X-Plane uses internally (any value)
    N rows of 36 bytes:
        s32  index      # the row number ticked on the Data Output screen
        f32  value[8]   # -999.0 marks a slot the row does not use

Rows read here (value slots 0-based, as labelled on the Data Output screen):

* 4 "Mach, VVI, g-load": slot 4 ``Gload normal``, 5 ``Gload axial``, 6 ``Gload side`` (g);
* 16 "Angular velocities": X-Plane 11 sends ``Q, P, R`` in rad/s; X-Plane 12 sends
  ``P, Q, R`` in deg/s (the slot order and the unit changed with version 12);
* 37 "Engine RPM" (optional): slot 0, engine 1 (rev/min).

Rows 4 and 16 must both be ticked; a datagram without them is counted as
``skipped: missing rows``. Other rows are ignored.

Axes and signs
--------------
X-Plane's body rates are the aeronautical ones (``sim/flightmodel/position/P, Q, R``):
P roll rate positive right wing down, Q pitch rate positive nose up, R yaw rate positive nose
right (x forward, y right, z down). In ISO 8855 (x forward, y left, z up):
``w = (P, -Q, -R)``. The g-loads are the specific force in g along the body axes
(``sim/flightmodel/forces/g_nrml``, ``g_axil``, ``g_side``): normal is +1 in level flight and
on the ground at rest (gravity included), axial positive when the specific force points
forward (thrust), side positive to the right, so ``f = G0 * (axial, -side, normal)``. The
slot positions, the X-Plane 11/12 difference of row 16 and these signs are those of the
ArduPilot SITL X-Plane backend (``libraries/SITL/SIM_XPlane.cpp``: ``accel_body = (axial,
side, -normal) * g`` in its x-forward, y-right, z-down frame; ``gyro = (P, Q, R)``), which
flies real autopilots against X-Plane; no captured datagram was available to pin them.

X-Plane sends no pause flag in ``DATA`` rows; while paused it keeps sending the frozen values
(so the cue holds its last value and washes out), and a stopped stream is seen as missing
packets by the source.
"""

from __future__ import annotations

import math
import struct
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, Vec3

__all__ = [
    "ROW",
    "ROW_ANGULAR_VELOCITY",
    "ROW_ENGINE_RPM",
    "ROW_GLOAD",
    "UNUSED",
    "XPlaneDecoder",
    "pack_data",
    "unpack_data",
]

# X-Plane itself listens on 49000 and sends from 49001 (49002 was its FLIR port): a receiver
# on the same PC takes the next free one, the usual choice of autopilot bridges.
DEFAULT_PORT = 49005

HEADER = b"DATA"
ROW = struct.Struct("<i8f")
"""One DATA row: index, 8 values (36 bytes)."""

UNUSED = -999.0
"""X-Plane's marker for a slot the row does not use."""

ROW_GLOAD = 4
ROW_ANGULAR_VELOCITY = 16
ROW_ENGINE_RPM = 37

MAX_ROWS = 200  # X-Plane has about 140 rows; more in one datagram is not X-Plane


def pack_data(rows: Mapping[int, Sequence[float]], internal: int = 0x2A) -> bytes:
    """A DATA datagram with the given rows (index -> 8 values), in the order given."""
    out = bytearray(HEADER)
    out.append(internal & 0xFF)
    for index, values in rows.items():
        vals = list(values) + [UNUSED] * (8 - len(values))
        out += ROW.pack(index, *vals[:8])
    return bytes(out)


def unpack_data(datagram: bytes) -> dict[int, tuple[float, ...]] | None:
    """Rows of a DATA datagram (index -> 8 values; a repeated index keeps the last), or None
    when it is not a whole DATA datagram."""
    n = len(datagram)
    if n < 5 or datagram[:4] != HEADER or (n - 5) % ROW.size != 0:
        return None
    rows: dict[int, tuple[float, ...]] = {}
    for index, *values in ROW.iter_unpack(memoryview(datagram)[5:]):
        rows[index] = tuple(values)
    return rows


@dataclass(frozen=True, slots=True)
class _Version:
    name: str
    pqr_slots: tuple[int, int, int]
    rate_scale: float  # to rad/s


_VERSIONS = {
    11: _Version("X-Plane 11", (1, 0, 2), 1.0),
    12: _Version("X-Plane 12", (0, 1, 2), math.pi / 180.0),
}


class XPlaneDecoder(Decoder):
    """Decoder of X-Plane ``DATA`` datagrams (rows 4 and 16 required).

    Parameters
    ----------
    version : {11, 12}
        X-Plane major version: it fixes the slot order and unit of row 16.

    Outcome reasons: ``sample``, ``skipped: truncated`` (shorter than a header and one row),
    ``skipped: foreign`` (no ``DATA`` header, or not a whole number of rows, or more rows
    than X-Plane has), ``skipped: missing rows`` (row 4 or 16 not ticked),
    ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "xplane"

    def __init__(self, version: int = 12) -> None:
        super().__init__()
        if version not in _VERSIONS:
            raise ValueError(f"X-Plane version {version!r} is not supported; allowed: 11, 12")
        self.version = version
        if version == 11:
            self.game = "xplane11"
        self._v = _VERSIONS[version]

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        n = len(datagram)
        if n >= 4 and datagram[:4] != HEADER:
            return DecodeResult("skipped", "skipped: foreign")
        if n < 5 + ROW.size:
            return DecodeResult("skipped", "skipped: truncated")
        if (n - 5) % ROW.size != 0 or (n - 5) // ROW.size > MAX_ROWS:
            return DecodeResult("skipped", "skipped: foreign")
        rows = unpack_data(datagram)
        assert rows is not None
        g = rows.get(ROW_GLOAD)
        av = rows.get(ROW_ANGULAR_VELOCITY)
        if g is None or av is None:
            return DecodeResult("skipped", "skipped: missing rows")
        v = self._v
        p, q, r = (av[i] * v.rate_scale for i in v.pqr_slots)
        normal, axial, side = g[4], g[5], g[6]
        f = (G0_M_S2 * axial, -G0_M_S2 * side, G0_M_S2 * normal)
        w = (p, -q, -r)
        extras: dict[str, object] = {}
        rpm_row = rows.get(ROW_ENGINE_RPM)
        if rpm_row is not None and rpm_row[0] != UNUSED:
            extras["rpm"] = rpm_row[0]
        return self._make(t_s, f, w, False, extras or None)


def _xplane11() -> XPlaneDecoder:
    return XPlaneDecoder(11)


def _encoder(version: int) -> Callable[[int, float, Vec3, Vec3], list[bytes]]:
    """The DATA datagram (rows 4 and 16) of a level aircraft for X-Plane 12 or 11."""

    def encode(k: int, t_s: float, f: Vec3, w: Vec3) -> list[bytes]:
        # decoder: f = g (axial, -side, normal), w = (P, -Q, -R); X-Plane 12 row 16 holds
        # P, Q, R in deg/s, X-Plane 11 holds Q, P, R in rad/s
        fx, fy, fz = f
        p, q, r = w[0], -w[1], -w[2]
        rates = (q, p, r) if version == 11 else tuple(math.degrees(v) for v in (p, q, r))
        u = UNUSED
        g = G0_M_S2
        gload = (0.0, u, 0.0, u, fz / g, fx / g, -fy / g, u)
        return [pack_data({4: gload, 16: rates})]

    return encode


INFO, INFO_11 = (
    register_game(
        GameInfo(
            name=name,
            default_port=DEFAULT_PORT,
            decoder=decoder,
            encoder=_encoder(version),
            title=f"X-Plane {version} UDP DATA output (rows 4 g-load and 16 angular velocities)",
        )
    )
    for name, version, decoder in (("xplane", 12, XPlaneDecoder), ("xplane11", 11, _xplane11))
)
