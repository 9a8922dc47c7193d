"""Load a controller description from ``configs/controllers/`` and dispatch on its kind.

A controller TOML names its ``kind`` (``imax``, ``mbox`` or ``easysmc``); the rest of the
file is read by that kind's module through ``controller_from_config(reader, name)``, which
returns that kind's frozen controller description.
"""

from __future__ import annotations

import importlib
from pathlib import Path

from .._config import ConfigReader, find_config, load_toml
from ._controller_api import Controller

__all__ = ["CONTROLLER_KINDS", "load_controller"]

CONTROLLER_KINDS = ("imax", "mbox", "easysmc")


def load_controller(name_or_path: str | Path) -> Controller:
    """Load a bundled controller config by name (``mbox6``) or from a TOML path.

    Returns
    -------
    Controller
        The kind's frozen controller description (see ``motioncue.output.<kind>``).
    """
    path = find_config("controllers", name_or_path)
    reader = ConfigReader(load_toml(path), path.name)
    kind = reader.string("kind", choices=CONTROLLER_KINDS)
    module = importlib.import_module(f"motioncue.output.{kind}")
    controller: Controller = module.controller_from_config(reader, path.stem)
    reader.finish()
    return controller
