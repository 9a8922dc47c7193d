"""The test helper that names ports ahead of the program under test (tests/_ports.py)."""

from __future__ import annotations

import socket

from _ports import _ephemeral_range, free_port


def test_free_ports_are_outside_the_kernels_range_distinct_and_bindable() -> None:
    lo, hi = _ephemeral_range()
    ports = [free_port() for _ in range(20)]
    assert len(set(ports)) == len(ports)
    for port in ports:
        assert not lo <= port <= hi and 1024 < port < 65536
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", port))


def test_a_port_in_use_is_not_handed_out() -> None:
    held = []
    try:
        for _ in range(5):
            s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            port = free_port()
            s.bind(("127.0.0.1", port))
            held.append(s)
        # every port now held: the next ones differ and bind
        taken = {s.getsockname()[1] for s in held}
        assert free_port() not in taken
    finally:
        for s in held:
            s.close()
