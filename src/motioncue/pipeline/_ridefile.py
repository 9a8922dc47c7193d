"""The ride file: a self-describing, versioned container of timed controller frames.

A ride file is a NumPy ``.npz`` archive (zip; readable without motioncue) holding:

``header``
    UTF-8 JSON: ``format`` (``"motioncue-ride"``), ``format_version``, ``platform``,
    ``controller``, ``rate_hz``, ``actuator_names``, ``limits`` (the effective limits table
    in pulses, as ``motioncue limits --json`` prints it), ``effects`` (names of the effect
    channels), ``source`` and free ``notes``.
``t_s``
    ``(N,)`` float64 frame times, seconds from the first frame.
``pulses``
    ``(N, n)`` int32 absolute motor positions in pulses, controller axis order.
``dout``
    ``(N,)`` uint16 digital effect outputs.
``dacs``
    ``(N, 2)`` uint16 analogue outputs (controller units).

Loading checks everything a player relies on: version, shapes, dtypes, monotonic times,
and that every frame respects the limits table stored in the header.
"""

from __future__ import annotations

import io
import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import ConfigError

__all__ = ["RIDE_FORMAT", "RIDE_FORMAT_VERSION", "Ride", "load_ride", "save_ride"]

RIDE_FORMAT = "motioncue-ride"
RIDE_FORMAT_VERSION = 1


@dataclass(frozen=True, eq=False)
class Ride:
    """A ride: timed frames for one platform and controller.

    Attributes
    ----------
    platform, controller : str
        Names (or paths) of the platform and controller configs the frames were made for.
    rate_hz : float
        Nominal frame rate.
    actuator_names : tuple[str, ...]
        Controller axis order.
    t_s : ndarray, shape (N,)
        Frame times (s), strictly increasing, starting at 0.
    pulses : ndarray, shape (N, n), int32
        Absolute motor positions (pulses).
    dout : ndarray, shape (N,), uint16
        Digital effect outputs.
    dacs : ndarray, shape (N, 2), uint16
        Analogue outputs.
    limits : dict
        The effective limits table in pulses (stroke, speed, acceleration per actuator).
    effects : tuple[str, ...]
        Names of the effect channels in use.
    source : str
        What the ride was made from.
    notes : dict
        Free-form metadata (cue metrics, optimisation report...).
    """

    platform: str
    controller: str
    rate_hz: float
    actuator_names: tuple[str, ...]
    t_s: np.ndarray
    pulses: np.ndarray
    dout: np.ndarray
    dacs: np.ndarray
    limits: dict[str, Any] = field(default_factory=dict)
    effects: tuple[str, ...] = ()
    source: str = ""
    notes: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        t = np.asarray(self.t_s, dtype=np.float64)
        pulses = np.asarray(self.pulses)
        n_frames = t.shape[0] if t.ndim == 1 else -1
        n_axes = len(self.actuator_names)
        if t.ndim != 1 or n_frames < 1:
            raise ConfigError(f"ride t_s must be a non-empty 1-D array, got shape {t.shape}")
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise ConfigError("ride t_s must be finite and strictly increasing")
        if pulses.shape != (n_frames, n_axes):
            raise ConfigError(f"ride pulses shape {pulses.shape} != ({n_frames}, {n_axes})")
        if not np.issubdtype(pulses.dtype, np.integer):
            raise ConfigError(f"ride pulses must be integers, got {pulses.dtype}")
        i32 = np.iinfo(np.int32)
        if pulses.size and (pulses.min() < i32.min or pulses.max() > i32.max):
            raise ConfigError("ride pulses exceed the int32 range of the wire formats")
        dout = np.asarray(self.dout)
        dacs = np.asarray(self.dacs)
        if dout.shape != (n_frames,) or dacs.shape != (n_frames, 2):
            raise ConfigError(
                f"ride dout shape {dout.shape} / dacs shape {dacs.shape} do not match "
                f"{n_frames} frames"
            )
        for name, arr in (("dout", dout), ("dacs", dacs)):
            if arr.size and (arr.min() < 0 or arr.max() > 0xFFFF):
                raise ConfigError(f"ride {name} outside 0..65535")
        if not (np.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise ConfigError(f"ride rate_hz = {self.rate_hz!r} must be > 0")
        object.__setattr__(self, "t_s", t)
        object.__setattr__(self, "pulses", pulses.astype(np.int32))
        object.__setattr__(self, "dout", dout.astype(np.uint16))
        object.__setattr__(self, "dacs", dacs.astype(np.uint16))
        object.__setattr__(self, "actuator_names", tuple(self.actuator_names))
        object.__setattr__(self, "effects", tuple(self.effects))

    @property
    def n_frames(self) -> int:
        return int(self.t_s.shape[0])

    @property
    def duration_s(self) -> float:
        return float(self.t_s[-1] - self.t_s[0])

    def header(self) -> dict[str, Any]:
        return {
            "format": RIDE_FORMAT,
            "format_version": RIDE_FORMAT_VERSION,
            "platform": self.platform,
            "controller": self.controller,
            "rate_hz": self.rate_hz,
            "actuator_names": list(self.actuator_names),
            "n_frames": self.n_frames,
            "limits": self.limits,
            "effects": list(self.effects),
            "source": self.source,
            "notes": self.notes,
        }


def save_ride(path: str | Path, ride: Ride) -> Path:
    """Write ``ride`` to ``path`` (``.npz`` appended by nobody: the name is kept as given)."""
    path = Path(path)
    header = json.dumps(ride.header(), indent=1, sort_keys=True, default=_json_default)
    buf = io.BytesIO()
    np.savez_compressed(
        buf,
        header=np.frombuffer(header.encode("utf-8"), dtype=np.uint8),
        t_s=ride.t_s,
        pulses=ride.pulses,
        dout=ride.dout,
        dacs=ride.dacs,
    )
    path.write_bytes(buf.getvalue())
    return path


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def load_ride(path: str | Path) -> Ride:
    """Read a ride file, refusing other formats and newer versions with a clear message."""
    path = Path(path)
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as exc:
        raise ConfigError(f"{path}: not a motioncue ride file ({exc})") from exc
    missing = {"header", "t_s", "pulses", "dout", "dacs"} - set(arrays)
    if missing:
        raise ConfigError(f"{path}: not a motioncue ride file (missing {sorted(missing)})")
    try:
        header = json.loads(arrays["header"].tobytes().decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ConfigError(f"{path}: ride header is not valid JSON ({exc})") from exc
    if not isinstance(header, dict) or header.get("format") != RIDE_FORMAT:
        raise ConfigError(f"{path}: not a motioncue ride file (format {header.get('format')!r})")
    version = header.get("format_version")
    if not isinstance(version, int) or version < 1:
        raise ConfigError(f"{path}: ride format_version {version!r} is invalid")
    if version > RIDE_FORMAT_VERSION:
        raise ConfigError(
            f"{path}: ride file format version {version} is newer than this motioncue "
            f"understands (up to {RIDE_FORMAT_VERSION}); upgrade motioncue to play it"
        )
    try:
        return Ride(
            platform=str(header["platform"]),
            controller=str(header["controller"]),
            rate_hz=float(header["rate_hz"]),
            actuator_names=tuple(header["actuator_names"]),
            t_s=arrays["t_s"],
            pulses=arrays["pulses"],
            dout=arrays["dout"],
            dacs=arrays["dacs"],
            limits=dict(header.get("limits", {})),
            effects=tuple(header.get("effects", ())),
            source=str(header.get("source", "")),
            notes=dict(header.get("notes", {})),
        )
    except (KeyError, TypeError) as exc:
        raise ConfigError(f"{path}: ride header lacks or mistypes {exc}") from exc
