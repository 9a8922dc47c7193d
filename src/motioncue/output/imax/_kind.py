"""The IMAX kind's registry entry: what ``motioncue.output`` can ask of it."""

from __future__ import annotations

from .._registry import Inspection, Refusals
from .._udp_cli import udp_controller_kind
from ._cli import inspect_decode, send_verb, split_stream, transport_options
from ._controller import ImaxController, controller_from_config
from ._emulator import ImaxEmulator

__all__ = ["KIND", "describe_refusal", "is_flow_control"]

BUFFER_OVERFLOW = 21  # Err21, buffer overflow (IMAX manual chapter 6)


def is_flow_control(function: int, channel: int) -> bool:
    """A refused frame (0x1x03) with error 21: the buffer was full, waiting cures it."""
    return function & 0xF == 3 and channel == BUFFER_OVERFLOW


def describe_refusal(function: int, channel: int) -> str:
    """0x1x03 error (the channel field carries the code), 0x1x04 e-stop, 0x1x05 command."""
    x = function & 0xF
    if x == 3:
        return f"error {channel}" + (" (buffer overflow)" if channel == BUFFER_OVERFLOW else "")
    return {4: "e-stop active", 5: "command error"}.get(x, "refused")


KIND = udp_controller_kind(
    "imax",
    "IMAX/SMC",
    ImaxController,
    controller_from_config,
    ImaxEmulator,
    send_verb,
    Inspection(split_stream, inspect_decode),
    transport_options,
    Refusals(is_flow_control, describe_refusal),
)
