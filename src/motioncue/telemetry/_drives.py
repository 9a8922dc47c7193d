"""The bundled sample drives and the set each belongs to (``configs/recordings/drives.toml``).

Sets: ``tuning`` (presets may be tuned on these), ``held-out`` (never tuned on: cue quality
is judged there) and ``demo`` (the bundled lap of ``motioncue demo``, never tuned on either).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .._errors import ConfigError

__all__ = ["DRIVE_SETS", "SampleDrive", "sample_drive_manifest", "sample_drives"]

DRIVE_SETS: tuple[str, ...] = ("tuning", "held-out", "demo")
"""The sets a bundled drive can belong to."""

_KINDS = ("car", "aircraft")
_MANIFEST = "drives.toml"


@dataclass(frozen=True)
class SampleDrive:
    """One bundled drive.

    Attributes
    ----------
    path : Path
        The recording CSV (``t, fx, fy, fz, wx, wy, wz, speed``; 100 Hz).
    set : str
        ``tuning``, ``held-out`` or ``demo``.
    kind : str
        ``car`` or ``aircraft``.
    description : str
    command : str
        The command (run from the repository root) that writes the file.
    """

    path: Path
    set: str
    kind: str
    description: str
    command: str

    @property
    def name(self) -> str:
        """The file's stem (``chicane-gt``)."""
        return self.path.stem


def sample_drive_manifest(
    folder: str | Path | None = None, manifest: str | Path | None = None
) -> list[SampleDrive]:
    """Every drive of the manifest, in its order.

    Parameters
    ----------
    folder : path, optional
        Folder holding the CSVs (and ``drives.toml``); default the bundled
        ``configs/recordings``.
    manifest : path, optional
        The manifest to read; default ``drives.toml`` in ``folder``. The bundled
        ``configs/recordings/generated.toml`` lists drives that are not bundled (each
        written by its command, ``tools/make_generated_drives.py``): read it with the folder
        they were written to.

    Raises
    ------
    ConfigError
        Unreadable or malformed manifest (the entry and the field named).
    """
    from .._config import config_dir, load_toml

    base = Path(folder) if folder is not None else config_dir("recordings")
    manifest = Path(manifest) if manifest is not None else base / _MANIFEST
    doc = load_toml(manifest)  # size, UTF-8 and syntax checked, one ConfigError line
    entries = doc.get("drive")
    if not isinstance(entries, list) or not entries:
        raise ConfigError(f"{manifest}: needs one or more [[drive]] tables")
    drives: list[SampleDrive] = []
    seen: set[str] = set()
    for i, entry in enumerate(entries):
        where = f"{manifest}: drive {i + 1}"
        if not isinstance(entry, dict):
            raise ConfigError(f"{where}: not a table")
        fields = {}
        for key in ("file", "set", "kind", "description", "command"):
            value = entry.get(key)
            if not isinstance(value, str) or not value.strip():
                raise ConfigError(f"{where}: {key!r} must be a non-empty string, got {value!r}")
            fields[key] = value
        unknown = sorted(set(entry) - {"file", "set", "kind", "description", "command"})
        if unknown:
            raise ConfigError(f"{where}: unknown key(s) {', '.join(unknown)}")
        if fields["set"] not in DRIVE_SETS:
            raise ConfigError(f"{where}: set = {fields['set']!r}; allowed: {', '.join(DRIVE_SETS)}")
        if fields["kind"] not in _KINDS:
            raise ConfigError(f"{where}: kind = {fields['kind']!r}; allowed: {', '.join(_KINDS)}")
        file = fields["file"]
        if Path(file).name != file or not file.endswith(".csv"):
            raise ConfigError(f"{where}: file = {file!r}; expected a CSV name in {base}")
        if file in seen:
            raise ConfigError(f"{where}: {file!r} is listed twice")
        seen.add(file)
        drives.append(
            SampleDrive(
                path=base / file,
                set=fields["set"],
                kind=fields["kind"],
                description=fields["description"],
                command=fields["command"],
            )
        )
    return drives


def sample_drives(
    set: str | None = None,
    kind: str | None = None,
    folder: str | Path | None = None,
) -> list[Path]:
    """Paths of the bundled sample drives of one set (and kind), in manifest order.

    Parameters
    ----------
    set : str, optional
        ``"tuning"``, ``"held-out"`` or ``"demo"``; None: every drive.
    kind : str, optional
        ``"car"`` or ``"aircraft"``; None: both.
    folder : path, optional
        As in :func:`sample_drive_manifest`.

    Returns
    -------
    list of Path

    Raises
    ------
    ConfigError
        An unknown set or kind, or a bad manifest.

    Examples
    --------
    >>> from motioncue.telemetry import sample_drives
    >>> [p.name for p in sample_drives("held-out", kind="aircraft")]
    ['flight-right-circuit.csv']
    """
    if set is not None and set not in DRIVE_SETS:
        raise ConfigError(f"sample drive set {set!r} is unknown; allowed: {', '.join(DRIVE_SETS)}")
    if kind is not None and kind not in _KINDS:
        raise ConfigError(f"sample drive kind {kind!r} is unknown; allowed: {', '.join(_KINDS)}")
    return [
        d.path
        for d in sample_drive_manifest(folder)
        if (set is None or d.set == set) and (kind is None or d.kind == kind)
    ]
