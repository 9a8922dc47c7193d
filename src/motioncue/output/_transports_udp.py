"""``udp://HOST:PORT``: datagrams to a controller, with request/reply for commands.

Frames are sent and forgotten (a late frame is worth nothing); register access and
commands use :meth:`UdpTransport.request`, which waits for an accepted reply and retries.
URL options: ``local_port`` (IMAX PA24: the host must send from this port),
``timeout_ms`` (default 250), ``retries`` (default 2) and ``silence_ms`` (default 500: a
job sending frames stops when the controller has been silent this long, see
the link watch; 0 = not watched, for a capture or a
sniffer that never answers).
"""

from __future__ import annotations

import select
import socket
import time
from collections.abc import Callable
from typing import Any

from .._errors import ConfigError, TransportError
from ._transport import Transport, TransportURL

__all__ = ["UdpTransport"]


def _int_option(url: TransportURL, key: str, default: int, lo: int, hi: int) -> int:
    raw = url.options.get(key)
    if raw is None:
        return default
    try:
        value = int(raw)
    except ValueError:
        value = lo - 1
    if not lo <= value <= hi:
        raise ConfigError(f"target option {key}={raw!r}; allowed: an integer in [{lo}, {hi}]")
    return value


class UdpTransport(Transport):
    """A UDP socket aimed at one controller address.

    Parameters
    ----------
    host, port : str, int
        Controller address (``255.255.255.255`` broadcasts, as the MBOX captures do).
    local_port : int
        Port to send from (0 = any).
    timeout_s : float
        Reply timeout of :meth:`request`.
    retries : int
        Extra attempts of :meth:`request` after a timeout.
    silence_s : float or None
        Longest silence of the controller a job sending frames accepts (s); None: not
        watched.
    """

    answers = True
    address: tuple[str, int]
    silence_s: float | None

    def __init__(
        self,
        host: str,
        port: int,
        *,
        local_port: int = 0,
        timeout_s: float = 0.25,
        retries: int = 2,
        silence_s: float | None = 0.5,
    ) -> None:
        if silence_s is not None and not (0.0 < silence_s <= 600.0):
            raise ConfigError(f"silence_s = {silence_s!r}; allowed: None or (0, 600] s")
        self.silence_s = silence_s
        self.address = (host, port)
        self.timeout_s = timeout_s
        self.retries = retries
        try:
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            if host == "255.255.255.255" or host.endswith(".255"):
                sock.setsockopt(socket.SOL_SOCKET, socket.SO_BROADCAST, 1)
            sock.bind(("", local_port))
            self.address = (socket.gethostbyname(host), port)
        except OSError as exc:
            raise TransportError(f"cannot open UDP socket for {host}:{port}: {exc}") from exc
        self._sock = sock

    @classmethod
    def from_url(cls, url: TransportURL, **overrides: Any) -> UdpTransport:
        """Open from a parsed URL; keyword ``overrides`` (``local_port``, ``timeout_s``,
        ``retries``) apply where the URL's query does not set the option."""
        options: dict[str, Any] = {
            "local_port": _int_option(url, "local_port", 0, 0, 65535),
            "timeout_s": _int_option(url, "timeout_ms", 250, 1, 60000) / 1000.0,
            "retries": _int_option(url, "retries", 2, 0, 100),
            "silence_s": (_int_option(url, "silence_ms", 500, 0, 600000) / 1000.0) or None,
        }
        given = {
            "local_port": "local_port",
            "timeout_s": "timeout_ms",
            "retries": "retries",
            "silence_s": "silence_ms",
        }
        for key, value in overrides.items():
            if key not in given:
                raise ConfigError(f"udp transport: unknown option {key!r}")
            if given[key] not in url.options:
                options[key] = value
        return cls(url.host, url.port, **options)

    @property
    def local_port(self) -> int:
        return int(self._sock.getsockname()[1])

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        """Send one datagram (``t_s`` is ignored: it leaves now)."""
        try:
            self._sock.sendto(data, self.address)
        except OSError as exc:
            raise TransportError(f"UDP send to {self.address[0]}:{self.address[1]}: {exc}") from exc

    def recv(self, timeout_s: float) -> bytes | None:
        """One datagram from anyone, or ``None`` after ``timeout_s``."""
        try:
            ready, _, _ = select.select([self._sock], [], [], max(0.0, timeout_s))
            if not ready:
                return None
            data, _peer = self._sock.recvfrom(65536)
            return data
        except OSError as exc:
            raise TransportError(f"UDP receive: {exc}") from exc

    def drain(self) -> int:
        """Discard datagrams already waiting (stale replies); returns how many."""
        n = 0
        while self.recv(0.0) is not None:
            n += 1
        return n

    def request(
        self,
        data: bytes,
        accept: Callable[[bytes], bool],
        *,
        timeout_s: float | None = None,
        retries: int | None = None,
    ) -> bytes:
        """Send ``data`` and return the first reply ``accept`` takes; retry on timeout.

        Raises
        ------
        TransportError
            No accepted reply after ``1 + retries`` attempts.
        """
        timeout = self.timeout_s if timeout_s is None else timeout_s
        tries = 1 + (self.retries if retries is None else retries)
        self.drain()
        for _ in range(tries):
            self.send(data)
            deadline = time.monotonic() + timeout
            while True:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                reply = self.recv(left)
                if reply is not None and accept(reply):
                    return reply
        raise TransportError(
            f"no reply from {self.address[0]}:{self.address[1]} after {tries} attempt(s) of "
            f"{timeout * 1000:.0f} ms"
        )

    def close(self) -> None:
        self._sock.close()
