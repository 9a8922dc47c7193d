"""DCS World: what motioncue's export script (``tools/dcs/MotioncueExport.lua``) sends.

Format
------
DCS World runs ``Saved Games/DCS/Scripts/Export.lua`` and calls its hooks every frame
(``LuaExportAfterNextFrame``); the export functions are those listed in the ``Export.lua``
that ships in the game's ``Scripts`` folder and on the hoggitworld wiki ("DCS Export
Script"). motioncue's script sends one ASCII datagram per frame over LuaSocket::

    MCDCS1 <model time s> <ax> <ay> <az> <wx> <wy> <wz>

with ``LoGetModelTime()``, ``LoGetAccelerationUnits()`` (g) and ``LoGetAngularVelocity()``
(rad/s), both in the aircraft's body axes: x towards the nose, y up, z towards the right
wing (a right-handed frame). The g-loads are those of a g-meter: ``y`` is +1 in level
flight and on the ground at rest.

Axes and conversion
-------------------
ISO 8855 axes are ``forward = x``, ``left = -z``, ``up = y`` (a proper rotation)::

    f = G0 * (ax, -az, ay)        w = (wx, -wz, wy)

so a roll towards the right wing (``wx > 0``) is a positive ISO roll rate, a nose-up pitch
(``wz > 0``) a negative ISO pitch rate, a nose-left yaw (``wy > 0``) a positive ISO yaw rate.
The body rates come straight from the flight model: a loop or a roll through 90 deg of pitch
has no Euler-angle singularity to cross (SimHub issue #2242's spikes came from Euler angles).
These axis directions are those the export documentation gives; no captured DCS data was
available to pin them against real flight.

Pause: the model time stands still while the simulation is paused; a repeated model time
marks the sample ``paused``. Nothing is sent in menus or without an own aircraft (the
source sees missing packets).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ._registry import GameInfo, register_game
from ._sample import G0_M_S2, Decoder, DecodeResult

__all__ = ["MAGIC", "DCSDecoder", "DCSFrame"]

DEFAULT_PORT = 20800  # the port MotioncueExport.lua sends to
MAGIC = b"MCDCS1 "
MAX_SIZE = 200


@dataclass(frozen=True, slots=True)
class DCSFrame:
    """One datagram of the export script, in DCS units and body axes (x nose, y up, z right).

    Attributes
    ----------
    model_time_s : float
        ``LoGetModelTime()`` (s).
    acc_g : tuple of 3 float
        ``LoGetAccelerationUnits()`` (g).
    ang_vel_rad_s : tuple of 3 float
        ``LoGetAngularVelocity()`` (rad/s).
    """

    model_time_s: float
    acc_g: tuple[float, float, float]
    ang_vel_rad_s: tuple[float, float, float]

    def pack(self) -> bytes:
        """The datagram, formatted as the Lua script's ``string.format`` does."""
        a, w = self.acc_g, self.ang_vel_rad_s
        text = (f"MCDCS1 {self.model_time_s:.4f} {a[0]:.5f} {a[1]:.5f} {a[2]:.5f} "
                f"{w[0]:.5f} {w[1]:.5f} {w[2]:.5f}")  # fmt: skip
        return text.encode("ascii")

    @classmethod
    def unpack(cls, datagram: bytes) -> DCSFrame | None:
        """The frame, or None when the datagram is not a whole one."""
        if not datagram.startswith(MAGIC) or len(datagram) > MAX_SIZE:
            return None
        try:
            v = [float(x) for x in datagram[len(MAGIC) :].split()]
        except ValueError:
            return None
        if len(v) != 7:
            return None
        return cls(v[0], (v[1], v[2], v[3]), (v[4], v[5], v[6]))


class DCSDecoder(Decoder):
    """Decoder of ``MotioncueExport.lua`` datagrams.

    Outcome reasons: ``sample``, ``skipped: foreign`` (no ``MCDCS1`` prefix, not seven
    numbers, or longer than 200 bytes), ``skipped: non-finite``, ``skipped: out of range``.
    """

    game = "dcs"
    default_port = DEFAULT_PORT
    title = "DCS World (motioncue's export script, tools/dcs/MotioncueExport.lua)"

    def __init__(self) -> None:
        super().__init__()
        self._last_time = math.nan

    def reset(self) -> None:
        self._last_time = math.nan

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        frame = DCSFrame.unpack(datagram)
        if frame is None:
            return DecodeResult("skipped", "skipped: foreign")
        t_model = frame.model_time_s
        if not math.isfinite(t_model):
            return DecodeResult("skipped", "skipped: non-finite")
        paused = t_model == self._last_time
        self._last_time = t_model
        ax, ay, az = frame.acc_g
        wx, wy, wz = frame.ang_vel_rad_s
        g = G0_M_S2
        return self._make(t_s, (g * ax, -g * az, g * ay), (wx, -wz, wy), paused)


INFO = register_game(GameInfo.of(DCSDecoder))
