"""A port for a test that must name it before the program under test binds it.

The usual trick (bind port 0, read the port, close, hand the number on) races: between the
close and the program's own bind, any socket bound to port 0 on the machine (an emulator
process, a sender, another worker's test) may be given the same number by the kernel, and
the program then fails with "Address already in use" (seen once in a whole-suite run at
load 10). Ports outside the kernel's ephemeral range are never handed out for port 0, so
:func:`free_port` picks one there, in a block of its own for each pytest-xdist worker and
from a start drawn per process, and checks that UDP and TCP can both bind it now.
"""

from __future__ import annotations

import itertools
import os
import random
import socket

_LOW_PORT = 20000  # below: ports well-known services commonly use
_TRIED: set[int] = set()  # handed out (or found taken) in this process


def _ephemeral_range() -> tuple[int, int]:
    try:
        with open("/proc/sys/net/ipv4/ip_local_port_range") as f:
            lo, hi = (int(v) for v in f.read().split())
        return lo, hi
    except (OSError, ValueError):
        return 32768, 60999  # Linux's default


def _pool() -> range:
    """Ports outside the ephemeral range: below it if there is room, else above it."""
    lo, hi = _ephemeral_range()
    if lo - _LOW_PORT >= 2000:
        return range(_LOW_PORT, lo)
    return range(hi + 1, 65536)


def _block(pool: range) -> range:
    """This xdist worker's share of ``pool`` (all of it outside xdist)."""
    worker = os.environ.get("PYTEST_XDIST_WORKER", "gw0")
    count = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1") or 1)
    index = int(worker[2:]) if worker[2:].isdigit() else 0
    size = len(pool) // max(count, 1)
    start = pool.start + (index % max(count, 1)) * size
    return range(start, start + size)


def _binds(port: int) -> bool:
    for kind in (socket.SOCK_DGRAM, socket.SOCK_STREAM):
        with socket.socket(socket.AF_INET, kind) as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                return False
    return True


def free_port() -> int:
    """A port on 127.0.0.1 that UDP and TCP can both bind now, never one the kernel hands
    out for port 0, not returned before in this process.

    Returns
    -------
    int
        The port number.

    Raises
    ------
    RuntimeError
        If no port of this worker's block can be bound.
    """
    block = _block(_pool())
    first = random.Random(os.getpid()).randrange(len(block))
    for k in itertools.chain(range(first, len(block)), range(first)):
        port = block.start + k
        if port in _TRIED:
            continue
        _TRIED.add(port)
        if _binds(port):
            return port
    raise RuntimeError(f"no free port in {block.start}-{block.stop - 1}")
