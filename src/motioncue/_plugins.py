"""Plug-ins: modules named in ``MOTIONCUE_PLUGINS``, imported by the command line first.

``MOTIONCUE_PLUGINS=module,module`` (comma-separated importable module names; blanks
ignored) lets code outside the package extend motioncue through its registries
(:func:`motioncue.cueing.register_cueing` and the others) before the command line is
parsed: a plug-in module registers on import. A module that cannot be imported is a
one-line error (``motioncue: error: ...``, exit 2), never a traceback.
"""

from __future__ import annotations

import importlib
import os
import sys

from ._errors import ConfigError, one_line

__all__ = ["PLUGINS_ENV", "import_plugins", "load_plugins", "plugin_modules"]

PLUGINS_ENV = "MOTIONCUE_PLUGINS"
"""The environment variable naming the plug-in modules."""


def plugin_modules(value: str | None = None) -> tuple[str, ...]:
    """The module names of ``value`` (default: the environment's ``MOTIONCUE_PLUGINS``)."""
    text = os.environ.get(PLUGINS_ENV, "") if value is None else value
    return tuple(name.strip() for name in text.split(",") if name.strip())


def import_plugins(value: str | None = None) -> tuple[str, ...]:
    """Import every plug-in module (each once per process); returns their names.

    Raises
    ------
    ConfigError
        A module that cannot be imported or fails while registering (named, with the
        reason).
    """
    names = plugin_modules(value)
    for name in names:
        try:
            importlib.import_module(name)
        except Exception as exc:  # any failure of foreign code: reported, not a traceback
            reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
            raise ConfigError(f"{PLUGINS_ENV}: cannot import {name!r}: {reason}") from exc
    return names


def load_plugins() -> bool:
    """:func:`import_plugins` for the command line: False (after one line on stderr) when
    a plug-in fails."""
    try:
        import_plugins()
    except ConfigError as exc:
        print(one_line(f"motioncue: error: {exc}"), file=sys.stderr)
        return False
    return True
