"""The EasySmc kind's registry entry: what ``motioncue.output`` can ask of it.

The EasySmc is a serial device: its emulator is a session of its own serving a
pseudo-terminal (``emulate`` without ``--listen``), not an emulator at a URL; its commands
are acknowledged on the serial line, not refused frame by frame on UDP.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._registry import ControllerKind, Inspection, for_type
from ._controller import EasySmcController, controller_from_config
from ._tools import inspect_decode, run_emulator, send_verb, split_stream

if TYPE_CHECKING:
    from pathlib import Path

__all__ = ["KIND", "SEND_WORDS"]

SEND_WORDS = ("estop", "reset", "home", "park", "outputs", "read", "write", "raw")


def _session(
    controller: EasySmcController, duration_s: float | None, trace_csv: Path | None
) -> int:
    return run_emulator(controller, duration_s, trace_csv=trace_csv)


KIND = ControllerKind(
    "easysmc",
    controller_from_config,
    title="EasySmc 2300",
    links=("serial", "pcap", "file"),
    emulator=None,
    emulator_schemes=(),
    emulator_session=for_type(EasySmcController, _session),
    send=for_type(EasySmcController, send_verb),
    send_words=SEND_WORDS,
    inspect=Inspection(split_stream, inspect_decode),
)
