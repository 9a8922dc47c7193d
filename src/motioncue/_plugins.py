"""Plugins: modules the command line imports before it builds its parser.

``MOTIONCUE_PLUGINS`` names modules (comma-separated, importable from ``sys.path``) that
register platform kinds, games, controllers or cueing algorithms with the registries
(:func:`motioncue.kinematics.register_platform_kind`,
:func:`motioncue.telemetry.register_game` ...). Imported before the parser is built, what
they register appears in every verb's choices and help.
"""

from __future__ import annotations

import importlib
import os

from ._errors import ConfigError

__all__ = ["ENV_VAR", "PLUGINS_ENV", "import_plugins", "load_plugins", "plugin_modules"]

ENV_VAR = "MOTIONCUE_PLUGINS"
"""The environment variable naming the plugin modules."""
PLUGINS_ENV = ENV_VAR


def plugin_modules(value: str | None = None) -> tuple[str, ...]:
    """The module names of ``value`` (default: the environment's ``MOTIONCUE_PLUGINS``)."""
    text = os.environ.get(ENV_VAR, "") if value is None else value
    return tuple(name.strip() for name in text.split(",") if name.strip())


def load_plugins(spec: str | None = None) -> tuple[str, ...]:
    """Import each module named in ``spec`` (default: ``$MOTIONCUE_PLUGINS``).

    Parameters
    ----------
    spec
        Module names separated by commas (spaces around them ignored); None reads
        :data:`ENV_VAR`.

    Returns
    -------
    tuple of str
        The modules imported, in order.

    Raises
    ------
    ConfigError
        A module that cannot be imported, or fails while importing (one line naming it).
    """
    names = plugin_modules(spec)
    for name in names:
        try:
            importlib.import_module(name)
        except Exception as exc:  # whatever a plugin raises, the user gets one line
            raise ConfigError(
                f"{ENV_VAR}: cannot import plugin {name!r}: {type(exc).__name__}: {exc}"
            ) from exc
    return names


import_plugins = load_plugins
"""The same import, by the name library code uses."""
