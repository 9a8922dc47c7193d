"""What the registries of named extensions (platform kinds, games) share: adding an entry
under its name and finding one by name, with the same refusals and messages."""

from __future__ import annotations

from collections.abc import Mapping, MutableMapping
from typing import Protocol, TypeVar

from ._errors import ConfigError

__all__ = ["register_entry", "registered_entry"]


class _Named(Protocol):
    @property
    def name(self) -> str: ...


T = TypeVar("T", bound=_Named)


def register_entry(
    registry: MutableMapping[str, T], entry: object, entry_type: type[T], caller: str
) -> T:
    """Add ``entry`` to ``registry`` under its ``name`` (replacing an entry of that name).

    Raises
    ------
    ConfigError
        ``entry`` is not an ``entry_type`` (the message names ``caller``, the function the
        user called).
    """
    if not isinstance(entry, entry_type):
        raise ConfigError(f"{caller}({entry!r}): allowed: a {entry_type.__name__}")
    registry[entry.name] = entry
    return entry


def registered_entry(registry: Mapping[str, T], name: str, what: str, plural: str) -> T:
    """The entry ``name`` of ``registry``.

    Raises
    ------
    ConfigError
        ``name`` is not registered: ``unknown WHAT 'name'; known PLURAL: a, b`` (sorted).
    """
    entry = registry.get(name)
    if entry is None:
        raise ConfigError(f"unknown {what} {name!r}; known {plural}: {', '.join(sorted(registry))}")
    return entry
