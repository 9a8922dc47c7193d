"""Verbs and their options declared as data, built into argparse parsers in one place.

* :class:`Option`: one command-line option (argparse's ``add_argument`` arguments), declared
  once and reused; :meth:`Option.but` derives a verb's variant (another help text, required).
  An option may carry a :class:`Allowed` range, checked before the verb runs.
* :class:`Verb`: a verb's name, help, description, options in help order and run function.
  :meth:`Verb.add_to` builds its parser; the run function it installs first checks every
  declared range, so the verbs' run functions do not repeat those checks.
* :func:`registrar`: a verb module's ``register(sub)``, from its verbs.
* :class:`Lazy`: a text (or choices) computed when the parser is built, not when the module is
  imported, for what depends on registries plugins extend (the games).

Errors found here are :class:`~motioncue.ConfigError`: one line, exit status 2 (see
:func:`motioncue.cli.main`).
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, TypeAlias

from .._errors import ConfigError

if TYPE_CHECKING:
    from ._common import Subparsers

__all__ = ["Allowed", "Lazy", "Option", "OptionGroup", "Run", "Verb", "add_verbs", "registrar"]

Run: TypeAlias = Callable[[argparse.Namespace], int]
"""A verb's run function: the parsed arguments in, the exit status out."""


@dataclass(frozen=True)
class Lazy:
    """A value computed when a parser is built (``fn()``), e.g. a help text naming the
    registered games, which plugins may have extended after this module was imported."""

    fn: Callable[[], object]


def _resolved(value: object) -> Any:
    return value.fn() if isinstance(value, Lazy) else value


@dataclass(frozen=True)
class Allowed:
    """The allowed values of a numeric option: finite, ``lo`` < (or <=) value < (or <=) ``hi``.

    Parameters
    ----------
    lo, hi : float, float or None
        Bounds, in the option's unit; ``hi`` None: no upper bound.
    lo_closed, hi_closed : bool
        Whether the bound itself is allowed.
    unit : str
        Appended to the range in the error message (``"Hz"``).
    show : str
        How the refused value is written: ``"r"`` (``repr``, ``5000.0``) or ``"g"`` (``5``).
    """

    lo: float
    hi: float | None = None
    lo_closed: bool = False
    hi_closed: bool = True
    unit: str = ""
    show: str = "r"

    def text(self) -> str:
        """The range as error messages write it: ``(0, 1000] Hz``, ``1 .. 1000 Hz`` (both
        ends allowed) or ``a number > 0`` (no upper bound)."""
        if self.hi is None:
            return f"a number {'>=' if self.lo_closed else '>'} {self.lo:g}"
        if self.lo_closed and self.hi_closed:
            text = f"{self.lo:g} .. {self.hi:g}"
        else:
            text = (
                f"{'[' if self.lo_closed else '('}{self.lo:g}, {self.hi:g}"
                f"{']' if self.hi_closed else ')'}"
            )
        return f"{text} {self.unit}" if self.unit else text

    def admits(self, value: float) -> bool:
        """Whether ``value`` is finite and within the bounds."""
        if not math.isfinite(value):
            return False
        if value < self.lo or (value == self.lo and not self.lo_closed):
            return False
        return self.hi is None or value < self.hi or (value == self.hi and self.hi_closed)

    def check(self, flag: str, value: float | None) -> None:
        """Refuse ``value`` of option ``flag`` outside the range (None: not given, fine).

        Raises
        ------
        ConfigError
            ``--rate 5000.0 is invalid; allowed: (0, 1000] Hz``.
        """
        if value is None or self.admits(value):
            return
        shown = repr(value) if self.show == "r" else format(value, self.show)
        raise ConfigError(f"{flag} {shown} is invalid; allowed: {self.text()}")


@dataclass(frozen=True)
class Option:
    """One option or positional argument: ``parser.add_argument(*flags, **kwargs)``.

    ``kwargs`` values may be :class:`Lazy` (computed when the parser is built). ``allowed``
    is checked on the parsed value before the verb runs (:meth:`Verb.add_to`).
    """

    flags: tuple[str, ...]
    kwargs: Mapping[str, object] = field(default_factory=dict)
    allowed: Allowed | None = None

    @classmethod
    def of(cls, *flags: str, allowed: Allowed | None = None, **kwargs: object) -> Option:
        """``Option.of("--rate", type=float, default=100.0, help=...)``."""
        return cls(tuple(flags), dict(kwargs), allowed)

    @classmethod
    def choice(cls, flag: str, choices: Sequence[str], *, help: str) -> Option:
        """``flag`` taking one of ``choices``, the first being the default."""
        return cls.of(flag, choices=tuple(choices), default=choices[0], help=help)

    def but(self, *, allowed: Allowed | None = None, **changes: object) -> Option:
        """This option with some ``add_argument`` arguments (or the range) replaced."""
        return replace(self, kwargs={**self.kwargs, **changes}, allowed=allowed or self.allowed)

    def add_to(self, parser: argparse.ArgumentParser) -> argparse.Action:
        """Add the option to ``parser``; returns argparse's action."""
        kwargs = {k: _resolved(v) for k, v in self.kwargs.items()}
        return parser.add_argument(*self.flags, **kwargs)


OptionGroup: TypeAlias = "Option | Sequence[Option] | Callable[[argparse.ArgumentParser], object]"
"""What a verb lists: an option, several in a row, or a function adding some to a parser."""


@dataclass(frozen=True)
class _Checked:
    """The run function a verb's parser calls: the declared ranges, then the verb's ``run``."""

    run: Run
    checks: tuple[tuple[str, str, Allowed], ...]

    def __call__(self, args: argparse.Namespace) -> int:
        for flag, dest, allowed in self.checks:
            allowed.check(flag, getattr(args, dest, None))
        return self.run(args)


@dataclass(frozen=True)
class Verb:
    """One verb of the command line, declared as data.

    Parameters
    ----------
    name : str
        The verb (``motioncue NAME``).
    run : callable
        ``run(args) -> exit status``; called after the options' ranges are checked.
    help : str or Lazy
        The one line of the top-level help.
    description : str, Lazy or None
        The paragraph of the verb's own help.
    options : sequence
        In help order: :class:`Option`, sequences of them, or ``add(parser)`` functions.
    """

    name: str
    run: Run
    help: str | Lazy
    description: str | Lazy | None = None
    options: Sequence[OptionGroup] = ()

    def add_to(self, sub: Subparsers) -> argparse.ArgumentParser:
        """Add this verb's parser (its options, then ``run``) to the verbs ``sub``."""
        parser = sub.add_parser(
            self.name, help=_resolved(self.help), description=_resolved(self.description)
        )
        checks: list[tuple[str, str, Allowed]] = []
        for item in self.options:
            for option in _flatten(item, parser):
                action = option.add_to(parser)
                if option.allowed is not None:
                    checks.append((option.flags[0], action.dest, option.allowed))
        parser.set_defaults(run=_Checked(self.run, tuple(checks)))
        return parser


def _flatten(item: OptionGroup, parser: argparse.ArgumentParser) -> Sequence[Option]:
    if isinstance(item, Option):
        return (item,)
    if callable(item):  # a function that adds its own options (returns nothing to add here)
        item(parser)
        return ()
    return tuple(item)


def add_verbs(sub: Subparsers, verbs: Sequence[Verb]) -> None:
    """Add each verb of ``verbs`` to ``sub`` in order."""
    for verb in verbs:
        verb.add_to(sub)


def registrar(*verbs: Verb) -> Callable[[Subparsers], None]:
    """A verb module's ``register(sub)`` (what :func:`motioncue.cli.build_parser` calls):
    adds ``verbs`` in order."""

    def register(sub: Subparsers) -> None:
        add_verbs(sub, verbs)

    return register
