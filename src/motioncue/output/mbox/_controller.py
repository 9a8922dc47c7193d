"""The SC-MBOX controller description (frozen) and its frame encoder (explicit state)."""

from __future__ import annotations

import dataclasses
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from numbers import Integral
from types import MappingProxyType
from typing import Any, ClassVar

from ..._config import ConfigReader
from ..._errors import ConfigError, LimitError, ProtocolError
from .._transport import parse_target
from .._udp_common import CONFIRM_MAIN, PASSCODE, WHO_ALL, FrameClock, check_int32
from ._messages import F_ABS, F_REL, _frame_struct
from ._params import FN_SPEC, fn_name

__all__ = ["MboxController", "MboxFrameEncoder", "controller_from_config"]


def _freeze(params: Mapping[str, int]) -> Mapping[str, int]:
    return MappingProxyType(dict(params))


def validate_parameters(values: Mapping[str, Any], where: str) -> dict[str, int]:
    """Factory defaults overridden by ``values``; names canonical, values within range."""
    out = {name: spec[2] for name, spec in FN_SPEC.items()}
    for key, value in values.items():
        try:
            name = fn_name(key)
        except ConfigError as exc:
            raise ConfigError(f"{where}: {exc}") from None
        if name not in FN_SPEC:
            raise ConfigError(
                f"{where}: {key} is not an MBOX parameter this package knows "
                f"(known: {', '.join(FN_SPEC)})"
            )
        lo, hi, _, meaning = FN_SPEC[name]
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise ConfigError(
                f"{where}: {name} = {value!r} is invalid ({meaning}); "
                f"allowed: an integer in [{lo}, {hi}]"
            )
        out[name] = value
    return out


@dataclass(frozen=True)
class MboxController:
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

    @property
    def controller_address(self) -> tuple[str, int]:
        p = self.parameters
        return (f"{p['Fn020']}.{p['Fn021']}.{p['Fn022']}.{p['Fn023']}", p["Fn025"])

    @property
    def host_address(self) -> tuple[str, int]:
        p = self.parameters
        return (f"{p['Fn030']}.{p['Fn031']}.{p['Fn032']}.{p['Fn033']}", p["Fn034"])

    @property
    def node(self) -> int:
        """Who node ``XX.YY`` of this box: the last two bytes of its IP (Fn022.Fn023)."""
        return (self.parameters["Fn022"] << 8) | self.parameters["Fn023"]

    def with_parameters(self, **changes: int) -> MboxController:
        """A copy with some parameters changed (``ctrl.with_parameters(Fn0C0=3000)``)."""
        merged = dict(self.parameters)
        merged.update({fn_name(k): v for k, v in changes.items()})
        return dataclasses.replace(self, parameters=merged)

    def frame_encoder(
        self,
        absolute_time: bool = True,
        *,
        t0_s: float | None = None,
        who_accept: int = WHO_ALL,
        who_reply: int = WHO_ALL,
        first_frame: int = 0,
    ) -> MboxFrameEncoder:
        """A fresh frame encoder (frame counter and time origin) for one run."""
        return MboxFrameEncoder(
            self, FrameClock(absolute_time, t0_s, first_frame), who_accept, who_reply
        )


def _integer(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise ProtocolError(f"{what} = {value!r} is not an integer")
    return int(value)


class MboxFrameEncoder:
    """Turns ``(t_s, pulses, dout, dacs)`` into MBOX frame datagrams, numbering frames.

    ``dout`` carries 24 effect outputs: bits 0-11 go to BaseDout, bits 12-23 to ExtDout.
    ``dacs`` are DAC1 and DAC2 in 0 .. Fn078 / Fn079 (full scale, default 10000 = 10 V).
    Positions outside ``[0, stroke]`` (when Fn0C0 is set) raise :class:`LimitError`;
    non-finite, fractional or out-of-int32 positions raise :class:`ProtocolError`.
    Nothing is counted for a refused frame.
    """

    __slots__ = (
        "_dac_max",
        "_head",
        "_pack",
        "_stroke",
        "clock",
        "controller",
        "n_axes",
        "who_accept",
        "who_reply",
    )

    def __init__(
        self, controller: MboxController, clock: FrameClock, who_accept: int, who_reply: int
    ) -> None:
        self.controller = controller
        self.clock = clock
        self.n_axes = controller.n_axes
        self.who_accept = who_accept
        self.who_reply = who_reply
        self._pack = _frame_struct(controller.n_axes, not clock.absolute_time).pack
        self._head = (
            CONFIRM_MAIN,
            PASSCODE,
            F_ABS if clock.absolute_time else F_REL,
            0 if controller.n_axes == 3 else 1,
            who_accept,
            who_reply,
        )
        self._stroke = controller.stroke_pulses
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
            lo, hi = self._stroke
            if min(pulses) < lo or max(pulses) > hi:
                raise LimitError(
                    f"positions {list(pulses)} leave the stroke [{lo}, {hi}] pulses (Fn0C0 x Fn0C1)"
                )
        self.clock.commit(t_s, abs_ms)
        return [data]


def controller_from_config(reader: ConfigReader, name: str) -> MboxController:
    """Build an :class:`MboxController` from a controller TOML (``kind = "mbox"``)."""
    axes = reader.integer("axes", lo=3, hi=6)
    if axes not in (3, 6):
        raise reader.error("axes", axes, "3 or 6")
    target = reader.string("default_target", "udp://127.0.0.1:7408")
    try:
        parse_target(target)
    except ConfigError as exc:
        raise reader.error("default_target", target, str(exc)) from None
    rpm = reader.number("max_motor_speed_rpm", 3000.0, lo=0.0, lo_open=True)
    params = reader.table("parameters", {})
    values = {k: params.raw(k) for k in params.keys()}
    params.finish()
    buffer_frames = reader.integer("buffer_frames", 256, lo=1, hi=65535)
    return MboxController(
        name=name,
        n_axes=axes,
        default_target=target,
        parameters=validate_parameters(values, f"{reader.where} [parameters]"),
        max_motor_speed_rpm=rpm,
        buffer_frames=buffer_frames,
    )
