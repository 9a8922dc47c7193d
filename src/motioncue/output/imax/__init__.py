"""IMAX / SMC multi-axis controller and drive-controller combo (Hangzhou Beijiafu),
Ethernet UDP.

Wire format (IMAX manual chapter 2): 12-byte header (ConfirmCode 0x55AA, or 0x33CC for
servo parameters and status reports; PassCode; FunctionCode; ObjectChannel; WhoAccept;
WhoReply) then the data, big-endian.

=============================  ==========================================================
message                        class
=============================  ==========================================================
0x1101 / 0x1201 registers      :class:`RegisterRead`, :class:`RegisterWrite`, replies
                               :class:`RegisterReply` (x = 2 OK, 3 error, 4 e-stop, 5)
0x1301 / 0x1401 frames         :class:`MotionFrame`, replies :class:`MotionFrameReply`
0x1801 / 0x1901 vibration      :class:`VibrationFrame`, :class:`VibrationFrameReply`
0x2101 / 0x2201 servo params   :class:`ServoRead`, :class:`ServoWrite`, :class:`ServoReply`
0x3101 status report           :class:`StatusReport`
=============================  ==========================================================

Contradictions in the manual and the decisions taken (more in ``_messages``):

* PortOut: 2 bytes in 0x1301, 4 in 0x1401, the replies and the vibration frames. The
  controller's ``port_out_bytes`` (2 or 4, default 2) chooses one width for all frames and
  replies; :func:`decode` without a width accepts either (the lengths differ).
* 0x1801's header row says "Relative Time", its data row "absolute time": absolute.
* 2.2.2.12's title says "absolute" for the 0x1902 reply: it is the relative one.
* 0x1401's channel row reads "2: x axes": read as "x: x axes" like 0x1301.
* The function table lists 0x1001 "report status" with no layout; 2.2.2.15 documents the
  report as 0x3101 (ConfirmCode 0x33CC). 0x3101 is implemented, 0x1001 is refused.
* The error-code table announced under 2.2.2.2 / 2.2.2.4 is missing.
* PA42: "axis 1 lift when PA40 = 0" in 2.3.1, "actuator maximum stroke" in 5.7; 5.5 lists
  the per-axis lifts as PA43..PA48 (shifted by one). The 2.3.1 table is followed
  (PA42..PA47 = axes 1..6); the stroke is the config's ``stroke_mm``, not a parameter.
* 5.2 says the CAN version needs PA00 = 0, its own table (and 2.3.1) say 10 = standard mode
  for CAN. 10 is used.
* PA98's example says "PA98 = 8" selects X01 and X02 (that is 3).
* Units of PA80..85 are not given; 5.2 and 5.10 use rpm (3000), so rpm. Command pulses per
  motor turn are taken as 4 x encoder lines (PA54: 20000 or 10000).
"""

from . import _messages
from ._cli import inspect_decode, send_verb, split_stream, transport_options
from ._controller import ImaxController, ImaxFrameEncoder, controller_from_config
from ._emulator import ImaxEmulator
from ._messages import *  # noqa: F403 - the message API is _messages.__all__
from ._params import PA_SPEC, pa_address, pa_name

__all__ = [
    "PA_SPEC",
    "ImaxController",
    "ImaxEmulator",
    "ImaxFrameEncoder",
    "controller_from_config",
    "inspect_decode",
    "pa_address",
    "pa_name",
    "send_verb",
    "split_stream",
    "transport_options",
]
__all__ += _messages.__all__
