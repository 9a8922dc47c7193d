"""What the IMAX and SC-MBOX controller descriptions and frame encoders share.

Both keep their parameters by manual name with factory defaults, address the box and the
host by four IP-byte parameters and a port parameter, take the Who node from the last two
IP bytes, and encode timed frames with a :class:`~._udp_common.FrameClock` and a stroke
check. The differences (parameter tables and names, frame tails, output checks) stay in
each kind's ``_controller`` module as data or as its own ``encode``.
"""

from __future__ import annotations

import dataclasses
import struct
from collections.abc import Callable, Mapping, Sequence
from typing import ClassVar, Generic, Protocol, Self, TypedDict, TypeVar

from .._config import ConfigReader
from .._errors import ConfigError, LimitError
from ._controller_api import check_whole_ms_rate
from ._transport import Transport, parse_target
from ._udp_common import (
    CHANNEL_OF_AXES,
    CONFIRM_MAIN,
    F_ABS,
    F_REL,
    PASSCODE,
    WHO_ALL,
    FrameClock,
    ParameterTable,
    check_int32,
)

__all__ = [
    "UdpController",
    "UdpFrameEncoder",
    "config_parameters",
    "config_target",
    "validate_parameters",
]

ParamSpec = Mapping[str, tuple[int, int, int, str]]
EncoderT = TypeVar("EncoderT")


def validate_parameters(
    values: Mapping[str, object],
    where: str,
    spec: ParamSpec,
    canonical: Callable[[str], str],
    unknown: str,
) -> dict[str, int]:
    """Defaults of ``spec`` overridden by ``values``; names canonical, values within range.

    ``spec`` maps name -> ``(lo, hi, default, meaning)``; ``canonical`` normalises a name
    (raising :class:`ConfigError`); ``unknown`` ends the message for a name ``spec`` lacks.
    """
    out = {name: entry[2] for name, entry in spec.items()}
    for key, value in values.items():
        try:
            name = canonical(key)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        if name not in spec:
            raise ConfigError(f"{where}: {key} {unknown}")
        lo, hi, _, meaning = spec[name]
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise ConfigError(
                f"{where}: {name} = {value!r} is invalid ({meaning}); "
                f"allowed: an integer in [{lo}, {hi}]"
            )
        out[name] = value
    return out


def config_target(reader: ConfigReader) -> str:
    """``default_target`` of a controller TOML (loopback by default), checked."""
    target = reader.string("default_target", "udp://127.0.0.1:7408")
    try:
        parse_target(target)
    except ConfigError as exc:
        raise reader.error("default_target", target, str(exc)) from None
    return target


def config_parameters(reader: ConfigReader) -> dict[str, object]:
    """The raw ``[parameters]`` table of a controller TOML (validated by the kind)."""
    params = reader.table("parameters", {})
    values = {k: params.raw(k) for k in params.keys()}
    params.finish()
    return values


class ControllerFields(TypedDict):
    """The fields every UDP controller description starts with (:class:`UdpController`)."""

    name: str
    n_axes: int
    default_target: str
    parameters: Mapping[str, int]


@dataclasses.dataclass(frozen=True)
class UdpController(Generic[EncoderT]):
    """Base of the frozen controller dataclasses: the fields both kinds start with,
    addresses, node, parameters and the frame-encoder factory.

    A subclass names, as class data, its parameter table (``PARAMS``) and how an unknown
    parameter is refused (``UNKNOWN_PARAM``), the parameters holding the controller's IP
    bytes and port (``CONTROLLER_PARAMS``) and the host's (``HOST_PARAMS``), and builds its
    encoder in :meth:`_encoder`.

    Attributes
    ----------
    name : str
        Config name (``imax6``, ``mbox6``).
    n_axes : int
        Axes the controller drives.
    default_target : str
        Where :mod:`motioncue` sends when the user names no target (loopback).
    parameters : Mapping[str, int]
        Every parameter by manual name: the table's defaults overridden by the config.
    """

    PARAMS: ClassVar[ParameterTable]
    UNKNOWN_PARAM: ClassVar[str]
    CONTROLLER_PARAMS: ClassVar[tuple[str, str, str, str, str]]
    HOST_PARAMS: ClassVar[tuple[str, str, str, str, str]]
    LABEL: ClassVar[str] = "controller"
    RATE_CAP_SOURCE: ClassVar[str] = "1 ms time stamps"

    name: str
    n_axes: int
    default_target: str
    parameters: Mapping[str, int]

    @classmethod
    def validate_parameters(cls, values: Mapping[str, object], where: str) -> dict[str, int]:
        """The table's defaults overridden by ``values``; names canonical, values within
        range (:func:`validate_parameters`)."""
        spec = cls.PARAMS.spec
        return validate_parameters(values, where, spec, cls.canonical_name, cls.UNKNOWN_PARAM)

    @classmethod
    def config_fields(
        cls, reader: ConfigReader, name: str, axes: int, target: str, values: Mapping[str, object]
    ) -> ControllerFields:
        """The shared fields of a controller TOML: ``values``, its raw ``[parameters]``
        table, validated (errors name the table)."""
        parameters = cls.validate_parameters(values, f"{reader.where} [parameters]")
        return ControllerFields(
            name=name, n_axes=axes, default_target=target, parameters=parameters
        )

    @classmethod
    def canonical_name(cls, text: str) -> str:
        """The canonical spelling of a parameter name (:class:`ConfigError` if none)."""
        return cls.PARAMS.names.name(text)

    @property
    def max_frame_rate_hz(self) -> float | None:  # pragma: no cover - overridden
        raise NotImplementedError

    @property
    def link_kind(self) -> str:
        """Frames travel as UDP datagrams."""
        return "udp"

    @property
    def replies_to_frames(self) -> bool:
        """Both kinds answer each frame (0x1x02 taken; another last digit refused)."""
        return True

    def command_streamer(self, transport: Transport, rate_hz: float) -> None:
        """Datagrams are sent as encoded: no command stream to keep fed."""
        return None

    @property
    def time_resolution_s(self) -> float:
        """Frame times travel as whole milliseconds (0x1301 / 0x1401 of both manuals)."""
        return 1e-3

    def check_rate(self, rate_hz: float) -> None:
        """Refuse a frame rate whose period is not a whole number of ms, or above the cap
        (see :func:`~._controller_api.check_whole_ms_rate`)."""
        cap = self.max_frame_rate_hz
        source = self.RATE_CAP_SOURCE
        if cap is None or cap > 1000.0:
            cap, source = 1000.0, "1 ms time stamps"
        check_whole_ms_rate(rate_hz, cap, f"{self.LABEL} {self.name}", source)

    def run_encoder(self, rate_hz: float, start_pulses: Sequence[int] | None = None) -> EncoderT:
        """A fresh absolute-time frame encoder for one run at ``rate_hz`` (checked)."""
        self.check_rate(rate_hz)
        return self.frame_encoder(absolute_time=True)

    def _address(self, names: tuple[str, str, str, str, str]) -> tuple[str, int]:
        p = self.parameters
        return (".".join(str(p[n]) for n in names[:4]), p[names[4]])

    @property
    def controller_address(self) -> tuple[str, int]:
        """``(ip, port)`` of the controller, from its parameters."""
        return self._address(self.CONTROLLER_PARAMS)

    @property
    def host_address(self) -> tuple[str, int]:
        """``(ip, port)`` of the host, from the controller's parameters."""
        return self._address(self.HOST_PARAMS)

    @property
    def node(self) -> int:
        """Who node ``XX.YY`` of this controller: the last two bytes of its IP."""
        c, d = self.CONTROLLER_PARAMS[2:4]
        return (self.parameters[c] << 8) | self.parameters[d]

    def with_parameters(self, **changes: int) -> Self:
        """A copy with some parameters changed (``ctrl.with_parameters(PA59=2)``)."""
        merged = dict(self.parameters)
        merged.update({self.canonical_name(k): v for k, v in changes.items()})
        return dataclasses.replace(self, parameters=merged)

    def _encoder(self, clock: FrameClock, who_accept: int, who_reply: int) -> EncoderT:
        raise NotImplementedError  # pragma: no cover - overridden

    def frame_encoder(
        self,
        absolute_time: bool = True,
        *,
        t0_s: float | None = None,
        who_accept: int = WHO_ALL,
        who_reply: int = WHO_ALL,
        first_frame: int = 0,
    ) -> EncoderT:
        """A fresh frame encoder (frame counter and time origin) for one run."""
        return self._encoder(FrameClock(absolute_time, t0_s, first_frame), who_accept, who_reply)


class _Framed(Protocol):
    """What the shared frame encoder needs of its controller description."""

    @property
    def n_axes(self) -> int: ...

    @property
    def stroke_pulses(self) -> tuple[int, int] | None: ...


class UdpFrameEncoder:
    """State both frame encoders keep: the clock, the fixed header fields and the stroke.

    The header carries 0x1301 / 0x1401 by the clock's time mode and the channel of the
    controller's axis count (0 = 3 axes, 1 = 6 axes, else n); the kind gives its frame
    layout (:meth:`_layout`) and any state of its own (:meth:`_init_kind`).
    ``STROKE_SOURCE`` names the settings a stroke violation comes from. ``clock`` is the
    run's :class:`~._udp_common.FrameClock` (the ``clock`` a
    :class:`~motioncue.output.FrameEncoder` declares), saved and restored by the output stage
    around a frame that is never sent.
    """

    __slots__ = (
        "_head",
        "_pack",
        "_stroke",
        "clock",
        "controller",
        "n_axes",
        "who_accept",
        "who_reply",
    )

    STROKE_SOURCE: ClassVar[str] = "stroke"

    def __init__(
        self, controller: _Framed, clock: FrameClock, who_accept: int, who_reply: int
    ) -> None:
        self.controller = controller
        self.clock = clock
        n = self.n_axes = controller.n_axes
        self.who_accept = who_accept
        self.who_reply = who_reply
        self._pack = self._layout(not clock.absolute_time).pack
        function = F_ABS if clock.absolute_time else F_REL
        self._head = (
            CONFIRM_MAIN,
            PASSCODE,
            function,
            CHANNEL_OF_AXES.get(n, n),
            who_accept,
            who_reply,
        )
        self._stroke: tuple[int, int] | None = controller.stroke_pulses
        self._init_kind()

    def _layout(self, relative: bool) -> struct.Struct:  # pragma: no cover - abstract
        """The kind's frame layout for this controller and time mode."""
        raise NotImplementedError

    def _init_kind(self) -> None:
        """The kind's own state (none by default)."""

    def _pack_frame(
        self, frame: int, field: int, pulses: Sequence[int], *tail: int
    ) -> tuple[bytes, Sequence[int]]:
        """The frame datagram (header, ``frame``, ``field``, ``pulses``, ``tail``) and the
        positions it carries: integral floats are converted, anything not an int32 raises
        :class:`~motioncue.ProtocolError` with a clear message (checked only if packing fails)."""
        try:
            return self._pack(*self._head, frame, field, *pulses, *tail), pulses
        except struct.error:
            pulses = check_int32(pulses, self.n_axes)
            return self._pack(*self._head, frame, field, *pulses, *tail), pulses

    def _check_stroke(self, pulses: Sequence[int]) -> None:
        """Raise :class:`LimitError` when a position leaves the stroke (if one is set)."""
        if self._stroke is not None:
            lo, hi = self._stroke
            if min(pulses) < lo or max(pulses) > hi:
                raise LimitError(
                    f"positions {list(pulses)} leave the stroke [{lo}, {hi}] "
                    f"pulses ({self.STROKE_SOURCE})"
                )
