"""--source auto: listens on several ports, locks onto the first game whose datagrams decode,
closes the other ports and says which game it locked onto; random traffic only counted."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable

import pytest

from motioncue._errors import ConfigError
from motioncue.telemetry import open_source
from motioncue.telemetry._lfs import OutSimMain
from motioncue.telemetry._rbr import RBRCar
from motioncue.telemetry._source import AutoSource, parse_live_spec


def _wait_for(cond: Callable[[], bool], timeout_s: float = 3.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return bool(cond())


def _lfs() -> bytes:
    return OutSimMain((0.0, 0.0, 0.1), 0.0, 0.0, 0.0, (1.0, 2.0, 0.0), (0.0, 20.0, 0.0)).outsim2()


def test_auto_locks_onto_the_game_that_decodes_and_closes_the_other_ports() -> None:
    src = AutoSource("127.0.0.1", listen=[(0, ["rbr"]), (0, ["lfs", "dcs"])])
    try:
        assert src.game == "auto" and len(src.ports) == 2
        lfs_port = next(p for p, g in src.ports.items() if "lfs" in g)
        rbr_port = next(p for p, g in src.ports.items() if g == ["rbr"])
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(b"not a game" * 10, ("127.0.0.1", rbr_port))  # foreign: counted only
            tx.sendto(bytes(664), ("127.0.0.1", lfs_port))  # RBR's size, on LFS's port
            assert _wait_for(lambda: src.stats["datagrams"] == 2)
            assert src.game == "auto" and src.latest() is None
            assert src.stats == {"datagrams": 2, "samples": 0, "receive errors": 0,
                                 "auto: no game recognised yet": 2}  # fmt: skip
            tx.sendto(_lfs(), ("127.0.0.1", lfs_port))
            assert _wait_for(lambda: src.game == "lfs")
            s = src.latest()
            assert s is not None and s.game == "lfs"
            assert src.port == lfs_port and src.stats["auto: locked onto lfs"] == 1
            assert "lfs" in repr(src)
            # the other port is closed: RBR datagrams there no longer arrive
            rbr = RBRCar(1, 0.0, 2, 50.0, (0.0, 0.0, 0.0), (0.0,) * 6, (0.0,) * 6, 3000.0)
            tx.sendto(rbr.pack(), ("127.0.0.1", rbr_port))
            for _ in range(3):
                tx.sendto(_lfs(), ("127.0.0.1", lfs_port))
            assert _wait_for(lambda: src.stats["datagrams"] == 6)
            time.sleep(0.1)
            assert src.game == "lfs" and src.stats["sample"] == 4
            assert src.stats["datagrams"] == 6
    finally:
        src.close()


def test_auto_specs() -> None:
    assert parse_live_spec("auto") == ("auto", "127.0.0.1", 0)
    assert parse_live_spec("auto:0.0.0.0") == ("auto", "0.0.0.0", 0)
    with pytest.raises(ConfigError, match="auto or auto:HOST"):
        parse_live_spec("auto:1.2.3.4:5")


def test_open_source_auto_binds_what_it_can() -> None:
    """The default ports may be taken on a shared machine: auto binds the free ones and
    lists the busy ones; asked games (ac, gt7) are not candidates."""
    src = open_source("auto")
    try:
        assert isinstance(src, AutoSource)
        games = {g for gs in src.ports.values() for g in gs}
        assert "ac" not in games and "gt7" not in games
        assert set(src.ports) | set(src.busy_ports) >= {20777, 4123, 6776, 20800}
    finally:
        src.close()
