"""``motioncue list``: the bundled platforms, controllers, presets, profiles and games."""

from __future__ import annotations

import argparse
import tomllib
from typing import Any

from .._errors import ConfigError
from ._common import json_option, print_json
from ._verb import Option, Verb, registrar

__all__ = ["bundled", "register"]

KINDS = ("platforms", "controllers", "presets", "profiles", "games")
"""What ``motioncue list`` lists, in the order it prints them."""

# the configs/ folder of each kind (presets are the cueing files)
_FOLDERS = {"platforms": "platforms", "controllers": "controllers", "presets": "cueing",
            "profiles": "profiles"}  # fmt: skip


def _kind_title(kind: str) -> str:
    """A controller kind's human name from the registry (``?`` for an unknown kind)."""
    from ..output import controller_kind

    try:
        return controller_kind(kind).title or kind
    except ConfigError:
        return "?"


def _describe(kind: str, data: dict[str, Any]) -> str:
    text = str(data.get("description", ""))
    if kind == "controllers" and not text:
        text = f"{_kind_title(str(data.get('kind')))} controller, {data.get('axes', '?')} axes"
    extra = []
    if kind == "platforms" and "default_preset" in data:
        extra.append(f"default preset {data['default_preset']}")
    if kind == "controllers" and "default_target" in data:
        extra.append(f"default target {data['default_target']}")
    if kind == "presets" and "algorithm" in data:
        extra.append(f"algorithm {data['algorithm']}")
    if kind == "profiles" and "source" in data:
        extra.append(f"source {data['source']}")
    return text + (f" ({'; '.join(extra)})" if extra else "")


def bundled(kind: str) -> list[tuple[str, str]]:
    """(name, description) of each bundled item of ``kind`` (one of :data:`KINDS`), sorted.

    Raises
    ------
    ConfigError
        ``kind`` is not one of :data:`KINDS`, or a bundled file is not readable TOML.
    """
    if kind == "games":
        from ..telemetry import GAMES

        return [
            (name, f"{info.title} (default port {info.default_port})")
            for name, info in sorted(GAMES.items())
        ]
    if kind not in _FOLDERS:
        raise ConfigError(f"list {kind!r}: unknown; allowed: {', '.join(KINDS)}")
    from .._config import bundled_names, config_dir

    folder = config_dir(_FOLDERS[kind])
    out = []
    for name in bundled_names(_FOLDERS[kind]):
        try:
            data = tomllib.loads((folder / f"{name}.toml").read_text(encoding="utf-8"))
        except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
            raise ConfigError(f"bundled {kind} file {name}.toml: {exc}") from exc
        out.append((name, _describe(kind, data)))
    return out


def _run(args: argparse.Namespace) -> int:
    kinds = (args.kind,) if args.kind else KINDS
    found = {kind: bundled(kind) for kind in kinds}
    if args.json:
        print_json({k: [{"name": n, "description": d} for n, d in v] for k, v in found.items()})
        return 0
    for i, (kind, items) in enumerate(found.items()):
        if len(kinds) > 1:
            print(("\n" if i else "") + f"{kind}:")
        width = max((len(n) for n, _ in items), default=0)
        for name, text in items:
            print(f"  {name:<{width}}  {text}".rstrip())
    return 0


_LIST = Verb(
    "list",
    _run,
    help="list the bundled platforms, controllers, presets, profiles and games",
    description="List what can be named without a path: the bundled platforms "
    "(--platform), controllers (--controller), cueing presets (--preset), game profiles "
    "(--profile) and the games whose telemetry the bridge reads (--source), one per line "
    "with its description.",
    options=(
        Option.of(
            "kind",
            nargs="?",
            choices=KINDS,
            metavar="KIND",
            help=f"one of {', '.join(KINDS)} (default: all)",
        ),
        json_option("the names and descriptions"),
    ),
)

register = registrar(_LIST)
