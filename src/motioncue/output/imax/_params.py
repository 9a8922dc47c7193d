"""IMAX controller parameters PA00..PAff (IMAX manual 2.3.1): range and default.

Names are canonical ``PA`` + two lower-case hex digits (``PA80``, ``PAa0``, ``PA0f``); the
register address on channel 1 is the hex number. The manual prints no factory-default
column: defaults come from its examples where it gives one (noted ``ex``), otherwise they
are this package's choice (noted ``chosen``) and a real controller should be read.
"""

from __future__ import annotations

import re

from .._udp_common import HexNames

__all__ = ["PA_SPEC", "pa_address", "pa_name"]

# name: (lo, hi, default, meaning)
PA_SPEC: dict[str, tuple[int, int, int, str]] = {
    "PA00": (0, 12, 10, "work mode: CAN 10 standard, 11 effects, 12 test (chosen 10)"),
    "PA01": (0, 65535, 0, "custom firmware number (0 = general)"),
    "PA02": (1, 12, 6, "servo axes in use"),
    "PA03": (0, 12, 0, "rotary axis number (0 = none)"),
    "PA04": (0, 65535, 0, "input inversion bits"),
    "PA05": (0, 65535, 0, "output inversion bits"),
    "PA06": (0, 1, 0, "fast-forward when more than 2 frames are buffered"),
    "PA07": (0, 10000, 3000, "maximum speed, rpm (ex 5.2: 3000)"),
    "PA08": (0, 1, 0, "manual reset: 1 homes, then reads 0"),
    "PA09": (0, 65535, 0, "fixed frame period when frames carry no time, ms"),
    "PA0a": (0, 1, 0, "use PA09"),
    "PA0b": (0, 65535, 0, "largest frame interval, ms (0 = no limit)"),
    "PA0c": (0, 3, 1, "homing: 0 per axis, 1 torque, 3 X-input sensor"),
    "PA0d": (0, 65535, 0, "home after frames stop, ms (0 = never)"),
    "PA0e": (0, 1, 0, "DPF0 reset: 0 find zero, 1 return to zero position"),
    "PA0f": (0, 2, 0, "1 initialise parameters, 2 save"),
    "PA10": (0, 255, 192, "controller IP A (ex 5.1)"),
    "PA11": (0, 255, 168, "controller IP B"),
    "PA12": (0, 255, 15, "controller IP C"),
    "PA13": (0, 255, 201, "controller IP D"),
    "PA14": (0, 65535, 7408, "controller UDP port"),
    "PA15": (0, 1, 1, "UDP replies enabled (chosen 1; the LEKE example uses 0)"),
    **{f"PA{a:02x}": (0, 255, 0, "MAC address byte") for a in range(0x16, 0x1C)},
    "PA1e": (0, 65535, 0, "status report interval, ms (0 = on alarm)"),
    "PA1f": (0, 2, 0, "status reports: 0 off, 1 to PA20-24, 2 to PA25-29"),
    "PA20": (0, 255, 192, "host IP A (ex 5.1)"),
    "PA21": (0, 255, 168, "host IP B"),
    "PA22": (0, 255, 15, "host IP C"),
    "PA23": (0, 255, 101, "host IP D"),
    "PA24": (0, 65535, 8410, "host port (the host must send from it)"),
    "PA25": (0, 255, 0, "report IP 2 A"),
    "PA26": (0, 255, 0, "report IP 2 B"),
    "PA27": (0, 255, 0, "report IP 2 C"),
    "PA28": (0, 255, 0, "report IP 2 D"),
    "PA29": (0, 65535, 0, "report port 2"),
    **{
        f"PA{0x30 + i:02x}": (0, 300, 40, f"axis {i + 1} homing torque (5.4: 35..47)")
        for i in range(11)
    },
    "PA3b": (0, 65535, 0, "485 homing sensor"),
    "PA3c": (0, 4095, 0, "per-axis homing: bit = sensor"),
    "PA3d": (0, 65535, 0, "power-up delay, ms"),
    "PA3e": (0, 65535, 0, "485 homing turns"),
    "PA3f": (0, 65535, 0, "485 homing speed"),
    "PA40": (0, 65535, 100, "lift after homing, 0.1 mm (ex 5.5: 100)"),
    "PA41": (1, 65535, 50, "actuator screw lead, 0.1 mm (ex 5.5: 50)"),
    **{
        f"PA{0x42 + i:02x}": (0, 65535, 0, f"axis {i + 1} lift when PA40 = 0, 0.1 mm")
        for i in range(6)
    },
    "PA4c": (0, 65535, 0, "end-of-command delay"),
    "PA4d": (0, 65535, 0, "command smoothing time"),
    "PA54": (0, 1, 0, "encoder: 0 = 5000 lines, 1 = 2500 lines"),
    "PA55": (0, 9, 0, "motion scale: 0 = 100 %, n = n x 10 %"),
    "PA59": (0, 1000, 1, "minimum frame period, ms (chosen 1)"),
    "PA5f": (0, 2, 0, "CAN rate: 0 1M, 1 500k, 2 250k"),
    "PA60": (0, 1, 0, "analogue position mode"),
    "PA61": (1, 65535, 1, "analogue position ratio numerator"),
    "PA62": (1, 65535, 1, "analogue position ratio denominator"),
    **{
        f"PA{0x70 + i:02x}": (0, 10000, 100, f"axis {i + 1} safe speed, rpm (chosen 100)")
        for i in range(6)
    },
    **{
        f"PA{0x80 + i:02x}": (0, 10000, 0, f"axis {i + 1} maximum speed, rpm (0 = none)")
        for i in range(6)
    },
    "PA90": (0, 15, 0, "IO functions: bit0 e-stop, bit1 jog, bit3 emergency reset"),
    "PA91": (0, 2, 0, "e-stop: 0 hold then go on, 1 to zero then go on, 2 hold until reset"),
    "PA92": (0, 4095, 0, "e-stop inputs (all selected must be active)"),
    "PA93": (0, 65535, 10, "input filter, ms (chosen 10)"),
    "PA94": (0, 10000, 0, "speed limit when the e-stop is released"),
    "PA95": (0, 11, 0, "axis offset into the frame (two controllers, one frame)"),
    "PA96": (0, 4095, 0, "jog-forward inputs"),
    "PA97": (0, 4095, 0, "jog-back inputs"),
    "PA98": (0, 4095, 0, "emergency-reset inputs"),
    "PA9d": (0, 1, 0, "1: ignore PortOut of frames (outputs by DPF1 only)"),
    "PA9e": (0, 4095, 0, "manual output bits"),
    "PA9f": (0, 4095, 0, "initial output bits"),
    **{
        f"PA{0xA0 + i:02x}": (1, 3000, 2, f"axis {i + 1} acceleration factor (ex 5.10: 2)")
        for i in range(6)
    },
    **{
        f"PA{0xB0 + i:02x}": (1, 3000, 1500, f"axis {i + 1} acceleration (ex 5.10: 1500)")
        for i in range(6)
    },
    **{f"PA{0xC0 + i:02x}": (0, 12, 0, f"axis {i + 1} homing input") for i in range(6)},
    **{f"PA{0xC6 + i:02x}": (0, 3, 0, f"axis {i + 1} homing method") for i in range(6)},
    "PAcd": (0, 65535, 0, "reverse homing limit"),
    "PAce": (0, 65535, 0, "forward homing limit"),
    "PAcf": (0, 65535, 0, "homing method 3 move-out"),
}

_PA = HexNames(
    re.compile(r"^pa[ _]?([0-9a-f]{1,2})$", re.IGNORECASE),
    "PA{:02x}",
    "an IMAX parameter name (PAxx, hexadecimal)",
)
pa_name = _PA.name
"""Canonical name (``pa 80``, ``PAA0`` -> ``PA80``, ``PAa0``)."""
pa_address = _PA.address
"""Register address (channel 1) of a parameter name."""


DP_POS = (0x06, 0x08, 0x0A, 0x21, 0x23, 0x25)
"""DP registers of the axis positions, low word first, high word after it (2.3.3)."""
DP_RECEIVE, DP_USE = 0x48, 0x49
"""DP receive and use pointers of the frame buffer: their difference is its depth."""
