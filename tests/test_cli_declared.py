"""The command line declared as data (``motioncue.cli._verb``): the ranges declared with an
option are checked before the verb runs, with the messages the verbs used to write
themselves, and the shared options read the same in every verb."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import pytest

from motioncue._errors import ConfigError
from motioncue.cli import build_parser, main
from motioncue.cli._verb import Allowed, Lazy, Option, Verb


def test_allowed_ranges_admit_their_bounds_as_declared_and_nothing_non_finite() -> None:
    half_open = Allowed(0.0, 1000.0, unit="Hz")
    assert half_open.text() == "(0, 1000] Hz"
    assert half_open.admits(1000.0) and half_open.admits(1e-9)
    assert not half_open.admits(0.0) and not half_open.admits(1000.001)
    closed = Allowed(1.0, 1000.0, lo_closed=True, unit="Hz")
    assert closed.text() == "1 .. 1000 Hz"
    assert closed.admits(1.0) and closed.admits(1000.0) and not closed.admits(0.999)
    above = Allowed(0.0, None)
    assert above.text() == "a number > 0"
    assert above.admits(1e300) and not above.admits(0.0)
    at_least = Allowed(0.0, None, lo_closed=True, show="g")
    assert at_least.text() == "a number >= 0"
    assert at_least.admits(0.0) and not at_least.admits(-1e-12)
    for allowed in (half_open, closed, above, at_least):
        assert not any(allowed.admits(x) for x in (math.nan, math.inf, -math.inf))
    at_least.check("--resync-after-ms", None)  # not given: nothing to check
    with pytest.raises(
        ConfigError, match=r"^--resync-after-ms -5 is invalid; allowed: a number >= 0$"
    ):
        at_least.check("--resync-after-ms", -5.0)
    with pytest.raises(ConfigError, match=r"^--rate 5000\.0 is invalid; allowed: \(0, 1000\] Hz$"):
        half_open.check("--rate", 5000.0)


def _parser_with(verb: Verb) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="t")
    verb.add_to(parser.add_subparsers(dest="verb"))
    return parser


def test_a_verb_runs_only_after_its_declared_ranges_pass() -> None:
    ran: list[float] = []

    def run(args: argparse.Namespace) -> int:
        ran.append(args.r)
        return 0

    verb = Verb(
        "v",
        run,
        help="h",
        options=(Option.of("--r", type=float, default=1.0, allowed=Allowed(0.0, 10.0)),),
    )
    parser = _parser_with(verb)
    args = parser.parse_args(["v", "--r", "11"])
    with pytest.raises(ConfigError, match=r"^--r 11\.0 is invalid; allowed: \(0, 10\]$"):
        args.run(args)
    assert ran == []
    args = parser.parse_args(["v", "--r", "10"])
    assert args.run(args) == 0 and ran == [10.0]


def test_a_variant_leaves_the_shared_option_as_it_was() -> None:
    base = Option.of("--x", type=float, default=1.0, help="a")
    variant = base.but(default=2.0, help="b", allowed=Allowed(0.0, 5.0))
    assert dict(base.kwargs) == {"type": float, "default": 1.0, "help": "a"}
    assert base.allowed is None
    assert dict(variant.kwargs) == {"type": float, "default": 2.0, "help": "b"}
    assert variant.but(help="c").allowed == Allowed(0.0, 5.0)  # the range is kept


def test_lazy_texts_and_choices_are_read_when_the_parser_is_built() -> None:
    names = ["a"]
    verb = Verb(
        "v",
        lambda args: 0,
        help=Lazy(lambda: ", ".join(names)),
        options=(Option.of("--k", choices=Lazy(lambda: tuple(names))),),
    )
    names.append("b")  # e.g. a game a plugin registers after the module was imported
    parser = _parser_with(verb)
    assert parser.parse_args(["v", "--k", "b"]).k == "b"
    assert "a, b" in parser.format_help()


_SHORT_RIG = ["--platform", "stewart6-linear", "--controller", "mbox6"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["omct", "--preset", "no-such", *_SHORT_RIG, "--rate", "0"],
         "--rate 0.0 is invalid; allowed: (0, 1000] Hz"),
        (["omct", "--preset", "no-such", *_SHORT_RIG, "--amplitude-scale", "100.5"],
         "--amplitude-scale 100.5 is invalid; allowed: (0, 100]"),
        (["compare", "--input", "no.csv", "--presets", "no-such", *_SHORT_RIG, "--report",
          "{tmp}/r", "--rate", "nan"], "--rate nan is invalid; allowed: (0, 1000] Hz"),
        (["cue", "--input", "no.csv", "--out", "{tmp}/p.csv", "--rate", "2000.5"],
         "--rate 2000.5 is invalid; allowed: (0, 2000] Hz"),
        (["generate", "--input", "no.csv", *_SHORT_RIG, "--out", "{tmp}/r.ride", "--rate", "inf"],
         "--rate inf is invalid; allowed: (0, 2000] Hz"),
        (["send-telemetry", "--game", "f1", "--input", "no.csv", "--rate", "0.5"],
         "--rate 0.5 is invalid; allowed: 1 .. 1000 Hz"),
        (["play", "{tmp}/no.ride", "--speed", "0"], "--speed 0.0 is invalid; allowed: (0, 1000]"),
        (["play", "{tmp}/no.ride", "--resync-after-ms", "-5"],
         "--resync-after-ms -5 is invalid; allowed: a number >= 0"),
        (["bridge", "--source", "f1", *_SHORT_RIG, "--target", "udp://127.0.0.1:9", "--duration",
          "0"], "--duration 0.0 is invalid; allowed: a number > 0"),
    ],
)  # fmt: skip
def test_a_value_out_of_range_is_refused_in_one_line_before_anything_is_read_or_written(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err == f"motioncue {argv[0]}: error: {message}\n"
    assert list(tmp_path.iterdir()) == []


def test_a_value_on_the_closed_bound_passes_the_range_check(
    capsys: pytest.CaptureFixture[str],
) -> None:
    # 1000 Hz is allowed: the refusal is the next check's (the unknown preset), not the rate's
    assert main(["omct", "--preset", "no-such", *_SHORT_RIG, "--rate", "1000"]) == 2
    err = capsys.readouterr().err
    assert "no-such" in err and "--rate" not in err


def _verb_parsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    raise AssertionError("no verbs")


def test_the_shared_options_read_the_same_in_every_verb() -> None:
    seen: dict[str, set[str]] = {"--json": set(), "--platform": set(), "--controller": set()}
    for name, parser in _verb_parsers().items():
        for action in parser._actions:
            flags = action.option_strings
            if "--json" in flags:
                seen["--json"].add(name)
                assert action.help is not None
                assert action.help.startswith("print "), name
                assert action.help.endswith(" as JSON on stdout instead of text"), name
            elif "--platform" in flags and action.required:
                seen["--platform"].add(name)
                assert action.help == "bundled platform name or TOML path", name
            elif "--controller" in flags and action.required:
                seen["--controller"].add(name)
                assert action.help == "bundled controller name or TOML path", name
    # every verb but demo prints a result; these need a platform, a controller
    assert seen["--json"] == set(_verb_parsers()) - {"demo"}
    analysis = {"generate", "bridge", "compare", "omct", "tune"}
    assert seen["--platform"] == analysis | {"limits", "ik", "workspace"}
    assert seen["--controller"] == analysis | {"emulate", "send"}
