"""SC-MBOX configuration parameters Fn (manual chapter 5): range and factory default.

The register address of ``FnXXX`` is ``0xXXX`` (the e-stop capture of 4.5.2 writes
``Fn090`` at address 0x0090). Names are canonical ``Fn`` + three upper-case hex digits.
"""

from __future__ import annotations

import re

from .._udp_common import HexNames

__all__ = ["FN_SPEC", "fn_address", "fn_name"]

# name: (lo, hi, factory default, meaning)
FN_SPEC: dict[str, tuple[int, int, int, str]] = {
    "Fn00A": (0, 1, 1, "stop on fault: 0 servo off, 1 hold position"),
    "Fn00B": (100, 10000, 500, "homing error band, pulses"),
    "Fn00C": (10, 1000, 100, "homing speed, rpm (manual: '100/300')"),
    "Fn00D": (-1, 10000, 500, "origin to over-travel distance, 100 pulses"),
    "Fn010": (0, 1, 1, "digital outputs taken from frames"),
    "Fn011": (0, 1, 1, "DACs taken from frames"),
    "Fn012": (-1, 10000, 1200, "playback speed, 1000 = real time; < 1000 automatic"),
    "Fn013": (10, 30000, 100, "jog move time (delta 0), ms"),
    "Fn014": (1, 300, 10, "rewind move time (negative delta), 0.1 s"),
    "Fn015": (0, 300, 30, "fast-forward threshold, 0.1 s (0 = off)"),
    "Fn016": (1, 300, 10, "fast-forward move time, 0.1 s"),
    "Fn017": (1, 300, 10, "e-stop execution time, 0.1 s"),
    "Fn018": (1, 300, 10, "e-stop release execution time, 0.1 s"),
    "Fn01C": (0, 1, 1, "1 FIFO playback, 0 latest frame only"),
    "Fn01D": (1, 30000, 100, "automatic playback speed: tolerated delay, ms"),
    "Fn01E": (1, 1000, 50, "automatic playback speed: K, 0.01"),
    "Fn01F": (0, 10000, 50, "automatic playback speed: T, ms"),
    "Fn020": (0, 255, 192, "MBOX IP A"),
    "Fn021": (0, 255, 168, "MBOX IP B"),
    "Fn022": (0, 255, 15, "MBOX IP C"),
    "Fn023": (0, 255, 201, "MBOX IP D"),
    "Fn024": (0, 32767, 7408, "MBOX send port"),
    "Fn025": (0, 32767, 7408, "MBOX receive port"),
    "Fn030": (0, 255, 192, "host IP A"),
    "Fn031": (0, 255, 168, "host IP B"),
    "Fn032": (0, 255, 15, "host IP C"),
    "Fn033": (0, 255, 101, "host IP D"),
    "Fn034": (0, 32767, 8410, "host send port"),
    "Fn035": (0, 32767, 8410, "host receive port"),
    "Fn040": (0, 2, 0, "status reports: 0 off, 1 periodic, 2 periodic while faulted"),
    "Fn041": (-30000, 30000, 3, "report interval: > 0 in s (x1000 ms), < 0 in ms"),
    "Fn042": (0, 255, 0, "report: first DX register"),
    "Fn043": (0, 32, 32, "report: number of DX registers"),
    "Fn051": (0, 15, 2, "Ethernet LED A mode"),
    "Fn052": (0, 15, 6, "Ethernet LED B mode"),
    "Fn053": (50, 10000, 100, "no-playback timeout, 4 ms"),
    "Fn061": (1, 1000, 500, "CAN baud, kbps"),
    "Fn069": (1, 192, 96, "MODBUS baud, 100 bps"),
    "Fn06A": (1, 255, 1, "MODBUS node"),
    "Fn078": (1, 32767, 10000, "DAC1 full scale"),
    "Fn079": (1, 32767, 10000, "DAC2 full scale"),
    "Fn07A": (-1, 256, 96, "DAC1 source"),
    "Fn07B": (-1, 256, 97, "DAC2 source"),
    "Fn07C": (-1000, 1000, 0, "DAC1 zero"),
    "Fn07D": (-1000, 1000, 0, "DAC2 zero"),
    "Fn07E": (-32768, 32767, -1, "DAC1 bit mask (manual default 0xffff)"),
    "Fn07F": (-32768, 32767, -1, "DAC2 bit mask (manual default 0xffff)"),
    "Fn080": (-1, 2, -1, "digital output mode"),
    **{f"Fn08{d}": (-32, 1, -1, f"DO{int(d, 16)} source") for d in "123456789ABC"},
    "Fn08D": (0, 4095, 0, "digital output inversion bits"),
    "Fn08E": (-32768, 32767, 0, "digital output initial value"),
    "Fn08F": (-32768, 32767, 0, "digital output safe value"),
    "Fn090": (-8, 1, 0, "e-stop: 0 off, 1 forced on, -n input n"),
    "Fn091": (-3, 2, 1, "e-stop method: 0 return to origin, 1 hold, 2 hold XYZ mean"),
    "Fn09D": (0, 255, 0, "digital input inversion bits"),
    "Fn0A0": (-1, 2, -1, "extended output mode"),
    **{f"Fn0A{d}": (-32, 1, -1, f"ExtDO{int(d, 16)} source") for d in "123456789ABC"},
    "Fn0AD": (0, 4095, 0, "extended output inversion bits"),
    "Fn0AE": (-32768, 32767, 0, "extended output initial value"),
    "Fn0AF": (-32768, 32767, 0, "extended output safe value"),
    "Fn0C0": (0, 30000, 0, "actuator stroke, 0.1 mm (0 = no limit)"),
    "Fn0C1": (1, 30000, 2000, "pulses per mm"),
    "Fn0C2": (1, 1000, 50, "lead per motor turn, 0.1 mm"),
    "Fn0C7": (1, 300, 50, "homing torque limit, %"),
    "Fn0CF": (0, 30000, 0, "continuous running limit, days (0 = none)"),
}

_FN = HexNames(
    re.compile(r"^fn[ _]?0?([0-9a-f]{1,3})$", re.IGNORECASE),
    "Fn{:03X}",
    "an MBOX parameter name (FnXXX, hexadecimal)",
)
fn_name = _FN.name
"""Canonical parameter name (``fn0c1``, ``Fn 0C1``, ``Fn_0C1`` -> ``Fn0C1``)."""
fn_address = _FN.address
"""Register address of an Fn parameter."""


# Dn status registers (6.1.1, 6.1.11): 32-bit positions, low word first, per axis
DX_ACTUAL = (0x06, 0x08, 0x0A, 0x21, 0x24, 0x26)
"""Actual motor positions."""
DX_COMMAND = (0x0C, 0x0E, 0x10, 0x28, 0x2A, 0x2C)
"""Commanded motor positions."""
DX_UDP = (0x6A, 0x6C, 0x6E, 0x70, 0x72, 0x74)
"""Positions of the last UDP frame."""
DX_DEPTH = 0x4B
"""Frames waiting in the UDP buffer."""
