"""motioncue.output: controller descriptions, wire formats, transports and emulators.

``load_controller(name)`` returns the frozen description of a bundled controller
(``imax3``, ``imax6``, ``mbox3``, ``mbox6``, ...); ``ctrl.frame_encoder()`` turns motor
positions into timed frames; ``open_transport(url)`` opens ``udp://``, ``pcap:``,
``file:`` or ``serial://`` targets. The wire formats live in the kind subpackages
(:mod:`motioncue.output.imax`, :mod:`motioncue.output.mbox`).
"""

from ._controller_api import Controller, DriveExpectations, FrameEncoder, PulseLimits
from ._controllers import CONTROLLER_KINDS, load_controller
from ._transport import Transport, TransportURL, parse_target
from ._transports_file import FileTransport, PcapPacket, PcapTransport, read_pcap
from ._transports_open import open_transport
from ._transports_udp import UdpTransport
from ._udp_emulator import Trace, Violation

__all__ = [
    "CONTROLLER_KINDS",
    "Controller",
    "DriveExpectations",
    "FileTransport",
    "FrameEncoder",
    "PcapPacket",
    "PcapTransport",
    "PulseLimits",
    "Trace",
    "Transport",
    "TransportURL",
    "UdpTransport",
    "Violation",
    "load_controller",
    "open_transport",
    "parse_target",
    "read_pcap",
]
