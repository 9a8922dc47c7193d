"""EasySmc 2300 step/servo pulse controller (Xiamen Hualing): wire formats, timed frames,
flow-controlled serial streaming, USB DLL adapter and an emulator.

Typical use::

    from motioncue.output._controllers import load_controller
    from motioncue.output._transport_serial import open_serial
    from motioncue.output.easysmc import EasySmcLink, EasySmcStreamer, send_commands

    ctrl = load_controller("easysmc")                   # XYZ, 19200 baud, address 00
    link = EasySmcLink(open_serial("serial:///dev/ttyUSB0?baud=19200"))
    streamer = EasySmcStreamer.for_controller(ctrl, link, frame_rate_hz=20)
    streamer.send_all(ctrl.setup_commands() + send_commands(ctrl, ["home"]))
    streamer.stream(ctrl.frame_encoder(20), frames)    # frames: (t_s, pulses) pairs
    streamer.drain(timeout_s=5)

Each frame becomes a speed command and a relative interpolated move (start condition 4)
lasting one frame period; ``ctrl.max_frame_rate_hz`` is what the serial link carries.
See ``MANUAL_DECISIONS`` for every place the manual contradicts itself and the decision
taken.
"""

from ._controller import (
    BAUD_RATES,
    PARAMETERS,
    EasySmcController,
    EasySmcFrameEncoder,
    LinkBudget,
    Unit,
    controller_from_config,
)
from ._emulator import (
    BUFFER_DEPTH,
    ControllerModel,
    EasySmcEmulator,
    FrameLimits,
    TraceEntry,
    Violation,
    frame_limits,
)
from ._link import EasySmcLink, EasySmcStreamer, StreamStats
from ._profile import feed_for_duration, max_distance, move_duration_s, move_progress
from ._protocol import (
    COMMANDS,
    MANUAL_DECISIONS,
    Command,
    CommandSpec,
    ErrorCode,
    ErrorReply,
    ExecStatus,
    ReadReply,
    Start,
    UsbReadReply,
    UsbReadRequest,
    UsbWriteReply,
    WordKind,
    WriteReply,
    checksum,
    decode_command,
    decode_reply,
    decode_usb_read_reply,
    decode_usb_write,
    decode_usb_write_reply,
    encode_command,
    encode_reply,
    encode_usb_read_reply,
    encode_usb_write,
    encode_usb_write_reply,
    serial_frame_size,
    signed_from_word,
    split_serial_frames,
    word_from_signed,
)
from ._tools import (
    SEND_USAGE,
    emulator,
    inspect_bytes,
    inspect_decode,
    run_emulator,
    run_send,
    send_commands,
    send_verb,
    split_stream,
)
from ._usb import UsbCommandLink, UsbDllLink, usb_read_request

__all__ = [
    "BAUD_RATES",
    "BUFFER_DEPTH",
    "COMMANDS",
    "MANUAL_DECISIONS",
    "PARAMETERS",
    "SEND_USAGE",
    "Command",
    "CommandSpec",
    "ControllerModel",
    "EasySmcController",
    "EasySmcEmulator",
    "EasySmcFrameEncoder",
    "EasySmcLink",
    "EasySmcStreamer",
    "ErrorCode",
    "ErrorReply",
    "ExecStatus",
    "FrameLimits",
    "LinkBudget",
    "ReadReply",
    "Start",
    "StreamStats",
    "TraceEntry",
    "Unit",
    "UsbCommandLink",
    "UsbDllLink",
    "UsbReadReply",
    "UsbReadRequest",
    "UsbWriteReply",
    "Violation",
    "WordKind",
    "WriteReply",
    "checksum",
    "controller_from_config",
    "decode_command",
    "decode_reply",
    "decode_usb_read_reply",
    "decode_usb_write",
    "decode_usb_write_reply",
    "emulator",
    "encode_command",
    "encode_reply",
    "encode_usb_read_reply",
    "encode_usb_write",
    "encode_usb_write_reply",
    "feed_for_duration",
    "frame_limits",
    "inspect_bytes",
    "inspect_decode",
    "max_distance",
    "move_duration_s",
    "move_progress",
    "run_emulator",
    "run_send",
    "send_commands",
    "send_verb",
    "serial_frame_size",
    "signed_from_word",
    "split_serial_frames",
    "split_stream",
    "usb_read_request",
    "word_from_signed",
]
