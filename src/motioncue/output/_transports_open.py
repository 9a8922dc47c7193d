"""``open_transport(url)``: one entry point for every target URL of conventions.md."""

from __future__ import annotations

import importlib
from typing import Any

from .._errors import ConfigError
from ._transport import Transport, TransportURL, parse_target

__all__ = ["open_transport"]

# scheme -> (module, class); each class has ``from_url(url, **options)``. The serial
# transport lives with the EasySmc work and is imported only when a serial URL is opened.
_SCHEMES: dict[str, tuple[str, str]] = {
    "udp": ("._transports_udp", "UdpTransport"),
    "pcap": ("._transports_file", "PcapTransport"),
    "file": ("._transports_file", "FileTransport"),
    "serial": ("._transport_serial", "SerialTransport"),
}


def open_transport(url: str | TransportURL, **options: Any) -> Transport:
    """Open the link a target URL names.

    Parameters
    ----------
    url : str or TransportURL
        ``udp://HOST:PORT[?local_port=8410&timeout_ms=250&retries=2]``, ``pcap:PATH``,
        ``file:PATH``, ``serial:///dev/ttyUSB0?baud=19200``.
    **options
        Passed to the transport: for ``pcap`` ``src``/``dst`` (``"ip:port"``) and
        ``epoch_s``; for ``udp`` ``local_port``, ``timeout_s``, ``retries`` (the URL's
        query, when it sets the same option, wins).

    Raises
    ------
    ConfigError
        The URL is malformed or an option is invalid.
    TransportError
        The link cannot be opened (the OS error is chained).
    """
    parsed = parse_target(url) if isinstance(url, str) else url
    module_name, class_name = _SCHEMES[parsed.scheme]
    try:
        module = importlib.import_module(module_name, __package__)
    except ModuleNotFoundError as exc:
        raise ConfigError(
            f"target {url!r}: the {parsed.scheme} transport is not installed ({exc.name})"
        ) from exc
    cls = getattr(module, class_name)  # the scheme's transport class, imported by name
    transport: Transport = cls.from_url(parsed, **options)
    return transport
