"""The output stage shared by ``play`` and ``bridge``: limiter -> pulses -> frames -> link.

:class:`OutputStage` owns the safety guarantee of everything sent: every frame passes the
real-time actuator limiter (with limits tightened by the pulse rounding, so the rounded
pulses still respect the limits table), is encoded by the controller's frame encoder and
sent. Parking is the same limiter driven to the park position until at rest there.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._errors import LimitError
from ._generate import pulse_rounding_limits
from ._realtime import wait_until
from ._ridefile import Ride

__all__ = ["OutputStage", "PlayReport", "make_frame_encoder", "play_ride", "receiver_throttle"]


def make_frame_encoder(controller: Any, rate_hz: float, start_pulses: Any = None) -> Any:
    """A fresh frame encoder for one run at ``rate_hz`` (absolute-time frames where they
    exist); the controller refuses a rate its clock cannot carry."""
    return controller.run_encoder(
        rate_hz, None if start_pulses is None else [int(p) for p in start_pulses]
    )


@dataclass
class OutputStage:
    """Limiter, drives, encoder and link, stepped one frame at a time.

    Parameters
    ----------
    platform : motioncue.kinematics.Platform
    controller
        From :func:`motioncue.output.load_controller`.
    limits : motioncue.trajectory.ActuatorLimits
        The limits table in SI (as ``motioncue limits`` prints it).
    rate_hz : float
        Frame rate.
    transport : motioncue.output.Transport
        Where frames go.
    q_start : array_like, optional
        Where the platform is when the stage starts (default: parked, at rest).
    """

    platform: Any
    controller: Any
    limits: Any
    rate_hz: float
    transport: Any
    q_start: Any = None
    frames: int = 0
    clamped_frames: int = 0
    t_s: float = 0.0
    last_pulses: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    _limiter: Any = None
    _state: Any = None
    _encoder: Any = None
    _streamer: Any = None

    def __post_init__(self) -> None:
        from motioncue.trajectory import JerkLimiter, RealtimeLimiter

        self.dt_s = 1.0 / self.rate_hz
        tight = pulse_rounding_limits(self.limits, self.platform, self.dt_s)
        # a configured jerk limit needs the jerk-aware limiter (slower, still well inside a
        # frame); without one the acceleration-limited limiter is exact and cheaper
        limiter_cls = RealtimeLimiter if tight.j_max is None else JerkLimiter
        self._limiter = limiter_cls(tight, self.dt_s)
        q0 = self.platform.q_park if self.q_start is None else np.asarray(self.q_start, float)
        self._state = self._limiter.initial_state(q0)
        self.last_pulses = self.platform.drives.to_pulses(np.asarray(q0, dtype=float))
        self._encoder = make_frame_encoder(self.controller, self.rate_hz, self.last_pulses)
        if self.controller.kind == "easysmc" and _is_serial(self.transport):
            # A live serial link: commands go through the flow-controlled streamer that keeps
            # the controller's 63-command buffer fed without overflowing it.
            from motioncue.output.easysmc import EasySmcLink, EasySmcStreamer

            link = EasySmcLink(self.transport)
            self._streamer = EasySmcStreamer.for_controller(self.controller, link, self.rate_hz)
            self._streamer.send_all(self.controller.setup_commands())

    @property
    def q(self) -> np.ndarray:
        """Position of the last frame sent (SI, limiter state)."""
        return np.asarray(self._state.q, dtype=float)

    @property
    def at_rest(self) -> bool:
        return bool(np.all(np.abs(np.asarray(self._state.v, dtype=float)) < 1e-12))

    def emit(self, q_target: Any, dout: int = 0, dacs: tuple[int, int] = (0, 0)) -> np.ndarray:
        """Limit, encode and send one frame toward ``q_target (n,)`` (SI); returns the pulses."""
        q_out = np.asarray(self._limiter.step(self._state, q_target), dtype=float)
        if not np.all(np.isfinite(q_out)):  # the limiter guarantees this; never send NaN
            raise LimitError("limiter produced a non-finite position; frame not sent")
        if not np.array_equal(q_out, np.asarray(q_target, dtype=float)):
            self.clamped_frames += 1
        pulses = self.platform.drives.to_pulses(q_out)
        frame = [int(p) for p in pulses]
        if self._streamer is not None:
            self._streamer.send_all(self._encoder.encode_commands(self.t_s, frame, dout, dacs))
            if (self.frames + 1) % self._streamer.poll_every_frames == 0:
                for addr in self._streamer.sent:
                    self._streamer.poll(addr)
        else:
            for msg in self._encoder.encode(self.t_s, frame, dout, dacs):
                self.transport.send(msg, t_s=self.t_s)
        self.last_pulses = pulses
        self.frames += 1
        self.t_s += self.dt_s
        return pulses

    def park_step(self) -> bool:
        """One frame toward the park position; True once parked and at rest."""
        self.emit(self.platform.q_park)
        return self.parked

    @property
    def parked(self) -> bool:
        return self.at_rest and bool(np.allclose(self.q, self.platform.q_park, atol=1e-12))

    def park_frames_bound(self) -> int:
        """An upper bound on the frames :meth:`park_step` needs from any admissible state."""
        lim = self.limits
        span = float(np.max(lim.q_max - lim.q_min))
        v, a = float(np.min(lim.v_max)), float(np.min(lim.a_max))
        return math.ceil((span / v + 2 * v / a) / self.dt_s) + 10


def receiver_throttle(
    received: Callable[[], int], ahead: int = 200, timeout_s: float = 5.0
) -> Callable[[int], None]:
    """A ``throttle`` for :func:`play_ride`: never run more than ``ahead`` frames ahead of
    what a receiver reports it has taken in (``received()``), waiting at most ``timeout_s``.

    For a receiver in this process (an emulator sharing the GIL), so that a busy machine slows
    the player down instead of overflowing the socket and losing frames.
    """

    def wait(sent: int) -> None:
        deadline = time.monotonic() + timeout_s
        while sent - received() > ahead and time.monotonic() < deadline:
            time.sleep(0.002)

    return wait


def _is_serial(transport: Any) -> bool:
    from motioncue.output._transport_serial import SerialTransport

    return isinstance(transport, SerialTransport)


@dataclass(frozen=True)
class PlayReport:
    """What ``play`` did: frames sent, clamped by the limiter, parking, timing."""

    frames_sent: int
    ride_frames_sent: int
    clamped_frames: int
    interrupted: bool
    park_frames: int
    late_frames: int
    wall_s: float


def play_ride(
    ride: Ride,
    platform: Any,
    controller: Any,
    limits: Any,
    transport: Any,
    *,
    speed: float = 1.0,
    paced: bool = True,
    stop: Any = None,
    spin_s: float = 0.001,
    throttle: Any = None,
) -> PlayReport:
    """Stream a ride's frames on time, from park, then park.

    The platform is assumed parked and at rest at the start (as after homing). Each frame
    passes the real-time limiter; a ride made by ``generate`` is feasible and starts at park,
    so the limiter changes nothing but rounding. A ride that starts elsewhere is ramped into
    by the limiter. On ``KeyboardInterrupt`` (Ctrl-C) or when ``stop()`` returns True the
    ride stops and the platform is parked smoothly before returning.

    Parameters
    ----------
    speed : float
        Playback speed factor for the pacing (frames keep their own time stamps).
    paced : bool
        False: send as fast as possible (files and pcaps).
    stop : callable, optional
        Polled each frame; True stops the ride (then parks).
    spin_s : float
        Busy-wait before each deadline (s) for low jitter; 0 sleeps only (kinder to other
        threads of this process, such as an in-process emulator).
    throttle : callable, optional
        Called with the number of frames sent before each frame; may block (back-pressure
        from a receiver that reports its progress).
    """
    stage = OutputStage(platform, controller, limits, ride.rate_hz, transport)
    q_frames = platform.drives.from_pulses(ride.pulses)
    t0 = time.perf_counter()
    late = 0
    interrupted = False
    sent = 0
    try:
        for k in range(ride.n_frames):
            if stop is not None and stop():
                interrupted = True
                break
            if throttle is not None:
                throttle(stage.frames)
            if paced:
                deadline = t0 + float(ride.t_s[k]) / speed
                if wait_until(deadline, spin_s) > 0.5 * stage.dt_s / speed:
                    late += 1
            stage.emit(q_frames[k], int(ride.dout[k]), (int(ride.dacs[k, 0]), int(ride.dacs[k, 1])))
            sent += 1
    except KeyboardInterrupt:
        interrupted = True
    park = 0
    bound = stage.park_frames_bound()
    t_park = time.perf_counter()
    while not stage.parked and park < bound:
        if paced:
            wait_until(t_park + (park + 1) * stage.dt_s / speed, spin_s)
        stage.park_step()
        park += 1
    return PlayReport(
        frames_sent=stage.frames,
        ride_frames_sent=sent,
        clamped_frames=stage.clamped_frames,
        interrupted=interrupted,
        park_frames=park,
        late_frames=late,
        wall_s=time.perf_counter() - t0,
    )
