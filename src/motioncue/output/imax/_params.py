"""IMAX controller parameters PA00..PAff (IMAX manual 2.3.1): range and default.

``PA_SPEC`` maps a name to ``(lo, hi, default, meaning)``, read from the data file
``params.toml`` beside this module (its header says where the defaults come from);
``pa_name`` gives a name's canonical spelling, ``pa_address`` its register address.
Names are canonical ``PA`` + two lower-case hex digits (``pa 80``, ``PAA0`` -> ``PA80``,
``PAa0``); the register address on channel 1 is the hex number.
"""

from __future__ import annotations

from .._udp_common import ParameterTable

__all__ = ["PA_SPEC", "pa_address", "pa_name"]

PA = ParameterTable.load(__package__)
PA_SPEC, pa_name, pa_address = PA.spec, PA.names.name, PA.names.address

DP_POS = (0x06, 0x08, 0x0A, 0x21, 0x23, 0x25)
"""DP registers of the axis positions, low word first, high word after it (2.3.3)."""
DP_RECEIVE, DP_USE = 0x48, 0x49
"""DP receive and use pointers of the frame buffer: their difference is its depth."""
