"""The game registry: name -> default UDP port and decoder factory.

Adding a game is one small module: a :class:`~motioncue.telemetry._sample.Decoder` subclass
that converts the game's axes and units, and a call to :func:`register_game` at import time;
then one name in ``_GAME_MODULES`` of the package ``__init__``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from .._errors import ConfigError
from ._sample import Decoder

__all__ = ["GAMES", "GameInfo", "decoder_for", "register_game"]


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
    """

    name: str
    default_port: int
    decoder: Callable[[], Decoder]
    title: str

    def __post_init__(self) -> None:
        if not self.name or not self.name.isidentifier() or self.name != self.name.lower():
            raise ConfigError(f"game name {self.name!r} must be a lower-case identifier")
        if not 1 <= self.default_port <= 65535:
            raise ConfigError(
                f"default_port = {self.default_port!r} for {self.name!r} is outside 1..65535"
            )
        if self.name == "replay":
            raise ConfigError("game name 'replay' is reserved for recorded files")


GAMES: dict[str, GameInfo] = {}
"""Registered games by name (``"f1"``, ``"forza"``, ``"beamng"``)."""


def register_game(info: GameInfo) -> GameInfo:
    """Add a game to :data:`GAMES`; re-registering the same name replaces it."""
    GAMES[info.name] = info
    return info


def decoder_for(game: str) -> Decoder:
    """A fresh decoder for a registered game.

    Raises
    ------
    ConfigError
        If ``game`` is not registered (the message lists the registered names).
    """
    info = GAMES.get(game)
    if info is None:
        raise ConfigError(f"unknown game {game!r}; known games: {', '.join(sorted(GAMES))}")
    return info.decoder()
