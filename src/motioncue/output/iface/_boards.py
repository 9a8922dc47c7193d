"""Byte-stream parsers of the boards' firmware, written from each board's documented format.

They share no code with the encoder (``_format``): each reads a byte stream the way its
firmware does and yields complete target sets (one value per motor, in the board's motor
order). Bytes that do not fit are counted (``malformed``), never raised: a board's
firmware drops them and resynchronises.

=============  =====================================================================
firmware       what the board reads
=============  =====================================================================
``smc3``       SMC3 (Arduino, 3 motors): 5-byte commands ``'[' c1 c2 c3 ']'``; ``A``,
               ``B``, ``C`` carry motor 1-3's target as ``hi lo`` (10 bits); ``ena``
               enables the motors, ``sav`` saves the settings; one frame per ``C``
               (the last motor of the string).
``ehmsc4``     eh-msc-4dof: ``'P' '4'``, four 16-bit big-endian targets, ``'!' '!'``.
``odrive6``    ODrive hexapod bridge: ``'H'``, six targets as four upper-case hex
               digits each, ``'\\n'``.
``decimal6``   knaufinator's mini rig: six decimal targets separated by ``','``, the
               frame ended by ``'X'``.
=============  =====================================================================
"""

from __future__ import annotations

from collections import Counter

__all__ = ["FIRMWARES", "BoardParser", "board_parser"]


class BoardParser:
    """Base: ``feed(bytes)`` -> complete frames; ``malformed`` counts what was dropped."""

    n_motors: int = 0
    full_scale: int = 0

    def __init__(self) -> None:
        self.malformed = 0
        self.commands: Counter[str] = Counter()

    def feed(self, data: bytes) -> list[tuple[int, ...]]:  # pragma: no cover - abstract
        raise NotImplementedError


class Smc3Parser(BoardParser):
    """SMC3: ``[`` then exactly three bytes then ``]`` (binary bytes may equal ``[``)."""

    n_motors = 3
    full_scale = 1023

    def __init__(self) -> None:
        super().__init__()
        self._buf = bytearray()
        self._in = False
        self._targets = [512, 512, 512]
        self.enabled = False
        self.frames_done = 0
        self.command_log: list[tuple[str, int]] = []
        """Each command word other than a target, with the frames completed before it."""

    def feed(self, data: bytes) -> list[tuple[int, ...]]:
        out: list[tuple[int, ...]] = []
        for b in data:
            if not self._in:
                if b == 0x5B:  # '['
                    self._in = True
                    self._buf.clear()
                else:
                    self.malformed += 1
                continue
            if len(self._buf) < 3:
                self._buf.append(b)
                continue
            self._in = False
            if b != 0x5D:  # ']'
                self.malformed += 1
                continue
            cmd, hi, lo = self._buf
            if cmd in (0x41, 0x42, 0x43):  # 'A' 'B' 'C'
                value = (hi << 8) | lo
                if value > self.full_scale:
                    self.malformed += 1
                    continue
                self._targets[cmd - 0x41] = value
                if cmd == 0x43:
                    out.append(tuple(self._targets))
                    self.frames_done += 1
            else:
                word = bytes(self._buf).decode("latin-1")
                if word == "ena":
                    self.enabled = True
                self.commands[word] += 1
                self.command_log.append((word, self.frames_done))
        return out


class EhMsc4Parser(BoardParser):
    """eh-msc-4dof: ``P4`` + 8 bytes (four big-endian u16) + ``!!``."""

    n_motors = 4
    full_scale = 65535

    def __init__(self) -> None:
        super().__init__()
        self._state = 0  # 0 wait 'P', 1 wait '4', 2 data, 3 first '!', 4 second '!'
        self._buf = bytearray()

    def feed(self, data: bytes) -> list[tuple[int, ...]]:
        out: list[tuple[int, ...]] = []
        for b in data:
            s = self._state
            if s == 0:
                if b == 0x50:
                    self._state = 1
                else:
                    self.malformed += 1
            elif s == 1:
                if b == 0x34:
                    self._state = 2
                    self._buf.clear()
                else:
                    self.malformed += 1
                    self._state = 1 if b == 0x50 else 0
            elif s == 2:
                self._buf.append(b)
                if len(self._buf) == 8:
                    self._state = 3
            elif b == 0x21 and s == 3:
                self._state = 4
            elif b == 0x21 and s == 4:
                self._state = 0
                v = self._buf
                out.append(tuple(v[2 * i] * 256 + v[2 * i + 1] for i in range(4)))
            else:
                self.malformed += 1
                self._state = 1 if b == 0x50 else 0
        return out


_HEX = {c: i for i, c in enumerate(b"0123456789ABCDEF")}


class ODrive6Parser(BoardParser):
    """ODrive hexapod bridge: ``H`` + 24 upper-case hex digits + ``\\n``."""

    n_motors = 6
    full_scale = 65535

    def __init__(self) -> None:
        super().__init__()
        self._buf: bytearray | None = None

    def feed(self, data: bytes) -> list[tuple[int, ...]]:
        out: list[tuple[int, ...]] = []
        for b in data:
            if self._buf is None:
                if b == 0x48:  # 'H'
                    self._buf = bytearray()
                else:
                    self.malformed += 1
                continue
            if len(self._buf) < 24:
                if b in _HEX:
                    self._buf.append(b)
                else:
                    self.malformed += 1
                    self._buf = bytearray() if b == 0x48 else None
                continue
            digits = self._buf
            self._buf = None
            if b != 0x0A:
                self.malformed += 1
                if b == 0x48:
                    self._buf = bytearray()
                continue
            values = []
            for i in range(6):
                v = 0
                for c in digits[4 * i : 4 * i + 4]:
                    v = v * 16 + _HEX[c]
                values.append(v)
            out.append(tuple(values))
        return out


class Decimal6Parser(BoardParser):
    """knaufinator's rig: ``d,d,d,d,d,dX`` (decimal, 12-bit, no padding)."""

    n_motors = 6
    full_scale = 4095

    def __init__(self) -> None:
        super().__init__()
        self._values: list[int] = []
        self._cur: int | None = None
        self._bad = False

    def feed(self, data: bytes) -> list[tuple[int, ...]]:
        out: list[tuple[int, ...]] = []
        for b in data:
            if 0x30 <= b <= 0x39:
                self._cur = (0 if self._cur is None else self._cur) * 10 + (b - 0x30)
                if self._cur > 99999:
                    self._bad = True
                    self._cur = 0
            elif b == 0x2C or b == 0x58:  # ',' or 'X'
                if self._cur is None or self._cur > self.full_scale:
                    self._bad = True
                else:
                    self._values.append(self._cur)
                self._cur = None
                if b == 0x58:
                    if self._bad or len(self._values) != 6:
                        self.malformed += 1
                    else:
                        out.append(tuple(self._values))
                    self._values = []
                    self._bad = False
            else:
                self._bad = True
        return out


FIRMWARES: dict[str, type[BoardParser]] = {
    "smc3": Smc3Parser,
    "ehmsc4": EhMsc4Parser,
    "odrive6": ODrive6Parser,
    "decimal6": Decimal6Parser,
}


def board_parser(firmware: str) -> BoardParser:
    """A fresh parser of ``firmware`` (a key of :data:`FIRMWARES`)."""
    return FIRMWARES[firmware]()
