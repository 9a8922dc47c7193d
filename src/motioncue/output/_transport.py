"""One interface for every link to a controller, addressed by the URLs of conventions.md.

``udp://HOST:PORT``, ``serial:///dev/ttyUSB0?baud=19200``, ``pcap:PATH``, ``file:PATH``.
Framing (how messages are delimited on a byte stream) and payload (what a message means) are
not the transport's business; a transport moves whole messages (datagrams) or bytes.
"""

from __future__ import annotations

import abc
import ipaddress
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import ClassVar
from urllib.parse import parse_qs, urlsplit

from .._errors import ConfigError, TransportError

__all__ = ["Transport", "TransportURL", "parse_target"]


@dataclass(frozen=True)
class TransportURL:
    """A parsed target URL.

    Attributes
    ----------
    scheme : str
        ``udp``, ``serial``, ``pcap`` or ``file``.
    host : str
        UDP host (empty otherwise).
    port : int
        UDP port (0 otherwise).
    path : str
        Device or file path (empty for UDP).
    options : dict[str, str]
        Query options (``baud=19200``).
    """

    scheme: str
    host: str = ""
    port: int = 0
    path: str = ""
    options: dict[str, str] = field(default_factory=dict)


_SCHEMES = ("udp", "serial", "pcap", "file")


def _udp_hint(url: str) -> str:
    """``"; did you mean udp://..."`` when ``url`` is a bare address (``192.168.15.201``,
    ``192.168.15.201:7408``, ``localhost:7408``), else ``""``."""
    host, sep, port = url.rpartition(":") if ":" in url else (url, "", "")
    if sep and not port.isdigit():
        return ""
    if host == "localhost":
        is_host = True
    else:
        try:
            ipaddress.ip_address(host.strip("[]"))
            is_host = True
        except ValueError:
            is_host = bool(sep) and bool(re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9.-]*", host))
    if not is_host:
        return ""
    return f"; did you mean udp://{host}:{port if sep else 'PORT'}?"


def parse_target(url: str) -> TransportURL:
    """Parse a target URL, rejecting anything not of the four forms with a clear message
    (a bare ``HOST[:PORT]`` is answered with the ``udp://`` spelling)."""
    if ":" not in url:
        raise ConfigError(
            f"target {url!r} is not a URL; use one of udp://HOST:PORT, "
            f"serial:///dev/ttyUSB0?baud=19200, pcap:PATH, file:PATH{_udp_hint(url)}"
        )
    scheme, rest = url.split(":", 1)
    scheme = scheme.lower()
    if scheme not in _SCHEMES:
        raise ConfigError(
            f"target {url!r}: scheme {scheme!r} unknown; allowed: {', '.join(_SCHEMES)}"
            f"{_udp_hint(url)}"
        )
    if scheme in ("pcap", "file"):
        path = rest[2:] if rest.startswith("//") else rest
        if not path:
            raise ConfigError(f"target {url!r}: empty path")
        return TransportURL(scheme, path=path)
    parts = urlsplit(url)
    options = {k: v[-1] for k, v in parse_qs(parts.query).items()}
    if scheme == "udp":
        try:
            port = parts.port
        except ValueError as exc:
            raise ConfigError(f"target {url!r}: bad port") from exc
        if not parts.hostname or port is None:
            raise ConfigError(f"target {url!r}: expected udp://HOST:PORT")
        return TransportURL(scheme, host=parts.hostname, port=port, options=options)
    if not parts.path:
        raise ConfigError(f"target {url!r}: expected serial:///dev/ttyXXX?baud=19200")
    return TransportURL(scheme, path=parts.path, options=options)


class Transport(abc.ABC):
    """A link that sends and receives whole messages.

    Implementations wrap OS errors in :class:`~motioncue.TransportError` (``raise ... from``).

    Attributes
    ----------
    answers : bool
        Whether :meth:`request` can ask the far end and wait for its answer (a live
        two-way link); send-only links (``file:``, ``pcap:``) say False.
    silence_s : float or None
        Longest silence of the controller a job sending frames accepts (s); None: not
        watched (links that carry no answers).
    address : tuple of (str, int) or None
        The far end's address where the link has one.
    """

    answers: ClassVar[bool] = False
    silence_s: float | None = None
    address: tuple[str, int] | None = None

    @abc.abstractmethod
    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        """Send one message; ``t_s`` is the frame time (pcap time stamps), ignored by links."""

    def recv(self, timeout_s: float) -> bytes | None:
        """Receive one message, or ``None`` after ``timeout_s``. Send-only links return None."""
        return None

    def request(
        self,
        data: bytes,
        accept: Callable[[bytes], bool],
        *,
        timeout_s: float | None = None,
        retries: int | None = None,
    ) -> bytes:
        """Send ``data`` and return the first answer ``accept`` takes (links whose
        :attr:`answers` is True); others raise :class:`~motioncue.TransportError`."""
        raise TransportError(f"{type(self).__name__} cannot ask and wait for an answer")

    def close(self) -> None:  # noqa: B027 - optional hook
        """Release the link."""

    def __enter__(self) -> Transport:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
