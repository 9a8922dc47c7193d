"""A toy game registered from outside the package, with its own trivial datagram.

Imported as a plugin (``MOTIONCUE_PLUGINS=toy_game``, this folder on ``sys.path``): the
whole game is this module, a decoder, an encoder and one
:func:`~motioncue.telemetry.register_game` call.

Datagram (32 bytes, little-endian): ``b"TOY1"``, then the vehicle's specific force
``fx, fy, fz`` (m/s^2) and angular velocity ``wx, wy, wz`` (rad/s) as float32, already in
ISO 8855 body axes, then a uint32 sample counter.
"""

from __future__ import annotations

import struct

from motioncue.telemetry import Decoder, DecodeResult, GameInfo, register_game

GAME = "toy"
PORT = 47999
MAGIC = b"TOY1"
LAYOUT = struct.Struct("<4s6fI")


class ToyDecoder(Decoder):
    """Reads the toy datagram; anything else is counted as foreign or the wrong size."""

    game = GAME

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        if datagram[:4] != MAGIC:
            return DecodeResult("skipped", "skipped: foreign")
        if len(datagram) != LAYOUT.size:
            return DecodeResult("skipped", "skipped: wrong size")
        _, fx, fy, fz, wx, wy, wz, _k = LAYOUT.unpack(datagram)
        return self._make(t_s, (fx, fy, fz), (wx, wy, wz), False)


def encode_toy(
    k: int, t_s: float, f: tuple[float, float, float], w: tuple[float, float, float]
) -> list[bytes]:
    """The one datagram of sample ``k``."""
    return [LAYOUT.pack(MAGIC, *f, *w, k & 0xFFFFFFFF)]


INFO = register_game(
    GameInfo(
        name=GAME,
        default_port=PORT,
        decoder=ToyDecoder,
        title="toy game: 6 float32 of motion in a 32-byte datagram",
        encoder=encode_toy,
    )
)
