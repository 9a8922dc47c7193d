"""The ``motioncue`` command line: one verb per job users do.

Each verb lives in its own private module exposing ``register(subparsers)``, which adds its
parser and sets ``run=<function(args) -> int>`` as default. The verbs are declared as data
(:class:`~motioncue.cli._verb.Verb`: name, help, options in help order, run function; the
module's ``register`` is ``registrar(*verbs)``), from the options several verbs share
(:mod:`motioncue.cli._common`). Errors motioncue raises on purpose
(:class:`~motioncue.MotioncueError`) print one clear line and exit with status 2.
"""

from __future__ import annotations

import argparse
import difflib
import importlib
import re
import sys
from collections.abc import Sequence
from typing import NoReturn

from .._errors import MotioncueError, one_line

__all__ = ["build_parser", "console", "main"]

# Verb modules, in the order of the data flow. Each registers one or more verbs.
_VERB_MODULES: tuple[str, ...] = (
    "_record",
    "_send_telemetry",
    "_cue",
    "_omct",
    "_compare",
    "_tune",
    "_kinematics",
    "_limits",
    "_pipeline",
    "_view",
    "_bridge",
    "_control",
    "_list",
)

# Which module registers each verb: ``motioncue VERB ...`` imports that module alone (a
# start costs the verb's imports, not every verb's; tests/test_cli_start.py checks this
# table against what the modules register).
_VERB_MODULE: dict[str, str] = {
    "record": "_record",
    "send-telemetry": "_send_telemetry",
    "cue": "_cue",
    "omct": "_omct",
    "compare": "_compare",
    "tune": "_tune",
    "ik": "_kinematics",
    "workspace": "_kinematics",
    "limits": "_limits",
    "generate": "_pipeline",
    "play": "_pipeline",
    "demo": "_pipeline",
    "view": "_view",
    "bridge": "_bridge",
    "emulate": "_control",
    "send": "_control",
    "inspect": "_control",
    "list": "_list",
}


def _did_you_mean(word: str, candidates: Sequence[str]) -> str:
    """``"; did you mean X?"`` for the closest of ``candidates`` (difflib), or ``""``."""
    close = difflib.get_close_matches(word, list(candidates), n=1, cutoff=0.6)
    return f"; did you mean {close[0]}?" if close else ""


class _Parser(argparse.ArgumentParser):
    """An argument parser that names a mistyped option, in the verb's own error form.

    Plain argparse leaves an unknown ``--option`` of a verb to the top-level parser (which
    prints the top-level usage), and when the mistyped option was a required one it first
    complains that the right spelling is missing. A verb parser built from this class
    checks the ``--words`` it is given against its own options before parsing, and every
    error offers the closest known spelling (:mod:`difflib`).
    """

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        if args is not None and self._subparsers is None:
            self._check_option_names(list(args))
        return super().parse_known_args(args, namespace)

    def _long_options(self) -> list[str]:
        return [s for s in self._option_string_actions if s.startswith("--")]

    def _check_option_names(self, args: list[str]) -> None:
        if any(a.nargs == argparse.REMAINDER for a in self._actions):
            return  # the words after a REMAINDER belong to it (``send ... raw --start C``)
        known = self._long_options()
        for token in args:
            if token == "--":
                break
            if not token.startswith("--"):
                continue
            name = token.split("=", 1)[0]
            if name in self._option_string_actions:
                continue
            if self.allow_abbrev and any(k.startswith(name) for k in known):
                continue  # an abbreviation: argparse accepts or refuses it by name
            self.unknown_options([name])

    def unknown_options(self, words: Sequence[str]) -> NoReturn:
        """Refuse ``words`` (not options of this parser), naming the closest spelling."""
        hints = [
            f"{w}{_did_you_mean(w, self._long_options())}" if w.startswith("-") else w
            for w in words
        ]
        noun = "argument" if len(words) == 1 else "arguments"
        self.error(f"unrecognized {noun}: {', '.join(hints)}")

    def error(self, message: str) -> NoReturn:
        m = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if m:
            choices = re.findall(r"'([^']*)'", m.group(2))
            message += _did_you_mean(m.group(1), choices)
        super().error(message)


def _verb_parsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def build_parser(verb: str | None = None) -> _Parser:
    """The command line's parser: every verb's, or (``verb`` given) only that verb's.

    Parameters
    ----------
    verb : str or None
        A verb name (a key of the verb table): only its module is imported and only its
        verbs are added, which is all that ``motioncue VERB ...`` parses. None, or a name
        that is not a verb: every verb (the top-level help and its errors list them all).
    """
    parser = _Parser(
        prog="motioncue",
        description="Vehicle motion to electric-cylinder motion platforms.",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"motioncue {__version__}")
    # the verb's name under its own key: a verb's positional arguments cannot overwrite it
    sub = parser.add_subparsers(dest="_verb_name", metavar="VERB")
    parser.set_defaults(run=None)  # no verb given: each verb's parser sets its own run
    only = _VERB_MODULE.get(verb or "")
    for name in _VERB_MODULES if only is None else (only,):
        module = importlib.import_module(f"{__name__}.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    from .._plugins import load_plugins

    try:
        load_plugins()  # before the parser: what plugins register is in choices and help
    except MotioncueError as exc:
        print(one_line(f"motioncue: error: {exc}"), file=sys.stderr)
        return 2
    words = sys.argv[1:] if argv is None else list(argv)
    # a verb first (the top-level options -h and --version exit): only its module is loaded
    parser = build_parser(words[0] if words else None)
    args, extras = parser.parse_known_args(words)
    if extras:
        # words no parser took: refused by the verb's parser, in the verb's error form
        verb_parser = _verb_parsers(parser).get(args._verb_name or "")
        if isinstance(verb_parser, _Parser):
            verb_parser.unknown_options(extras)
        parser.unknown_options(extras)
    run = args.run
    if run is None:
        parser.print_help()
        return 2
    verb = args._verb_name
    from .._atomic import Interrupted, interrupt_on_stop_signals

    try:
        # before any output is opened: SIGTERM, SIGHUP and SIGQUIT interrupt like Ctrl-C, so
        # the outputs being written are discarded (verbs that park install their own)
        with interrupt_on_stop_signals():
            return int(run(args) or 0)
    except MotioncueError as exc:
        # one printable line of bounded length, whatever the message quotes
        print(one_line(f"motioncue {verb}: error: {exc}"), file=sys.stderr)
        return 2
    except KeyboardInterrupt as exc:
        by = exc.signal_name if isinstance(exc, Interrupted) else None
        try:
            print(f"motioncue {verb}: interrupted{f' by {by}' if by else ''}", file=sys.stderr)
        except OSError:  # the terminal is gone (SIGHUP)
            pass
        return 130
    except BrokenPipeError:
        # the reader went away (``motioncue inspect x.pcap | head``): not an error of ours.
        # Point stdout at /dev/null so the interpreter's final flush does not fail again.
        _silence_stdout()
        return 0


def _silence_stdout() -> None:
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError):  # no real file descriptor (tests capture stdout)
        pass


def console() -> None:
    """Entry point of the ``motioncue`` command and ``python -m motioncue``: :func:`main`,
    then exit with its status.

    Past :func:`main` the platform is parked: the stop signals are ignored so that a late
    Ctrl-C or SIGTERM cannot turn a clean exit into a death by signal (or a traceback) while
    the interpreter shuts down. Ignored, not blocked: a blocked mask is per thread, and the
    kernel hands a process-directed signal to any thread that does not block it (a library's
    thread still finishing), whose default action would end the process. (Not done inside
    :func:`main`, which tests call in-process.)
    """
    import signal

    from .._atomic import STOP_SIGNALS

    status = main()
    for sig in STOP_SIGNALS:
        signal.signal(sig, signal.SIG_IGN)
    raise SystemExit(status)
