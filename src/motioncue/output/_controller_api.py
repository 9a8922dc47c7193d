"""The one interface every controller kind implements, and the limits its parameters imply.

A controller description (:func:`motioncue.output.load_controller`) is the single source of
truth for everything its parameters imply: its axes, the frame rates its clock can carry, how
many pulses a motor turn is, the stroke, speed and acceleration its settings allow, how much
faster than the frames' own time stamps it may play (catch-up), its buffer and its encoder.
:meth:`motioncue.trajectory.ActuatorLimits.from_platform` derives the limits from this interface
alone, without naming a controller kind; the emulators check frames with the same numbers.

Adding a controller kind is one package whose config reader returns an object satisfying
:class:`Controller`, plus one :func:`~motioncue.output.register_controller_kind` call
declaring what the kind can do (:class:`~motioncue.output.ControllerKind`), including what
ends a session on its link once the park is confirmed (``end_of_run``: an interface
string's stop string; other kinds end with the park frames).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from .._errors import ConfigError
from .._frozen import readonly, set_fields

if TYPE_CHECKING:
    import numpy.typing as npt

    from ._feedback import PositionQuery
    from ._transport import Transport
    from ._udp_common import FrameClock

__all__ = [
    "CommandStreamer",
    "Controller",
    "DriveExpectations",
    "FrameEncoder",
    "PulseLimits",
    "check_whole_ms_rate",
    "snap_rate_hz",
    "whole_ms_rates",
]


def _axis_array(name: str, value: npt.ArrayLike | None, n: int, fill: float) -> np.ndarray:
    arr = np.full(n, fill) if value is None else np.array(value, dtype=float).reshape(-1)
    if arr.size == 1 and n != 1:
        arr = np.full(n, float(arr[0]))
    if arr.shape != (n,) or np.any(np.isnan(arr)):
        raise ConfigError(f"{name} = {value!r} is invalid; allowed: {n} numbers (inf = none)")
    return readonly(arr)


@dataclass(frozen=True, eq=False, init=False)  # its own __init__: array-likes in, arrays kept
class PulseLimits:
    """Per-axis limits implied by a controller's parameters, on the controller's own clock.

    Every quantity is in motor pulses (what the frames carry); ``inf`` means that the
    controller's parameters set no limit for that axis.

    Attributes
    ----------
    n_axes : int
    stroke_lo, stroke_hi : ndarray, shape (n_axes,)
        Allowed position range (pulses); ``-inf`` / ``inf`` where none.
    max_speed_pulses_s : ndarray, shape (n_axes,)
        Largest speed the controller lets a motor reach (pulses/s).
    max_accel_pulses_s2 : ndarray, shape (n_axes,)
        Largest acceleration (pulses/s^2).
    sources : Mapping[str, str]
        Which parameters each limit (``stroke``, ``v_max``, ``a_max``) comes from.
    """

    n_axes: int
    stroke_lo: npt.NDArray[np.float64]
    stroke_hi: npt.NDArray[np.float64]
    max_speed_pulses_s: npt.NDArray[np.float64]
    max_accel_pulses_s2: npt.NDArray[np.float64]
    sources: Mapping[str, str]

    def __init__(
        self,
        n_axes: int,
        stroke_lo: npt.ArrayLike | None = None,
        stroke_hi: npt.ArrayLike | None = None,
        max_speed_pulses_s: npt.ArrayLike | None = None,
        max_accel_pulses_s2: npt.ArrayLike | None = None,
        sources: Mapping[str, str] | None = None,
    ) -> None:
        """Each limit: one number or ``n_axes`` (None: none); stored as read-only arrays."""
        n = int(n_axes)
        lo = _axis_array("stroke_lo", stroke_lo, n, -math.inf)
        hi = _axis_array("stroke_hi", stroke_hi, n, math.inf)
        v = _axis_array("max_speed_pulses_s", max_speed_pulses_s, n, math.inf)
        a = _axis_array("max_accel_pulses_s2", max_accel_pulses_s2, n, math.inf)
        if np.any(lo >= hi):
            raise ConfigError(f"stroke [{lo.tolist()}, {hi.tolist()}] pulses: need lo < hi")
        for name, arr in (("max_speed_pulses_s", v), ("max_accel_pulses_s2", a)):
            if np.any(arr <= 0):
                raise ConfigError(f"{name} = {arr.tolist()} is invalid; allowed: > 0 (inf: none)")
        set_fields(
            self,
            n_axes=n_axes,
            stroke_lo=lo,
            stroke_hi=hi,
            max_speed_pulses_s=v,
            max_accel_pulses_s2=a,
            sources={} if sources is None else dict(sources),
        )

    @property
    def has_stroke(self) -> bool:
        return bool(np.any(np.isfinite(self.stroke_lo)) or np.any(np.isfinite(self.stroke_hi)))

    @property
    def has_speed(self) -> bool:
        return bool(np.all(np.isfinite(self.max_speed_pulses_s)))

    @property
    def has_accel(self) -> bool:
        return bool(np.all(np.isfinite(self.max_accel_pulses_s2)))


@dataclass(frozen=True)
class DriveExpectations:
    """What a controller's parameters say about the drives it commands.

    A platform's drive must agree, or the positions sent would mean other lengths than
    planned; :meth:`motioncue.trajectory.ActuatorLimits.from_platform` refuses a disagreement
    with both values named.

    Attributes
    ----------
    pulses_per_rev : float or None
        Pulses of a frame position per motor turn (None: the controller does not say).
    pulses_per_rev_source : str
    lead_m : float or None
        Screw lead per motor turn for linear actuators (m; None: not a parameter).
    lead_source : str
    """

    pulses_per_rev: float | None = None
    pulses_per_rev_source: str = ""
    lead_m: float | None = None
    lead_source: str = ""


@runtime_checkable
class FrameEncoder(Protocol):
    """Turns timed motor positions into the bytes of one controller's frames (explicit state:
    frame numbers, time origin). One encoder per run.

    Attributes
    ----------
    clock : FrameClock or None
        The frame numbering and time stamps the encoder steps with each frame (MBOX, IMAX),
        which the output stage saves before a frame and restores when that frame is never
        sent, so a refused or failed frame leaves no gap in the numbers; None for an encoder
        without one (its state is left unchanged when it refuses a frame).
    """

    @property
    def clock(self) -> FrameClock | None: ...

    def encode(
        self, t_s: float, pulses: Sequence[int], dout: int = 0, dacs: tuple[int, int] = (0, 0)
    ) -> list[bytes]: ...


class CommandStreamer(Protocol):
    """A flow-controlled command stream a controller's frames are fed through (the EasySmc
    on a live serial link): ``send_all`` the encoder's ``encode_commands``, and every
    ``poll_every_frames`` frames ``poll`` each address in ``sent``."""

    poll_every_frames: int

    @property
    def sent(self) -> Mapping[int, int]: ...

    # the commands are the kind's own type (what its encoder's ``encode_commands`` gives)
    def send_all(self, cmds: Sequence[Any]) -> None: ...

    def poll(self, addr: int) -> object: ...


@runtime_checkable
class Controller(Protocol):
    """A frozen controller description: everything its parameters imply.

    Attributes
    ----------
    kind : str
        Registry name of the kind (``mbox``, ``imax``, ``easysmc``).
    name : str
        Config name.
    n_axes : int
        Motor axes the frames carry.
    default_target : str
        Where frames go when the user names no target (loopback or a file).
    buffer_frames : int
        Frames the controller queues before refusing (its buffer depth).
    max_frame_rate_hz : float or None
        Highest frame rate the controller (or its link) accepts; None: not stated.
    time_resolution_s : float or None
        Resolution of frame time stamps on the wire (1 ms for MBOX/IMAX); None for a
        controller whose frames carry no time (each frame is a move of its own duration).
    catch_up_factor : float
        How much faster than the frames' time stamps the controller may play them (>= 1;
        MBOX Fn012 / 1000). Limits planned on the host's clock are the motor's divided by
        this (speed) and its square (acceleration).
    dout_max : int
        Largest digital-output word a frame may carry.
    dac_max : tuple[int, int]
        Largest analogue outputs (``(0, 0)``: none).
    link_kind : str
        How frames travel: ``udp``, ``serial`` or ``usb``.
    replies_to_frames : bool
        The controller answers each frame on the link (taken / refused), so a player can
        count refusals.
    """

    @property
    def kind(self) -> str: ...

    @property
    def name(self) -> str: ...

    @property
    def n_axes(self) -> int: ...

    @property
    def default_target(self) -> str: ...

    @property
    def buffer_frames(self) -> int: ...

    @property
    def max_frame_rate_hz(self) -> float | None: ...

    @property
    def time_resolution_s(self) -> float | None: ...

    @property
    def catch_up_factor(self) -> float: ...

    @property
    def dout_max(self) -> int: ...

    @property
    def dac_max(self) -> tuple[int, int]: ...

    @property
    def link_kind(self) -> str: ...

    @property
    def replies_to_frames(self) -> bool: ...

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits:
        """Limits the parameters imply (for frames at ``rate_hz`` when they depend on it)."""
        ...

    def drive_expectations(self) -> DriveExpectations:
        """What the parameters say about the drives (pulses per turn, lead)."""
        ...

    def check_rate(self, rate_hz: float) -> None:
        """Raise :class:`~motioncue.ConfigError` for a frame rate the controller cannot
        carry on its own clock, naming the rates it can."""
        ...

    def position_query(self) -> PositionQuery | None:
        """``(request datagram, reply parser)`` asking where the motors are
        (a position query), or None when it cannot be asked."""
        ...

    def command_streamer(self, transport: Transport, rate_hz: float) -> CommandStreamer | None:
        """A flow-controlled command stream for ``transport`` when frames must be fed
        through one (its ``send_all``, ``poll``, ``sent`` and ``poll_every_frames``, and the
        encoder's ``encode_commands``), else None: frames are sent as encoded."""
        ...

    def run_encoder(
        self, rate_hz: float, start_pulses: Sequence[int] | None = None
    ) -> FrameEncoder:
        """A fresh encoder for one run of frames at ``rate_hz`` (checked by
        :meth:`check_rate`), the motors being at ``start_pulses`` (default: 0)."""
        ...


def whole_ms_rates(cap_hz: float | None, count: int = 12) -> list[float]:
    """Frame rates whose period is a whole number of milliseconds, fastest first, at most
    ``cap_hz``."""
    out: list[float] = []
    k = 1
    while len(out) < count and k <= 1000:
        rate = 1000.0 / k
        if cap_hz is None or rate <= cap_hz * (1 + 1e-12):
            out.append(rate)
        k += 1
    return out


def check_whole_ms_rate(rate_hz: float, cap_hz: float | None, who: str, cap_source: str) -> None:
    """Refuse a frame rate a millisecond time stamp cannot carry exactly.

    MBOX and IMAX frames carry whole milliseconds: at 60 Hz the 16.667 ms period is stamped
    16, 17, 17, 16 ... ms, so a frame planned for 16.667 ms is played in 16 ms (4 % over the
    planned speed; at 300 Hz 3 ms instead of 3.333 ms, 11 %), and above 1000 Hz successive
    frames carry the same stamp (which the controller reads as a jog). Rates whose period is
    a whole number of ms are played exactly as planned.
    """
    if isinstance(rate_hz, bool) or not isinstance(rate_hz, int | float):
        raise ConfigError(f"frame rate {rate_hz!r} is not a number")
    if not (math.isfinite(rate_hz) and rate_hz > 0):
        raise ConfigError(f"frame rate {rate_hz!r} Hz is invalid; allowed: > 0")
    if cap_hz is not None and rate_hz > cap_hz * (1 + 1e-12):
        allowed = ", ".join(f"{r:g}" for r in whole_ms_rates(cap_hz, 6))
        raise ConfigError(
            f"frame rate {rate_hz:g} Hz is above {who}'s cap of {cap_hz:g} Hz ({cap_source}); "
            f"allowed: {allowed} ... Hz (1000/k for whole k)"
        )
    period_ms = 1000.0 / rate_hz
    whole = round(period_ms)
    if whole >= 1 and abs(period_ms - whole) <= 1e-9 * period_ms:
        return
    lo = max(1, math.floor(period_ms))
    hi = lo + 1
    if cap_hz is not None:
        while 1000.0 / lo > cap_hz * (1 + 1e-12):
            lo += 1
            hi = max(hi, lo + 1)
    over = period_ms / max(lo, 1) - 1.0
    raise ConfigError(
        f"frame rate {rate_hz:g} Hz has a period of {period_ms:.3f} ms, but {who}'s frames "
        f"carry whole milliseconds: frames would be played in {lo} ms steps, up to "
        f"{over:.0%} faster than planned. Use a rate whose period is whole ms, e.g. "
        f"{1000.0 / lo:.6g} Hz ({lo} ms) or {1000.0 / hi:.6g} Hz ({hi} ms)"
    )


def snap_rate_hz(rate_hz: float, controller: Controller) -> float:
    """A typed rate such as ``333.33`` read as the whole-ms rate it stands for (1000/3 Hz)
    when the controller stamps whole ms and the two differ by less than 0.05 %; any other
    rate is returned unchanged (and checked later by ``controller.check_rate``)."""
    if controller.time_resolution_s != 1e-3:
        return rate_hz
    if not (isinstance(rate_hz, int | float) and math.isfinite(rate_hz) and rate_hz > 0):
        return rate_hz
    k = round(1000.0 / rate_hz)
    if k >= 1 and abs(1000.0 / k - rate_hz) <= 5e-4 * rate_hz:
        return 1000.0 / k
    return rate_hz
