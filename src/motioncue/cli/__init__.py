"""The ``motioncue`` command line: one verb per job users do.

Each verb lives in its own private module exposing ``register(subparsers)``; the module adds
its parser and sets ``run=<function(args) -> int>`` as default. Errors motioncue raises on
purpose (:class:`~motioncue.MotioncueError`) print one clear line and exit with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from .._errors import MotioncueError, one_line

__all__ = ["build_parser", "console", "main"]

# Verb modules, in the order of the data flow. Each registers one or more verbs.
_VERB_MODULES: tuple[str, ...] = (
    "_record",
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
)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="motioncue",
        description="Vehicle motion to electric-cylinder motion platforms.",
    )
    from .. import __version__

    parser.add_argument("--version", action="version", version=f"motioncue {__version__}")
    # the verb's name under its own key: a verb's positional arguments cannot overwrite it
    sub = parser.add_subparsers(dest="_verb_name", metavar="VERB")
    for name in _VERB_MODULES:
        module = importlib.import_module(f"{__name__}.{name}")
        module.register(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit status."""
    parser = build_parser()
    args = parser.parse_args(argv)
    run = getattr(args, "run", None)
    if run is None:
        parser.print_help()
        return 2
    verb = args._verb_name
    from .._atomic import interrupt_on_stop_signals

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
        by = getattr(exc, "signal_name", None)
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

    Past :func:`main` the platform is parked: the stop signals are blocked so that a late
    Ctrl-C or SIGTERM cannot turn a clean exit into a death by signal (or a traceback) while
    the interpreter shuts down. (Not done inside :func:`main`, which tests call in-process.)
    """
    import signal

    status = main()
    names = ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT")
    signal.pthread_sigmask(
        signal.SIG_BLOCK, [getattr(signal, n) for n in names if hasattr(signal, n)]
    )
    raise SystemExit(status)
