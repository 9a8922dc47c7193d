"""Helpers the ``send`` / ``inspect`` hooks of the UDP controller kinds share."""

from __future__ import annotations

import abc
import dataclasses
import enum
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar, Protocol, TextIO, TypeVar, runtime_checkable

from .._errors import ConfigError, ProtocolError
from ._registry import ControllerKind, Inspection, Refusals, for_type
from ._transport import Transport, TransportURL
from ._udp_common import WHO_ALL, WireMessage, format_who

if TYPE_CHECKING:
    from .._config import ConfigReader
    from ._controller_api import Controller, FrameEncoder, PulseLimits
    from ._registry import Emulator

__all__ = [
    "VERBS",
    "RegisterLink",
    "SendWords",
    "describe",
    "exchange",
    "need_args",
    "park",
    "parse_bits",
    "parse_value",
    "positions_from_words",
    "require_request",
    "split_datagrams",
    "transport_options",
    "udp_controller_kind",
]

VERBS = ("estop", "reset", "home", "park", "outputs", "read", "write")
"""The ``motioncue send`` verbs every UDP controller kind answers."""


@runtime_checkable
class FunctionCoded(Protocol):
    """A message with a function code (every IMAX / MBOX message but the IMAX status
    report, whose function is implied by its confirm code)."""

    @property
    def function(self) -> int: ...


class Request(FunctionCoded, WireMessage, Protocol):
    """A request a ``send`` word sends: encoded, and answered by function code."""


class UdpAddressed(Protocol):
    """A controller description with the host and controller addresses of its config."""

    @property
    def controller_address(self) -> tuple[str, int]: ...

    @property
    def host_address(self) -> tuple[str, int]: ...


class Parkable(Protocol):
    """What ``send park`` needs of a UDP controller description."""

    @property
    def n_axes(self) -> int: ...

    @property
    def catch_up_factor(self) -> float: ...

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits: ...

    def frame_encoder(
        self, absolute_time: bool = True, *, t0_s: float | None = None
    ) -> FrameEncoder: ...


def transport_options(
    controller: UdpAddressed, url: TransportURL, *, fixed_source_port: bool
) -> dict[str, object]:
    """Options for ``open_transport`` taken from the controller's addresses.

    ``pcap:`` packets are written from the host address to the controller address of the
    config; a ``udp://`` target that is not loopback sends from the host port when the
    controller only accepts that source port (IMAX PA24).
    """
    if url.scheme == "pcap":
        return {"src": controller.host_address, "dst": controller.controller_address}
    loopback = url.host in ("localhost", "::1") or url.host.startswith("127.")
    if url.scheme == "udp" and fixed_source_port and not loopback:
        return {"local_port": controller.host_address[1]}
    return {}


def _fmt(name: str, value: object) -> str:
    if isinstance(value, enum.Enum):
        return value.name
    if name.startswith("who_") and isinstance(value, int):
        return format_who(value)
    if isinstance(value, tuple):
        return "[" + ",".join(str(v) for v in value) + "]"
    if isinstance(value, int) and name in (
        "base_dout",
        "ext_dout",
        "port_out",
        "port",
        "outputs",
        "inputs",
        "function",
    ):
        return f"0x{value:X}"
    return str(value)


def describe(msg: object) -> str:
    """One line naming a decoded message (a dataclass) and its fields."""
    name = type(msg).__name__
    parts = []
    if not dataclasses.is_dataclass(msg):
        return f"{name} {msg!r}"
    if isinstance(msg, FunctionCoded) and not any(
        f.name == "function" for f in dataclasses.fields(msg)
    ):
        parts.append(f"function=0x{msg.function:04X}")
    for f in dataclasses.fields(msg):
        value = getattr(msg, f.name)
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            parts.append(describe(value))
            continue
        parts.append(f"{f.name}={_fmt(f.name, value)}")
    return f"{name} " + " ".join(parts)


def parse_value(text: str, what: str = "value") -> int:
    """An integer in decimal, 0x.. hexadecimal or 0b.. binary."""
    try:
        return int(text, 0)
    except ValueError as exc:
        raise ConfigError(f"{what} {text!r} is not an integer (decimal, 0x.. or 0b..)") from exc


def parse_bits(text: str, n_bits: int) -> int:
    value = parse_value(text, "output bits")
    if not 0 <= value < 1 << n_bits:
        raise ConfigError(f"output bits {text!r}: allowed 0 .. {(1 << n_bits) - 1:#x}")
    return value


def exchange(
    transport: Transport,
    data: bytes,
    decode: Callable[[bytes], WireMessage],
    is_reply: Callable[[WireMessage], bool],
    expect_reply: bool,
    out: TextIO,
) -> WireMessage | None:
    """Send a command; if the link and the Who fields ask for one, wait for its reply.

    Prints what was sent and what came back; returns the decoded reply or ``None``.
    """
    print(f"sent {describe(decode(data))} [{data.hex().upper()}]", file=out)
    if not expect_reply or not transport.answers:
        transport.send(data)
        return None

    def accept(raw: bytes) -> bool:
        try:
            return bool(is_reply(decode(raw)))
        except ProtocolError:
            return False

    raw = transport.request(data, accept)
    reply = decode(raw)
    print(f"reply {describe(reply)}", file=out)
    return reply


def park(
    controller: Parkable,
    transport: Transport,
    current: Sequence[int],
    out: TextIO,
    *,
    period_s: float = 0.02,
    speed_fraction: float = 0.25,
    realtime: bool = True,
) -> int:
    """Bring every axis from ``current`` to 0 (the homed origin) on a raised-cosine ramp
    whose peak speed is ``speed_fraction`` of the axis limit; frames every ``period_s``.
    Returns the number of frames sent. The axis limit is the controller's own
    (``pulse_limits``), divided by its catch-up factor: the box may play the frames that much
    faster than stamped."""
    vmax = controller.pulse_limits().max_speed_pulses_s / controller.catch_up_factor
    duration = 1.0
    for p, v in zip(current, vmax, strict=True):
        if math.isfinite(v) and v > 0:
            duration = max(duration, math.pi * abs(p) / (2 * speed_fraction * v))
    n = max(1, math.ceil(duration / period_s))
    enc = controller.frame_encoder(absolute_time=False, t0_s=-period_s)
    start = time.monotonic()
    for k in range(1, n + 1):
        s = 0.5 * (1 + math.cos(math.pi * k / n))
        pulses = [round(p * s) for p in current]
        for msg in enc.encode((k - 1) * period_s, pulses):
            if realtime:
                delay = start + (k - 1) * period_s - time.monotonic()
                if delay > 0:
                    time.sleep(delay)
            transport.send(msg)
    print(f"parked: {n} frames over {n * period_s:.2f} s from {list(current)} to 0", file=out)
    return n


def need_args(verb: str, args: Sequence[str], n: int) -> None:
    """Raise :class:`ConfigError` unless ``send verb`` got exactly ``n`` arguments."""
    if len(args) != n:
        raise ConfigError(f"send {verb}: expected {n} argument(s), got {args!r}")


def require_request(transport: Transport) -> None:
    """``send park`` reads the positions first, so it needs a link that answers."""
    if not transport.answers:
        raise ConfigError("send park needs a udp:// target: it reads the positions first")


def positions_from_words(words: Sequence[int], addresses: Sequence[int]) -> list[int]:
    """Signed 32-bit positions from register pairs, low word at each address, high after."""
    out = []
    for a in addresses:
        v = words[a] | words[a + 1] << 16
        out.append(v - (1 << 32) if v & 0x80000000 else v)
    return out


def _is_reply_to(function: int) -> Callable[[WireMessage], bool]:
    """A decoded message answering request ``function`` (0x..01 -> 0x..0x, x != 1)."""
    base = function & 0xFFF0

    def is_reply(msg: WireMessage) -> bool:
        if not isinstance(msg, FunctionCoded):
            return False
        f = msg.function
        return f & 0xFFF0 == base and f != function

    return is_reply


@dataclass(frozen=True)
class RegisterLink:
    """Register reads and writes of one ``send`` command: encode the kind's request with
    the command's Who fields, send it and (when a reply is asked for) wait for the reply
    to that request, printing both to ``out``."""

    transport: Transport
    decode: Callable[[bytes], WireMessage]
    read_request: Callable[[int, int, int, int, int], Request]
    write_request: Callable[[int, int, tuple[int, ...], int, int], Request]
    who: tuple[int, int]
    out: TextIO

    def _exchange(self, msg: Request) -> WireMessage | None:
        return exchange(
            self.transport,
            msg.encode(),
            self.decode,
            _is_reply_to(msg.function),
            self.who[1] != 0,
            self.out,
        )

    def read(self, channel: int, start: int, count: int) -> WireMessage | None:
        return self._exchange(self.read_request(channel, start, count, *self.who))

    def write(self, channel: int, start: int, values: tuple[int, ...]) -> WireMessage | None:
        return self._exchange(self.write_request(channel, start, values, *self.who))


def split_datagrams(blob: bytes, size_at: Callable[[bytes, int], int]) -> list[bytes]:
    """Cut a raw ``file:`` capture (datagrams back to back) into datagrams.

    ``size_at(blob, offset)`` gives the size of the datagram starting at ``offset`` from
    its header, or raises :class:`ProtocolError`.
    """
    out = []
    off = 0
    while off < len(blob):
        size = size_at(blob, off)
        if off + size > len(blob):
            raise ProtocolError(f"byte {off}: message of {size} bytes truncated")
        out.append(blob[off : off + size])
        off += size
    return out


C = TypeVar("C")
C_contra = TypeVar("C_contra", contravariant=True)


class UdpEmulatorClass(Protocol[C_contra]):
    """An emulator class of a UDP kind: ``cls(controller, host, port, homing_time_s=...)``."""

    def __call__(
        self, controller: C_contra, host: str, port: int, *, homing_time_s: float
    ) -> Emulator: ...


def udp_controller_kind(
    name: str,
    title: str,
    description: type[C],
    read_config: Callable[[ConfigReader, str], Controller],
    emulator: UdpEmulatorClass[C],
    send: Callable[..., int],
    inspect: Inspection,
    options: Callable[[C, TransportURL], dict[str, object]],
    refusals: Refusals,
) -> ControllerKind:
    """The registry entry of an IMAX-like UDP kind: frames on ``udp://`` (or written to
    ``pcap:`` / ``file:``), an emulator on ``udp://``, the common ``send`` words
    (:data:`VERBS`), ``inspect``, and frame refusals in the replies. ``description`` is
    the kind's controller class (its hooks are refused any other kind's description)."""

    def at_url(controller: C, url: TransportURL, homing_time_s: float) -> Emulator:
        return emulator(controller, url.host, url.port, homing_time_s=homing_time_s)

    return ControllerKind(
        name,
        read_config,
        title=title,
        links=("udp", "pcap", "file"),
        emulator=for_type(description, at_url),
        send=for_type(description, send),
        send_words=VERBS,
        inspect=inspect,
        transport_options=for_type(description, options),
        refusals=refusals,
    )


Write = Callable[[int, int, tuple[int, ...]], WireMessage | None]


class SendWords(abc.ABC):
    """The ``motioncue send`` words of a UDP kind: the words, their arguments and the
    printing here, the registers each word touches in the kind's subclass.

    Parameters
    ----------
    decode, read_request, write_request
        The kind's datagram decoder and register read / write request messages.

    Attributes
    ----------
    PARK_READ : tuple of int
        ``(channel, count)`` of the register read ``park`` starts from.
    """

    PARK_READ: ClassVar[tuple[int, int]]

    def __init__(
        self,
        decode: Callable[[bytes], WireMessage],
        read_request: Callable[[int, int, int, int, int], Request],
        write_request: Callable[[int, int, tuple[int, ...], int, int], Request],
    ) -> None:
        self._messages = (decode, read_request, write_request)

    def link(self, transport: Transport, who: tuple[int, int], out: TextIO) -> RegisterLink:
        """A register link speaking the kind's messages."""
        return RegisterLink(transport, *self._messages, who, out)

    @abc.abstractmethod
    def estop(self, write: Write, args: Sequence[str]) -> WireMessage | None:
        """``estop ...`` (checks its own arguments)."""

    @abc.abstractmethod
    def reset(self, write: Write) -> WireMessage | None: ...

    @abc.abstractmethod
    def home(self, write: Write) -> WireMessage | None: ...

    @abc.abstractmethod
    def outputs(self, write: Write, bits: str) -> WireMessage | None: ...

    @abc.abstractmethod
    def register(self, name: str, *, for_write: bool, save: bool) -> tuple[int, int, str]:
        """``(channel, address, label)`` of a register name."""

    @abc.abstractmethod
    def read_name(self, channel: int, address: int) -> str:
        """How a register read back is printed."""

    @abc.abstractmethod
    def values(self, reply: WireMessage | None) -> Sequence[int] | None:
        """The values of a read reply that succeeded, else None."""

    @abc.abstractmethod
    def error(self, reply: WireMessage | None) -> str | None:
        """``"error reply: ..."`` text for an error reply, else None."""

    @abc.abstractmethod
    def park_from(self, values: Sequence[int], n_axes: int) -> list[int]:
        """Motor positions in the values of the :attr:`PARK_READ` read."""

    def after_write(self, write: Write, channel: int, save: bool) -> None:  # noqa: B027
        """What follows a ``write`` (the IMAX saves parameters with PA0f = 2)."""

    def run(
        self,
        controller: Parkable,
        transport: Transport,
        verb: str,
        args: Sequence[str],
        *,
        who: tuple[int, int] = (WHO_ALL, WHO_ALL),
        save: bool = False,
        out: TextIO,
    ) -> int:
        """Run one word; returns the exit status (0 ok, 1 error reply)."""
        link = self.link(transport, who, out)
        write, read = link.write, link.read
        if verb == "estop":
            reply = self.estop(write, args)
        elif verb in ("reset", "home"):
            need_args(verb, args, 0)
            reply = self.reset(write) if verb == "reset" else self.home(write)
        elif verb == "outputs":
            need_args(verb, args, 1)
            reply = self.outputs(write, args[0])
        elif verb == "read":
            if len(args) not in (1, 2):
                raise ConfigError("send read REG [COUNT]")
            channel, start, _label = self.register(args[0], for_write=False, save=save)
            count = parse_value(args[1], "count") if len(args) == 2 else 1
            reply = read(channel, start, count)
            for i, v in enumerate(self.values(reply) or ()):
                print(f"{self.read_name(channel, start + i)} = {v} (0x{v:04X})", file=out)
        elif verb == "write":
            if len(args) < 2:
                raise ConfigError("send write REG VALUE...")
            channel, start, _label = self.register(args[0], for_write=True, save=save)
            reply = write(channel, start, tuple(parse_value(v) & 0xFFFF for v in args[1:]))
            self.after_write(write, channel, save)
        elif verb == "park":
            need_args(verb, args, 0)
            require_request(transport)
            park_channel, park_count = self.PARK_READ
            values = self.values(read(park_channel, 0, park_count))
            if values is None:
                return 1
            park(controller, transport, self.park_from(values, controller.n_axes), out)
            return 0
        else:
            raise ConfigError(f"send {verb!r}: allowed {', '.join(VERBS)}")
        text = self.error(reply)
        if text is not None:
            print(text, file=out)
            return 1
        return 0
