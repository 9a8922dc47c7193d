"""The SC-MBOX kind's registry entry: what ``motioncue.output`` can ask of it."""

from __future__ import annotations

from .._registry import Inspection, Refusals
from .._udp_cli import udp_controller_kind
from ._cli import inspect_decode, send_verb, split_stream, transport_options
from ._controller import MboxController, controller_from_config
from ._emulator import MboxEmulator

__all__ = ["KIND", "describe_refusal", "is_flow_control"]


def is_flow_control(function: int, channel: int) -> bool:
    """0x1x03: the buffer was full, waiting cures it."""
    return function & 0xF == 3


def describe_refusal(function: int, channel: int) -> str:
    """0x1x03 buffer full, 0x1x04 frame shorter than required (manual 4.2.7)."""
    return {
        3: "buffer full",
        4: "frame shorter than required (a frame of the other axis mode: is the box in "
        "3- or 6-axis mode?)",
    }.get(function & 0xF, "refused")


KIND = udp_controller_kind(
    "mbox",
    "SC-MBOX",
    MboxController,
    controller_from_config,
    MboxEmulator,
    send_verb,
    Inspection(split_stream, inspect_decode),
    transport_options,
    Refusals(is_flow_control, describe_refusal),
)
