"""motioncue.output: controller descriptions, wire formats, transports and emulators.

``load_controller(name)`` returns the frozen description of a bundled controller
(``imax3``, ``imax6``, ``mbox3``, ``mbox6``, ...); ``ctrl.run_encoder(rate_hz)`` turns motor
positions into timed frames; ``open_transport(url)`` opens ``udp://``, ``pcap:``,
``file:`` or ``serial://`` targets. The wire formats live in the kind subpackages
(:mod:`motioncue.output.imax`, :mod:`motioncue.output.mbox`, :mod:`motioncue.output.easysmc`),
each declared once in the kind registry (:func:`register_controller_kind`,
:class:`ControllerKind`): a new kind is one package and one registry call.
"""

from ._controller_api import Controller, DriveExpectations, FrameEncoder, PulseLimits
from ._controllers import load_controller
from ._registry import (
    ControllerKind,
    Emulator,
    EmulatorReadout,
    Inspection,
    Refusals,
    controller_kind,
    controller_kinds,
    register_controller_kind,
)
from ._transport import Transport, TransportURL, parse_target
from ._transports_file import FileTransport, PcapPacket, PcapTransport, read_pcap
from ._transports_open import open_transport
from ._transports_udp import UdpTransport
from ._udp_common import FrameClock
from ._udp_emulator import Trace, UdpEmulatorBase, Violation

__all__ = [
    "Controller",
    "ControllerKind",
    "DriveExpectations",
    "Emulator",
    "EmulatorReadout",
    "FileTransport",
    "FrameClock",
    "FrameEncoder",
    "Inspection",
    "PcapPacket",
    "PcapTransport",
    "PulseLimits",
    "Refusals",
    "Trace",
    "Transport",
    "TransportURL",
    "UdpEmulatorBase",
    "UdpTransport",
    "Violation",
    "controller_kind",
    "controller_kinds",
    "load_controller",
    "open_transport",
    "parse_target",
    "read_pcap",
    "register_controller_kind",
]
