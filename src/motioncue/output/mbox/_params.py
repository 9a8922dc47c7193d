"""SC-MBOX configuration parameters Fn (manual chapter 5): range and factory default.

``FN_SPEC`` maps a name to ``(lo, hi, default, meaning)``, read from the data file
``params.toml`` beside this module; ``fn_name`` gives a name's canonical spelling
(``fn0c1``, ``Fn 0C1``, ``Fn_0C1`` -> ``Fn0C1``: ``Fn`` + three upper-case hex digits),
``fn_address`` its register address: that of ``FnXXX`` is ``0xXXX`` (the e-stop capture
of 4.5.2 writes ``Fn090`` at address 0x0090).
"""

from __future__ import annotations

from .._udp_common import ParameterTable

__all__ = ["FN_SPEC", "fn_address", "fn_name"]

FN = ParameterTable.load(__package__)
FN_SPEC, fn_name, fn_address = FN.spec, FN.names.name, FN.names.address

# Dn status registers (6.1.1, 6.1.11): 32-bit positions, low word first, per axis
DX_ACTUAL = (0x06, 0x08, 0x0A, 0x21, 0x24, 0x26)
"""Actual motor positions."""
DX_COMMAND = (0x0C, 0x0E, 0x10, 0x28, 0x2A, 0x2C)
"""Commanded motor positions."""
DX_UDP = (0x6A, 0x6C, 0x6E, 0x70, 0x72, 0x74)
"""Positions of the last UDP frame."""
DX_DEPTH = 0x4B
"""Frames waiting in the UDP buffer."""
