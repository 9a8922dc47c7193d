"""Interface-string controllers: the description a TOML of kind ``iface`` makes, its encoder.

These boards (SMC3, eh-msc-4dof, ODrive bridges, Arduino rigs) take each target as it
arrives: no time stamp, no buffer. So the send clock is the controller's clock: the send
rate is the frame rate, the limits hold between successive frames one period apart, and
park and ramp-in are positions sent like any other. ``frame_rate_hz`` is the send rate the
emulator judges on (the rate rides for the board are made at). A serial link carries
``baud / (10 * bytes per frame)`` frames per second (8N1: 10 bits a byte); a frame rate
above that is refused with the maximum named.

Positions: motioncue's pulses ``pulses_range = [lo, hi]`` map linearly onto the axis
values ``0 .. 2**bits - 1`` (exact when ``hi - lo`` equals the full scale).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ..._config import ConfigReader
from ..._errors import ConfigError, ProtocolError
from .._controller_api import DriveExpectations, PulseLimits
from ._boards import FIRMWARES
from ._format import InterfaceFormat, literal_bytes

__all__ = ["BITS_PER_BYTE", "IfaceController", "IfaceEncoder", "controller_from_config"]

BITS_PER_BYTE = 10
"""Bits a serial byte takes on the line (8N1: start, 8 data, stop)."""


@dataclass(frozen=True)
class IfaceController:
    """A frozen interface-string controller description (satisfies ``Controller``).

    Attributes
    ----------
    name : str
    fmt : InterfaceFormat
        The output string.
    firmware : str
        Which board parser its emulator uses (``smc3``, ``ehmsc4``, ``odrive6``,
        ``decimal6``; ``none``: no emulator).
    start_bytes, stop_bytes : bytes
        Sent before the first frame (e.g. SMC3 ``[ena]``) / once after the park, by the
        kind's end-of-run step (``ControllerKind.end_of_run``: ``play`` and ``bridge`` on
        every way out where the park was sent).
    link_kind : str
        ``serial`` or ``udp``.
    baud : int or None
        Serial baud rate (None on UDP).
    frame_rate_hz : float
        The send rate (Hz) its emulator judges frames on; it must fit the link.
    pulses_lo, pulses_hi : int
        Pulses mapped onto axis values 0 and ``2**bits - 1``.
    max_speed_counts_s, max_accel_counts_s2 : float
        The rig's limits in axis values per second (squared), judged on the send clock.
    default_target : str
    pulses_per_rev : int or None
        Pulses a "turn" of the platform's drive is, when the values are tied to one (a pot
        spanning the stroke: the full scale over the stroke, written as one turn); a platform
        whose drive disagrees is refused instead of planned in the wrong units.
    lead_mm : float or None
        The stroke that turn spans (mm), for linear drives.
    """

    name: str
    fmt: InterfaceFormat
    firmware: str
    start_bytes: bytes
    stop_bytes: bytes
    link_kind: str
    baud: int | None
    frame_rate_hz: float
    pulses_lo: int
    pulses_hi: int
    max_speed_counts_s: float
    max_accel_counts_s2: float
    default_target: str
    pulses_per_rev: int | None = None
    lead_mm: float | None = None
    kind: str = "iface"
    buffer_frames: int = 1
    time_resolution_s: None = None
    catch_up_factor: float = 1.0
    dout_max: int = 0
    dac_max: tuple[int, int] = (0, 0)
    replies_to_frames: bool = False

    def __post_init__(self) -> None:
        if self.firmware != "none" and self.firmware not in FIRMWARES:
            raise ConfigError(
                f"firmware = {self.firmware!r} is invalid; allowed: "
                f"{' | '.join([*FIRMWARES, 'none'])}"
            )
        if self.pulses_lo >= self.pulses_hi:
            raise ConfigError(
                f"pulses_range = [{self.pulses_lo}, {self.pulses_hi}] is invalid; allowed: lo < hi"
            )
        if not (math.isfinite(self.frame_rate_hz) and self.frame_rate_hz > 0):
            raise ConfigError(f"frame_rate_hz = {self.frame_rate_hz!r} is invalid; allowed: > 0")
        cap = self.max_frame_rate_hz
        if cap is not None and self.frame_rate_hz > cap:
            raise ConfigError(self._over_cap(self.frame_rate_hz))

    @property
    def n_axes(self) -> int:
        return self.fmt.n_axes

    @property
    def pulses_per_count(self) -> float:
        return (self.pulses_hi - self.pulses_lo) / self.fmt.full_scale

    @property
    def frame_bytes(self) -> int:
        """Most bytes one frame takes on the wire."""
        return self.fmt.max_frame_bytes()

    @property
    def max_frame_rate_hz(self) -> float | None:
        """``baud / (10 * frame_bytes)`` on serial; None (not stated) on UDP."""
        if self.baud is None:
            return None
        return self.baud / (BITS_PER_BYTE * self.frame_bytes)

    def _over_cap(self, rate_hz: float) -> str:
        return (
            f"frame rate {rate_hz:g} Hz is more than {self.name}'s serial link carries: "
            f"{self.frame_bytes} bytes a frame at {self.baud} baud (10 bits a byte) is at most "
            f"{self.max_frame_rate_hz:.6g} Hz"
        )

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits:
        n = self.n_axes
        ppc = self.pulses_per_count
        return PulseLimits(
            n,
            [self.pulses_lo] * n,
            [self.pulses_hi] * n,
            [self.max_speed_counts_s * ppc] * n,
            [self.max_accel_counts_s2 * ppc] * n,
            {
                "stroke": f"{self.name} pulses_range (axis values 0 .. {self.fmt.full_scale})",
                "v_max": f"{self.name} max_speed_counts_s",
                "a_max": f"{self.name} max_accel_counts_s2",
            },
        )

    def drive_expectations(self) -> DriveExpectations:
        return DriveExpectations(
            None if self.pulses_per_rev is None else float(self.pulses_per_rev),
            f"{self.name} pulses_per_rev",
            None if self.lead_mm is None else self.lead_mm / 1000.0,
            f"{self.name} lead_mm",
        )

    def check_rate(self, rate_hz: float) -> None:
        """Refuse a rate the serial link cannot carry (the maximum named)."""
        if isinstance(rate_hz, bool) or not isinstance(rate_hz, int | float):
            raise ConfigError(f"frame rate {rate_hz!r} is not a number")
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ConfigError(f"frame rate {rate_hz!r} Hz is invalid; allowed: > 0")
        cap = self.max_frame_rate_hz
        if cap is not None and rate_hz > cap * (1 + 1e-12):
            raise ConfigError(self._over_cap(rate_hz))

    def position_query(self) -> None:
        return None

    def command_streamer(self, transport: object, rate_hz: float) -> None:
        return None

    def counts(self, pulses: Sequence[int]) -> list[int]:
        """Axis values for motor positions in pulses (rounded to the nearest value)."""
        lo = self.pulses_lo
        span = self.pulses_hi - lo
        full = self.fmt.full_scale
        return [math.floor((int(p) - lo) * full / span + 0.5) for p in pulses]

    def run_encoder(
        self, rate_hz: float, start_pulses: Sequence[int] | None = None
    ) -> IfaceEncoder:
        self.check_rate(rate_hz)
        return IfaceEncoder(self)

    def stop_frame(self) -> bytes:
        """The stop string (what the kind's end-of-run step sends after the park)."""
        return self.stop_bytes


class IfaceEncoder:
    """Frames of one run: the start string before the first frame, then one string a frame.

    A position outside ``pulses_range`` raises :class:`~motioncue.ProtocolError` (nothing
    sent for that frame): positions are never clipped on the way out.

    Its ``clock`` is None (see :class:`~motioncue.output.FrameEncoder`): the strings carry no
    frame numbers or times.
    """

    clock: None = None

    def __init__(self, controller: IfaceController) -> None:
        self.controller = controller
        self._format = controller.fmt.encoder().format_unchecked
        self._n = controller.n_axes
        self._lo = controller.pulses_lo
        self._hi = controller.pulses_hi
        self._exact = controller.pulses_hi - controller.pulses_lo == controller.fmt.full_scale
        self._started = False

    def encode(
        self, t_s: float, pulses: Sequence[int], dout: int = 0, dacs: tuple[int, int] = (0, 0)
    ) -> list[bytes]:
        lo = self._lo
        if len(pulses) != self._n or min(pulses) < lo or max(pulses) > self._hi:
            self._refuse(pulses)
        values: Sequence[int]
        if self._exact:
            values = tuple(map(int, pulses)) if lo == 0 else tuple([int(p) - lo for p in pulses])
        else:
            values = self.controller.counts(pulses)
        frame = self._format(values)
        if not self._started:
            self._started = True
            if self.controller.start_bytes:
                return [self.controller.start_bytes + frame]
        return [frame]

    def _refuse(self, pulses: Sequence[int]) -> None:
        c = self.controller
        if len(pulses) != c.n_axes:
            raise ProtocolError(f"{len(pulses)} positions for the {c.n_axes}-axis {c.name}")
        bad = next(p for p in pulses if not c.pulses_lo <= p <= c.pulses_hi)
        raise ProtocolError(
            f"position {bad} pulses outside {c.name}'s pulses_range [{c.pulses_lo}, {c.pulses_hi}]"
        )


def controller_from_config(reader: ConfigReader, name: str) -> IfaceController:
    """Every key of an ``iface`` TOML besides ``kind`` (see ``configs/controllers/smc3.toml``)."""
    axes_raw = reader.raw("axes")
    if not isinstance(axes_raw, list) or not all(isinstance(a, str) for a in axes_raw):
        raise reader.error("axes", axes_raw, 'a list of tokens, e.g. ["Axis1a", "Axis2a"]')
    rng = reader.raw("pulses_range")
    if (
        not isinstance(rng, list)
        or len(rng) != 2
        or not all(isinstance(v, int) and not isinstance(v, bool) for v in rng)
    ):
        raise reader.error("pulses_range", rng, "two integers [lo, hi]")
    link = reader.string("link", choices=("serial", "udp"))
    baud = reader.integer("baud", lo=300, hi=10_000_000) if link == "serial" else None
    fmt = InterfaceFormat(
        reader.string("template"),
        tuple(axes_raw),
        reader.integer("bits", lo=8, hi=16),
        reader.string("encoding", choices=("binary", "hex", "decimal")),
    )
    return IfaceController(
        name,
        fmt,
        reader.string("firmware"),
        literal_bytes(reader.string("start", ""), "start"),
        literal_bytes(reader.string("stop", ""), "stop"),
        link,
        baud,
        reader.number("frame_rate_hz", lo=0, lo_open=True),
        int(rng[0]),
        int(rng[1]),
        reader.number("max_speed_counts_s", lo=0, lo_open=True),
        reader.number("max_accel_counts_s2", lo=0, lo_open=True),
        reader.string("default_target"),
        reader.integer("pulses_per_rev", lo=1) if reader.has("pulses_per_rev") else None,
        reader.number("lead_mm", lo=0, lo_open=True) if reader.has("lead_mm") else None,
    )
