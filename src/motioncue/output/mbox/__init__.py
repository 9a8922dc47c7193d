"""SC-MBOX motion-platform controller (Beijing Hollysys), Ethernet UDP.

Wire format (SC-MBOX manual chapter 4): 12-byte header (ConfirmCode 0x55AA, PassCode,
FunctionCode, ObjectChannel, WhoAccept, WhoReply) then the data, big-endian.

========================  ================================================================
message                   class
========================  ================================================================
0x1001 status report      :class:`StatusReport`
0x1101 read DX / FX       :class:`RegisterRead`, replies :class:`RegisterReadReply`,
                          :class:`RegisterError` (0x1103)
0x1201 write FXm/FX/CX    :class:`RegisterWrite`, replies :class:`RegisterWriteReply`,
                          :class:`RegisterError` (0x1203)
0x1301 / 0x1401 frames    :class:`MotionFrame`, replies :class:`MotionFrameReply`
                          (OK, buffer full, short frame)
========================  ================================================================

Contradictions in the manual and the decisions taken:

* 4.2.7 says the 6-axis frames use channel 0; its table and 4.2.9 say 1. Channel 1.
* 4.5.1 "reset": the text says ObjectChannel = 2 (CX), the printed data shows
  ``...1201 0000 FFFF...``. Wireshark marked the capture's UDP checksum 0x582d correct; it
  is correct only for channel 0x0002 (the printed bytes give 0x582f). The datagram sent
  was therefore ``55AA000012010002FFFFFFFF000000010000``: CX writes use channel 2, and the
  printed line is a typo (kept as a decoding test case: it decodes as an FXm write).
* 4.2.3 refers to "section 1.5.6" for the report parameters; they are Fn040-043 (5.6).
  Fn041's unit is not given: > 0 is read as seconds ("unit x1000"), < 0 as ms.
* Fn07E/07F: range -32768..32767 but default printed 0xffff: taken as -1.
* Fn00C's default is printed "100/300": 100 is used.
* Fn011's sentence mentions Fn010; Fn011 governs the DACs.
* The U-axis actual position in 6.1.1 spans three rows (0x21-0x23); U is taken at
  0x21/0x22 (low word first, as the note under Fn0D0 says for 32-bit values).
* The manual gives no error-code table, no frame reply during e-stop or homing, and no
  FIFO depth: see :mod:`motioncue.output.mbox._emulator` for the decisions.
"""

from . import _messages
from ._cli import inspect_decode, send_verb, split_stream, transport_options
from ._controller import MboxController, MboxFrameEncoder, controller_from_config
from ._emulator import MboxEmulator
from ._messages import *  # noqa: F403 - the message API is _messages.__all__
from ._params import FN_SPEC, fn_address, fn_name

__all__ = [
    "FN_SPEC",
    "MboxController",
    "MboxEmulator",
    "MboxFrameEncoder",
    "controller_from_config",
    "fn_address",
    "fn_name",
    "inspect_decode",
    "send_verb",
    "split_stream",
    "transport_options",
]
__all__ += _messages.__all__
