"""Game telemetry readers: UDP datagrams -> body-frame specific force and angular velocity.

Every reader converts its game's axes and units to the conventions of motioncue (ISO 8855
body frame, x forward, y left, z up; specific force ``f = a - g`` in m/s^2, ``(0, 0,
+9.80665)`` at rest; angular velocity in rad/s) and flags paused or menu states. Games:

* ``f1``: EA SPORTS F1 23 / 24 / 25 (Motion + Motion Ex, Session for pause), port 20777
* ``forza``: Forza Motorsport 7 / 2023 and Forza Horizon 4 / 5 / 6 Data Out, port 5301
* ``beamng``: BeamNG.drive MotionSim (``BNG1``), port 4444
* ``xplane`` / ``xplane11``: X-Plane 12 / 11 UDP ``DATA`` output (rows 4 and 16), port 49005
* ``dirt``: Codemasters ``extradata="3"`` UDP (DiRT Rally, DiRT Rally 2.0, DiRT 4...), 20777
* ``pcars2``: Project CARS 2 / 3 and Automobilista 2 UDP (Project CARS 2 protocol), 5606
* ``ac``: Assetto Corsa remote telemetry (asked at port 9996: ``ac@HOST``)
* ``gt7``: Gran Turismo 7 (heartbeat to the console's 33739: ``gt7@CONSOLE``), port 33740
* ``lfs``: Live for Speed OutSim (OutSim Opts 1ff, or the classic OutSimPack), port 4123
* ``wrc``: EA SPORTS WRC (motioncue's packet structure, tools/wrc), port 20790
* ``dcs``: DCS World (motioncue's export script, tools/dcs), port 20800
* ``rbr``: Richard Burns Rally (RSF / NGP UDP telemetry; signs unverified), port 6776

Typical use::

    from motioncue.telemetry import open_source
    src = open_source("f1")            # or "forza:5301", "replay:lap.mctr?speed=1"
    s = src.latest(max_age_s=0.25)     # TelemetrySample | None, never blocks
    src.close()

Decoders never raise on bad datagrams: truncated, foreign, non-finite or out-of-range
datagrams are counted by reason in ``decoder.stats`` and skipped. Raw datagrams can be
recorded (:func:`record`, ``motioncue record``) to a documented container and replayed.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from ._container import (
    DatagramRecording,
    RecordingWriter,
    RecordSummary,
    decode_recording,
    iter_recording_samples,
    read_recording_file,
    record,
)
from ._motion import is_datagram_recording, load_motion, samples_to_recording
from ._registry import GAMES, GameInfo, decoder_for, encodable_games, register_game
from ._sample import (
    G0_M_S2,
    Decoder,
    DecodeResult,
    SampleArrays,
    TelemetrySample,
    samples_to_arrays,
)
from ._source import ReplaySource, TelemetrySource, open_source

if TYPE_CHECKING:
    from ._drives import SampleDrive, sample_drive_manifest, sample_drives
    from ._recording import Recording, read_recording_csv, resample, write_recording_csv

__all__ = [
    "G0_M_S2",
    "GAMES",
    "DatagramRecording",
    "DecodeResult",
    "Decoder",
    "GameInfo",
    "RecordSummary",
    "Recording",
    "RecordingWriter",
    "ReplaySource",
    "SampleArrays",
    "SampleDrive",
    "TelemetrySample",
    "TelemetrySource",
    "decode_recording",
    "decoder_for",
    "encodable_games",
    "is_datagram_recording",
    "iter_recording_samples",
    "load_motion",
    "open_source",
    "read_recording_csv",
    "read_recording_file",
    "record",
    "register_game",
    "resample",
    "sample_drive_manifest",
    "sample_drives",
    "samples_to_arrays",
    "samples_to_recording",
    "write_recording_csv",
]

# The vehicle-motion CSV recordings (numpy-backed) load on first use, so that importing the
# telemetry readers for the live path stays light.
_LAZY = {"Recording", "read_recording_csv", "resample", "write_recording_csv"}
_LAZY_DRIVES = {"SampleDrive", "sample_drive_manifest", "sample_drives"}  # the bundled drives


def __getattr__(name: str) -> object:
    if name in _LAZY:
        from . import _recording

        return getattr(_recording, name)
    if name in _LAZY_DRIVES:
        from . import _drives

        return getattr(_drives, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# One module per game; each registers itself in GAMES on import.
_GAME_MODULES: tuple[str, ...] = ("_f1", "_forza", "_beamng", "_xplane", "_dirt", "_pcars2")
_GAME_MODULES += ("_ac",)  # Assetto Corsa
_GAME_MODULES += ("_gt7",)  # Gran Turismo 7
_GAME_MODULES += ("_lfs",)  # Live for Speed
_GAME_MODULES += ("_wrc",)  # EA SPORTS WRC
_GAME_MODULES += ("_dcs",)  # DCS World
_GAME_MODULES += ("_rbr",)  # Richard Burns Rally
for _name in _GAME_MODULES:
    importlib.import_module(f"{__name__}.{_name}")
del _name
