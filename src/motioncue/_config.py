"""Strict TOML configuration reading shared by every loader.

Every loader reads its table through :class:`ConfigReader`, which converts nothing by itself
but guarantees three things the conventions ask for: a missing key, an unknown key and a value
out of range are each rejected with a :class:`~motioncue.ConfigError` that names the file, the
key and the value.
"""

from __future__ import annotations

import math
import os
import tomllib
from collections.abc import Callable, Mapping, Sequence
from importlib import resources
from pathlib import Path
from typing import Any

from ._errors import ConfigError, one_line

__all__ = [
    "ConfigReader",
    "bundled_names",
    "config_dir",
    "find_config",
    "load_toml",
    "read_capped",
]

_MISSING = object()


def config_dir(kind: str) -> Path:
    """Folder of bundled configs of one kind (``platforms``, ``controllers``, ``cueing``).

    An installed wheel carries them as package data; a source checkout (editable install)
    reads the repository's ``configs/`` folder.
    """
    try:
        packaged = Path(str(resources.files("motioncue") / "_bundled_configs" / kind))
        if packaged.is_dir():
            return packaged
    except (ModuleNotFoundError, TypeError):  # pragma: no cover - exotic importers
        pass
    return Path(__file__).resolve().parents[2] / "configs" / kind


def bundled_names(kind: str) -> list[str]:
    """Names of the bundled configs of one kind, sorted."""
    folder = config_dir(kind)
    return sorted(p.stem for p in folder.glob("*.toml")) if folder.is_dir() else []


def find_config(kind: str, name_or_path: str | Path) -> Path:
    """Resolve a bundled config name (``stewart6-linear``) or a path to a TOML file."""
    candidate = Path(name_or_path)
    if candidate.suffix == ".toml" or candidate.exists():
        if not candidate.is_file():
            raise ConfigError(f"{kind} config file {str(candidate)!r} does not exist")
        return candidate
    bundled = config_dir(kind) / f"{name_or_path}.toml"
    if bundled.is_file():
        return bundled
    raise ConfigError(
        f"unknown {kind} config {str(name_or_path)!r}; bundled: {', '.join(bundled_names(kind))}"
        " (or give a path to a .toml file)"
    )


MAX_CONFIG_BYTES = 1 << 20
"""Largest configuration file read (1 MiB; the bundled ones are a few kB)."""


def read_capped(
    path: str | os.PathLike[str],
    limit: int,
    what: str,
    *,
    error: type[Exception] = ConfigError,
    where: str | None = None,
    advice: str = "",
    check_head: Callable[[bytes], None] | None = None,
    head_size: int = 0,
) -> bytes:
    """The whole file ``path``, refused unless it has at most ``limit`` bytes.

    Nothing beyond the first ``head_size`` bytes is read before the size is checked: those
    go to ``check_head`` first (a magic number: the wrong kind of file is named as such),
    then a file over ``limit`` is refused from its size. The read is capped at
    ``limit + 1`` bytes, so a device or a file that grew meanwhile is refused as well. An
    ``OSError`` is left to the caller, which names the file its own way.

    Parameters
    ----------
    path : path-like
        The file.
    limit : int
        Largest size read (bytes).
    what : str
        What the file is, for the refusal (``"a ride file"``).
    error : type
        The exception raised for a file over ``limit`` (one line: ``where``, the size,
        ``limit``, ``what``, ``advice``).
    where : str, optional
        The file's name in the message (default ``path``).
    advice : str
        Appended to the message (``"; split it"``).
    check_head : callable, optional
        Raises for a wrong head (given the bytes read, fewer than ``head_size`` for a short
        file).
    head_size : int
        Bytes given to ``check_head``.

    Returns
    -------
    bytes
        The file's bytes.
    """
    name = os.fspath(path) if where is None else where
    cap = f"the {limit} bytes {what} may have{advice}"
    with open(path, "rb") as fh:
        head = b""
        if check_head is not None:
            head = fh.read(head_size)
            check_head(head)
        size = os.fstat(fh.fileno()).st_size
        if size > limit:
            raise error(f"{name}: {size} bytes is larger than {cap}")
        blob = head + fh.read(limit + 1 - len(head))
    if len(blob) > limit:  # a device or a file that grew
        raise error(f"{name}: more than {cap}")
    return blob


def load_toml(path: Path) -> dict[str, Any]:
    """Parse a TOML file, turning every problem into one :class:`ConfigError` line.

    The size is checked before reading (at most :data:`MAX_CONFIG_BYTES`); bytes that are
    not UTF-8 are refused with their line and byte offset; syntax errors name the place.
    """

    try:
        blob = read_capped(path, MAX_CONFIG_BYTES, "a configuration file")
    except OSError as exc:
        raise ConfigError(f"{path}: cannot read: {exc}") from exc
    try:
        text = blob.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = blob.count(b"\n", 0, exc.start) + 1
        raise ConfigError(
            f"{path}: not UTF-8 text: byte {blob[exc.start]:#04x} at offset {exc.start} "
            f"(line {line}); save the file as UTF-8"
        ) from exc
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(one_line(f"{path}: not valid TOML: {exc}")) from exc


class ConfigReader:
    """Read one TOML table, tracking which keys were used.

    Parameters
    ----------
    data
        The table.
    where
        Where the table comes from, for messages (``"stewart6-linear.toml [geometry]"``).

    Call :meth:`finish` after reading: any key not read is an unknown key and is rejected.
    """

    def __init__(self, data: object, where: str) -> None:
        if not isinstance(data, Mapping):
            raise ConfigError(f"{where}: expected a table, got {type(data).__name__}")
        self._data = data
        self._where = where
        self._used: set[str] = set()

    @property
    def where(self) -> str:
        return self._where

    def has(self, key: str) -> bool:
        return key in self._data

    def keys(self) -> list[str]:
        return list(self._data)

    def _get(self, key: str, default: object) -> object:
        self._used.add(key)
        if key in self._data:
            return self._data[key]
        if default is _MISSING:
            raise ConfigError(f"{self._where}: missing key {key!r}")
        return default

    def error(self, key: str, value: object, allowed: str) -> ConfigError:
        """A :class:`ConfigError` naming this table, the key, the value and what is allowed."""
        return ConfigError(f"{self._where}: {key} = {value!r} is invalid; allowed: {allowed}")

    def number(
        self,
        key: str,
        default: object = _MISSING,
        *,
        lo: float = -math.inf,
        hi: float = math.inf,
        lo_open: bool = False,
        hi_open: bool = False,
    ) -> float:
        """A finite float in ``[lo, hi]`` (bounds exclusive when ``*_open``)."""
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.error(key, value, "a number")
        value = float(value)
        below = value <= lo if lo_open else value < lo
        above = value >= hi if hi_open else value > hi
        if not math.isfinite(value) or below or above:
            left = "(" if lo_open else "["
            right = ")" if hi_open else "]"
            raise self.error(key, value, f"a finite number in {left}{lo}, {hi}{right}")
        return value

    def integer(
        self, key: str, default: object = _MISSING, *, lo: int | None = None, hi: int | None = None
    ) -> int:
        """An integer in ``[lo, hi]``."""
        value = self._get(key, default)
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.error(key, value, "an integer")
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise self.error(key, value, f"an integer in [{lo}, {hi}]")
        return value

    def string(
        self, key: str, default: object = _MISSING, *, choices: Sequence[str] | None = None
    ) -> str:
        value = self._get(key, default)
        if not isinstance(value, str):
            raise self.error(key, value, "a string")
        if choices is not None and value not in choices:
            raise self.error(key, value, " | ".join(choices))
        return value

    def boolean(self, key: str, default: object = _MISSING) -> bool:
        value = self._get(key, default)
        if not isinstance(value, bool):
            raise self.error(key, value, "true or false")
        return value

    def vector(
        self, key: str, length: int | None = None, default: object = _MISSING
    ) -> tuple[float, ...]:
        """A list of finite numbers, of a given length when ``length`` is set."""
        value = self._get(key, default)
        if (
            not isinstance(value, list | tuple)
            or (length is not None and len(value) != length)
            or not all(
                isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v)
                for v in value
            )
        ):
            what = f"a list of {length} finite numbers" if length else "a list of finite numbers"
            raise self.error(key, value, what)
        return tuple(float(v) for v in value)

    def table(self, key: str, default: object = _MISSING) -> ConfigReader:
        """A sub-table, read by its own reader."""
        value = self._get(key, {} if default is not _MISSING else default)
        return ConfigReader(value, f"{self._where} [{key}]")

    def tables(self, key: str) -> list[ConfigReader]:
        """An array of tables (``[[key]]``)."""
        value = self._get(key, _MISSING)
        if not isinstance(value, list) or not all(isinstance(v, Mapping) for v in value):
            raise self.error(key, value, "an array of tables ([[" + key + "]])")
        return [ConfigReader(v, f"{self._where} [[{key}]] #{i}") for i, v in enumerate(value)]

    def raw(self, key: str, default: object = _MISSING) -> Any:
        return self._get(key, default)

    def finish(self) -> None:
        """Reject every key that was present but not read."""
        unknown = sorted(set(self._data) - self._used)
        if unknown:
            raise ConfigError(
                f"{self._where}: unknown key(s) {', '.join(repr(k) for k in unknown)}; "
                f"known: {', '.join(sorted(self._used))}"
            )
