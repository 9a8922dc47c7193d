"""``serial://`` transport through pyserial (``serial:///dev/ttyUSB0?baud=19200``).

A serial port is a byte stream: :meth:`SerialTransport.send` writes bytes and
:meth:`SerialTransport.recv` returns whatever bytes arrived (framing is the controller
module's business). OS and pyserial errors become :class:`~motioncue.TransportError`
raised ``from`` the cause.
"""

from __future__ import annotations

from typing import Any, Protocol

from .._errors import ConfigError, TransportError
from ._transport import Transport, TransportURL, parse_target

__all__ = ["SerialTransport", "open_serial"]

_PARITY = {"N": "N", "E": "E", "O": "O"}


class _SerialPort(Protocol):
    """What :class:`SerialTransport` uses of a ``serial.Serial`` (pyserial has no types)."""

    timeout: float | None

    @property
    def in_waiting(self) -> int: ...

    def write(self, data: bytes, /) -> int | None: ...

    def flush(self) -> None: ...

    def read(self, size: int = 1, /) -> bytes: ...

    def close(self) -> None: ...


class SerialTransport(Transport):
    """A serial port opened with pyserial.

    Parameters
    ----------
    path : str
        Device (``/dev/ttyUSB0``, ``COM3``, a pseudo-terminal path).
    baud : int
        Baud rate (the EasySmc 2300 allows 2400, 4800, 9600, 19200).
    bytesize, parity, stopbits
        Character format (8N1 by default, as the EasySmc manual says).
    """

    def __init__(
        self, path: str, baud: int = 19200, bytesize: int = 8, parity: str = "N", stopbits: int = 1
    ) -> None:
        import serial  # pyserial: imported here so `import motioncue` stays light

        if baud <= 0:
            raise ConfigError(f"serial baud {baud} must be positive")
        self.path = path
        self.baud = baud
        self.bytes_sent = 0
        self.bytes_received = 0
        try:
            self._port: _SerialPort = serial.Serial(
                port=path,
                baudrate=baud,
                bytesize=bytesize,
                parity=_PARITY[parity],
                stopbits=stopbits,
                timeout=0,
                write_timeout=2.0,
                xonxoff=False,
                rtscts=False,
            )
        except (serial.SerialException, OSError, ValueError) as exc:
            raise TransportError(f"cannot open serial port {path!r} at {baud} baud: {exc}") from exc

    @classmethod
    def from_url(cls, url: str | TransportURL, **options: Any) -> SerialTransport:
        """Open ``serial://PATH?baud=..`` (the ``open_transport`` entry point).

        ``options`` may override ``baud``, ``bytesize``, ``parity``, ``stopbits``.
        """
        target = parse_target(url) if isinstance(url, str) else url
        if target.scheme != "serial":
            raise ConfigError(f"not a serial target: {url!r}")
        opts = {**target.options, **{k: str(v) for k, v in options.items()}}
        try:
            baud = int(opts.pop("baud", "19200"))
            bytesize = int(opts.pop("bytesize", "8"))
            stopbits = int(opts.pop("stopbits", "1"))
        except ValueError as exc:
            raise ConfigError(f"target {url!r}: baud/bytesize/stopbits must be integers") from exc
        parity = opts.pop("parity", "N").upper()
        if parity not in _PARITY:
            raise ConfigError(f"target {url!r}: parity {parity!r}; allowed N | E | O")
        if opts:
            raise ConfigError(
                f"target {url!r}: unknown option(s) {', '.join(sorted(opts))}; "
                "known: baud, bytesize, parity, stopbits"
            )
        return cls(target.path, baud, bytesize, parity, stopbits)

    def send(self, data: bytes, *, t_s: float | None = None) -> None:
        import serial

        try:
            self._port.write(data)
            self._port.flush()
        except (serial.SerialException, OSError) as exc:
            raise TransportError(f"serial write to {self.path!r} failed: {exc}") from exc
        self.bytes_sent += len(data)

    def recv(self, timeout_s: float) -> bytes | None:
        """Bytes that arrived within ``timeout_s`` (at least one), or None."""
        import serial

        try:
            self._port.timeout = max(timeout_s, 0.0)
            first = self._port.read(1)
            if not first:
                return None
            waiting = self._port.in_waiting
            rest = self._port.read(waiting) if waiting else b""
        except (serial.SerialException, OSError) as exc:
            raise TransportError(f"serial read from {self.path!r} failed: {exc}") from exc
        data = bytes(first + rest)
        self.bytes_received += len(data)
        return data

    def close(self) -> None:
        try:
            self._port.close()
        except Exception:
            pass


def open_serial(url: str | TransportURL) -> SerialTransport:
    """Open ``serial:///dev/ttyUSB0?baud=19200`` (options: baud, bytesize, parity, stopbits)."""
    return SerialTransport.from_url(url)
