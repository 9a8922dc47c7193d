"""Interface-string controllers: the SimTools / FlyPT Mover output string of DIY boards.

Typical use::

    from motioncue.output import load_controller

    smc3 = load_controller("smc3")            # [A<Axis1a>][B<Axis2a>][C<Axis3a>], 10-bit
    enc = smc3.run_encoder(smc3.frame_rate_hz)
    enc.encode(0.0, [481, 481, 481])          # pulses 481 = value 512 (pulses_range -31..992)
    # -> [b"[ena][A\\x02\\x00][B\\x02\\x00][C\\x02\\x00]"]

See ``_format`` for the string syntax, ``_boards`` for the firmware parsers the emulator
uses, ``_controller`` for the send-clock rules (no time stamps, no buffer).
"""

from ._boards import FIRMWARES, BoardParser, board_parser
from ._controller import BITS_PER_BYTE, IfaceController, IfaceEncoder, controller_from_config
from ._emulator import IfaceEmulator
from ._format import ENCODINGS, FrameFormatter, InterfaceFormat, literal_bytes, parse_template

__all__ = [
    "BITS_PER_BYTE",
    "ENCODINGS",
    "FIRMWARES",
    "BoardParser",
    "FrameFormatter",
    "IfaceController",
    "IfaceEmulator",
    "IfaceEncoder",
    "InterfaceFormat",
    "board_parser",
    "controller_from_config",
    "literal_bytes",
    "parse_template",
]
