"""EasySmc 2300 controller description, link budget and timed-frame encoder.

The controller has no time stamp: each motion frame becomes a relative interpolated move,
queued with start condition 4 ("in sequence"), whose feed is chosen so that the move lasts one
frame period (XYZ: ``A3`` then ``57``; XYZU: ``A6`` then ``5B`` + ``5C``). Six axes use two
controllers on one RS485 bus (addresses 00 and 01), each receiving its own pair.

Both the link and the controller's own ramp are constraints of a ride: ``check_rate`` refuses a
frame rate the link cannot carry, and ``pulse_limits(rate)`` bounds each frame's step by the
longest move that ramps up and down within one period (:meth:`EasySmcController.max_frame_pulses`),
so that every frame the limiter produces is accepted and ends on time.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib import resources
from types import MappingProxyType
from typing import TYPE_CHECKING

from ..._config import ConfigReader
from ..._errors import ConfigError, LimitError, ProtocolError
from ..._frozen import set_fields
from .._controller_api import DriveExpectations, PulseLimits
from .._transport import Transport, parse_target
from ._profile import feed_for_duration, max_distance, move_duration_s
from ._protocol import (
    MAX_MAGNITUDE,
    Command,
    Start,
    encode_command,
    serial_frame_size,
    word_from_signed,
)

if TYPE_CHECKING:
    from ._link import EasySmcStreamer

__all__ = [
    "BAUD_RATES",
    "BITS_PER_BYTE",
    "PARAMETERS",
    "USB_COMMANDS_PER_S",
    "EasySmcController",
    "EasySmcFrameEncoder",
    "LinkBudget",
    "Unit",
    "controller_from_config",
]

BAUD_RATES = (2400, 4800, 9600, 19200)  # manual 4.3.3 (SEL3, SEL4)
BITS_PER_BYTE = 10  # 8N1: start + 8 data + stop (manual ch. 5)
USB_COMMANDS_PER_S = 100.0  # manual ch. 2 item 9: "100 commands per second, 10 ms period"
WRITE_REPLY_BYTES = serial_frame_size(0)
QUERY_BYTES = serial_frame_size(1)
STATUS_REPLY_BYTES = serial_frame_size(3)


@dataclass(frozen=True)
class _Param:
    code: str
    meaning: str
    default: int
    lo: int
    hi: int


def _parameters() -> dict[str, _Param]:
    """The table declared as data in ``params.toml`` beside this module."""
    text = resources.files(__package__).joinpath("params.toml").read_text(encoding="utf-8")
    data = tomllib.loads(text)
    ranges: dict[str, list[int]] = data["ranges"]
    return {
        name: _Param(row["code"], row["meaning"], row["default"], *ranges[row["range"]])
        for name, row in data["parameters"].items()
    }


PARAMETERS: Mapping[str, _Param] = MappingProxyType(_parameters())
"""Parameters a config may set, named after the manual's command codes, with the factory
defaults of the manual's appendix and the allowed range."""

_SOFT = {
    "X": ("27_XFMAX", "21_XZMAX"),
    "Y": ("28_YFMAX", "22_YZMAX"),
    "Z": ("29_ZFMAX", "23_ZZMAX"),
    "U": ("AF_UFMAX", "AF_UZMAX"),
}


@dataclass(frozen=True)
class Unit:
    """One EasySmc 2300 on the bus: its address and the axes it drives (``XYZ`` / ``XYZU``)."""

    address: int
    axes: str

    def __post_init__(self) -> None:
        if not 0 <= self.address <= 3:
            raise ConfigError(f"EasySmc address {self.address} outside 00..03 (DIP SEL1/SEL2)")
        if self.axes not in ("XYZ", "XYZU"):
            raise ConfigError(f"EasySmc axes {self.axes!r}; allowed: XYZ | XYZU")

    @property
    def speed_code(self) -> int:
        return 0xA3 if self.axes == "XYZ" else 0xA6

    @property
    def move_codes(self) -> tuple[int, ...]:
        return (0x57,) if self.axes == "XYZ" else (0x5B, 0x5C)

    def frame_commands_bytes(self) -> int:
        """Serial bytes of the commands of one frame, with their 9-byte write replies."""
        cmd = serial_frame_size(3) + sum(
            serial_frame_size(len(self.axes) // len(self.move_codes)) for _ in self.move_codes
        )
        return cmd + WRITE_REPLY_BYTES * (1 + len(self.move_codes))


@dataclass(frozen=True)
class LinkBudget:
    """What one motion frame costs on the link.

    On the serial link the host waits for each write reply, so a frame costs its command bytes
    plus their 9-byte replies plus, every ``poll_every_frames`` frames, one status query (16
    bytes) and its reply (30 bytes), each byte 10 bits (8N1). ``max_frame_rate_hz`` is
    ``baud / (bytes_per_frame x 10)``. On USB the DLL carries 100 commands per second.
    """

    link: str
    baud: int
    bytes_per_frame: float
    commands_per_frame: int

    @property
    def max_frame_rate_hz(self) -> float:
        if self.link == "usb":
            return USB_COMMANDS_PER_S / self.commands_per_frame
        return self.baud / (self.bytes_per_frame * BITS_PER_BYTE)

    def describe(self, frame_rate_hz: float) -> str:
        if self.link == "usb":
            return (
                f"{self.commands_per_frame} commands per frame x {frame_rate_hz:g} Hz = "
                f"{self.commands_per_frame * frame_rate_hz:g} commands/s; USB carries "
                f"{USB_COMMANDS_PER_S:g}/s (max {self.max_frame_rate_hz:.1f} Hz)"
            )
        bits = self.bytes_per_frame * BITS_PER_BYTE
        return (
            f"{self.bytes_per_frame:g} bytes per frame x {BITS_PER_BYTE} bits / "
            f"{self.baud} baud = {bits / self.baud * 1e3:.1f} ms per frame; "
            f"{frame_rate_hz:g} Hz leaves {1e3 / frame_rate_hz:.1f} ms "
            f"(max {self.max_frame_rate_hz:.1f} Hz)"
        )

    def check(self, frame_rate_hz: float) -> None:
        """Refuse a frame rate the link cannot carry (:class:`LimitError` with the figure)."""
        if not (math.isfinite(frame_rate_hz) and frame_rate_hz > 0):
            raise LimitError(f"frame rate {frame_rate_hz!r} Hz must be finite and positive")
        if frame_rate_hz > self.max_frame_rate_hz:
            raise LimitError(
                f"EasySmc link cannot carry {frame_rate_hz:g} Hz: " + self.describe(frame_rate_hz)
            )


@dataclass(frozen=True)
class EasySmcController:
    """Frozen description of one EasySmc 2300 set-up (one or two controllers).

    Attributes
    ----------
    name : str
        Config name.
    units : tuple of Unit
        Controllers on the bus, in axis order (the frame's pulses are split in this order).
    link : str
        ``"serial"`` (RS232/422/485) or ``"usb"`` (EM2300 DLL).
    baud : int
        Serial baud, one of 2400, 4800, 9600, 19200 (factory 19200).
    default_target : str
        Target URL used when the user names none (a file, never a device).
    parameters : Mapping[str, int]
        Manual parameters by name (see :data:`PARAMETERS`).
    poll_every_frames : int
        Frames between two execution-status queries (command 38) of each unit.
    lead_frames : int
        Frames the streamer keeps queued ahead in the 63-command buffer.
    """

    name: str
    units: tuple[Unit, ...]
    link: str = "serial"
    baud: int = 19200
    default_target: str = "file:easysmc.bin"
    parameters: Mapping[str, int] = field(default_factory=dict)
    poll_every_frames: int = 10
    lead_frames: int = 6
    description: str = ""
    kind: str = "easysmc"

    def __post_init__(self) -> None:
        if self.link not in ("serial", "usb"):
            raise ConfigError(f"link {self.link!r}; allowed: serial | usb")
        if self.baud not in BAUD_RATES:
            raise ConfigError(f"baud {self.baud}; the EasySmc 2300 allows {BAUD_RATES}")
        if not self.units or len({u.address for u in self.units}) != len(self.units):
            raise ConfigError(f"units {self.units}: need at least one, distinct addresses")
        if self.link == "usb" and len(self.units) != 1:
            raise ConfigError("the USB link drives one controller (address fixed at 00)")
        params = {k: p.default for k, p in PARAMETERS.items()}
        for k, v in dict(self.parameters).items():
            if k not in PARAMETERS:
                raise ConfigError(
                    f"unknown EasySmc parameter {k!r}; known: {', '.join(PARAMETERS)}"
                )
            p = PARAMETERS[k]
            if isinstance(v, bool) or not isinstance(v, int) or not p.lo <= v <= p.hi:
                raise ConfigError(f"parameter {k} = {v!r}; allowed: an integer in [{p.lo}, {p.hi}]")
            params[k] = v
        set_fields(self, parameters=MappingProxyType(params))
        if not 1 <= self.poll_every_frames <= 1000:
            raise ConfigError(f"poll_every_frames {self.poll_every_frames}; allowed 1..1000")
        frame_cmds = 1 + max(len(u.move_codes) for u in self.units)
        if not 1 <= self.lead_frames * frame_cmds <= 60:
            raise ConfigError(
                f"lead_frames {self.lead_frames} x {frame_cmds} commands must "
                "fit the 63-command buffer with 3 to spare (<= 60)"
            )

    @property
    def n_axes(self) -> int:
        return sum(len(u.axes) for u in self.units)

    @property
    def axis_names(self) -> tuple[str, ...]:
        return tuple(
            f"{a}{u.address}" if len(self.units) > 1 else a for u in self.units for a in u.axes
        )

    def link_budget(self) -> LinkBudget:
        per_frame = 0.0
        commands = 0
        for u in self.units:
            per_frame += u.frame_commands_bytes()
            per_frame += (QUERY_BYTES + STATUS_REPLY_BYTES) / self.poll_every_frames
            commands += 1 + len(u.move_codes)
        return LinkBudget(self.link, self.baud, per_frame, commands)

    @property
    def max_frame_rate_hz(self) -> float:
        """Highest frame rate the link carries (see :class:`LinkBudget`)."""
        return self.link_budget().max_frame_rate_hz

    @property
    def buffer_frames(self) -> int:
        """Frames the 63-command buffer holds (a frame is 1 + len(move codes) commands)."""
        return 63 // (1 + max(len(u.move_codes) for u in self.units))

    @property
    def time_resolution_s(self) -> None:
        """Frames carry no time: each is a move whose feed makes it last one period."""
        return None

    @property
    def catch_up_factor(self) -> float:
        """Moves run at the feed the host sets, so frames are never played ahead of their
        times: each move ends at or up to one feed rounding before its frame's time (the feed
        is rounded up to whole hertz), and the next move is timed to its own frame's time."""
        return 1.0

    @property
    def dout_max(self) -> int:
        """16 output bits per unit (X0-1 .. U0-4)."""
        return (1 << (16 * len(self.units))) - 1

    @property
    def dac_max(self) -> tuple[int, int]:
        """No analogue outputs."""
        return (0, 0)

    @property
    def link_kind(self) -> str:
        """``serial`` or ``usb``."""
        return self.link

    @property
    def replies_to_frames(self) -> bool:
        """Frame commands are answered on the serial link, read by the streamer."""
        return False

    def position_query(self) -> None:
        """The EasySmc is not asked where it is (``play`` expects it homed, at park)."""
        return None

    def command_streamer(self, transport: Transport, rate_hz: float) -> EasySmcStreamer | None:
        """On a live serial link, the flow-controlled streamer that keeps the 63-command
        buffer fed without overflowing it (after this controller's set-up commands); None
        for files and captures, which take the commands as encoded."""
        from .._transport_serial import SerialTransport

        if not isinstance(transport, SerialTransport):
            return None
        from ._link import EasySmcLink, EasySmcStreamer

        streamer = EasySmcStreamer.for_controller(self, EasySmcLink(transport), rate_hz)
        streamer.send_all(self.setup_commands())
        return streamer

    def check_rate(self, rate_hz: float) -> None:
        """Refuse a frame rate the link cannot carry (:class:`LinkBudget`), naming the
        highest one it can (:class:`~motioncue.ConfigError`)."""
        if isinstance(rate_hz, bool) or not isinstance(rate_hz, int | float):
            raise ConfigError(f"frame rate {rate_hz!r} is not a number")
        try:
            self.link_budget().check(rate_hz)
        except LimitError as exc:
            top = self.max_frame_rate_hz
            hint = (
                f"; the highest rate this link carries is {top:.1f} Hz: use at most "
                f"{math.floor(top * 10) / 10:g} Hz (e.g. {max(1, math.floor(top)):d} Hz)"
                if math.isfinite(rate_hz) and rate_hz > 0
                else ""
            )
            raise ConfigError(f"{exc}{hint}") from exc

    def run_encoder(
        self, rate_hz: float, start_pulses: Sequence[int] | None = None
    ) -> EasySmcFrameEncoder:
        """A fresh encoder for frames at ``rate_hz`` from ``start_pulses`` (checked)."""
        self.check_rate(rate_hz)
        return self.frame_encoder(rate_hz, None if start_pulses is None else list(start_pulses))

    def unit_profile(self, unit: Unit) -> tuple[int, int, int, int]:
        """``(F0, A, F, B)`` of a frame move of ``unit``: the start frequency (02 DAT2, see
        ``MANUAL_DECISIONS``), and the A3 (XYZ) or A6 (XYZU) acceleration, feed cap and
        deceleration (Hz, Hz/s)."""
        prefix = "A3" if unit.axes == "XYZ" else "A6"
        p = self.parameters
        return (
            self.start_frequency_hz(),
            p[f"{prefix}_acc_a_hz_s"],
            p[f"{prefix}_feed_hz"],
            p[f"{prefix}_acc_b_hz_s"],
        )

    def max_frame_pulses(self, rate_hz: float) -> tuple[int, ...]:
        """Largest move per frame (pulses, per axis) the encoder accepts at ``rate_hz`` from
        any state it can be in, and the controller runs within the frame's period.

        Each frame's move starts and ends at the start frequency ``F0`` (so frames do not
        constrain one another's speed or acceleration) and must last at most one period
        ``T = 1 / rate_hz``: the encoder rounds the feed up and waits down, so no move ends
        after its frame's time and the next move always has at least ``T``. Within ``T`` a
        move covers at most :func:`~motioncue.output.easysmc.max_distance` ``(T, F, F0, A,
        B)`` pulses along its longest axis; this is that, rounded down to whole pulses.
        """
        if isinstance(rate_hz, bool) or not isinstance(rate_hz, int | float):
            raise ConfigError(f"frame rate {rate_hz!r} is not a number")
        if not (math.isfinite(rate_hz) and rate_hz > 0):
            raise ConfigError(f"frame rate {rate_hz!r} Hz is invalid; allowed: > 0")
        period_s = 1.0 / float(rate_hz)
        out: list[int] = []
        for u in self.units:
            f0, acc_a, cap, acc_b = self.unit_profile(u)
            # the tiny relative margin keeps the bound on the accepted side of the
            # encoder's floating-point feed computation
            d = math.floor(max_distance(period_s, cap, f0, acc_a, acc_b) * (1.0 - 1e-9))
            if d < 1:
                raise ConfigError(
                    f"at {rate_hz:g} Hz an EasySmc frame move ({'A3' if u.axes == 'XYZ' else 'A6'}"
                    f": F0 = {f0} Hz, A = {acc_a} Hz/s, feed <= {cap} Hz, B = {acc_b} Hz/s) "
                    "covers less than one pulse: raise the start frequency or the accelerations"
                )
            out.extend([d] * len(u.axes))
        return tuple(out)

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits:
        """Limits of frames at ``rate_hz`` (or at any rate, for ``None``).

        Stroke: the soft limits (21..29, AF).

        Speed, ``rate_hz`` given: :meth:`max_frame_pulses` per period, i.e.
        ``floor(D(T)) / T`` with ``D(T)`` the longest move the A3/A6 ramps (from the start
        frequency ``F0``, at ``A`` up to at most the feed cap ``F``, at ``B`` down to ``F0``)
        cover in one period ``T``. Any frame sequence whose per-frame steps stay within it is
        accepted by the encoder and every move ends within its period (the encoder never lets
        a move end late, so each move has a full period); one pulse more per frame is refused.
        At the factory settings (F0 = 2 kHz, A = B = 20 kHz/s) this is 2240 pulses/s at 20 Hz.
        No acceleration limit: every move starts and ends at ``F0`` whatever the previous one
        did, and the motor's own acceleration is the controller's ``A`` / ``B``.

        Speed, ``rate_hz`` None: the feed cap ``F`` (the motor's peak pulse rate within any
        move), a necessary bound only.

        Within a frame the motor runs up to the frame's feed, which may be up to twice the
        frame's mean rate (a triangular move from a low ``F0``) but never above ``F``: keep
        ``F`` at most the drive's rated speed in pulses/s.
        """
        soft = self.soft_limits()
        sources = {"stroke": "EasySmc soft limits (21..29, AF)"}
        if rate_hz is None:
            caps = [float(self.unit_profile(u)[2]) for u in self.units for _ in u.axes]
            sources["v_max"] = (
                "EasySmc A3/A6 feed cap, pulses/s (necessary only: each frame's move also "
                "ramps at the A3/A6 accelerations from the start frequency within its period)"
            )
        else:
            per_frame = self.max_frame_pulses(rate_hz)
            caps = [float(d) * float(rate_hz) for d in per_frame]
            f0, acc_a, cap, acc_b = self.unit_profile(self.units[0])
            sources["v_max"] = (
                f"EasySmc frame move within one period at {float(rate_hz):g} Hz: "
                f"{per_frame[0]} pulses per frame = longest move from the start frequency "
                f"F0 = {f0} Hz at A = {acc_a} Hz/s up to at most the feed cap F = {cap} Hz and "
                f"down at B = {acc_b} Hz/s to F0 in T = {1e3 / float(rate_hz):.2f} ms "
                "(02 DAT2, A3/A6), rounded down to whole pulses"
            )
        return PulseLimits(
            self.n_axes,
            [lo for lo, _ in soft],
            [hi for _, hi in soft],
            caps,
            None,
            sources,
        )

    def drive_expectations(self) -> DriveExpectations:
        """The EasySmc counts pulses only: nothing to compare with the drives."""
        return DriveExpectations()

    def soft_limits(self) -> tuple[tuple[int, int], ...]:
        """Per-axis ``(negative, positive)`` soft limits in pulses, in axis order."""
        p = self.parameters
        return tuple((p[_SOFT[a][0]], p[_SOFT[a][1]]) for u in self.units for a in u.axes)

    def start_frequency_hz(self) -> int:
        """Start frequency of a frame move (X's linear-interpolation start frequency)."""
        return self.parameters["02_x_linear_start_hz"]

    def setup_commands(self) -> list[Command]:
        """Commands that prepare each unit for timed frames (immediate, in order).

        Reset the command numbering (so the streamer's count matches the controller's),
        select the standard mode, write the start frequencies and soft limits the encoder
        assumes.
        """
        p = self.parameters
        out: list[Command] = []
        for u in self.units:
            a = u.address
            out.append(Command.named("control", 0x3000000, addr=a))
            out.append(Command.named("control", 0x3000001, addr=a))
            for code, key in (
                (0x02, "02_x_linear_start_hz"),
                (0x09, "09_y_linear_start_hz"),
                (0x14, "14_z_linear_start_hz"),
            ):
                f0 = p[key]
                out.append(Command(code, (f0, f0, f0), Start.IMMEDIATE, a))
            for axis, pos_code, neg_code in (
                ("X", 0x21, 0x27),
                ("Y", 0x22, 0x28),
                ("Z", 0x23, 0x29),
            ):
                neg, pos = p[_SOFT[axis][0]], p[_SOFT[axis][1]]
                out.append(Command(pos_code, (word_from_signed(pos),), Start.IMMEDIATE, a))
                out.append(Command(neg_code, (word_from_signed(neg),), Start.IMMEDIATE, a))
        return out

    def frame_encoder(
        self, frame_rate_hz: float, start_pulses: Sequence[int] | None = None
    ) -> EasySmcFrameEncoder:
        """A new encoder for timed frames at ``frame_rate_hz`` (checked against the link)."""
        return EasySmcFrameEncoder(self, frame_rate_hz, start_pulses)


def controller_from_config(reader: ConfigReader, name: str) -> EasySmcController:
    """Read the rest of an ``kind = "easysmc"`` controller TOML (``kind`` already read)."""
    description = reader.string("description", "")
    link = reader.string("link", "serial", choices=("serial", "usb"))
    baud = reader.integer("baud", 19200)
    if baud not in BAUD_RATES:
        raise reader.error("baud", baud, " | ".join(str(b) for b in BAUD_RATES))
    target = reader.string("default_target", "file:easysmc.bin")
    url = parse_target(target)
    if url.scheme == "udp":
        raise reader.error("default_target", target, "serial:..., file:... or pcap:...")
    poll = reader.integer("poll_every_frames", 10, lo=1, hi=1000)
    lead = reader.integer("lead_frames", 6, lo=1, hi=60)
    units = []
    for ur in reader.tables("units"):
        units.append(
            Unit(ur.integer("address", lo=0, hi=3), ur.string("axes", choices=("XYZ", "XYZU")))
        )
        ur.finish()
    pr = reader.table("parameters", {})
    params = {}
    for key, p in PARAMETERS.items():
        if pr.has(key):
            params[key] = pr.integer(key, lo=p.lo, hi=p.hi)
    pr.finish()
    try:
        return EasySmcController(
            name, tuple(units), link, baud, target, params, poll, lead, description
        )
    except ConfigError as exc:
        raise ConfigError(f"{reader.where}: {exc}") from exc


@dataclass
class _UnitState:
    pulses: list[int]
    done_s: float = 0.0  # controller time consumed by this unit's queued moves
    feed_hz: int = 0


class EasySmcFrameEncoder:
    """Turn absolute per-axis pulse targets at times ``t_s`` into EasySmc commands.

    State (explicit, inspectable): the last pulses sent per axis, the controller time each
    unit's queued moves add up to, the output bits, the frame count and the command numbers.

    Each frame becomes, for each unit, a speed command (``A3`` / ``A6``) whose feed makes the
    following relative move (``57`` / ``5B`` + ``5C``) end when the frame's time is reached;
    a frame without motion becomes a wait (``19`` + ``1xxxxxx`` ms). Because the moves are
    differences of rounded absolute targets, they sum exactly to the commanded pulses, and
    because each move's duration is aimed at the frame's absolute time (not at one period),
    rounding of the feed to whole hertz does not accumulate either.

    Its ``clock`` is None (see :class:`~motioncue.output.FrameEncoder`): EasySmc commands
    carry no frame numbers, and a refused frame leaves its state unchanged.
    """

    clock: None = None

    def __init__(
        self,
        controller: EasySmcController,
        frame_rate_hz: float,
        start_pulses: Sequence[int] | None = None,
    ) -> None:
        controller.link_budget().check(frame_rate_hz)
        self.controller = controller
        self.frame_rate_hz = float(frame_rate_hz)
        self.period_s = 1.0 / self.frame_rate_hz
        n = controller.n_axes
        start = [0] * n if start_pulses is None else [int(p) for p in start_pulses]
        if len(start) != n:
            raise ProtocolError(f"start_pulses has {len(start)} values, expected {n}")
        self._units: list[_UnitState] = []
        i = 0
        for u in controller.units:
            self._units.append(_UnitState(start[i : i + len(u.axes)]))
            i += len(u.axes)
        self.t0_s: float | None = None
        self.t_last_s: float | None = None
        self.dout = 0
        self.n_frames = 0
        # Numbers the controller will give the next command of each unit (after setup).
        self.next_number = {u.address: 1 for u in controller.units}

    @property
    def last_pulses(self) -> tuple[int, ...]:
        return tuple(p for s in self._units for p in s.pulses)

    def setup(self) -> list[bytes]:
        """Serial frames of :meth:`EasySmcController.setup_commands`; resets numbering."""
        cmds = self.controller.setup_commands()
        for u in self.controller.units:
            n = sum(1 for c in cmds if c.addr == u.address)
            self.next_number[u.address] = n + 1  # 19 3000000 is number 1, the rest follow
        return [encode_command(c) for c in cmds]

    def encode(
        self, t_s: float, pulses: Sequence[float], dout: int = 0, dacs: Sequence[float] = (0, 0)
    ) -> list[bytes]:
        """Serial ASCII frames for one motion frame (see :meth:`encode_commands`)."""
        return [encode_command(c) for c in self.encode_commands(t_s, pulses, dout, dacs)]

    def encode_commands(
        self, t_s: float, pulses: Sequence[float], dout: int = 0, dacs: Sequence[float] = (0, 0)
    ) -> list[Command]:
        """Commands for one motion frame.

        Parameters
        ----------
        t_s : float
            Frame time in seconds; strictly increasing, at most one frame period faster
            than ``frame_rate_hz`` (10 % jitter allowed).
        pulses : sequence of float, shape (n_axes,)
            Absolute motor positions in pulses (rounded to the nearest pulse).
        dout : int
            Output bits: bit ``16 k + i`` is output ``i`` (X0-1 .. U0-4) of unit ``k``.
        dacs : pair of float
            Must be zero: the EasySmc 2300 has no analogue outputs.

        Raises
        ------
        ProtocolError
            Non-finite or wrongly sized input, non-increasing time, DACs requested.
        LimitError
            Soft limits, feed cap, accelerations or frame spacing exceeded.
        On error the encoder state is unchanged.
        """
        ctrl = self.controller
        t = float(t_s)
        if not math.isfinite(t):
            raise ProtocolError(f"frame time {t_s!r} is not finite")
        if self.t_last_s is not None:
            dt = t - self.t_last_s
            if not dt > 0:
                raise ProtocolError(f"frame time {t} s does not increase (last {self.t_last_s} s)")
            if dt < 0.9 * self.period_s:
                raise LimitError(
                    f"frames {dt * 1e3:.1f} ms apart, faster than the {self.frame_rate_hz:g} Hz "
                    "the link budget was checked for"
                )
        if len(pulses) != ctrl.n_axes:
            raise ProtocolError(f"{len(pulses)} pulse values, expected {ctrl.n_axes}")
        target: list[int] = []
        for axis, value, (lo, hi) in zip(ctrl.axis_names, pulses, ctrl.soft_limits(), strict=True):
            v = float(value)
            if not math.isfinite(v):
                raise ProtocolError(f"axis {axis}: pulse target {value!r} is not finite")
            p = round(v)
            if not lo <= p <= hi:
                raise LimitError(f"axis {axis}: {p} pulses outside soft limits [{lo}, {hi}]")
            target.append(p)
        if any(d != 0 for d in dacs):
            raise ProtocolError(
                f"DAC values {tuple(dacs)} requested: the EasySmc 2300 has no analogue outputs"
            )
        n_out = 16 * len(ctrl.units)
        if isinstance(dout, bool) or not 0 <= int(dout) < (1 << n_out):
            raise ProtocolError(f"dout {dout!r} outside the {n_out} output bits")
        dout = int(dout)

        t0 = t if self.t0_s is None else self.t0_s
        end_s = (t - t0) + self.period_s  # controller time at which this frame must end
        cmds: list[Command] = []
        new_states: list[_UnitState] = []
        i = 0
        for k, (unit, st) in enumerate(zip(ctrl.units, self._units, strict=True)):
            a = unit.address
            n = len(unit.axes)
            goal = target[i : i + n]
            i += n
            deltas = [g - q for g, q in zip(goal, st.pulses, strict=True)]
            for axis, d in zip(unit.axes, deltas, strict=True):
                if abs(d) > MAX_MAGNITUDE:
                    raise LimitError(f"axis {axis}{a}: move of {d} pulses exceeds one word")
            changed = (dout ^ self.dout) >> (16 * k) & 0xFFFF
            bits = (dout >> (16 * k)) & 0xFFFF
            for bit in range(16):
                if changed >> bit & 1:
                    lead = 0xD if bits >> bit & 1 else 0xC
                    cmds.append(Command(0x19, ((lead << 24) | bit,), Start.SEQUENCE, a))
            want_s = end_s - st.done_s
            dist = max(abs(d) for d in deltas)
            if dist == 0:
                # whole ms, rounded down: the wait never ends after the frame's time, so the
                # next move has at least one full period (pulse_limits relies on it)
                ms = max(0, math.floor(want_s * 1e3 + 1e-6))
                if ms > MAX_MAGNITUDE:
                    raise LimitError(f"wait of {ms} ms exceeds one word")
                cmds.append(Command(0x19, ((1 << 24) | ms,), Start.SEQUENCE, a))
                new_states.append(_UnitState(goal, st.done_s + ms / 1e3, st.feed_hz))
                continue
            prefix = "A3" if unit.axes == "XYZ" else "A6"
            f0, acc_a, cap, acc_b = ctrl.unit_profile(unit)
            if want_s <= 0:
                raise LimitError(f"unit {a:02X} is {-want_s * 1e3:.1f} ms behind its schedule")
            feed = feed_for_duration(dist, want_s, f0, acc_a, acc_b)
            # whole hertz, rounded up: the move never ends after the frame's time (a higher
            # feed is never slower), so the next move has at least one full period and a
            # frame within pulse_limits(rate) is always accepted; the feed (the motor's peak
            # pulse rate) stays within the cap, which is a whole number
            feed_i = max(1, math.ceil(feed * (1.0 - 1e-12)))
            if feed_i > cap:
                raise LimitError(
                    f"unit {a:02X}: {dist} pulses in {want_s * 1e3:.1f} ms needs {feed_i} Hz, "
                    f"above the feed cap {prefix}_feed_hz = {cap} Hz"
                )
            cmds.append(Command(unit.speed_code, (acc_a, feed_i, acc_b), Start.SEQUENCE, a))
            per = n // len(unit.move_codes)
            for j, code in enumerate(unit.move_codes):
                cmds.append(Command.move(code, deltas[j * per : (j + 1) * per], Start.SEQUENCE, a))
            took = move_duration_s(dist, feed_i, f0, acc_a, acc_b)
            new_states.append(_UnitState(goal, st.done_s + took, feed_i))
        # commit
        self._units = new_states
        self.t0_s = t0
        self.t_last_s = t
        self.dout = dout
        self.n_frames += 1
        for c in cmds:
            self.next_number[c.addr] += 1
        return cmds

    def schedule_s(self) -> tuple[float, ...]:
        """Controller time (s since the first frame's start) each unit's queue adds up to."""
        return tuple(s.done_s for s in self._units)
