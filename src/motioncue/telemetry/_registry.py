"""The game registry: name -> default UDP port, decoder factory and (optionally) encoder.

Adding a game is one small module: a :class:`~motioncue.telemetry._sample.Decoder` subclass
that converts the game's axes and units and names the game, its default port and title
(class attributes), and ``register_game(GameInfo.of(TheDecoder, encoder))`` at import time
(in the package: one name in ``_GAME_MODULES`` of its ``__init__``; outside it: a plugin
module named in ``MOTIONCUE_PLUGINS``). The command line builds its game lists from this
registry (``bridge --source``, ``record --source``, ``send-telemetry --game``, ``list
games``), so a registered game appears there with nothing else to edit.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .._errors import ConfigError
from .._registry import register_entry, registered_entry
from ._sample import Decoder, Vec3

__all__ = [
    "GAMES",
    "Encoder",
    "GameInfo",
    "decoder_for",
    "encodable_games",
    "game_info",
    "games_text",
    "register_game",
]

Encoder = Callable[[int, float, Vec3, Vec3], list[bytes]]
"""``encoder(k, t_s, f, w)``: the datagrams a game sends for sample ``k`` at game time
``t_s`` (s) of a level vehicle with specific force ``f`` (m/s^2) and angular velocity ``w``
(rad/s), ISO 8855 body axes, in sending order (see :func:`~motioncue.telemetry._encode.
encode_motion`)."""


@dataclass(frozen=True, slots=True)
class GameInfo:
    """What the registry knows about one game.

    Attributes
    ----------
    name : str
        Registered name, used in source specs (``"f1:20777"``) and recording files.
    default_port : int
        UDP port the game sends to by default (or the community's usual choice).
    decoder : callable
        Factory returning a fresh, stateful :class:`Decoder`.
    title : str
        Human-readable list of the games and formats covered.
    encoder : callable or None
        :data:`Encoder` writing the game's datagrams from vehicle motion, which its decoder
        reads back (``send-telemetry``); None when the game cannot be imitated that way.
    asked : bool
        The game sends telemetry only when asked: its decoders are
        :class:`motioncue.telemetry.Requester` (requests, farewell, ``PEER_PORT``,
        ``LISTEN_PORT``), a live source talks to it and ``GAME@ADDRESS`` names where; the
        ``auto`` source does not listen for it. False: it sends on its own.
    """

    name: str
    default_port: int
    decoder: Callable[[], Decoder]
    title: str
    encoder: Encoder | None = None
    asked: bool = False

    @classmethod
    def of(
        cls, decoder: type[Decoder], encoder: Encoder | None = None, *, asked: bool = False
    ) -> GameInfo:
        """The game a decoder class declares: its ``game`` (the name), ``default_port`` and
        ``title`` class attributes, the class as the decoder factory, ``encoder`` and
        ``asked``."""
        return cls(decoder.game, decoder.default_port, decoder, decoder.title, encoder, asked)

    def __post_init__(self) -> None:
        if not self.name or not self.name.isidentifier() or self.name != self.name.lower():
            raise ConfigError(f"game name {self.name!r} must be a lower-case identifier")
        if not 1 <= self.default_port <= 65535:
            raise ConfigError(
                f"default_port = {self.default_port!r} for {self.name!r} is outside 1..65535"
            )
        if self.name == "replay":
            raise ConfigError("game name 'replay' is reserved for recorded files")
        if not callable(self.decoder):
            raise ConfigError(f"game {self.name!r}: decoder is not callable")
        if self.encoder is not None and not callable(self.encoder):
            raise ConfigError(f"game {self.name!r}: encoder is not callable")
        if not isinstance(self.asked, bool):
            raise ConfigError(f"game {self.name!r}: asked = {self.asked!r} must be true or false")


GAMES: dict[str, GameInfo] = {}
"""Registered games by name (``"f1"``, ``"forza"``, ``"beamng"``), in registration order."""


def register_game(info: GameInfo) -> GameInfo:
    """Add a game to :data:`GAMES`; re-registering the same name replaces it."""
    return register_entry(GAMES, info, GameInfo, "register_game")


def decoder_for(game: str) -> Decoder:
    """A fresh decoder for a registered game.

    Raises
    ------
    ConfigError
        If ``game`` is not registered (the message lists the registered names).
    """
    return game_info(game).decoder()


def game_info(game: str) -> GameInfo:
    """The registered game ``game``.

    Raises
    ------
    ConfigError
        If ``game`` is not registered (the message lists the registered names).
    """
    return registered_entry(GAMES, game, "game", "games")


def encodable_games() -> tuple[str, ...]:
    """The registered games with an encoder, in registration order (``send-telemetry``)."""
    return tuple(name for name, info in GAMES.items() if info.encoder is not None)


def games_text(*, ports: bool = True, encodable: bool = False) -> str:
    """The registered games for help texts: ``"f1 (port 20777), forza (port 5301), ..."``.

    Parameters
    ----------
    ports
        Give each game's default port.
    encodable
        Only the games with an encoder.
    """
    names = encodable_games() if encodable else tuple(GAMES)
    if not ports:
        return ", ".join(names)
    return ", ".join(f"{n} (port {GAMES[n].default_port})" for n in names)
