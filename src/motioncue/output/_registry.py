"""The registry of controller kinds: each kind declared once, with what it can do.

python-can's backend registry is the model: a kind is a name mapped to a frozen
:class:`ControllerKind` (or, for the bundled kinds, to ``"module:attribute"`` imported on
first use, so that loading one kind does not import the others). Everything the rest of
motioncue asks of a kind is a field of that description; a field left ``None`` (or empty)
declares that the kind cannot do it, and the callers say so instead of probing:

==================  ==============================================================
field               used by
==================  ==============================================================
read_config         :func:`motioncue.output.load_controller` (the TOML's ``kind``)
emulator            ``emulate --listen URL``, ``demo`` (an emulator at a URL of
                    ``emulator_schemes``)
emulator_session    ``emulate`` without ``--listen`` (a kind serving its own
                    session, e.g. a pseudo-terminal)
send                ``send`` (the words it knows: ``send_words``; ``park`` among
                    them means it can park the motors from where they are)
inspect             ``inspect`` (split a raw capture, one line per message)
transport_options   ``send`` (extra ``open_transport`` options, e.g. a source port)
refusals            frame-reply codes for the link watch (which refusals are flow
                    control, what each means)
end_of_run          ``play``, ``bridge``: bytes sent once the park is confirmed, on
                    every way out where the link still works (an interface
                    string's stop string; :func:`end_of_run_messages`)
==================  ==============================================================

What depends on one controller's parameters (its axes, rates, limits, encoder, the
position query, a command streamer) is a method of the controller description itself
(:class:`~motioncue.output.Controller`); every kind implements all of them (``None``
where it cannot, e.g. ``position_query()`` on a send-only link).

Adding a kind is one package and one call, from anywhere::

    register_controller_kind("toy", ControllerKind("toy", read_config=toy_from_config, ...))

A kind outside motioncue can also be found by the command line: name its module in the
environment variable ``MOTIONCUE_PLUGINS`` (comma-separated; imported on the first lookup,
the module calls :func:`register_controller_kind`), or publish an entry point in the group
``motioncue.controllers`` whose object is a :class:`ControllerKind`.
"""

from __future__ import annotations

import importlib
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Concatenate, ParamSpec, Protocol, TextIO, TypeVar

from .._errors import ConfigError
from .._plugins import ENV_VAR, load_plugins

if TYPE_CHECKING:
    from .._config import ConfigReader
    from ._controller_api import Controller
    from ._transport import Transport, TransportURL
    from ._udp_emulator import Trace, Violation

__all__ = [
    "PLUGINS_ENV",
    "ControllerKind",
    "Emulator",
    "EmulatorReadout",
    "Inspection",
    "Refusals",
    "controller_kind",
    "controller_kinds",
    "end_of_run_messages",
    "for_type",
    "register_controller_kind",
]

PLUGINS_ENV = ENV_VAR
"""Environment variable naming modules (comma-separated) that register kinds on import."""

ENTRY_POINT_GROUP = "motioncue.controllers"


class EmulatorReadout(Protocol):
    """What an emulator has played, read while it runs (the live monitor reads only this).

    ``received`` counts the datagrams that reached it, ``frames_received`` the frames among
    them (what a host's frame counter must equal: status requests and parameter reads are
    datagrams, not frames), ``trace`` is what it played (times,
    frame numbers and positions in pulses, on the controller's clock), ``violations``
    every limit or protocol rule the frames broke.
    """

    @property
    def received(self) -> int: ...

    @property
    def frames_received(self) -> int: ...

    @property
    def trace(self) -> Trace: ...

    @property
    def violations(self) -> Sequence[Violation]: ...


class Emulator(EmulatorReadout, Protocol):
    """What ``emulate`` and ``demo`` use of a running emulator: its
    :class:`EmulatorReadout`, ``internal_errors`` (the emulator's own failures while
    serving; none expected), where it listens, start and stop.
    """

    @property
    def internal_errors(self) -> Sequence[str]: ...

    @property
    def where(self) -> str:
        """The URL it listens on (after ``start``), e.g. ``udp://127.0.0.1:40123``."""
        ...

    def start(self) -> Emulator: ...

    def stop(self) -> None: ...


EmulatorFactory = Callable[["Controller", "TransportURL", float], Emulator]
"""``(controller, url, homing_time_s)`` -> an unstarted emulator listening at ``url``."""

SessionRunner = Callable[["Controller", "float | None", "Path | None"], int]
"""``(controller, duration_s, trace_csv)`` -> exit status: a session the kind runs itself."""

SendVerb = Callable[..., int]
"""``(controller, transport, word, args, *, who, save, out)`` -> exit status."""

TransportOptions = Callable[["Controller", "TransportURL"], "dict[str, object]"]

EndOfRun = Callable[["Controller"], "Sequence[bytes]"]
"""``(controller) -> messages`` sent after the park (none: an empty sequence)."""


@dataclass(frozen=True)
class Inspection:
    """How ``inspect`` reads a kind's raw bytes.

    Attributes
    ----------
    split : callable
        Raw capture bytes -> messages, in order (raises :class:`~motioncue.ProtocolError`
        when the bytes are not this kind's).
    describe : callable
        One message -> one line (raises :class:`~motioncue.ProtocolError`).
    """

    split: Callable[[bytes], list[bytes]]
    describe: Callable[[bytes], str]


@dataclass(frozen=True)
class Refusals:
    """What a kind's frame replies mean when they refuse a frame.

    Attributes
    ----------
    is_flow_control : callable
        ``(function, channel) -> bool``: a refusal waiting cures (a full buffer).
    describe : callable
        ``(function, channel) -> str``: the manual's reason.
    """

    is_flow_control: Callable[[int, int], bool]
    describe: Callable[[int, int], str]


P = ParamSpec("P")
R = TypeVar("R")
C = TypeVar("C")


def for_type(
    cls: type[C], hook: Callable[Concatenate[C, P], R]
) -> Callable[Concatenate[Controller, P], R]:
    """``hook`` (written for the kind's own description ``cls``) as a registry hook taking
    any :class:`Controller`; another kind's description is refused with a
    :class:`ConfigError` instead of failing inside the hook."""

    def checked(controller: Controller, /, *args: P.args, **kwargs: P.kwargs) -> R:
        if not isinstance(controller, cls):
            raise ConfigError(
                f"controller {controller.name} is of kind {controller.kind}, not {cls.__name__}"
            )
        return hook(controller, *args, **kwargs)

    checked.__doc__ = hook.__doc__
    return checked


def _no_options(controller: Controller, url: TransportURL) -> dict[str, object]:
    return {}


@dataclass(frozen=True)
class ControllerKind:
    """The frozen description of one controller kind: how to read its config, and what it
    can do (module docstring).

    Attributes
    ----------
    name : str
        The ``kind`` a controller TOML names.
    read_config : callable
        ``(reader, config_name) -> Controller``; reads every other key of the TOML.
    title : str
        Human name (``SC-MBOX``), for listings.
    links : tuple of str
        Target schemes frames may be sent to (``udp``, ``serial``, ``pcap``, ``file``).
    emulator : callable or None
        ``(controller, url, homing_time_s) -> Emulator`` listening at ``url``.
    emulator_schemes : tuple of str
        The URL schemes ``emulator`` listens on.
    emulator_session : callable or None
        ``(controller, duration_s, trace_csv) -> status``: the kind's own session for
        ``emulate`` without ``--listen``.
    send : callable or None
        The ``send`` verb: ``(controller, transport, word, args, *, who, save, out)``.
    send_words : tuple of str
        The words ``send`` knows (``park``: moves the motors home from where they are).
    inspect : Inspection or None
    transport_options : callable
        ``(controller, url) -> dict`` of extra ``open_transport`` options.
    refusals : Refusals or None
        Meaning of refused-frame replies (None: the kind refuses no frames on the link).
    end_of_run : callable or None
        ``(controller) -> messages``: what ends a session on the link, sent by the player
        and the bridge once the park is confirmed (after the last park frame), also after
        an error or a signal, but not when the park itself could not be sent (None: the
        kind ends with the park frames).
    """

    name: str
    read_config: Callable[[ConfigReader, str], Controller]
    title: str = ""
    links: tuple[str, ...] = ("udp", "pcap", "file")
    emulator: EmulatorFactory | None = None
    emulator_schemes: tuple[str, ...] = ("udp",)
    emulator_session: SessionRunner | None = None
    send: SendVerb | None = None
    send_words: tuple[str, ...] = ()
    inspect: Inspection | None = None
    transport_options: TransportOptions = field(default=_no_options)
    refusals: Refusals | None = None
    end_of_run: EndOfRun | None = None

    def __post_init__(self) -> None:
        if not (self.name and self.name.isidentifier() and self.name.islower()):
            raise ConfigError(
                f"controller kind name {self.name!r} is invalid; allowed: a lower-case identifier"
            )
        if not callable(self.read_config):
            raise ConfigError(f"controller kind {self.name}: read_config is not callable")
        unknown = set(self.links) - _SCHEMES
        if unknown:
            raise ConfigError(
                f"controller kind {self.name}: links {sorted(unknown)} unknown; allowed: "
                f"{', '.join(sorted(_SCHEMES))}"
            )

    def open_emulator(
        self, controller: Controller, url: TransportURL, homing_time_s: float = 1.0
    ) -> Emulator:
        """An unstarted emulator of ``controller`` at ``url``; a :class:`ConfigError`
        naming the schemes it listens on otherwise."""
        if self.emulator is None or url.scheme not in self.emulator_schemes:
            where = (
                ", ".join(f"{s}://..." for s in self.emulator_schemes)
                if self.emulator is not None
                else "nothing (it has no emulator at a URL)"
            )
            raise ConfigError(f"the {self.name} emulator listens on {where}, not {url.scheme}:")
        return self.emulator(controller, url, homing_time_s)

    def send_verb(
        self,
        controller: Controller,
        transport: Transport,
        word: str,
        args: list[str],
        *,
        who: tuple[int, int],
        save: bool,
        out: TextIO,
    ) -> int:
        """Run one ``send`` word (a :class:`ConfigError` when the kind has no ``send``)."""
        if self.send is None:
            raise ConfigError(f"the {self.name} controller kind has no send verb")
        return int(self.send(controller, transport, word, args, who=who, save=save, out=out))


_SCHEMES = frozenset(("udp", "serial", "pcap", "file"))

# the bundled kinds, imported on first use ("module:attribute" of their ControllerKind)
_BUNDLED: dict[str, str] = {
    "mbox": "motioncue.output.mbox._kind:KIND",
    "imax": "motioncue.output.imax._kind:KIND",
    "easysmc": "motioncue.output.easysmc._kind:KIND",
    "iface": "motioncue.output.iface._kind:KIND",
}

_lock = threading.RLock()
_kinds: dict[str, ControllerKind | str] = dict(_BUNDLED)
_plugins_loaded = False


def register_controller_kind(
    name: str, kind: ControllerKind | str, *, replace: bool = False
) -> None:
    """Register a controller kind under ``name`` (what a TOML's ``kind`` names).

    Parameters
    ----------
    name : str
        Must equal ``kind.name``.
    kind : ControllerKind or str
        The description, or ``"module:attribute"`` naming it (imported on first use).
    replace : bool
        Replace a kind already registered under ``name`` (default: refuse).

    Raises
    ------
    ConfigError
        The name is taken by another kind, or differs from the description's.
    """
    with _lock:
        if isinstance(kind, ControllerKind) and kind.name != name:
            raise ConfigError(f"register_controller_kind({name!r}): the kind says {kind.name!r}")
        old = _kinds.get(name)
        if old is not None and old != kind and not replace:
            raise ConfigError(
                f"controller kind {name!r} is already registered (replace=True replaces it)"
            )
        _kinds[name] = kind


def _resolve_lazy(name: str, entry: ControllerKind | str) -> ControllerKind:
    if isinstance(entry, ControllerKind):
        return entry
    module_name, _, attr = entry.partition(":")
    try:
        obj = getattr(importlib.import_module(module_name), attr)
    except (ImportError, AttributeError) as exc:
        raise ConfigError(f"controller kind {name!r}: cannot load {entry}: {exc}") from exc
    if not isinstance(obj, ControllerKind) or obj.name != name:
        raise ConfigError(f"controller kind {name!r}: {entry} is not its ControllerKind")
    return obj


def _load_plugins() -> None:
    """Import the modules of ``MOTIONCUE_PLUGINS`` and register the entry points of
    ``motioncue.controllers`` (once)."""
    global _plugins_loaded
    with _lock:
        if _plugins_loaded:
            return
        _plugins_loaded = True
        load_plugins()
        from importlib.metadata import entry_points

        for ep in entry_points(group=ENTRY_POINT_GROUP):
            obj = ep.load()
            if not isinstance(obj, ControllerKind):
                raise ConfigError(
                    f"entry point {ep.name} ({ENTRY_POINT_GROUP}) is not a ControllerKind"
                )
            register_controller_kind(obj.name, obj)


def controller_kinds() -> tuple[str, ...]:
    """The names of every registered kind (bundled first, then in registration order)."""
    _load_plugins()
    with _lock:
        return tuple(_kinds)


def controller_kind(name: str) -> ControllerKind:
    """The registered kind ``name``.

    Raises
    ------
    ConfigError
        No kind of that name, with the registered names.
    """
    if name not in _kinds:  # plugins (an entry-point scan takes tens of ms) only on a miss
        _load_plugins()
    with _lock:
        entry = _kinds.get(name)
        if entry is None:
            raise ConfigError(f"controller kind {name!r} unknown; allowed: {', '.join(_kinds)}")
        kind = _resolve_lazy(name, entry)
        _kinds[name] = kind
        return kind


def end_of_run_messages(controller: Controller) -> list[bytes]:
    """What ``controller``'s kind sends once the park is confirmed (its ``end_of_run``);
    none for a kind without one, or for a controller of no registered kind (a stand-in)."""
    try:
        kind = controller_kind(controller.kind)
    except ConfigError:
        return []
    if kind.end_of_run is None:
        return []
    return [bytes(m) for m in kind.end_of_run(controller) if m]
