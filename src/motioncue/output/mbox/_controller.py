"""The SC-MBOX controller description (frozen) and its frame encoder (explicit state)."""

from __future__ import annotations

import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from numbers import Integral
from types import MappingProxyType
from typing import Any, ClassVar

from ..._config import ConfigReader
from ..._errors import ConfigError, ProtocolError
from .._transport import parse_target
from .._udp_common import FrameClock, check_int32
from .._udp_controller import (
    UdpController,
    UdpFrameEncoder,
    config_parameters,
    config_target,
)
from .._udp_controller import validate_parameters as _validate
from ._messages import F_ABS, F_REL, _frame_struct
from ._params import FN_SPEC, fn_name

__all__ = ["MboxController", "MboxFrameEncoder", "controller_from_config"]


def _freeze(params: Mapping[str, int]) -> Mapping[str, int]:
    return MappingProxyType(dict(params))


def validate_parameters(values: Mapping[str, Any], where: str) -> dict[str, int]:
    """Factory defaults overridden by ``values``; names canonical, values within range."""
    unknown = f"is not an MBOX parameter this package knows (known: {', '.join(FN_SPEC)})"
    return _validate(values, where, FN_SPEC, fn_name, unknown)


@dataclass(frozen=True)
class MboxController(UdpController["MboxFrameEncoder"]):
    """An SC-MBOX motion-platform controller (3-axis or 6-axis mode).

    Attributes
    ----------
    name : str
        Config name (``mbox6``).
    n_axes : int
        3 or 6 (object channel 0 or 1 of the frames).
    default_target : str
        Where :mod:`motioncue` sends when the user names no target (loopback).
    parameters : Mapping[str, int]
        Every Fn parameter by manual name (``"Fn0C1"``): factory defaults overridden by
        the config.
    max_motor_speed_rpm : float
        Motor speed limit (the HS servo's, not an MBOX parameter): speed checks and limits.
    buffer_frames : int
        Depth of the emulated FIFO (the manual gives none; Dn4A/Dn4B observe it).
    """

    kind: ClassVar[str] = "mbox"
    # IP bytes and port of the box (receive port Fn025) and of the host (Fn034)
    CONTROLLER_PARAMS: ClassVar[tuple[str, str, str, str, str]] = (
        "Fn020",
        "Fn021",
        "Fn022",
        "Fn023",
        "Fn025",
    )
    HOST_PARAMS: ClassVar[tuple[str, str, str, str, str]] = (
        "Fn030",
        "Fn031",
        "Fn032",
        "Fn033",
        "Fn034",
    )
    canonical_name = staticmethod(fn_name)

    name: str
    n_axes: int
    default_target: str
    parameters: Mapping[str, int]
    max_motor_speed_rpm: float = 3000.0
    buffer_frames: int = 256

    def __post_init__(self) -> None:
        if self.n_axes not in (3, 6):
            raise ConfigError(f"MBOX {self.name}: axes = {self.n_axes}; allowed: 3, 6")
        parse_target(self.default_target)
        object.__setattr__(
            self, "parameters", _freeze(validate_parameters(self.parameters, f"MBOX {self.name}"))
        )
        if not self.max_motor_speed_rpm > 0:
            raise ConfigError(
                f"MBOX {self.name}: max_motor_speed_rpm = "
                f"{self.max_motor_speed_rpm!r}; allowed: > 0"
            )
        if not 1 <= self.buffer_frames <= 65535:
            raise ConfigError(
                f"MBOX {self.name}: buffer_frames = {self.buffer_frames}; allowed: 1..65535"
            )

    # -- derived ------------------------------------------------------------------------
    @property
    def max_frame_rate_hz(self) -> float | None:
        """The MBOX manual states no frame-rate limit."""
        return None

    @property
    def pulses_per_mm(self) -> float:
        """Fn0C1."""
        return float(self.parameters["Fn0C1"])

    @property
    def lead_mm(self) -> float:
        """Fn0C2 (0.1 mm per motor turn)."""
        return self.parameters["Fn0C2"] / 10.0

    @property
    def stroke_pulses(self) -> tuple[int, int] | None:
        """Allowed position range ``(0, Fn0C0 x Fn0C1)`` in pulses (0 is the homed origin);
        ``None`` when Fn0C0 = 0 (no stroke limit)."""
        stroke = self.parameters["Fn0C0"]
        return None if stroke == 0 else (0, round(stroke / 10.0 * self.parameters["Fn0C1"]))

    @property
    def max_speed_pulses_s(self) -> tuple[float, ...]:
        """Per-axis speed limit: rpm / 60 x lead x pulses per mm."""
        v = self.max_motor_speed_rpm / 60.0 * self.lead_mm * self.pulses_per_mm
        return (v,) * self.n_axes

    def _encoder(self, clock: FrameClock, who_accept: int, who_reply: int) -> MboxFrameEncoder:
        return MboxFrameEncoder(self, clock, who_accept, who_reply)


def _integer(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ProtocolError(f"{what} = {value!r} is not an integer")
    return int(value)


class MboxFrameEncoder(UdpFrameEncoder):
    """Turns ``(t_s, pulses, dout, dacs)`` into MBOX frame datagrams, numbering frames.

    ``dout`` carries 24 effect outputs: bits 0-11 go to BaseDout, bits 12-23 to ExtDout.
    ``dacs`` are DAC1 and DAC2 in 0 .. Fn078 / Fn079 (full scale, default 10000 = 10 V).
    Positions outside ``[0, stroke]`` (when Fn0C0 is set) raise :class:`LimitError`;
    non-finite, fractional or out-of-int32 positions raise :class:`ProtocolError`.
    Nothing is counted for a refused frame.
    """

    __slots__ = ("_dac_max",)
    STROKE_SOURCE: ClassVar[str] = "Fn0C0 x Fn0C1"

    def __init__(
        self, controller: MboxController, clock: FrameClock, who_accept: int, who_reply: int
    ) -> None:
        super().__init__(
            controller,
            clock,
            who_accept,
            who_reply,
            layout=_frame_struct(controller.n_axes, not clock.absolute_time),
            functions=(F_ABS, F_REL),
            channel=0 if controller.n_axes == 3 else 1,
        )
        self._dac_max = (controller.parameters["Fn078"], controller.parameters["Fn079"])

    def encode(
        self, t_s: float, pulses: Sequence[Any], dout: int = 0, dacs: tuple[int, int] = (0, 0)
    ) -> list[bytes]:
        """One frame datagram for the positions ``pulses`` (len ``n_axes``) at ``t_s``."""
        if len(pulses) != self.n_axes:
            raise ProtocolError(f"{len(pulses)} positions given, the MBOX runs {self.n_axes} axes")
        if type(dout) is not int:  # plain ints skip the slower ABC checks
            dout = _integer(dout, "dout")
        if not 0 <= dout < 1 << 24:
            raise ProtocolError(f"dout = {dout!r}: allowed 24 output bits, 0 .. 0xFFFFFF")
        if len(dacs) != 2:
            raise ProtocolError(f"dacs = {dacs!r}: the MBOX has 2 DACs")
        d1, d2 = dacs
        if type(d1) is not int or type(d2) is not int:
            d1, d2 = _integer(d1, "dacs[0]"), _integer(d2, "dacs[1]")
        if not (0 <= d1 <= self._dac_max[0] and 0 <= d2 <= self._dac_max[1]):
            raise ProtocolError(f"dacs = {dacs!r}: allowed 0 .. Fn078/Fn079 = {self._dac_max}")
        frame, field, abs_ms = self.clock.stamp(t_s)
        try:
            data = self._pack(*self._head, frame, field, *pulses, dout & 0xFFF, d1, d2, dout >> 12)
        except struct.error:
            pulses = check_int32(pulses, self.n_axes)  # raises with a clear message, or
            data = self._pack(
                *self._head, frame, field, *pulses, dout & 0xFFF, d1, d2, dout >> 12
            )  # integral floats
        if self._stroke is not None:
            self._check_stroke(pulses)
        self.clock.commit(t_s, abs_ms)
        return [data]


def controller_from_config(reader: ConfigReader, name: str) -> MboxController:
    """Build an :class:`MboxController` from a controller TOML (``kind = "mbox"``)."""
    axes = reader.integer("axes", lo=3, hi=6)
    if axes not in (3, 6):
        raise reader.error("axes", axes, "3 or 6")
    target = config_target(reader)
    rpm = reader.number("max_motor_speed_rpm", 3000.0, lo=0.0, lo_open=True)
    values = config_parameters(reader)
    buffer_frames = reader.integer("buffer_frames", 256, lo=1, hi=65535)
    return MboxController(
        name=name,
        n_axes=axes,
        default_target=target,
        parameters=validate_parameters(values, f"{reader.where} [parameters]"),
        max_motor_speed_rpm=rpm,
        buffer_frames=buffer_frames,
    )
