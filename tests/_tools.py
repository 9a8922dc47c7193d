"""Load a script of ``tools/`` as a module (the tools are not a package), once per process."""

from __future__ import annotations

import functools
import importlib.util
from pathlib import Path
from types import ModuleType

TOOLS = Path(__file__).resolve().parents[1] / "tools"


@functools.cache
def load_tool(name: str) -> ModuleType:
    """``tools/NAME.py`` as a module (loaded once; its ``__name__`` is ``tool_NAME``)."""
    spec = importlib.util.spec_from_file_location(f"tool_{name}", TOOLS / f"{name}.py")
    assert spec is not None and spec.loader is not None, name
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
