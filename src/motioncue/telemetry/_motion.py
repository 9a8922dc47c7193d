"""Vehicle-motion files for offline commands: a recording CSV or a raw datagram recording.

:func:`load_motion` lets every command that takes a recording CSV (``t, fx..wz``) also take a
file written by ``motioncue record``: the datagrams are decoded with the game's decoder and
their receive times, and become the same :class:`~motioncue.telemetry.Recording`.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

from .._errors import ConfigError, TransportError
from ._container import MAGIC, decode_recording
from ._sample import TelemetrySample, samples_to_arrays

if TYPE_CHECKING:
    from ._recording import Recording

__all__ = ["is_datagram_recording", "load_motion", "samples_to_recording"]


def is_datagram_recording(path: str | os.PathLike[str]) -> bool:
    """True if the file starts with the datagram-recording magic (see ``_container``)."""
    try:
        with open(path, "rb") as fh:
            return fh.read(len(MAGIC)) == MAGIC
    except OSError as exc:
        raise TransportError(f"cannot read {os.fspath(path)!r}: {exc}") from exc


def samples_to_recording(
    samples: Sequence[TelemetrySample], *, include_paused: bool = False
) -> Recording:
    """Telemetry samples as a :class:`Recording` (time relative to the first kept sample).

    Parameters
    ----------
    samples : sequence of TelemetrySample
        In time order.
    include_paused : bool
        Keep samples flagged ``paused`` (menus, pause screens); dropped by default so a ride
        made from a session does not cue the menus.
    """
    from ._recording import Recording

    kept = [s for s in samples if include_paused or not s.paused]
    a = samples_to_arrays(kept)
    t0 = a.t_s[0] if len(kept) else 0.0
    return Recording(a.t_s - t0, a.f, a.w)


def load_motion(path: str | os.PathLike[str], *, include_paused: bool = False) -> Recording:
    """Read vehicle motion from a recording CSV or a ``motioncue record`` file.

    Raises
    ------
    ConfigError
        A CSV with missing columns or bad numbers, or a datagram recording without a single
        decodable sample (its decoder counters are named in the message).
    ProtocolError
        A corrupt datagram recording.
    TransportError
        The file cannot be read.
    """
    if is_datagram_recording(path):
        samples, stats = decode_recording(path)
        rec = samples_to_recording(samples, include_paused=include_paused)
        if len(rec) == 0:
            counts = ", ".join(f"{k}: {v}" for k, v in sorted(stats.items())) or "empty"
            raise ConfigError(f"{os.fspath(path)}: no usable motion samples ({counts})")
        return rec
    from ._recording import read_recording_csv

    return read_recording_csv(os.fspath(path))
