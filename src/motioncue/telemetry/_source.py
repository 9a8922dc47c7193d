"""Telemetry sources: a live UDP receiver and a real-time replay of recording files.

Both run their own thread, decode each datagram on arrival and publish the newest sample in
a last-value slot (a plain attribute: assigning a reference is atomic under the GIL) plus a
bounded deque for consumers that want every sample. The consumer never blocks: ``latest()``
and ``drain()`` are a few attribute reads.

Source specs (``open_source``)::

    f1                 live UDP, the game's default port, bound on 127.0.0.1
    f1:20777           live UDP on port 20777
    f1:0.0.0.0:20777   bound on every interface (a console or another PC sends)
    replay:FILE        a recording, replayed with its original timing
    replay:FILE?speed=2    twice as fast; speed=0 replays as fast as possible
    auto               every known port (of the games that send on their own), locked onto
                       the first game whose datagrams decode; auto:0.0.0.0 on every interface
    gt7@192.168.1.20   a game that must be asked for its telemetry (Assetto Corsa ``ac``,
                       Gran Turismo 7 ``gt7``): requests go to that address (default
                       127.0.0.1), at the game's own port; with a peer that is not a
                       loopback address the receiver binds every interface

A game that must be asked has a decoder with ``requests(now_s) -> list[bytes]`` (sent to
the peer about every 50 ms when not empty), ``farewell() -> list[bytes]`` (sent at close),
``PEER_PORT`` (the game's port) and ``LISTEN_PORT`` (the local port bound by default);
see :class:`Requester`.
"""

from __future__ import annotations

import ipaddress
import math
import os
import selectors
import socket
import threading
import time
from collections import deque
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Protocol, runtime_checkable
from urllib.parse import parse_qs

from .._errors import ConfigError, TransportError
from ._container import MAX_DATAGRAM, _bind_udp, read_recording_file
from ._registry import GAMES, decoder_for
from ._sample import Decoder, DecodeResult, TelemetrySample

__all__ = [
    "AutoSource",
    "ReplaySource",
    "Requester",
    "TelemetrySource",
    "is_loopback",
    "open_source",
    "parse_live_spec",
    "split_peer",
]

DEFAULT_HOST = "127.0.0.1"
AUTO = "auto"
TALK_PERIOD_S = 0.05
"""How often a live source asks a talking decoder for requests (s)."""


@runtime_checkable
class Requester(Protocol):
    """A decoder of a game that sends telemetry only when asked (handshake, heartbeat)."""

    PEER_PORT: int
    LISTEN_PORT: int

    def requests(self, now_s: float) -> list[bytes]: ...

    def farewell(self) -> list[bytes]: ...


def split_peer(spec: str) -> tuple[str, str | None]:
    """Split ``GAME@PEER[:...]`` into (``GAME[:...]``, PEER); PEER is None when absent.

    Raises
    ------
    ConfigError
        An empty peer, or a game that is not asked for telemetry.
    """
    head, sep, rest = spec.partition(":")
    game, at, peer = head.partition("@")
    if not at:
        return spec, None
    if not peer:
        raise ConfigError(f"source {spec!r}: '@' needs the game's address, e.g. gt7@192.168.1.20")
    info = GAMES.get(game)
    if info is not None and not info.asked:
        raise ConfigError(
            f"source {spec!r}: {game!r} sends on its own; '@ADDRESS' is for games that must "
            f"be asked ({', '.join(g for g, i in sorted(GAMES.items()) if i.asked)})"
        )
    return game + sep + rest, peer


def _listen_port(game: str) -> int:
    """The local port a live source binds by default for ``game``: a game that must be asked
    declares its own (``LISTEN_PORT``; 0 = any free port), the others send to their
    ``default_port``."""
    info = GAMES[game]
    if not info.asked:
        return info.default_port
    dec = info.decoder()
    if not isinstance(dec, Requester):
        raise ConfigError(
            f"game {game!r} is registered as asked, but its decoder is no Requester "
            "(requests, farewell, PEER_PORT, LISTEN_PORT)"
        )
    return int(dec.LISTEN_PORT)


def is_loopback(host: str) -> bool:
    """Whether ``host`` (``localhost`` or an IP address text) names this machine's loopback."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def parse_live_spec(spec: str) -> tuple[str, str, int]:
    """Split ``GAME[:[HOST:]PORT]`` into (game, host, port); port 0 binds a free port.

    Raises
    ------
    ConfigError
        Unknown game, or a port that is not an integer in 0..65535.
    """
    spec, peer = split_peer(spec)
    parts = spec.split(":")
    game = parts[0]
    if game == AUTO:
        if len(parts) > 2:
            raise ConfigError(f"source {spec!r}: expected auto or auto:HOST")
        return AUTO, (parts[1] if len(parts) == 2 and parts[1] else DEFAULT_HOST), 0
    if game not in GAMES:
        raise ConfigError(
            f"source {spec!r}: unknown game {game!r}; known: {', '.join(sorted(GAMES))}"
            " (or replay:FILE)"
        )
    host, port_text = DEFAULT_HOST, None
    if peer is not None and not is_loopback(peer):
        host = "0.0.0.0"  # a console or another PC answers: listen beyond loopback
    if len(parts) == 2:
        port_text = parts[1]
    elif len(parts) == 3:
        host, port_text = parts[1] or DEFAULT_HOST, parts[2]
    elif len(parts) > 3:
        raise ConfigError(f"source {spec!r}: expected GAME, GAME:PORT or GAME:HOST:PORT")
    if port_text is None:
        return game, host, _listen_port(game)
    try:
        port = int(port_text)
    except ValueError:
        port = -1
    if not 0 <= port <= 65535:
        raise ConfigError(f"source {spec!r}: port {port_text!r} is not an integer in 0..65535")
    return game, host, port


class _ThreadedSource:
    """Shared last-value slot, history deque, counters and thread handling."""

    game: str

    def __init__(self, decoder: Decoder, history: int) -> None:
        if history < 1:
            raise ConfigError(f"history = {history!r} must be >= 1")
        self.decoder = decoder
        self.game = decoder.game
        self._latest: TelemetrySample | None = None
        self._history: deque[TelemetrySample] = deque(maxlen=history)
        self._datagrams = 0
        self._samples = 0
        self._errors = 0
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self.last_datagram_s = math.nan
        """perf_counter time of the last datagram of any kind (nan before the first)."""
        self.on_sample: Callable[[TelemetrySample], None] | None = None
        """Called with each new sample on the receiver thread, as soon as it is decoded
        (the shared-memory child publishes from here instead of polling)."""

    def _start(self, name: str) -> None:
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def _run(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def _deliver(self, data: bytes, t_s: float) -> None:
        self._datagrams += 1
        self.last_datagram_s = t_s
        sample = self.decoder.feed(data, t_s)
        if sample is not None:
            self._history.append(sample)
            self._latest = sample
            self._samples += 1
            cb = self.on_sample
            if cb is not None:
                cb(sample)

    def latest(self, max_age_s: float | None = None) -> TelemetrySample | None:
        """The newest sample, or None before the first one. Never blocks.

        Parameters
        ----------
        max_age_s : float, optional
            If given and the newest sample is older than this (``time.perf_counter()`` minus
            its ``t_s``), it is returned with ``paused=True``: the game stopped sending
            (F1 and Forza pause menus, BeamNG pause all just go quiet).
        """
        s = self._latest
        if s is not None and max_age_s is not None and not s.paused:
            if time.perf_counter() - s.t_s > max_age_s:
                return replace(s, paused=True)
        return s

    def drain(self) -> list[TelemetrySample]:
        """Every sample since the previous call (at most ``history`` of them), oldest first."""
        out = []
        pop = self._history.popleft
        try:
            while True:
                out.append(pop())
        except IndexError:
            pass
        return out

    @property
    def stats(self) -> dict[str, int]:
        """Source counters (``datagrams``, ``samples``, ``receive errors``) and the decoder's."""
        d = {
            "datagrams": self._datagrams,
            "samples": self._samples,
            "receive errors": self._errors,
        }
        d.update(dict(self.decoder.stats))
        return d

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def finished(self) -> bool:
        """True once the source will deliver nothing more (end of a replayed file).

        Always False for a live receiver: a game that goes quiet may resume at any time.
        """
        return False

    def close(self) -> None:
        """Stop the thread and release the socket or file. Idempotent."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(timeout=2.0)

    def __enter__(self) -> _ThreadedSource:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class TelemetrySource(_ThreadedSource):
    """Live UDP receiver: binds a port, receives and decodes in its own thread.

    Each datagram is stamped with ``time.perf_counter()`` on arrival and fed to the game's
    decoder; the newest sample is available from :meth:`latest` without blocking.

    Parameters
    ----------
    game : str
        Registered game name.
    port : int, optional
        UDP port (default: the game's); 0 binds a free port (see :attr:`port`).
    host : str
        Address to bind; 127.0.0.1 by default, ``0.0.0.0`` for every interface.
    history : int
        Samples kept for :meth:`drain`.
    on_datagram : callable, optional
        Called in the receiver thread with ``(t_s, datagram)`` for every datagram (e.g. to
        record while bridging). It must be quick; an exception from it is counted as a
        receive error.
    peer : str, optional
        For a game that must be asked (:class:`Requester`): its address (default 127.0.0.1).
    peer_port : int, optional
        Its port (default: the game's own, ``PEER_PORT``; tests use stand-in games).
    """

    def __init__(
        self,
        game: str,
        port: int | None = None,
        host: str = DEFAULT_HOST,
        *,
        history: int = 1024,
        on_datagram: Callable[[float, bytes], None] | None = None,
        peer: str | None = None,
        peer_port: int | None = None,
    ) -> None:
        super().__init__(decoder_for(game), history)
        self._on_datagram = on_datagram
        dec = self.decoder
        self.peer: tuple[str, int] | None = None
        """Where requests go, for a game that must be asked (``Requester``), else None."""
        if isinstance(dec, Requester):
            self.peer = (
                peer or DEFAULT_HOST,
                int(dec.PEER_PORT if peer_port is None else peer_port),
            )
            if port is None:
                port = int(dec.LISTEN_PORT)
        elif peer is not None or peer_port is not None:
            raise ConfigError(f"{game!r} sends on its own: it takes no peer address {peer!r}")
        self._sock = _bind_udp(host, GAMES[game].default_port if port is None else port)
        self._sock.settimeout(TALK_PERIOD_S)
        self.host = host
        self.port: int = self._sock.getsockname()[1]
        self.requests_sent = 0
        self._start(f"motioncue-telemetry-{game}")

    def _talk(self, datagrams: list[bytes]) -> None:
        """Send requests to the peer; a failure is a counted receive error, never fatal."""
        assert self.peer is not None
        for d in datagrams:
            try:
                self._sock.sendto(d, self.peer)
                self.requests_sent += 1
            except OSError:
                self._errors += 1

    def _run(self) -> None:
        buf = bytearray(MAX_DATAGRAM + 1)
        sock = self._sock
        recv_into = sock.recv_into
        clock = time.perf_counter
        asker = self.decoder if isinstance(self.decoder, Requester) else None
        next_talk = -math.inf
        try:
            while not self._stop.is_set():
                if asker is not None:
                    now = clock()
                    if now >= next_talk:
                        next_talk = now + TALK_PERIOD_S
                        try:
                            self._talk(asker.requests(now))
                        except Exception:
                            self._errors += 1
                try:
                    n = recv_into(buf)
                except TimeoutError:
                    continue
                except OSError:
                    if self._stop.is_set():
                        break
                    self._errors += 1
                    time.sleep(0.01)
                    continue
                t = clock()
                data = bytes(buf[:n])
                try:
                    if self._on_datagram is not None:
                        self._on_datagram(t, data)
                except Exception:
                    self._errors += 1
                try:
                    self._deliver(data, t)
                except Exception:  # never let the receiver thread die
                    self._errors += 1
        finally:
            if asker is not None:
                try:
                    self._talk(asker.farewell())
                except Exception:
                    self._errors += 1
            sock.close()

    def __repr__(self) -> str:
        peer = "" if self.peer is None else f", asking {self.peer[0]}:{self.peer[1]}"
        return f"TelemetrySource({self.game!r}, udp://{self.host}:{self.port}{peer})"


class ReplaySource(_ThreadedSource):
    """Replays a recording file through the game's decoder, with its original timing.

    Samples are stamped with ``time.perf_counter()`` at replay, like a live source, so a
    consumer cannot tell the difference. The file's clock starts when the consumer first
    asks for a sample (:meth:`latest`, :meth:`drain` or :meth:`begin`), not when the source
    is opened: a consumer that takes seconds to get ready (a loaded machine) still sees the
    whole recording, as it would see a game started after it. ``speed`` scales time (2 =
    twice as fast); 0 replays as fast as possible. :attr:`done` is set, and :attr:`finished`
    becomes True, when the file is exhausted (or the replay thread ended for any other
    reason): a bridge then fades out, parks and ends instead of waiting for more telemetry.

    Parameters
    ----------
    path : str or os.PathLike
        Recording written by ``motioncue record``.
    speed : float
        Time scale, >= 0.
    history : int
        Samples kept for :meth:`drain`.
    """

    port: int = 0
    """The UDP port it listens on: none (0, as for a source on several ports)."""

    def __init__(
        self, path: str | os.PathLike[str], speed: float = 1.0, *, history: int = 1024
    ) -> None:
        if not (math.isfinite(speed) and speed >= 0):
            raise ConfigError(f"replay speed = {speed!r} must be >= 0 (0 = as fast as possible)")
        self.recording = read_recording_file(path)
        super().__init__(decoder_for(self.recording.game), history)
        self.path = os.fspath(path)
        self.speed = float(speed)
        self.done = threading.Event()
        self._go = threading.Event()
        self._start(f"motioncue-replay-{self.game}")

    def begin(self) -> None:
        """Start the file's clock (once; later calls do nothing)."""
        self._go.set()

    def latest(self, max_age_s: float | None = None) -> TelemetrySample | None:
        """As :meth:`TelemetrySource.latest`; the first call starts the replay."""
        self._go.set()
        return super().latest(max_age_s)

    def drain(self) -> list[TelemetrySample]:
        """As :meth:`TelemetrySource.drain`; the first call starts the replay."""
        self._go.set()
        return super().drain()

    def _run(self) -> None:
        rec = self.recording
        clock = time.perf_counter
        try:
            if not rec.t_s:
                return
            while not self._go.wait(0.05):
                if self._stop.is_set():
                    return
            t_first = rec.t_s[0]
            t0 = clock()
            for t_rec, data in zip(rec.t_s, rec.datagrams, strict=True):
                if self._stop.is_set():
                    return
                if self.speed > 0:
                    due = t0 + (t_rec - t_first) / self.speed
                    while True:
                        left = due - clock()
                        if left <= 0 or self._stop.is_set():
                            break
                        time.sleep(min(left, 0.05))
                self._deliver(data, clock())
        finally:
            self.done.set()

    @property
    def finished(self) -> bool:
        """True once every datagram of the file has been delivered (or the replay stopped)."""
        return self.done.is_set()

    def __repr__(self) -> str:
        return f"ReplaySource({self.path!r}, speed={self.speed})"


class _AutoDecoder(Decoder):
    """Tries the decoders of the games expected on the port a datagram came to
    (``port``, set by the source before each datagram) until one yields a sample; from then
    on only that one decodes (its counters become this decoder's)."""

    game = AUTO

    def __init__(self, listen: Sequence[tuple[int, Sequence[str]]]) -> None:
        super().__init__()
        self.candidates = {g: decoder_for(g) for _p, gs in listen for g in gs}
        self.by_port: dict[int, list[Decoder]] = {}
        self.port = 0
        self.locked: Decoder | None = None

    def _decode(self, datagram: bytes, t_s: float) -> DecodeResult:  # pragma: no cover
        raise AssertionError("decode() is overridden")

    def decode(self, datagram: bytes, t_s: float) -> DecodeResult:
        if self.locked is not None:
            return self.locked.decode(datagram, t_s)
        for dec in self.by_port.get(self.port, ()):
            r = dec.decode(datagram, t_s)
            if r.status == "sample":
                self.locked = dec
                self.game = dec.game
                return r
        self._count("auto: no game recognised yet")
        return DecodeResult("skipped", "auto: no game recognised yet")

    @property
    def stats(self) -> dict[str, int]:
        if self.locked is None:
            return self._own
        out = dict(self.locked.stats)
        out[f"auto: locked onto {self.locked.game}"] = 1
        return out

    @stats.setter
    def stats(self, value: dict[str, int]) -> None:
        self._own = value


class AutoSource(_ThreadedSource):
    """Listens on the default port of every game that sends on its own and locks onto the
    first game whose datagrams decode into a sample (``--source auto``).

    Until then each datagram is offered to the decoders of the games expected on its port
    (counted as ``auto: no game recognised yet`` when none takes it); once one yields a
    sample, the other ports are closed and ``game`` names the game (``stats`` gains
    ``auto: locked onto GAME``). Games that must be asked (Assetto Corsa, Gran Turismo 7)
    are not candidates: they need their address (``ac@HOST``, ``gt7@CONSOLE``). Several
    games share a port (F1 and DiRT on 20777; X-Plane 12 and 11 on 49005, where auto reads
    X-Plane 12's layout).

    Parameters
    ----------
    host : str
        Address to bind (127.0.0.1 by default, 0.0.0.0 for every interface).
    history : int
        Samples kept for :meth:`drain`.
    listen : sequence of (port, games), optional
        Ports to bind and the games expected on each (default: every passive game's default
        port; port 0 binds a free one, for tests).

    Raises
    ------
    TransportError
        When no port at all can be bound (the busy ones are listed in ``busy_ports``).
    """

    def __init__(
        self,
        host: str = DEFAULT_HOST,
        *,
        history: int = 1024,
        listen: Sequence[tuple[int, Sequence[str]]] | None = None,
    ) -> None:
        if listen is None:
            by_port: dict[int, list[str]] = {}
            for g, info in sorted(GAMES.items()):
                if not info.asked:
                    by_port.setdefault(info.default_port, []).append(g)
            listen = sorted(by_port.items())
        auto = _AutoDecoder(listen)
        super().__init__(auto, history)
        self.host = host
        self.port = 0
        self.ports: dict[int, list[str]] = {}
        self.busy_ports: list[int] = []
        self._socks: dict[int, socket.socket] = {}
        for port, games in listen:
            try:
                sock = _bind_udp(host, port)
            except TransportError:
                self.busy_ports.append(port)
                continue
            sock.setblocking(False)
            bound = sock.getsockname()[1]
            self._socks[bound] = sock
            self.ports[bound] = list(games)
            auto.by_port[bound] = [auto.candidates[g] for g in games]
        if not self._socks:
            raise TransportError(
                f"auto: no game port could be bound on {host} (busy: {self.busy_ports})"
            )
        self._start("motioncue-telemetry-auto")

    @property
    def game(self) -> str:
        """``auto`` until a game is recognised, then that game's name."""
        return self.decoder.game

    @game.setter
    def game(self, value: str) -> None:
        pass  # set by the base class; the decoder's name is the truth

    def _run(self) -> None:
        sel = selectors.DefaultSelector()
        for port, sock in self._socks.items():
            sel.register(sock, selectors.EVENT_READ, port)
        buf = bytearray(MAX_DATAGRAM + 1)
        clock = time.perf_counter
        dec = self.decoder
        assert isinstance(dec, _AutoDecoder)
        try:
            while not self._stop.is_set():
                for key, _ev in sel.select(timeout=TALK_PERIOD_S):
                    rx = self._socks.get(int(key.data))
                    if rx is None:  # closed when the source locked, in this same batch
                        continue
                    try:
                        n = rx.recv_into(buf)
                    except BlockingIOError:
                        continue
                    except OSError:
                        self._errors += 1
                        continue
                    t = clock()
                    dec.port = int(key.data)
                    was_locked = dec.locked is not None
                    try:
                        self._deliver(bytes(buf[:n]), t)
                    except Exception:  # never let the receiver thread die
                        self._errors += 1
                    if not was_locked and dec.locked is not None:
                        self.port = int(key.data)
                        for port, other in list(self._socks.items()):
                            if port != self.port:
                                sel.unregister(other)
                                other.close()
                                del self._socks[port]
        finally:
            sel.close()
            for sock in self._socks.values():
                sock.close()

    def __repr__(self) -> str:
        where = f"port {self.port}" if self.port else f"ports {sorted(self.ports)}"
        return f"AutoSource({self.game!r}, udp://{self.host}, {where})"


def open_source(spec: str, *, history: int = 1024) -> TelemetrySource | ReplaySource | AutoSource:
    """Open a live or replay telemetry source from a spec string (see module docstring).

    Raises
    ------
    ConfigError
        Unknown game, bad port or bad replay option.
    TransportError
        The port cannot be bound or the file cannot be read.
    ProtocolError
        The file is not a recording.
    """
    if spec.startswith("replay:"):
        rest = spec[len("replay:") :]
        path, _, query = rest.partition("?")
        if not path:
            raise ConfigError(f"source {spec!r}: replay needs a file, replay:FILE[?speed=X]")
        opts = parse_qs(query, keep_blank_values=True, strict_parsing=False)
        unknown = set(opts) - {"speed"}
        if unknown:
            raise ConfigError(f"source {spec!r}: unknown replay option(s) {sorted(unknown)}")
        speed = 1.0
        if "speed" in opts:
            text = opts["speed"][-1]
            try:
                speed = float(text)
            except ValueError:
                raise ConfigError(f"source {spec!r}: speed {text!r} is not a number") from None
        return ReplaySource(path, speed, history=history)
    game, host, port = parse_live_spec(spec)
    if game == AUTO:
        return AutoSource(host, history=history)
    return TelemetrySource(game, port, host, history=history, peer=split_peer(spec)[1])
