"""The test helper that names ports ahead of the program under test (tests/_ports.py)."""

from __future__ import annotations

import socket

import pytest

import _ports
from _ports import _ephemeral_range, free_port


def test_free_ports_are_outside_the_kernels_range_distinct_and_bindable() -> None:
    lo, hi = _ephemeral_range()
    ports = [free_port() for _ in range(20)]
    assert len(set(ports)) == len(ports)
    for port in ports:
        assert not lo <= port <= hi and 1024 < port < 65536
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", port))


def test_a_port_in_use_is_not_handed_out(monkeypatch: pytest.MonkeyPatch) -> None:
    # with nothing tried yet, this process starts its search at the same port every time:
    # hold that port, forget it was handed out, and the next search must pass it by
    monkeypatch.setattr(_ports, "_TRIED", set())
    first = free_port()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.bind(("127.0.0.1", first))
        monkeypatch.setattr(_ports, "_TRIED", set())
        second = free_port()
    assert second != first
