"""The IMAX controller description (frozen) and its frame encoder (explicit state)."""

from __future__ import annotations

import math
import struct
from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Integral
from types import MappingProxyType
from typing import ClassVar

from ..._config import ConfigReader
from ..._errors import ConfigError, LimitError, ProtocolError
from ..._frozen import set_fields
from .._controller_api import DriveExpectations, PulseLimits
from .._feedback import PositionQuery, register_position_query
from .._transport import parse_target
from .._udp_common import FrameClock, check_int32
from .._udp_controller import (
    UdpController,
    UdpFrameEncoder,
    config_parameters,
    config_target,
)
from ._messages import (
    F_VIB_ABS,
    F_VIB_REL,
    PORT_OUT_BYTES,
    _frame_struct,
    _vib_struct,
)
from ._params import DP_POS, DP_RECEIVE, DP_USE, PA

__all__ = ["IMAX_RAMP_PERIOD_S", "ImaxController", "ImaxFrameEncoder", "controller_from_config"]

IMAX_RAMP_PERIOD_S = 1e-3
"""Control period of the IMAX speed ramp (5.10: the speed rises in PAax steps of PAbx rpm);
the manual does not state it: 1 ms is an assumption, named in the limits' sources."""


@dataclass(frozen=True)
class ImaxController(UdpController["ImaxFrameEncoder"]):
    """An IMAX / SMC multi-axis controller (up to 12 axes; 3 and 6 are common).

    Attributes
    ----------
    name : str
    n_axes : int
        Axes this controller drives (PA02).
    default_target : str
        Loopback URL used when the user names no target.
    parameters : Mapping[str, int]
        PA00..PAff by name (``"PA80"``, ``"PAa0"``).
    stroke_mm : float
        Usable actuator stroke above mechanical zero (0 = unchecked). Not an IMAX parameter:
        the manual's PA42 is "axis 1 lift" in 2.3.1 but "maximum stroke" in 5.7.
    buffer_frames : int
        Depth of the emulated frame buffer (not stated in the manual).
    counts_per_rev : int or None
        What one motor turn is in frame positions. The manual gives positions no unit
        ("the motor's absolute position"; vibration amplitudes are "pulses"), and two readings
        fit it: quadrature encoder counts, 4 x the PA54 encoder lines (20000 for 5000 lines,
        10000 for 2500), or the servo's command pulses at its electronic gear. None takes the
        first reading; give the number your drives use (the bundled configs: 10000).
    port_out_bytes : int
        Width of PortOut in frames and frame replies, 2 or 4 bytes. The manual prints 2 in
        the 0x1301 frame (2.2.2.5) and 4 in the 0x1401 frame, the replies and the vibration
        frames (2.2.2.7-2.2.2.12); one width is used for all (see
        :mod:`motioncue.output.imax._messages`). Default 2.
    """

    kind: ClassVar[str] = "imax"
    PARAMS = PA
    UNKNOWN_PARAM = "is not an IMAX parameter this package knows"
    CONTROLLER_PARAMS = ("PA10", "PA11", "PA12", "PA13", "PA14")
    HOST_PARAMS = ("PA20", "PA21", "PA22", "PA23", "PA24")

    stroke_mm: float = 0.0
    buffer_frames: int = 256
    counts_per_rev: int | None = None
    port_out_bytes: int = 2
    LABEL: ClassVar[str] = "IMAX"
    RATE_CAP_SOURCE: ClassVar[str] = "1000 / PA59, the minimum communication period"

    def __post_init__(self) -> None:
        if not 2 <= self.n_axes <= 12:
            raise ConfigError(f"IMAX {self.name}: axes = {self.n_axes}; allowed: 2..12")
        parse_target(self.default_target)
        params = self.validate_parameters(self.parameters, f"IMAX {self.name}")
        if params["PA02"] != self.n_axes:
            raise ConfigError(
                f"IMAX {self.name}: PA02 = {params['PA02']} but axes = "
                f"{self.n_axes}; they must agree"
            )
        set_fields(self, parameters=MappingProxyType(params))
        if not (math.isfinite(self.stroke_mm) and self.stroke_mm >= 0):
            raise ConfigError(f"IMAX {self.name}: stroke_mm = {self.stroke_mm}; allowed >= 0")
        c = self.counts_per_rev
        bad = isinstance(c, bool) or not isinstance(c, int) or not 1 <= c <= 1 << 24
        if c is not None and bad:
            raise ConfigError(
                f"IMAX {self.name}: counts_per_rev = {c!r}; allowed: an integer in [1, 2**24]"
            )
        w = self.port_out_bytes
        if type(w) is not int or w not in PORT_OUT_BYTES:
            raise ConfigError(
                f"IMAX {self.name}: port_out_bytes = {w!r}; allowed: 2 or 4 (the manual "
                "prints PortOut as 2 bytes in 0x1301 and 4 in 0x1401)"
            )

    @property
    def max_frame_rate_hz(self) -> float | None:
        """1000 / PA59 (minimum communication period), ``None`` when PA59 = 0."""
        period = self.parameters["PA59"]
        return None if period == 0 else 1000.0 / period

    @property
    def pulses_per_rev(self) -> int:
        """Frame position counts per motor turn: ``counts_per_rev`` when configured, else
        4 x the PA54 encoder lines (5000 lines: 20000; 2500 lines: 10000)."""
        if self.counts_per_rev is not None:
            return self.counts_per_rev
        return 20000 if self.parameters["PA54"] == 0 else 10000

    def _pulses_per_rev_source(self) -> str:
        if self.counts_per_rev is not None:
            return f"IMAX {self.name} counts_per_rev = {self.counts_per_rev}"
        return f"IMAX PA54 = {self.parameters['PA54']}: 4 x encoder lines"

    @property
    def lead_mm(self) -> float:
        return self.parameters["PA41"] / 10.0

    @property
    def pulses_per_mm(self) -> float:
        return self.pulses_per_rev / self.lead_mm

    def max_speed_rpm(self, axis: int) -> float:
        """Smallest of PA07, PA8x (when > 0) and PAax x PAbx (5.10) for axis ``axis``."""
        p = self.parameters
        limits = [p["PA07"]] if p["PA07"] > 0 else []
        if axis < 6:
            if p[f"PA8{axis:x}"] > 0:
                limits.append(p[f"PA8{axis:x}"])
            limits.append(p[f"PAa{axis:x}"] * p[f"PAb{axis:x}"])
        return float(min(limits)) if limits else float("inf")

    @property
    def max_speed_pulses_s(self) -> tuple[float, ...]:
        return tuple(self.max_speed_rpm(i) / 60.0 * self.pulses_per_rev for i in range(self.n_axes))

    @property
    def catch_up_factor(self) -> float:
        """1 with PA06 = 0 (every frame played as stamped). PA06 = 1 fast-forwards when more
        than two frames are buffered, at a speed the manual does not state: refused."""
        if self.parameters["PA06"]:
            raise LimitError(
                f"IMAX {self.name}: PA06 = 1 fast-forwards buffered frames at a speed the "
                "manual does not state, so no speed limit can be guaranteed; set PA06 = 0"
            )
        return 1.0

    @property
    def dout_max(self) -> int:
        """PortOut Y01..Y12."""
        return 0xFFF

    @property
    def dac_max(self) -> tuple[int, int]:
        """The IMAX has no analogue outputs."""
        return (0, 0)

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits:
        """Stroke from ``stroke_mm`` above the PA40 lift; speed min(PA07, PA8x, PAax x PAbx)
        rpm; acceleration PAbx rpm per ramp step of :data:`IMAX_RAMP_PERIOD_S` (assumed)."""
        n = self.n_axes
        ppr = self.pulses_per_rev
        p = self.parameters
        rpm = [self.max_speed_rpm(i) for i in range(n)]
        acc = [
            p[f"PAb{i:x}"] / IMAX_RAMP_PERIOD_S / 60.0 * ppr
            if i < 6 and p[f"PAa{i:x}"] and p[f"PAb{i:x}"]
            else math.inf
            for i in range(n)
        ]
        sources = {
            "v_max": f"IMAX min(PA07, PA8x, PAax x PAbx) rpm x {self._pulses_per_rev_source()}",
            "a_max": f"IMAX PAbx rpm per {IMAX_RAMP_PERIOD_S * 1e3:g} ms ramp step (assumed)",
        }
        stroke = self.stroke_pulses
        if stroke is not None:
            sources["stroke"] = f"IMAX stroke_mm = {self.stroke_mm:g} above the PA40 lift"
        return PulseLimits(
            n,
            None if stroke is None else [stroke[0]] * n,
            None if stroke is None else [stroke[1]] * n,
            [r / 60.0 * ppr for r in rpm],
            acc,
            sources,
        )

    def position_query(self) -> PositionQuery:
        """One register read of DP00..DP49 (2.3.3): axis positions and the receive / use
        pointers of the frame buffer; moving while frames wait in it."""
        from ._messages import (
            CHANNEL_DP,
            ImaxMessage,
            RegisterRead,
            RegisterReply,
            ReplyStatus,
            decode,
        )

        count = DP_USE + 1

        def registers(msg: ImaxMessage) -> tuple[int, ...] | None:
            if not (
                isinstance(msg, RegisterReply)
                and msg.function == 0x1102
                and msg.status == ReplyStatus.OK
                and msg.start == 0
                and len(msg.values) == count
            ):
                return None
            return msg.values

        def status(values: Sequence[int], pulses: tuple[int, ...]) -> tuple[bool, int]:
            depth = (values[DP_RECEIVE] - values[DP_USE]) & 0xFFFF
            return depth > 0, depth

        request = RegisterRead(CHANNEL_DP, 0, count).encode()
        return register_position_query(request, decode, registers, DP_POS[: self.n_axes], status)

    def drive_expectations(self) -> DriveExpectations:
        """Counts per motor turn (see ``counts_per_rev``); PA41 the screw lead."""
        return DriveExpectations(
            pulses_per_rev=float(self.pulses_per_rev),
            pulses_per_rev_source=self._pulses_per_rev_source(),
            lead_m=self.lead_mm * 1e-3,
            lead_source=f"IMAX PA41 = {self.parameters['PA41']} (0.1 mm)",
        )

    @property
    def stroke_pulses(self) -> tuple[int, int] | None:
        """Allowed position range: position 0 is mechanical zero + PA40 lift (5.7)."""
        if self.stroke_mm == 0:
            return None
        lift = self.parameters["PA40"] / 10.0
        return (
            round(-lift * self.pulses_per_mm),
            round((self.stroke_mm - lift) * self.pulses_per_mm),
        )

    def _encoder(self, clock: FrameClock, who_accept: int, who_reply: int) -> ImaxFrameEncoder:
        return ImaxFrameEncoder(self, clock, who_accept, who_reply)


class ImaxFrameEncoder(UdpFrameEncoder):
    """Turns ``(t_s, pulses, dout)`` into IMAX frames (0x1301 / 0x1401), or vibration
    frames (0x1801 / 0x1901) when ``vibration`` is given.

    ``dout`` = Y01..Y12 (12 bits), in a PortOut field of the controller's
    ``port_out_bytes``. The IMAX has no DACs: ``dacs`` must be ``(0, 0)``.
    """

    __slots__ = ()
    STROKE_SOURCE: ClassVar[str] = "stroke_mm, PA40 lift"
    controller: ImaxController

    def _layout(self, relative: bool) -> struct.Struct:
        return _frame_struct(self.n_axes, relative, self.controller.port_out_bytes)

    def encode(
        self,
        t_s: float,
        pulses: Sequence[int],
        dout: int = 0,
        dacs: tuple[int, int] = (0, 0),
        vibration: Sequence[tuple[int, int]] | None = None,
    ) -> list[bytes]:
        """One frame datagram for ``pulses`` (len ``n_axes``) at ``t_s``.

        ``vibration``: per axis ``(period in 0.125 ms, amplitude in pulses)``, both u16.
        """
        if len(pulses) != self.n_axes:
            raise ProtocolError(f"{len(pulses)} positions given, the IMAX drives {self.n_axes}")
        if isinstance(dout, bool) or not isinstance(dout, Integral) or not 0 <= dout <= 0xFFF:
            raise ProtocolError(f"dout = {dout!r}: allowed Y01..Y12, 0 .. 0xFFF")
        if tuple(dacs) != (0, 0):
            raise ProtocolError(f"dacs = {dacs!r}: the IMAX has no analogue outputs")
        dout = int(dout)
        frame, field, abs_ms = self.clock.stamp(t_s)
        if vibration is None:
            data, pulses = self._pack_frame(frame, field, pulses, dout, 0)
        else:
            pulses = check_int32(pulses, self.n_axes)
            if len(vibration) != self.n_axes:
                raise ProtocolError(f"{len(vibration)} vibration pairs for {self.n_axes} axes")
            flat = [int(v) for pair in vibration for v in pair]
            if len(flat) != 2 * self.n_axes or not all(0 <= v <= 0xFFFF for v in flat):
                raise ProtocolError(f"vibration {vibration!r}: (period, amplitude) u16 pairs")
            head = (
                *self._head[:2],
                F_VIB_ABS if self.clock.absolute_time else F_VIB_REL,
                *self._head[3:],
            )
            relative = not self.clock.absolute_time
            layout = _vib_struct(self.n_axes, relative, self.controller.port_out_bytes)
            data = layout.pack(*head, frame, field, *pulses, dout, *flat)
        self._check_stroke(pulses)
        self.clock.commit(t_s, abs_ms)
        return [data]


def controller_from_config(reader: ConfigReader, name: str) -> ImaxController:
    """Build an :class:`ImaxController` from a controller TOML (``kind = "imax"``)."""
    axes = reader.integer("axes", lo=2, hi=12)
    target = config_target(reader)
    stroke = reader.number("stroke_mm", 0.0, lo=0.0)
    buffer_frames = reader.integer("buffer_frames", 256, lo=1, hi=65535)
    counts = reader.integer("counts_per_rev", 0, lo=0, hi=1 << 24)
    port_out_bytes = reader.integer("port_out_bytes", 2, lo=2, hi=4)
    if port_out_bytes not in PORT_OUT_BYTES:
        raise reader.error("port_out_bytes", port_out_bytes, "2 or 4")
    values = config_parameters(reader)
    values.setdefault("PA02", axes)
    return ImaxController(
        **ImaxController.config_fields(reader, name, axes, target, values),
        stroke_mm=stroke,
        buffer_frames=buffer_frames,
        counts_per_rev=counts or None,
        port_out_bytes=port_out_bytes,
    )
