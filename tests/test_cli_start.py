"""``motioncue VERB ...`` loads the verb's own module, not every verb's (issue 21: the suite
starts the command hundreds of times), and parses and helps exactly as the whole parser does.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from motioncue import cli
from motioncue.cli import build_parser

SRC = Path(__file__).resolve().parents[1] / "src"


def _verbs(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    raise AssertionError("no verbs")


def test_the_verb_table_names_each_verb_s_module_in_help_order() -> None:
    full = _verbs(build_parser())
    assert list(cli._VERB_MODULE) == list(full)  # every verb, in the top-level help's order
    assert set(cli._VERB_MODULE.values()) == set(cli._VERB_MODULES)
    for verb, module in cli._VERB_MODULE.items():
        alone = _verbs(build_parser(verb))
        assert verb in alone, (verb, module)
        # only the verbs of that module: the verbs the table gives the same module
        assert set(alone) == {v for v, m in cli._VERB_MODULE.items() if m == module}


@pytest.mark.parametrize("verb", sorted(cli._VERB_MODULE))
def test_a_verb_alone_helps_and_refuses_as_in_the_whole_parser(verb: str) -> None:
    whole, alone = _verbs(build_parser())[verb], _verbs(build_parser(verb))[verb]
    assert alone.format_help() == whole.format_help()
    assert alone.prog == whole.prog == f"motioncue {verb}"
    assert [a.option_strings for a in alone._actions] == [a.option_strings for a in whole._actions]


def test_not_a_verb_first_builds_every_verb() -> None:
    for first in (None, "--help", "--version", "gen", "no-such-verb"):
        assert list(_verbs(build_parser(first))) == list(cli._VERB_MODULE)


_PROBE = """
import json, sys
sys.argv = ["motioncue", *sys.argv[1:]]
from motioncue.cli import main
try:
    status = main()
except SystemExit as exc:
    status = exc.code
print(json.dumps({"status": status, "modules": sorted(sys.modules)}), file=sys.stderr)
"""


def _modules_after(*argv: str) -> tuple[int, set[str]]:
    env = {**os.environ, "PYTHONPATH": str(SRC)}
    env.pop("MOTIONCUE_PLUGINS", None)
    proc = subprocess.run(
        [sys.executable, "-c", _PROBE, *argv], env=env, capture_output=True, text=True,
        timeout=120,
    )  # fmt: skip
    report = json.loads(proc.stderr.strip().splitlines()[-1])
    return int(report["status"]), set(report["modules"])


def test_one_start_imports_the_verb_s_module_only() -> None:
    """A fresh interpreter (the modules a start loads), through ``main()`` reading
    ``sys.argv`` as the command does."""
    status, modules = _modules_after("limits", "--help")
    assert status == 0
    verb_modules = {m for m in modules if m.startswith("motioncue.cli._") and m.count(".") == 2}
    shared = {"motioncue.cli._verb", "motioncue.cli._common", "motioncue.cli._preset",
              "motioncue.cli._monitor"}  # fmt: skip
    assert verb_modules - shared == {"motioncue.cli._limits"}
    # and the whole command line when no verb comes first
    status, modules = _modules_after("--help")
    assert status == 0
    assert {f"motioncue.cli.{m}" for m in cli._VERB_MODULES} <= modules


def test_the_games_load_without_the_gt7_cipher_until_a_gt7_packet_is_decoded() -> None:
    """``bridge --help`` names the games (every game module is imported); the GT7 cipher's
    libraries (pycryptodome through cffi and pycparser, PyNaCl) load only when decoding."""
    status, modules = _modules_after("bridge", "--help")
    assert status == 0
    assert "motioncue.telemetry._gt7" in modules
    assert not {m for m in modules if m.split(".")[0] in ("Crypto", "cffi", "nacl")}
    assert "motioncue.telemetry._gt7_cipher" not in modules
