"""Load a controller description from ``configs/controllers/`` and dispatch on its kind.

A controller TOML names its ``kind`` (any registered kind: :func:`controller_kinds`); the
rest of the file is read by that kind's ``read_config(reader, name)``, which returns the
kind's frozen controller description.
"""

from __future__ import annotations

from pathlib import Path

from .._config import ConfigReader, find_config, load_toml
from .._errors import ConfigError
from ._controller_api import Controller
from ._registry import controller_kind, controller_kinds

__all__ = ["load_controller"]


def load_controller(name_or_path: str | Path) -> Controller:
    """Load a bundled controller config by name (``mbox6``) or from a TOML path.

    Returns
    -------
    Controller
        The kind's frozen controller description (see ``motioncue.output.<kind>``).
    """
    path = find_config("controllers", name_or_path)
    reader = ConfigReader(load_toml(path), path.name)
    kind = reader.string("kind")
    try:
        described = controller_kind(kind)
    except ConfigError:
        raise reader.error("kind", kind, " | ".join(controller_kinds())) from None
    controller = described.read_config(reader, path.stem)
    reader.finish()
    return controller
