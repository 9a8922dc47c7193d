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
    ``(N,)`` uint16 digital effect outputs (bits 0-15; the MBOX's ExtDout bits 16-23 and a
    second EasySmc unit's outputs are not carried by ride files).
``dacs``
    ``(N, 2)`` uint16 analogue outputs (controller units).
``digest``
    ASCII ``sha256:<64 hex digits>``: the SHA-256 of the content as written (see
    :func:`content_digest`), so that a ride changed after it was made is recognised.

Loading trusts nothing in the file: every archive member is parsed by hand (no pickles, only
plain numeric dtypes, sizes checked against the shapes before anything is allocated), the
header's keys and types are checked, and :class:`Ride` checks shapes, ranges and times. Any
damage becomes a :class:`~motioncue.ConfigError` naming the file. Whether the frames suit the
rig about to be driven is :func:`motioncue.pipeline.check_ride_for`'s job.

Integrity: :func:`load_ride` recomputes the digest and records the verdict in
:attr:`Ride.integrity` (``"intact"``, ``"edited"``: the content differs from what was
written, or ``"unsigned"``: no digest, an older motioncue's ride or one rewritten by another
program). What to do about it is the player's decision (``motioncue play`` refuses both unless
``--accept-edited``; :func:`motioncue.pipeline.check_ride_integrity`). The digest is no
signature: anyone can compute one; it catches rides changed by accident or by a script, not
by someone who means to deceive.

Writing is atomic (:mod:`motioncue._atomic`): a refused or interrupted save leaves no file.
"""

from __future__ import annotations

import hashlib
import io
import json
import math
import os
import re
import struct
import warnings
import zipfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any, BinaryIO, TypeVar

import numpy as np

from .._atomic import atomic_write_bytes, stop_signals_deferred
from .._config import read_capped
from .._errors import ConfigError, MotioncueError, one_line
from .._frozen import set_fields

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = [
    "INTEGRITY_STATES",
    "MAX_RIDE_BYTES",
    "MAX_RIDE_RATE_HZ",
    "MIN_RIDE_RATE_HZ",
    "RIDE_FORMAT",
    "RIDE_FORMAT_VERSION",
    "Ride",
    "content_digest",
    "load_ride",
    "save_ride",
]

RIDE_FORMAT = "motioncue-ride"
RIDE_FORMAT_VERSION = 1
MIN_RIDE_RATE_HZ = 1.0
"""Smallest ``rate_hz`` a ride may declare (the players' limiters take periods up to 1 s)."""
MAX_RIDE_RATE_HZ = 10_000.0
"""Largest ``rate_hz`` a ride may declare (no controller takes frames faster than 1 kHz;
each controller's own cap is checked by :func:`~motioncue.pipeline.check_ride_for`)."""
MAX_RIDE_DURATION_S = 0xFFFFFFFF / 1000.0
"""Last frame time allowed: the u32 millisecond time field of the MBOX/IMAX frames."""
MAX_RIDE_BYTES = 1 << 30
"""Largest ride file, and largest array in one, that :func:`load_ride` reads (1 GiB)."""
_MAX_HEADER_BYTES = 16 << 20
_ZIP_MAGIC = b"PK\x03\x04"
"""How every ride file (a zip with members) starts."""
_ARRAY_KINDS = {
    "header": "u", "t_s": "fiu", "pulses": "iu", "dout": "iu", "dacs": "iu", "digest": "u",
}  # fmt: skip
_ARRAY_NDIM = {"header": 1, "t_s": 1, "pulses": 2, "dout": 1, "dacs": 2, "digest": 1}
_DIGEST_PREFIX = "sha256:"
INTEGRITY_STATES = ("made", "intact", "edited", "unsigned")
"""Values of :attr:`Ride.integrity`: made in memory (not read from a file), read with a
matching digest, read with a digest that does not match, read without a digest."""


@dataclass(frozen=True, eq=False)
class Ride:
    """A ride: timed frames for one platform and controller.

    Attributes
    ----------
    platform, controller : str
        Names (or paths) of the platform and controller configs the frames were made for.
    rate_hz : float
        Nominal frame rate, in ``[MIN_RIDE_RATE_HZ, MAX_RIDE_RATE_HZ]``.
    actuator_names : tuple[str, ...]
        Controller axis order (at least one, non-empty strings).
    t_s : ndarray, shape (N,)
        Frame times (s), finite, strictly increasing, starting at exactly 0 and ending by
        ``MAX_RIDE_DURATION_S`` (u32 ms).
    pulses : ndarray, shape (N, n), int32
        Absolute motor positions (pulses).
    dout : ndarray, shape (N,), uint16
        Digital effect outputs (whole numbers in 0 .. 65535).
    dacs : ndarray, shape (N, 2), uint16
        Analogue outputs (whole numbers in 0 .. 65535).
    limits : dict
        The effective limits table in pulses (stroke, speed, acceleration per actuator).
    effects : tuple[str, ...]
        Names of the effect channels in use.
    source : str
        What the ride was made from.
    notes : dict
        Free-form metadata (cue metrics, optimisation report...).
    integrity : str
        Not a constructor argument: ``"made"`` for a ride built in memory;
        :func:`load_ride` sets ``"intact"``, ``"edited"`` or ``"unsigned"`` (see
        :data:`INTEGRITY_STATES`). ``dataclasses.replace`` gives ``"made"`` again.

    Raises
    ------
    ConfigError
        Any field of the wrong type, shape or range (named, with the value or shape).
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
        for name in ("platform", "controller", "source"):
            if not isinstance(getattr(self, name), str):
                raise ConfigError(
                    f"ride {name} = {getattr(self, name)!r} is invalid; allowed: a string"
                )
        names = self.actuator_names
        if (
            not isinstance(names, list | tuple)
            or not names
            or not all(isinstance(a, str) and a for a in names)
        ):
            raise ConfigError(
                f"ride actuator_names = {names!r} is invalid; allowed: one or more non-empty "
                "strings"
            )
        effects = self.effects
        if not isinstance(effects, list | tuple) or not all(isinstance(e, str) for e in effects):
            raise ConfigError(f"ride effects = {effects!r} is invalid; allowed: a list of strings")
        for name in ("limits", "notes"):
            if not isinstance(getattr(self, name), dict):
                raise ConfigError(
                    f"ride {name} = {getattr(self, name)!r} is invalid; allowed: a table (dict)"
                )
        rate = self.rate_hz
        if (
            isinstance(rate, bool)
            or not isinstance(rate, int | float | np.integer | np.floating)
            or not math.isfinite(float(rate))
            or not MIN_RIDE_RATE_HZ <= float(rate) <= MAX_RIDE_RATE_HZ
        ):
            raise ConfigError(
                f"ride rate_hz = {rate!r} is invalid; allowed: a number in "
                f"[{MIN_RIDE_RATE_HZ:g}, {MAX_RIDE_RATE_HZ:g}] Hz"
            )
        t = _numeric("t_s", self.t_s, "fiu")
        pulses = _numeric("pulses", self.pulses, "iu")
        dout = _numeric("dout", self.dout, "iu")
        dacs = _numeric("dacs", self.dacs, "iu")
        n_frames = t.shape[0] if t.ndim == 1 else -1
        n_axes = len(names)
        if t.ndim != 1 or n_frames < 1:
            raise ConfigError(f"ride t_s must be a non-empty 1-D array, got shape {t.shape}")
        t = t.astype(np.float64)
        if not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
            raise ConfigError("ride t_s must be finite and strictly increasing")
        if t[0] != 0.0 or t[-1] > MAX_RIDE_DURATION_S:
            raise ConfigError(
                f"ride t_s runs from {float(t[0])!r} to {float(t[-1])!r} s; allowed: from 0 to "
                f"at most {MAX_RIDE_DURATION_S:.0f} s (the u32 ms frame clock)"
            )
        if pulses.shape != (n_frames, n_axes):
            raise ConfigError(f"ride pulses shape {pulses.shape} != ({n_frames}, {n_axes})")
        i32 = np.iinfo(np.int32)
        if pulses.size and (pulses.min() < i32.min or pulses.max() > i32.max):
            raise ConfigError("ride pulses exceed the int32 range of the wire formats")
        if dout.shape != (n_frames,) or dacs.shape != (n_frames, 2):
            raise ConfigError(
                f"ride dout shape {dout.shape} / dacs shape {dacs.shape} do not match "
                f"{n_frames} frames"
            )
        for name, arr, top in (("dout", dout, 0xFFFF), ("dacs", dacs, 0xFFFF)):
            if arr.size and (arr.min() < 0 or arr.max() > top):
                raise ConfigError(
                    f"ride {name} outside 0..{top} (found {int(arr.min())}..{int(arr.max())})"
                )
        set_fields(
            self,
            rate_hz=float(rate),
            t_s=t,
            pulses=pulses.astype(np.int32),
            dout=dout.astype(np.uint16),
            dacs=dacs.astype(np.uint16),
            actuator_names=tuple(names),
            effects=tuple(effects),
        )

    @property
    def integrity(self) -> str:
        """``"made"``, ``"intact"``, ``"edited"`` or ``"unsigned"`` (:data:`INTEGRITY_STATES`).
        Not a field: no constructor argument, and ``dataclasses.replace`` gives ``"made"``."""
        return str(self.__dict__.get("_integrity", "made"))

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


def _numeric(name: str, value: ArrayLike, kinds: str) -> np.ndarray:
    """``value`` as an array of a plain numeric dtype of one of ``kinds`` (no bool, object,
    complex or structured data)."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ConfigError(f"ride {name} is not an array of numbers ({exc})") from exc
    if arr.dtype.kind not in kinds or arr.dtype.fields is not None:
        allowed = {"fiu": "real numbers", "iu": "integers", "u": "unsigned bytes"}[kinds]
        raise ConfigError(f"ride {name} has dtype {arr.dtype}; allowed: {allowed}")
    return arr


def content_digest(
    header: bytes, t_s: np.ndarray, pulses: np.ndarray, dout: np.ndarray, dacs: np.ndarray
) -> str:
    """``sha256:<hex>`` of a ride's content: the header member's bytes exactly as stored,
    then each array's shape and values in a fixed layout (little-endian float64 times, int32
    pulses, uint16 outputs, C order), each part preceded by its length. Independent of the
    archive's compression and of the arrays' stored dtypes (the values are what counts)."""
    h = hashlib.sha256(b"motioncue-ride-digest-1\0")
    parts: list[bytes] = [bytes(header)]
    for arr, dtype in ((t_s, "<f8"), (pulses, "<i4"), (dout, "<u2"), (dacs, "<u2")):
        a = np.ascontiguousarray(np.asarray(arr).astype(dtype, copy=False))
        parts.append(json.dumps(list(a.shape)).encode() + b"\0" + a.tobytes())
    for part in parts:
        h.update(len(part).to_bytes(8, "little"))
        h.update(part)
    return _DIGEST_PREFIX + h.hexdigest()


def ride_bytes(ride: Ride) -> bytes:
    """The bytes of a ride file for ``ride`` (what :func:`save_ride` writes), its content
    digest included.

    A stop signal during the encoding does not cut it where zipfile cannot recover (a handler
    raising with a member open made numpy's close raise ``ValueError`` over the
    interruption: a traceback, not "interrupted"). It is recorded
    (:func:`motioncue._atomic.stop_signals_deferred`), the encoding is abandoned before its
    next chunk of at most 16 MiB with the member and the archive closed normally, and the
    signal's handler runs then. One that only records (a park in progress) does not raise:
    the encoding is then done again, to the end.
    """
    header = json.dumps(ride.header(), indent=1, sort_keys=True, default=_json_default)
    header_bytes = header.encode("utf-8")
    digest = content_digest(header_bytes, ride.t_s, ride.pulses, ride.dout, ride.dacs)
    members = {
        "header": np.frombuffer(header_bytes, dtype=np.uint8),
        "t_s": ride.t_s,
        "pulses": ride.pulses,
        "dout": ride.dout,
        "dacs": ride.dacs,
        "digest": np.frombuffer(digest.encode("ascii"), dtype=np.uint8),
    }
    with stop_signals_deferred() as stops:
        try:
            return _npz_bytes(members, stops.event.is_set)
        except _Abandoned:
            pass  # the handler of the signal runs as the block ends
    with stop_signals_deferred():  # it did not raise: the whole archive, unchecked
        return _npz_bytes(members, lambda: False)


class _Abandoned(Exception):
    """A stop signal came while a ride was encoded: left between two chunks."""


class _StopCheckedMember:
    """A zip member open for writing, given to numpy's ``write_array`` (which writes a header,
    then chunks of at most 16 MiB): once ``should_stop()`` is true the next write raises
    :class:`_Abandoned`, an ordinary exception that leaves through ``with`` blocks closing
    the member and the archive."""

    def __init__(self, fid: IO[bytes], should_stop: Callable[[], bool]) -> None:
        self._fid = fid
        self._should_stop = should_stop

    def write(self, data: bytes) -> int:
        if self._should_stop():
            raise _Abandoned
        return self._fid.write(data)


def _npz_bytes(members: dict[str, np.ndarray], should_stop: Callable[[], bool]) -> bytes:
    """A compressed ``.npz`` of ``members``: what ``np.savez_compressed`` writes (the same
    zipfile calls and ``write_array``), with :class:`_StopCheckedMember` between them."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, mode="w", compression=zipfile.ZIP_DEFLATED, allowZip64=True) as zf:
        for key, value in members.items():
            with zf.open(key + ".npy", "w", force_zip64=True) as fid:
                np.lib.format.write_array(
                    _StopCheckedMember(fid, should_stop), np.asanyarray(value), allow_pickle=False
                )
    return buf.getvalue()


def save_ride(path: str | Path, ride: Ride) -> Path:
    """Write ``ride`` to ``path`` atomically (the name is kept as given, no suffix added).

    Raises
    ------
    TransportError
        The file cannot be written (nothing is left under ``path``).
    """
    return atomic_write_bytes(Path(path), ride_bytes(ride), "ride file")


def _json_default(obj: object) -> object:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")


def _read_source(
    source: str | os.PathLike[str] | bytes | BinaryIO, name: str | None
) -> tuple[bytes, str]:
    if isinstance(source, bytes | bytearray | memoryview):
        return bytes(source), name or "<ride bytes>"
    if isinstance(source, str | os.PathLike):
        path = Path(source)
        where = name or str(path)

        def check_head(head: bytes) -> None:
            if head != _ZIP_MAGIC:
                raise ConfigError(
                    f"{where}: not a motioncue ride file (not a zip archive: starts with "
                    f"{_short(head)})"
                )

        try:
            data = read_capped(
                path,
                MAX_RIDE_BYTES,
                "a ride file",
                where=where,
                check_head=check_head,
                head_size=len(_ZIP_MAGIC),
            )
        except OSError as exc:
            raise ConfigError(f"{where}: cannot read ride file: {exc}") from exc
    else:  # a binary stream (BytesIO has no name)
        where = name or str(getattr(source, "name", "<ride stream>"))
        try:
            data = source.read(MAX_RIDE_BYTES + 1)
        except OSError as exc:
            raise ConfigError(f"{where}: cannot read: {exc}") from exc
    if not isinstance(data, bytes):
        raise ConfigError(f"{where}: not a motioncue ride file (read {type(data).__name__})")
    if len(data) > MAX_RIDE_BYTES:  # a stream
        raise ConfigError(f"{where}: more than the {MAX_RIDE_BYTES} bytes a ride file may have")
    return data, where


_NPY_HEADER_LENGTH = {(1, 0): struct.Struct("<H"), (2, 0): struct.Struct("<I")}
_CANONICAL_NPY_HEADER = re.compile(
    rb"\{'descr': '[<>|=]?[a-zA-Z][0-9]{0,2}', 'fortran_order': (?:True|False), "
    rb"'shape': \((?:[0-9]{1,19}, ?)*[0-9]{0,19}\), \} *\n"
)
"""A ``.npy`` header as numpy writes it for a plain array (no escapes, nothing to filter):
the only kind whose parse :func:`_read_npy_header` keeps."""
_NPY_HEADERS: dict[bytes, tuple[tuple[int, ...], bool, np.dtype[Any]]] = {}
_NPY_HEADERS_MAX = 256


def _read_up_to(fp: IO[bytes], size: int) -> bytes:
    """Up to ``size`` bytes of ``fp``, read as numpy's ``.npy`` reader reads them (again until
    ``size`` bytes or an empty read), without its error on a short read."""
    data = b""
    while True:
        chunk = fp.read(size - len(data))
        data += chunk
        if not chunk or len(data) == size:
            return data


def _read_npy_header(
    fp: IO[bytes], version: tuple[int, int]
) -> tuple[tuple[int, ...], bool, np.dtype[Any]]:
    """``(shape, fortran_order, dtype)`` of the ``.npy`` header at ``fp`` (after the magic):
    numpy's own parser and its errors (``read_array_header_1_0`` / ``_2_0``), given the same
    bytes as it would read from ``fp``. A canonical header's parse is kept (at most
    :data:`_NPY_HEADERS_MAX`, then forgotten), so that the same header is not parsed twice:
    numpy parses it with Python's compiler (``ast.literal_eval``), most of a small ride's
    reading time.
    """
    length = _NPY_HEADER_LENGTH[version]
    raw = _read_up_to(fp, length.size)
    if len(raw) == length.size:
        raw += _read_up_to(fp, length.unpack(raw)[0])
    held = _NPY_HEADERS.get(raw)
    if held is not None:
        return held
    # numpy parses the header text with Python's literal parser, which warns on a
    # damaged header's stray backslash escapes ("invalid escape sequence"): a line on
    # the user's terminal before the refusal says why, so the warning is dropped
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        warnings.simplefilter("ignore", SyntaxWarning)
        if version == (1, 0):
            parsed = np.lib.format.read_array_header_1_0(io.BytesIO(raw))
        else:
            parsed = np.lib.format.read_array_header_2_0(io.BytesIO(raw))
    if len(raw) <= 512 and _CANONICAL_NPY_HEADER.fullmatch(raw, length.size):
        if len(_NPY_HEADERS) >= _NPY_HEADERS_MAX:
            _NPY_HEADERS.clear()
        _NPY_HEADERS[raw] = parsed
    return parsed


def _read_member(zf: zipfile.ZipFile, info: zipfile.ZipInfo, key: str, where: str) -> np.ndarray:
    """One ``.npy`` member, parsed by hand: version 1/2 header, plain dtype of the allowed
    kinds, sizes checked before reading."""
    if info.file_size > MAX_RIDE_BYTES:
        raise ConfigError(f"{where}: array {key!r} claims {info.file_size} bytes; too large")
    with zf.open(info) as fp:
        version = np.lib.format.read_magic(fp)
        if version not in ((1, 0), (2, 0)):
            raise ConfigError(
                f"{where}: array {key!r} has .npy version {version}; allowed 1.0, 2.0"
            )
        shape, fortran, dtype = _read_npy_header(fp, version)
        if (
            dtype.hasobject
            or dtype.fields is not None
            or dtype.subdtype is not None
            or dtype.kind not in _ARRAY_KINDS[key]
            or dtype.itemsize > 8
        ):
            raise ConfigError(f"{where}: array {key!r} has dtype {dtype}; not a ride array")
        if len(shape) != _ARRAY_NDIM[key]:
            raise ConfigError(
                f"{where}: array {key!r} has shape {shape}; expected {_ARRAY_NDIM[key]}-D"
            )
        count = math.prod(int(d) for d in shape)
        nbytes = count * dtype.itemsize
        if nbytes > MAX_RIDE_BYTES or (key == "header" and nbytes > _MAX_HEADER_BYTES):
            raise ConfigError(f"{where}: array {key!r} of shape {shape} is too large")
        raw = fp.read(nbytes)
        if len(raw) != nbytes:
            raise ConfigError(
                f"{where}: array {key!r} holds {len(raw)} bytes; its shape {shape} needs {nbytes}"
            )
    arr = np.frombuffer(raw, dtype=dtype, count=count)
    return arr.reshape(shape[::-1]).T if fortran else arr.reshape(shape)


def _read_arrays(data: bytes, where: str) -> dict[str, np.ndarray]:
    arrays: dict[str, np.ndarray] = {}
    key = "?"
    try:
        zf = zipfile.ZipFile(io.BytesIO(data))
        with zf:
            for info in zf.infolist():
                if not info.filename.endswith(".npy") or info.filename[:-4] not in _ARRAY_KINDS:
                    continue
                key = info.filename[:-4]
                arrays[key] = _read_member(zf, info, key, where)
    except MotioncueError:
        raise
    except Exception as exc:  # any damage of an untrusted archive is refused
        # zipfile, zlib and numpy's header parser raise many kinds (BadZipFile, zlib.error,
        # NotImplementedError for unknown compression, RuntimeError for encryption,
        # struct.error, OverflowError, EOFError, MemoryError, ...): all mean a damaged file
        what = "not a zip archive" if key == "?" and not arrays else f"damaged array {key!r}"
        # the message may quote the damaged bytes: one printable line, bounded
        detail = one_line(str(exc), 160)
        raise ConfigError(
            f"{where}: not a motioncue ride file ({what}: {type(exc).__name__}: {detail})"
        ) from exc
    return arrays


_T = TypeVar("_T")


def _header_value(
    header: Mapping[str, object],
    key: str,
    where: str,
    kind: type[_T] | tuple[type[_T], ...],
    default: object,
) -> _T:
    """``header[key]`` checked to be a ``kind`` (never a bool for another kind); ``default``
    when absent, :data:`_REQUIRED` to refuse its absence."""
    value = header.get(key, default)
    if value is _REQUIRED:
        raise ConfigError(f"{where}: ride header lacks {key!r}")
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        raise ConfigError(f"{where}: ride header {key} = {_short(value)} has the wrong type")
    return value


def _short(value: object) -> str:
    return one_line(repr(value), 80)


_REQUIRED = object()


def load_ride(
    source: str | os.PathLike[str] | bytes | BinaryIO, *, name: str | None = None
) -> Ride:
    """Read a ride file, refusing anything that is not a valid ride with a clear message.

    Parameters
    ----------
    source : path, bytes or binary file object
        The ride file, or its bytes.
    name : str, optional
        What to call the source in messages (default: the path).

    Raises
    ------
    ConfigError
        Unreadable or damaged file, another format, a newer version, a header key missing
        or of the wrong type, an array of the wrong dtype, shape or range; the message starts
        with the file's name. Nothing else escapes, whatever the bytes.
    """
    data, where = _read_source(source, name)
    arrays = _read_arrays(data, where)
    missing = {"header", "t_s", "pulses", "dout", "dacs"} - set(arrays)
    if missing:
        raise ConfigError(f"{where}: not a motioncue ride file (missing {sorted(missing)})")
    try:
        header = json.loads(arrays["header"].tobytes().decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError) as exc:
        raise ConfigError(f"{where}: ride header is not valid JSON ({exc})") from exc
    if not isinstance(header, dict):
        raise ConfigError(
            f"{where}: not a motioncue ride file (header is {type(header).__name__}, not a table)"
        )
    if header.get("format") != RIDE_FORMAT:
        raise ConfigError(
            f"{where}: not a motioncue ride file (format {_short(header.get('format'))})"
        )
    version = header.get("format_version")
    if isinstance(version, bool) or not isinstance(version, int) or version < 1:
        raise ConfigError(f"{where}: ride format_version {_short(version)} is invalid")
    if version > RIDE_FORMAT_VERSION:
        raise ConfigError(
            f"{where}: ride file format version {version} is newer than this motioncue "
            f"understands (up to {RIDE_FORMAT_VERSION}); upgrade motioncue to play it"
        )
    get = header.get
    n_frames = get("n_frames")
    if n_frames is not None and (
        isinstance(n_frames, bool)
        or not isinstance(n_frames, int)
        or n_frames != arrays["t_s"].shape[0]
    ):
        raise ConfigError(
            f"{where}: ride header n_frames = {_short(n_frames)} but t_s holds "
            f"{arrays['t_s'].shape[0]} frames"
        )
    try:
        ride = Ride(
            platform=_header_value(header, "platform", where, str, _REQUIRED),
            controller=_header_value(header, "controller", where, str, _REQUIRED),
            rate_hz=_header_value(header, "rate_hz", where, (int, float), _REQUIRED),
            actuator_names=tuple(_header_value(header, "actuator_names", where, list, _REQUIRED)),
            t_s=arrays["t_s"],
            pulses=arrays["pulses"],
            dout=arrays["dout"],
            dacs=arrays["dacs"],
            limits=_header_value(header, "limits", where, dict, {}),
            effects=tuple(_header_value(header, "effects", where, list, [])),
            source=_header_value(header, "source", where, str, ""),
            notes=_header_value(header, "notes", where, dict, {}),
        )
    except ConfigError as exc:
        if str(exc).startswith(where):
            raise
        raise ConfigError(f"{where}: {exc}") from exc
    set_fields(ride, _integrity=_integrity(arrays, ride))
    return ride


def _integrity(arrays: dict[str, np.ndarray], ride: Ride) -> str:
    """``"intact"``, ``"edited"`` or ``"unsigned"`` (see :data:`INTEGRITY_STATES`)."""
    stored = arrays.get("digest")
    if stored is None:
        return "unsigned"
    try:
        text = stored.tobytes().decode("ascii")
    except UnicodeDecodeError:
        return "edited"
    actual = content_digest(arrays["header"].tobytes(), ride.t_s, ride.pulses, ride.dout, ride.dacs)
    return "intact" if text == actual else "edited"
