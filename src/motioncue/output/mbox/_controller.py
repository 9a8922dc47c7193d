"""The SC-MBOX controller description (frozen) and its frame encoder (explicit state)."""

from __future__ import annotations

import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from numbers import Integral
from types import MappingProxyType
from typing import ClassVar

from ..._config import ConfigReader
from ..._errors import ConfigError, LimitError, ProtocolError
from ..._frozen import set_fields
from .._controller_api import DriveExpectations, PulseLimits
from .._feedback import PositionQuery, register_position_query, words_to_positions
from .._transport import parse_target
from .._udp_common import FrameClock
from .._udp_controller import (
    UdpController,
    UdpFrameEncoder,
    config_parameters,
    config_target,
)
from ._messages import _frame_struct
from ._params import DX_ACTUAL, DX_COMMAND, DX_DEPTH, FN

__all__ = ["MboxController", "MboxFrameEncoder", "controller_from_config"]


def _freeze(params: Mapping[str, int]) -> Mapping[str, int]:
    return MappingProxyType(dict(params))


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
    LABEL: ClassVar[str] = "MBOX"
    PARAMS = FN
    UNKNOWN_PARAM = f"is not an MBOX parameter this package knows (known: {', '.join(FN.spec)})"
    # IP bytes and port of the box (receive port Fn025) and of the host (Fn034)
    CONTROLLER_PARAMS = ("Fn020", "Fn021", "Fn022", "Fn023", "Fn025")
    HOST_PARAMS = ("Fn030", "Fn031", "Fn032", "Fn033", "Fn034")

    max_motor_speed_rpm: float = 3000.0
    buffer_frames: int = 256

    def __post_init__(self) -> None:
        if self.n_axes not in (3, 6):
            raise ConfigError(f"MBOX {self.name}: axes = {self.n_axes}; allowed: 3, 6")
        parse_target(self.default_target)
        params = self.validate_parameters(self.parameters, f"MBOX {self.name}")
        set_fields(self, parameters=_freeze(params))
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
        """The MBOX manual states no frame-rate limit (its 1 ms time stamps cap it at 1 kHz)."""
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
    def pulses_per_rev(self) -> float:
        """Pulses per motor turn: Fn0C1 (pulses/mm) x Fn0C2 (lead)."""
        return self.pulses_per_mm * self.lead_mm

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

    @property
    def catch_up_factor(self) -> float:
        """Fn012 / 1000: the box plays frames this much faster than their time stamps (5.3.3:
        1000 = as stamped; the factory 1200 drains its buffer, the motors moving 1.2x as fast
        as the frames say). Fn012 < 1000 selects automatic speed control (Fn01D-01F) whose
        fastest speed the manual does not state: refused, since no limit could be kept."""
        fn012 = self.parameters["Fn012"]
        if fn012 < 1000:
            raise LimitError(
                f"MBOX {self.name}: Fn012 = {fn012} selects automatic playback speed "
                "(Fn01D..Fn01F), whose fastest speed the manual does not state, so no speed "
                "limit can be guaranteed; set Fn012 >= 1000 (1000 = as stamped, factory 1200)"
            )
        return fn012 / 1000.0

    @property
    def dout_max(self) -> int:
        """24 effect outputs: BaseDout (bits 0-11) and ExtDout (bits 12-23)."""
        return 0xFFFFFF

    @property
    def dac_max(self) -> tuple[int, int]:
        """DAC1 / DAC2 full scale: Fn078 / Fn079."""
        return (self.parameters["Fn078"], self.parameters["Fn079"])

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits:
        """Stroke from Fn0C0 x Fn0C1 (0 = none); speed from ``max_motor_speed_rpm`` (the
        servo's, not an MBOX parameter). The MBOX sets no acceleration limit."""
        n = self.n_axes
        stroke = self.stroke_pulses
        sources = {
            "v_max": f"MBOX {self.name} max_motor_speed_rpm = {self.max_motor_speed_rpm:g} "
            f"x Fn0C2 lead {self.lead_mm:g} mm x Fn0C1 {self.pulses_per_mm:g} pulses/mm",
        }
        if stroke is not None:
            sources["stroke"] = f"MBOX Fn0C0 = {self.parameters['Fn0C0']} (0.1 mm) x Fn0C1"
        return PulseLimits(
            n,
            None if stroke is None else [stroke[0]] * n,
            None if stroke is None else [stroke[1]] * n,
            self.max_speed_pulses_s,
            None,
            sources,
        )

    def position_query(self) -> PositionQuery:
        """One register read of Dn00..Dn4B (6.1): actual and commanded positions, and the
        frames waiting in the buffer (Dn4B); moving while any wait or the two differ."""
        from ._messages import CHANNEL_DX, MboxMessage, RegisterRead, RegisterReadReply, decode

        n, count = self.n_axes, DX_DEPTH + 1

        def registers(msg: MboxMessage) -> tuple[int, ...] | None:
            if not (
                isinstance(msg, RegisterReadReply)
                and msg.channel == CHANNEL_DX
                and msg.start == 0
                and len(msg.values) == count
            ):
                return None
            return msg.values

        def status(values: Sequence[int], actual: tuple[int, ...]) -> tuple[bool, int]:
            depth = values[DX_DEPTH]
            return depth > 0 or actual != words_to_positions(values, DX_COMMAND[:n]), depth

        request = RegisterRead(CHANNEL_DX, 0, count).encode()
        return register_position_query(request, decode, registers, DX_ACTUAL[:n], status)

    def drive_expectations(self) -> DriveExpectations:
        """Fn0C1 x Fn0C2 pulses per motor turn; Fn0C2 the screw lead."""
        return DriveExpectations(
            pulses_per_rev=self.pulses_per_rev,
            pulses_per_rev_source=f"MBOX Fn0C1 = {self.parameters['Fn0C1']} pulses/mm x "
            f"Fn0C2 = {self.parameters['Fn0C2']} (0.1 mm)",
            lead_m=self.lead_mm * 1e-3,
            lead_source=f"MBOX Fn0C2 = {self.parameters['Fn0C2']} (0.1 mm)",
        )

    def _encoder(self, clock: FrameClock, who_accept: int, who_reply: int) -> MboxFrameEncoder:
        return MboxFrameEncoder(self, clock, who_accept, who_reply)


def _integer(value: object, what: str) -> int:
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
    controller: MboxController

    def _layout(self, relative: bool) -> struct.Struct:
        return _frame_struct(self.n_axes, relative)

    def _init_kind(self) -> None:
        self._dac_max = self.controller.dac_max

    def encode(
        self, t_s: float, pulses: Sequence[int], dout: int = 0, dacs: tuple[int, int] = (0, 0)
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
        data, pulses = self._pack_frame(frame, field, pulses, dout & 0xFFF, d1, d2, dout >> 12)
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
        **MboxController.config_fields(reader, name, axes, target, values),
        max_motor_speed_rpm=rpm,
        buffer_frames=buffer_frames,
    )
