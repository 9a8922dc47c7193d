"""EA SPORTS WRC (2023) UDP telemetry: the JSON-described packet.

Format
------
EA's "How to use User Datagram Protocol (UDP) on PC" guide (answers.ea.com, November 2023)
and the files the game writes to ``Documents/My Games/WRC/telemetry``: ``config.json`` lists
the packets to send (structure, packet, ip, port, frequency), each *structure* file
(``udp/NAME.json``, EA's own in ``readme/udp/wrc.json``) lists the channels of each packet
in order, and ``readme/channels.json`` gives each channel's type and unit. A packet is the
channels' values back to back, little-endian, unpadded (``float32``, ``float64``, ``uint8``,
``uint16``, ``uint32``, ``uint64``, ``int16``, ``boolean`` = 1 byte, ``fourcc`` = 4 bytes).

motioncue ships its own structure, ``motioncue.json`` (:data:`MOTIONCUE_STRUCTURE`, the file
in ``tools/wrc/``), with the channels it reads; the user copies it to ``telemetry/udp/`` and
adds a ``session_update`` entry for it to ``config.json`` (docs/games/wrc.md). Any other
structure whose ``session_update`` packet holds the same channels can be read too
(:meth:`WRCDecoder.from_structure`).

Channels read: ``game_total_time`` (s), ``stage_current_time`` (s),
``vehicle_acceleration_x/y/z`` (m/s^2, world axes), ``vehicle_left_direction_*``,
``vehicle_forward_direction_*``, ``vehicle_up_direction_*`` (unit vectors, world axes),
``vehicle_engine_rpm_max`` / ``_current``, ``vehicle_gear_index`` (0 neutral, 10 reverse).

Axes and conversion
-------------------
The car's forward, left and up unit vectors are given in world axes, so the body components
of any world vector are its projections on them, whatever the world's handedness:
``f = (a' . F, a' . L, a' . U)`` with ``a' = a + G0 * up_world``. The acceleration is taken
as kinematic (gravity excluded) and the world's up axis as +y, as in the Codemasters EGO
games' telemetry (DiRT Rally 2.0, whose reader ``dirt`` is pinned on a real capture).

No angular velocity is sent; it follows from the change of the body axes between two
packets over the game clock (``game_total_time``): for a small rotation ``w dt``,
``w_x = (dL . U)/dt``, ``w_y = (dU . F)/dt``, ``w_z = (dF . L)/dt`` (the first packet, and
any after a gap over 0.1 s or a clock going backwards, only restarts it: ``partial``).

Pause: ``paused`` while ``stage_current_time`` does not advance (pause menu, before the
start, after the finish). No capture of this format was available to pin the signs on real
driving; ``motioncue record wrc`` makes one.
"""

from __future__ import annotations

import json
import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

from .._errors import ConfigError
from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult, wrong_size

__all__ = [
    "CHANNEL_TYPES",
    "MOTIONCUE_STRUCTURE",
    "WRCDecoder",
    "WRCLayout",
    "structure_json",
]

DEFAULT_PORT = 20790  # the port motioncue's config.json entry names (the game has none)

CHANNEL_TYPES: dict[str, str] = {
    "float32": "f", "float64": "d", "uint8": "B", "uint16": "H", "uint32": "I",
    "uint64": "Q", "int16": "h", "boolean": "?", "fourcc": "4s",
}  # fmt: skip
"""``channels.json`` type -> struct code."""

_VEC = ("vehicle_acceleration", "vehicle_left_direction", "vehicle_forward_direction",
        "vehicle_up_direction")  # fmt: skip
MOTIONCUE_STRUCTURE: tuple[tuple[str, str], ...] = (
    ("packet_uid", "uint64"),
    ("game_total_time", "float32"),
    ("game_delta_time", "float32"),
    ("stage_current_time", "float32"),
    ("vehicle_speed", "float32"),
    *((f"vehicle_velocity_{a}", "float32") for a in "xyz"),
    *((f"{v}_{a}", "float32") for v in _VEC for a in "xyz"),
    ("vehicle_engine_rpm_max", "float32"),
    ("vehicle_engine_rpm_current", "float32"),
    ("vehicle_gear_index", "uint8"),
)
"""motioncue's ``session_update`` packet: (channel, type) in order (93 bytes)."""

_NEEDED = ("game_total_time", "stage_current_time",
           *(f"{v}_{a}" for v in _VEC for a in "xyz"))  # fmt: skip
_OPTIONAL = ("vehicle_engine_rpm_max", "vehicle_engine_rpm_current", "vehicle_gear_index")
MAX_GAP_S = 0.1


def structure_json(name: str = "motioncue", port: int = DEFAULT_PORT) -> dict[str, object]:
    """motioncue's structure file (``udp/motioncue.json``) and the ``config.json`` entry
    that sends it: ``{"structure": {...}, "config_entry": {...}}``."""
    return {
        "structure": {
            "versions": {"schema": 1, "data": 3},
            "id": name,
            "header": {"channels": []},
            "packets": [{"id": "session_update",
                         "channels": [c for c, _t in MOTIONCUE_STRUCTURE]}],
        },
        "config_entry": {"structure": name, "packet": "session_update", "ip": "127.0.0.1",
                         "port": port, "frequencyHz": -1, "bEnabled": True},
    }  # fmt: skip


@dataclass(frozen=True)
class WRCLayout:
    """A packet layout: channel names in order, the struct reading them, name -> index."""

    channels: tuple[str, ...]
    packer: struct.Struct
    index: dict[str, int]

    @classmethod
    def from_channels(cls, channels: Sequence[tuple[str, str]]) -> WRCLayout:
        fmt = "<"
        for name, kind in channels:
            code = CHANNEL_TYPES.get(kind)
            if code is None:
                raise ConfigError(f"WRC channel {name!r} has type {kind!r}; known types: "
                                  f"{', '.join(sorted(CHANNEL_TYPES))}")  # fmt: skip
            fmt += code
        names = tuple(n for n, _k in channels)
        missing = [n for n in _NEEDED if n not in names]
        if missing:
            raise ConfigError(f"a WRC session_update packet for motion needs {missing}")
        return cls(names, struct.Struct(fmt), {n: i for i, n in enumerate(names)})

    def pack(self, values: dict[str, object]) -> bytes:
        """A packet with these channel values (missing ones 0)."""
        return self.packer.pack(*(values.get(n, 0) for n in self.channels))


class WRCDecoder(Decoder):
    """Decoder of EA SPORTS WRC ``session_update`` packets of a known structure.

    Parameters
    ----------
    channels : sequence of (name, type), optional
        The packet's channels in order; default :data:`MOTIONCUE_STRUCTURE`.

    Outcome reasons: ``sample``, ``partial`` (first packet or after a gap: the angular
    velocity restarts), ``skipped: truncated`` / ``skipped: wrong size`` (not the
    structure's size), ``skipped: foreign`` (direction vectors that are not unit vectors),
    ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "wrc"
    default_port = DEFAULT_PORT
    title = "EA SPORTS WRC UDP (motioncue's session_update structure, tools/wrc)"

    def __init__(self, channels: Sequence[tuple[str, str]] = MOTIONCUE_STRUCTURE) -> None:
        super().__init__()
        self.layout = WRCLayout.from_channels(channels)
        ix = self.layout.index
        self._time, self._stage = ix["game_total_time"], ix["stage_current_time"]
        self._vec = [ix[f"{v}_x"] for v in _VEC]
        self._opt = {n: ix.get(n) for n in _OPTIONAL}
        self._prev: tuple[float, float, tuple[float, ...]] | None = None

    @classmethod
    def from_structure(cls, structure: str | Path, channels: str | Path) -> WRCDecoder:
        """A decoder for the ``session_update`` packet of a structure file (``udp/X.json``),
        with the types of ``readme/channels.json``."""
        try:
            s = json.loads(Path(structure).read_text(encoding="utf-8"))
            c = json.loads(Path(channels).read_text(encoding="utf-8"))
            types = {ch["id"]: ch["type"] for ch in c["channels"]}
            names = list(s["header"]["channels"])
            names += next(p["channels"] for p in s["packets"] if p["id"] == "session_update")
        except (OSError, ValueError, KeyError, TypeError, StopIteration) as exc:
            raise ConfigError(f"{structure}, {channels}: not a WRC structure and channel "
                              f"list with a session_update packet ({exc})") from None  # fmt: skip
        unknown = [n for n in names if n not in types]
        if unknown:
            raise ConfigError(f"{structure}: channels {unknown} are not in {channels}")
        return cls([(n, types[n]) for n in names])

    def reset(self) -> None:
        self._prev = None

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        size = self.layout.packer.size
        n = len(datagram)
        if n != size:
            return wrong_size(n, size)
        v = self.layout.packer.unpack(datagram)
        ia, il, iff, iu = self._vec
        ax, ay, az = v[ia], v[ia + 1] + G0_M_S2, v[ia + 2]  # world up is +y
        axes = (v[iff], v[iff + 1], v[iff + 2], v[il], v[il + 1], v[il + 2],
                v[iu], v[iu + 1], v[iu + 2])  # fmt: skip
        fx_, fy_, fz_, lx, ly, lz, ux, uy, uz = axes
        for x, y, z in ((fx_, fy_, fz_), (lx, ly, lz), (ux, uy, uz)):
            norm = x * x + y * y + z * z
            if not math.isfinite(norm):
                return DecodeResult("skipped", "skipped: non-finite")
            if abs(norm - 1.0) > 0.01:
                return DecodeResult("skipped", "skipped: foreign")
        t_game, stage = float(v[self._time]), float(v[self._stage])
        prev, self._prev = self._prev, (t_game, stage, axes)
        if prev is None or not 0.0 < t_game - prev[0] <= MAX_GAP_S:
            return DecodeResult("partial", "partial")
        dt = t_game - prev[0]
        pf, pl, pu = prev[2][0:3], prev[2][3:6], prev[2][6:9]
        # w_x = dL . U, w_y = dU . F, w_z = dF . L (over dt)
        wx = ((lx - pl[0]) * ux + (ly - pl[1]) * uy + (lz - pl[2]) * uz) / dt
        wy = ((ux - pu[0]) * fx_ + (uy - pu[1]) * fy_ + (uz - pu[2]) * fz_) / dt
        wz = ((fx_ - pf[0]) * lx + (fy_ - pf[1]) * ly + (fz_ - pf[2]) * lz) / dt
        f = (ax * fx_ + ay * fy_ + az * fz_, ax * lx + ay * ly + az * lz,
             ax * ux + ay * uy + az * uz)  # fmt: skip
        extras: dict[str, object] = {}
        o = self._opt
        if o["vehicle_engine_rpm_current"] is not None:
            extras["rpm"] = v[o["vehicle_engine_rpm_current"]]
        if o["vehicle_engine_rpm_max"] is not None:
            extras["rpm_max"] = v[o["vehicle_engine_rpm_max"]]
        if o["vehicle_gear_index"] is not None:
            g = v[o["vehicle_gear_index"]]
            extras["gear"] = -1 if g == 10 else g
        return self._make(t_s, f, (wx, wy, wz), stage == prev[1], extras)


INFO = register_game(GameInfo.of(WRCDecoder))
