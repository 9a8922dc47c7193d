"""The import graph keeps the stages in layers: no stage imports a later one at module level.

Read from the code (which stage needs which other stage's objects), the layers are, lowest
first:

====  ==========================================  =========================================
rank  stages                                      why there
====  ==========================================  =========================================
0     ``_errors``, ``_frozen``                    the exception tree everyone raises; setting
                                                  a frozen dataclass's normalised fields
1     ``_atomic``, ``_config``, ``_registry``     files written whole; bundled configs; what
                                                  the named registries share
2     ``telemetry``, ``kinematics``, ``output``   independent leaves: game packets; platform
                                                  geometry; controller descriptions, wire
                                                  formats and transports
3     ``trajectory``                              limits from a platform (kinematics) and a
                                                  controller (output)
4     ``cueing``                                  algorithms given the rig (platform, limits)
5     ``washout``                                 the old name of cueing, an alias of it
6     ``pipeline``                                generate, play, bridge: all of the above
7     ``viewer``                                  shows rides and bridges (pipeline)
8     ``analysis``                                compare, omct, tune: the chain, offline
9     ``cli``                                     the verbs
10    ``__main__``                                ``python -m motioncue``
====  ==========================================  =========================================

Checked here with :mod:`ast` over ``src/``: every import at module level (in ``if`` /
``try`` blocks at the top too, ``if TYPE_CHECKING:`` included, since the types follow the
layers as well) that names another stage must name a lower rank. Two stages of one rank
must not import each other. Imports inside functions are not checked (they run late and
may serve a lazy start, e.g. the verbs). The package's own ``__init__`` is the facade over
everything and is not a stage. A new stage (a new subpackage) fails the test until it is
given a rank here.
"""

from __future__ import annotations

import ast
import textwrap
from collections.abc import Iterator
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = "motioncue"

RANKS: dict[str, int] = {
    "_errors": 0,
    "_frozen": 0,
    "_atomic": 1,
    "_config": 1,
    "_plugins": 1,
    "_registry": 1,
    "telemetry": 2,
    "kinematics": 2,
    "output": 2,
    "trajectory": 3,
    "cueing": 4,
    "washout": 5,
    "pipeline": 6,
    "viewer": 7,
    "analysis": 8,
    "cli": 9,
    "__main__": 10,
}
"""Rank of each stage (a subpackage or a private module of the package's root)."""

FACADE = ""
"""The stage name of the package itself (``motioncue/__init__.py``): above every rank."""


def _module_name(path: Path, src: Path) -> str:
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _is_package(path: Path) -> bool:
    return path.name == "__init__.py"


def _stage(module: str, src: Path, *, maybe_name: bool = False) -> str | None:
    """The stage of a dotted module name of the package, or None for other packages.

    ``maybe_name``: the last part may be a name taken from the package itself (``from
    motioncue import __version__``), the facade, when no module of that name exists.
    """
    parts = module.split(".")
    if parts[0] != PACKAGE:
        return None
    if len(parts) == 1:
        return FACADE
    first = src / PACKAGE / parts[1]
    exists = first.is_dir() or first.with_suffix(".py").is_file()
    if maybe_name and len(parts) == 2 and not exists and parts[1] not in RANKS:
        return FACADE
    return parts[1]


def _top_level_imports(body: list[ast.stmt]) -> Iterator[ast.Import | ast.ImportFrom]:
    """The imports a module runs (or type-checks) when it is imported: its statements at
    module level and those in its top-level ``if`` / ``try`` blocks, not in functions."""
    for node in body:
        if isinstance(node, ast.Import | ast.ImportFrom):
            yield node
        elif isinstance(node, ast.If):
            yield from _top_level_imports(node.body)
            yield from _top_level_imports(node.orelse)
        elif isinstance(node, ast.Try):
            yield from _top_level_imports(node.body)
            for handler in node.handlers:
                yield from _top_level_imports(handler.body)
            yield from _top_level_imports(node.orelse)
            yield from _top_level_imports(node.finalbody)


def _targets(
    node: ast.Import | ast.ImportFrom, module: str, package: bool
) -> list[tuple[str, bool]]:
    """The dotted names an import statement brings in (relative imports resolved), each
    with whether its last part may be a name rather than a module (``from X import name``)."""
    if isinstance(node, ast.Import):
        return [(alias.name, False) for alias in node.names]
    if node.level:
        base = module.split(".") if package else module.split(".")[:-1]
        base = base[: len(base) - (node.level - 1)]
        stem = ".".join(base + ([node.module] if node.module else []))
    else:
        stem = node.module or ""
    if node.module and stem != PACKAGE:
        return [(stem, False)]
    return [(f"{stem}.{alias.name}", True) for alias in node.names]


def layer_violations(src: Path) -> list[str]:
    """Every module-level import under ``src/motioncue`` that breaks :data:`RANKS`, as
    ``file:line: stage (rank) imports stage (rank): target`` lines."""
    out: list[str] = []
    for path in sorted((src / PACKAGE).rglob("*.py")):
        module = _module_name(path, src)
        here = _stage(module, src)
        if here is None or here == FACADE:
            continue
        if here not in RANKS:
            out.append(f"{path.relative_to(src)}: stage {here!r} has no rank in RANKS")
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        for node in _top_level_imports(tree.body):
            for target, maybe_name in _targets(node, module, _is_package(path)):
                there = _stage(target, src, maybe_name=maybe_name)
                if there is None or there == here:
                    continue
                where = f"{path.relative_to(src)}:{node.lineno}"
                if there == FACADE:
                    out.append(f"{where}: {here} imports the package facade: {target}")
                elif there not in RANKS:
                    out.append(f"{where}: {here} imports {there!r}, which has no rank in RANKS")
                elif RANKS[there] >= RANKS[here]:
                    out.append(
                        f"{where}: {here} (rank {RANKS[here]}) imports {there} "
                        f"(rank {RANKS[there]}): {target}"
                    )
    return out


def test_no_stage_imports_a_later_stage_at_module_level() -> None:
    assert (SRC / PACKAGE / "__init__.py").is_file()
    violations = layer_violations(SRC)
    assert not violations, "imports against the layers:\n" + "\n".join(violations)


def test_every_stage_of_the_package_has_a_rank() -> None:
    stages = {
        p.stem if p.is_file() else p.name
        for p in (SRC / PACKAGE).iterdir()
        if (p.is_dir() and (p / "__init__.py").is_file())
        or (p.suffix == ".py" and p.name != "__init__.py")
    }
    assert stages <= set(RANKS), f"stages without a rank: {sorted(stages - set(RANKS))}"


def _write(root: Path, rel: str, text: str) -> None:
    path = root / rel
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(textwrap.dedent(text), encoding="utf-8")


@pytest.fixture
def toy_src(tmp_path: Path) -> Path:
    """A package laid out like motioncue, importing only downwards."""
    _write(tmp_path, "motioncue/__init__.py", "from .pipeline import run\n")
    _write(tmp_path, "motioncue/_errors.py", "class MotioncueError(Exception): ...\n")
    _write(tmp_path, "motioncue/kinematics/__init__.py", "from .._errors import MotioncueError\n")
    _write(tmp_path, "motioncue/output/__init__.py", "")
    _write(
        tmp_path,
        "motioncue/trajectory/_limits.py",
        """
        from typing import TYPE_CHECKING
        from motioncue.kinematics import Platform
        if TYPE_CHECKING:
            from ..output import Controller

        def late():
            from ..pipeline import run  # inside a function: not checked
        """,
    )
    _write(tmp_path, "motioncue/trajectory/__init__.py", "from ._limits import late\n")
    _write(
        tmp_path,
        "motioncue/pipeline/__init__.py",
        "from ..trajectory import late\nfrom .. import _errors\nrun = late\n",
    )
    return tmp_path


def test_the_check_accepts_a_package_that_imports_downwards(toy_src: Path) -> None:
    assert layer_violations(toy_src) == []


@pytest.mark.parametrize(
    ("statement", "expect"),
    [
        ("from ..pipeline import run", "trajectory (rank 3) imports pipeline (rank 6)"),
        ("import motioncue.cueing", "trajectory (rank 3) imports cueing (rank 4)"),
        ("from motioncue import cli", "trajectory (rank 3) imports cli (rank 9)"),
        ("from .. import __version__", "trajectory imports the package facade"),
        (
            "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from ..viewer import X",
            "trajectory (rank 3) imports viewer (rank 7)",
        ),
        ("try:\n    from ..pipeline import run\nexcept ImportError:\n    pass", "pipeline"),
        ("from ..newstage import thing", "imports 'newstage', which has no rank"),
    ],
)
def test_the_check_finds_an_import_against_the_layers(
    toy_src: Path, statement: str, expect: str
) -> None:
    _write(toy_src, "motioncue/trajectory/_bad.py", statement + "\n")
    found = layer_violations(toy_src)
    assert len(found) == 1 and "trajectory/_bad.py:" in found[0], found
    assert expect in found[0], found


def test_the_check_refuses_imports_between_stages_of_one_rank(toy_src: Path) -> None:
    _write(toy_src, "motioncue/output/_bad.py", "from ..kinematics import Platform\n")
    found = layer_violations(toy_src)
    assert found == [
        "motioncue/output/_bad.py:1: output (rank 2) imports kinematics (rank 2): "
        "motioncue.kinematics"
    ]


def test_the_check_names_a_stage_without_a_rank(toy_src: Path) -> None:
    _write(toy_src, "motioncue/newstage/__init__.py", "")
    assert layer_violations(toy_src) == [
        "motioncue/newstage/__init__.py: stage 'newstage' has no rank in RANKS"
    ]
