"""The output stage shared by ``play`` and ``bridge``: limiter -> pulses -> frames -> link.

:class:`OutputStage` owns the safety guarantee of everything sent: every frame passes the
real-time actuator limiter (with limits tightened by the pulse rounding, so the rounded
pulses still respect the limits table), is encoded by the controller's frame encoder and
sent. Parking is the same limiter driven to the park position until at rest there, with the
effect outputs (digital outputs, DACs) at zero.

A frame is atomic: the limiter state, the frame counter, the encoder's clock and the stage
time advance only once the frame was encoded and handed to the link. An encoder that refuses
a value (a DAC above full scale, a position outside the controller's stroke...) or a send
that fails leaves the stage exactly where the motor last was, so the next frame (usually the
first of the park) continues from there. Transient send errors (``ENOBUFS``, ``EAGAIN``,
``EINTR``, ``ECONNREFUSED`` of an earlier datagram...) are retried within half a frame
period and counted; a send that keeps failing raises :class:`~motioncue.TransportError`.

:func:`play_ride` parks on every way out of a ride (its end, ``stop()``, SIGINT, SIGTERM,
SIGHUP, SIGQUIT, any exception); the park itself is not interruptible (signals only set a
flag while it runs). If the park cannot be sent it raises :class:`ParkFailed`.

On a live UDP link the stage watches the controller
(the link watch of the output stage): a controller silent for longer than the
target's ``silence_ms`` (default 500 ms) stops the job with
:class:`~motioncue._errors.ControllerSilent` ("controller silent for N ms"), and frames refused
for a reason waiting does not cure stop it at the third refusal
(:class:`~motioncue._errors.FramesRefused`). The park after either is sent all the same, and
:func:`confirm_park` then asks the controller to confirm it: "parked" is only said when the
controller answered the final park frame (or, for a controller that does not answer frames,
answered at all after it). The EasySmc's own link waits for a reply to every command and
raises :class:`~motioncue._errors.ControllerSilent` when none comes.
"""

from __future__ import annotations

import errno
import functools
import math
import operator
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol, cast

import numpy as np

from .._errors import (
    ConfigError,
    ControllerSilent,
    LimitError,
    MotioncueError,
    TransportError,
)
from ..output._feedback import LinkWatch, describe_refusal, is_flow_control, read_position
from ..output._registry import end_of_run_messages
from ..output._transport_serial import SerialTransport
from ..output._transports_udp import UdpTransport
from ..trajectory import JerkLimiter, JerkLimiterState, LimiterState, RealtimeLimiter
from ..trajectory._derive import planning_limits, within_controller_stroke
from ._realtime import wait_until
from ._ridefile import Ride
from ._signals import SignalGuard

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..kinematics import Platform
    from ..output import Controller, FrameEncoder, Transport
    from ..trajectory import ActuatorLimits

__all__ = [
    "HoldUp",
    "OutputStage",
    "ParkFailed",
    "PlayAborted",
    "PlayReport",
    "confirm_park",
    "make_frame_encoder",
    "park_stage",
    "play_ride",
    "receiver_throttle",
]

# errno values of a send worth retrying: the kernel is short of buffers, the call was
# interrupted, or an ICMP error of an earlier datagram is reported on this one
TRANSIENT_ERRNOS = frozenset(
    getattr(errno, name)
    for name in (
        "ENOBUFS",
        "EAGAIN",
        "EWOULDBLOCK",
        "EINTR",
        "ECONNREFUSED",
        "ENOMEM",
        "EHOSTUNREACH",
        "ENETUNREACH",
    )
    if hasattr(errno, name)
)


def _errno_of(exc: OSError) -> int | None:
    """The errno of a failed send, or of the OSError it was raised from (a TransportError
    wrapping the socket's); None when neither carries a whole number."""
    code: object = exc.errno
    if code is None and isinstance(exc.__cause__, OSError):
        code = exc.__cause__.errno
    return code if isinstance(code, int) else None


class CommandEncoder(Protocol):
    """The encoder of a controller fed through a command stream (``encode_commands``)."""

    def encode_commands(
        self, t_s: float, pulses: Sequence[int], dout: int = 0, dacs: tuple[int, int] = (0, 0)
    ) -> Sequence[object]: ...


class CommandStreamer(Protocol):
    """A flow-controlled command stream (:meth:`Controller.command_streamer`): the commands
    of :meth:`CommandEncoder.encode_commands` go out through ``send_all``; every
    ``poll_every_frames`` frames each address of ``sent`` is polled."""

    poll_every_frames: int

    @property
    def sent(self) -> Iterable[int]: ...

    def send_all(self, cmds: Sequence[object]) -> None: ...

    def poll(self, addr: int) -> object: ...


def make_frame_encoder(
    controller: Controller, rate_hz: float, start_pulses: Iterable[float] | None = None
) -> FrameEncoder:
    """A fresh frame encoder for one run at ``rate_hz`` (absolute-time frames where they
    exist); the controller refuses a rate its clock cannot carry."""
    return controller.run_encoder(
        rate_hz, None if start_pulses is None else [int(p) for p in start_pulses]
    )


class _StateSaver:
    """Copies of a limiter state's attributes (slotted: lists of floats and counters), taken
    before each frame and put back if the frame is not sent."""

    __slots__ = ("_get", "_names")

    def __init__(self, state: LimiterState | JerkLimiterState) -> None:
        self._names = tuple(type(state).__slots__)
        self._get = operator.attrgetter(*self._names)

    def save(self, state: LimiterState | JerkLimiterState) -> tuple[object, ...]:
        return tuple([v.copy() if type(v) is list else v for v in self._get(state)])

    def restore(self, state: LimiterState | JerkLimiterState, saved: tuple[object, ...]) -> None:
        for name, value in zip(self._names, saved, strict=True):
            setattr(state, name, value)


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
    q_start : array_like or "auto", optional
        Where the platform is (at rest) when the stage starts. None (default): parked.
        ``"auto"``: ask the controller (IMAX, SC-MBOX over ``udp://``) for its motor
        positions and start there; if it cannot or does not answer, parked (``notes`` says
        which). A position outside the limits, or a controller still playing frames, is
        refused with :class:`~motioncue.LimitError` before anything is sent.
    send_retries : int
        Attempts after a transient send error, within half a frame period (0..100).
    silence_s : float, None or "link"
        Longest silence of the controller accepted while frames are sent (s), on a live
        UDP link; ``"link"`` (default): the transport's ``silence_s`` (``udp://...?
        silence_ms=``, default 0.5 s); None: not watched.

    Attributes
    ----------
    frames, clamped_frames : int
        Frames sent; frames the limiter changed.
    send_errors : int
        Transient send errors met (and retried).
    notes : list of str
        Things the user should know (where the stage started and why).
    watch : LinkWatch or None
        The controller's liveness and refusals (live UDP links), read by players.
    """

    platform: Platform
    controller: Controller
    limits: ActuatorLimits
    rate_hz: float
    transport: Transport
    q_start: ArrayLike | Literal["auto"] | None = None
    send_retries: int = 3
    silence_s: float | Literal["link"] | None = "link"
    frames: int = 0
    clamped_frames: int = 0
    send_errors: int = 0
    t_s: float = 0.0
    last_pulses: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    notes: list[str] = field(default_factory=list)
    _limiter: RealtimeLimiter | JerkLimiter = field(init=False)
    _state: LimiterState | JerkLimiterState = field(init=False)
    _encoder: FrameEncoder = field(init=False)
    _streamer: CommandStreamer | None = field(init=False)
    _saver: _StateSaver = field(init=False)
    _step: Callable[[Sequence[float] | np.ndarray], list[float]] = field(init=False)
    watch: LinkWatch | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.send_retries, int) and 0 <= self.send_retries <= 100):
            raise ConfigError(f"send_retries = {self.send_retries!r}; allowed: 0..100")
        self.dt_s = 1.0 / self.rate_hz
        # plan within the controller's own stroke (MBOX Fn0C0...) even when the limits
        # table was made for wider parameters: a frame beyond it is refused by the encoder,
        # and a platform moving toward that end could not brake in time, park included
        self.limits, narrowed = within_controller_stroke(
            self.limits, self.platform, self.controller, self.rate_hz
        )
        if narrowed is not None:
            self.notes.append(narrowed)
        # park on a stroke end (MBOX pulse 0) stays reachable
        tight = planning_limits(self.limits, self.platform, self.dt_s)
        # a configured jerk limit needs the jerk-aware limiter (slower, still well inside a
        # frame); without one the acceleration-limited limiter is exact and cheaper
        limiter_cls = RealtimeLimiter if tight.j_max is None else JerkLimiter
        self._limiter = limiter_cls(tight, self.dt_s)
        q0 = self._start_position()
        self._start_limiter(self._limiter, q0)
        self.last_pulses = self.platform.drives.to_pulses(np.asarray(q0, dtype=float))
        self._encoder = make_frame_encoder(self.controller, self.rate_hz, self.last_pulses)
        # a controller fed through a command stream (the EasySmc on a live serial link:
        # its 63-command buffer kept fed without overflowing) gives its streamer here
        self._streamer = self.controller.command_streamer(self.transport, self.rate_hz)
        self.watch = self._make_watch()

    def _start_limiter(self, limiter: RealtimeLimiter | JerkLimiter, q0: ArrayLike) -> None:
        """Use ``limiter`` from rest at ``q0``: its state, a saver of that state, its step."""
        if isinstance(limiter, JerkLimiter):
            jerk_state = limiter.initial_state(q0)
            self._state, self._step = jerk_state, functools.partial(limiter.step, jerk_state)
        else:
            state = limiter.initial_state(q0)
            self._state, self._step = state, functools.partial(limiter.step, state)
        self._limiter = limiter
        self._saver = _StateSaver(self._state)

    def _make_watch(self) -> LinkWatch | None:
        """A :class:`LinkWatch` on a live UDP link to a controller that answers on it."""
        if not isinstance(self.transport, UdpTransport):
            return None
        silence = self.transport.silence_s if self.silence_s == "link" else self.silence_s
        if silence is None:
            return None
        if not self.controller.replies_to_frames and (self.controller.position_query() is None):
            return None  # nothing on this link answers: nothing to watch
        return LinkWatch(self.transport, self.controller, float(silence))

    def _supervise(self) -> None:
        """Before a frame: stop when the controller is silent or refuses frames."""
        if self.watch is not None:
            self.watch.check()

    def _start_position(self) -> np.ndarray:
        park = np.asarray(self.platform.q_park, dtype=float)
        if self.q_start is None:
            return park
        if isinstance(self.q_start, str):
            if self.q_start != "auto":
                raise ConfigError(f"q_start = {self.q_start!r}; allowed: None, 'auto', positions")
            rep = read_position(self.controller, self.transport)
            if rep is None:
                self.notes.append(
                    "start: the controller did not report its position; assuming parked at rest"
                )
                return park
            if rep.moving:
                raise LimitError(
                    f"the controller reports it is still playing frames ({rep.depth} buffered, "
                    f"motors at {list(rep.pulses)} pulses); wait until the platform stops"
                )
            q0 = np.asarray(self.platform.drives.from_pulses(np.asarray(rep.pulses)), float)
            park_pulses = self.platform.drives.to_pulses(park)
            off = int(np.max(np.abs(np.asarray(rep.pulses) - park_pulses)))
            self.notes.append(
                f"start: the controller reports motors at {list(rep.pulses)} pulses "
                f"({'parked' if off == 0 else f'{off} pulses from park'}); starting there"
            )
            if not self._limiter.is_admissible(q0):
                raise LimitError(
                    f"the controller reports motors at {list(rep.pulses)} pulses, outside the "
                    "limits table; move the platform home (motioncue send ... home) first"
                )
            return q0
        return np.asarray(self.q_start, dtype=float)

    @property
    def q(self) -> np.ndarray:
        """Position of the last frame sent (SI, limiter state)."""
        return np.asarray(self._state.q, dtype=float)

    @property
    def v(self) -> np.ndarray:
        """Speed of the last frame sent (SI, limiter state); read by monitors."""
        return np.asarray(self._state.v, dtype=float)

    @property
    def at_rest(self) -> bool:
        return bool(np.all(np.abs(np.asarray(self._state.v, dtype=float)) < 1e-12))

    def emit(
        self, q_target: Sequence[float] | np.ndarray, dout: int = 0, dacs: tuple[int, int] = (0, 0)
    ) -> np.ndarray:
        """Limit, encode and send one frame toward ``q_target (n,)`` (SI); returns the pulses.

        Atomic: on any exception (a refused output value, an encoder or link error) the
        stage is left as it was before the call, at the last frame the link took.

        Raises
        ------
        TransportError
            The link kept failing (after ``send_retries`` retries of transient errors, or
            at once for other errors).
        ProtocolError, LimitError
            The encoder refused the frame (output values, stroke of the controller).
        ControllerSilent, FramesRefused
            The controller has been silent too long, or refuses frames (:attr:`watch`);
            nothing was sent.
        """
        self._supervise()
        state = self._state
        saved = self._saver.save(state)
        clock = self._encoder.clock  # declared: None for an encoder without one
        saved_clock = None if clock is None else clock.snapshot()
        try:
            q_out = np.asarray(self._step(q_target), dtype=float)
            if not np.all(np.isfinite(q_out)):  # the limiter guarantees this; never send NaN
                raise LimitError("limiter produced a non-finite position; frame not sent")
            pulses = self.platform.drives.to_pulses(q_out)
            frame = [int(p) for p in pulses]
            if self._streamer is not None:
                # the EasySmc encoder leaves its state unchanged when it refuses a frame
                cmds = cast(CommandEncoder, self._encoder).encode_commands(
                    self.t_s, frame, dout, dacs
                )
            else:
                if self.frames == 0 and not np.array_equal(pulses, self.last_pulses):
                    self._hold_first()  # sent: kept whatever happens to this frame
                    if clock is not None:
                        saved_clock = clock.snapshot()
                msgs = self._encoder.encode(self.t_s, frame, dout, dacs)
                for msg in msgs:  # one datagram per frame for the UDP controllers
                    self._send(msg)
        except BaseException:
            self._saver.restore(state, saved)
            if saved_clock is not None and clock is not None:
                clock.restore(saved_clock)
            raise
        if self._streamer is not None:
            # A serial command may have reached the controller before the link failed, so
            # the frame counts as sent whatever happens from here.
            self._commit(q_out, q_target, pulses)
            self._streamer.send_all(cmds)
            if self.frames % self._streamer.poll_every_frames == 0:
                for addr in self._streamer.sent:
                    self._streamer.poll(addr)
            return pulses
        self._commit(q_out, q_target, pulses)
        return pulses

    def _hold_first(self) -> None:
        """Open the run with a frame where the motors are, at rest (outputs at zero).

        The IMAX and SC-MBOX play the first frame of a run over their own jog time (IMAX
        PA59, MBOX Fn013), not over one frame period; a first frame that moves would be
        played that much faster. Starting with a frame at the start position makes every
        move a frame-to-frame step on the frame clock. Called before the first moving frame
        only (a ride that starts where the platform is needs none).
        """
        for msg in self._encoder.encode(self.t_s, [int(p) for p in self.last_pulses], 0, (0, 0)):
            self._send(msg)
        self.frames += 1
        self.t_s += self.dt_s

    def _commit(self, q_out: np.ndarray, q_target: ArrayLike, pulses: np.ndarray) -> None:
        if not np.array_equal(q_out, np.asarray(q_target, dtype=float)):
            self.clamped_frames += 1
        self.last_pulses = pulses
        self.frames += 1
        self.t_s += self.dt_s

    def _send(self, msg: bytes) -> None:
        """Send one datagram, retrying transient errors within half a frame period."""
        attempt = 0
        deadline = math.inf
        while True:
            try:
                self.transport.send(msg, t_s=self.t_s)
                if self.watch is not None:
                    self.watch.sent_frame()
                return
            except OSError as exc:  # TransportError is an OSError
                code = _errno_of(exc)
                if code not in TRANSIENT_ERRNOS:
                    if isinstance(exc, TransportError):
                        raise
                    raise TransportError(f"send: {exc}") from exc
                self.send_errors += 1
                attempt += 1
                now = time.perf_counter()
                if deadline == math.inf:
                    deadline = now + 0.5 * self.dt_s
                if attempt > self.send_retries or now >= deadline:
                    raise TransportError(
                        f"send failed {attempt} time(s) in a row within half a frame period "
                        f"({500 * self.dt_s:.1f} ms): {exc}"
                    ) from exc
                time.sleep(min(deadline - now, 0.0002 * 2**attempt))

    def park_step(self) -> bool:
        """One frame toward the park position, outputs at zero; True once parked and at rest."""
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


class PlayAborted(MotioncueError):
    """A ride stopped on an error; the platform was parked. ``report`` says what was sent."""

    def __init__(self, message: str, report: PlayReport | None = None) -> None:
        super().__init__(message)
        self.report = report


class ParkFailed(PlayAborted):
    """The park could not be sent (link down): the platform may not be at rest at park."""


def park_stage(
    stage: OutputStage,
    *,
    wait: Callable[[int], object] | None = None,
    give_up_s: float = 1.0,
) -> int:
    """Drive ``stage`` to the park position and rest there; returns the frames sent.

    Each frame goes through the same limiter with the effect outputs at zero. A frame that
    fails (transport, encoder) is tried again at the next slot, the stage staying at the
    last frame the link took, until failures have lasted ``give_up_s`` seconds of frames.

    Parameters
    ----------
    wait : callable, optional
        Called with the slot number (1, 2, ...) before each frame; blocks until its time
        (None: as fast as possible).

    Raises
    ------
    ParkFailed
        The park could not be sent, or did not reach rest at park within the bound.
    """
    if stage.watch is not None:
        stage.watch.armed = False  # the park is sent whatever the controller says
    bound = stage.park_frames_bound()
    max_failures = max(5, math.ceil(give_up_s * stage.rate_hz))
    sent = failures = slot = 0
    failing_since = math.inf
    while not stage.parked:
        if sent >= bound:
            raise ParkFailed(f"PARK FAILED: not at rest at park after {sent} frames")
        slot += 1
        if wait is not None:
            wait(slot)
        try:
            stage.park_step()
        except Exception as exc:
            failures += 1
            now = time.monotonic()
            failing_since = min(failing_since, now)
            # a link that blocks on each failure (a serial controller that does not answer)
            # gives up on the wall clock too
            if failures >= max_failures or (failures > 1 and now - failing_since >= give_up_s):
                what = "PARK NOT CONFIRMED" if isinstance(exc, ControllerSilent) else "PARK FAILED"
                raise ParkFailed(
                    f"{what} after {sent} park frames: {failures} frames in a row could "
                    f"not be sent ({type(exc).__name__}: {exc}); the platform may be stopped "
                    "away from park or still moving: check it before anyone gets on"
                ) from exc
            continue
        failures = 0
        failing_since = math.inf
        sent += 1
    return sent


def confirm_park(stage: OutputStage, *, paced: bool = True, tries: int = 50) -> str | None:
    """Ask the controller to confirm the park just sent (:attr:`OutputStage.watch`).

    Waits (up to the watch's ``silence_s``) for the answer to the final park frame; while
    it is refused for a full buffer, sends it again (at rest at park) up to ``tries``
    times. A controller that does not answer frames confirms by answering anything (its
    status) after the final frame was sent.

    Returns
    -------
    str or None
        None when confirmed (or when the link cannot be watched); otherwise, for a
        controller that refused every frame it was sent and took none, why: nothing moved.

    Raises
    ------
    ParkFailed
        ``PARK NOT CONFIRMED``: the controller stayed silent, or refused the final park
        frame for a reason waiting does not cure, or kept it refused.
    """

    watch = stage.watch
    if watch is None or stage.frames == 0:
        return None
    replies = watch.replies
    for _ in range(tries):
        last = stage.frames - 1
        heard_before = replies.heard
        t_sent = time.monotonic()
        while replies.last_answered_frame < last:
            watch.poll(0.02, until_frame=last)
            if replies.heard > heard_before and replies.replies == 0:
                break  # a controller that does not answer frames answered its status
            if time.monotonic() - t_sent > watch.silence_s:
                raise ParkFailed(
                    "PARK NOT CONFIRMED: "
                    + watch.silence_message(watch.silent_s())
                    + "; the park was sent but the platform may be stopped away from park or "
                    "still moving: check it before anyone gets on"
                )
        if replies.last_refused_frame != last:
            return None
        code = replies.last_refusal
        if code is None or not is_flow_control(watch.kind, *code):
            if replies.accepted == 0 and replies.refused >= stage.frames:
                return (
                    f"the controller took none of the {stage.frames} frames sent: "
                    f"{watch.refusal_message()}; nothing was played, the platform did not move"
                )
            why = "?" if code is None else describe_refusal(watch.kind, *code)
            raise ParkFailed(
                f"PARK NOT CONFIRMED: the controller refused the final park frame ({why}); "
                f"{watch.refusal_message()}; check the platform"
            )
        if paced:
            time.sleep(stage.dt_s)
        stage.park_step()
    raise ParkFailed(
        f"PARK NOT CONFIRMED: the controller refused the final park frame {tries} times "
        f"({replies.refused} frames refused in all); check the platform"
    )


def end_run(stage: OutputStage) -> bool:
    """End the session on the link once the park is confirmed: send the controller kind's
    end-of-run messages (an interface string's stop string; none for most kinds).

    Called by the player and the bridge after :func:`park_stage` and :func:`confirm_park`
    succeeded, on every way out (end, stop, signal, error) where the link still works; never
    before the park, never after a failed one. A message the link refuses is noted in
    ``stage.notes`` (the platform is parked all the same).

    Returns
    -------
    bool
        True when every message was sent (or there was none).
    """
    try:
        for msg in end_of_run_messages(stage.controller):
            stage.transport.send(msg, t_s=stage.t_s)
    except Exception as exc:  # the platform is parked: nothing here may turn that into a crash
        stage.notes.append(
            f"end of run: the stop string could not be sent ({type(exc).__name__}: {exc}); "
            "the platform is parked"
        )
        return False
    return True


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


def _is_serial(transport: Transport) -> bool:
    return isinstance(transport, SerialTransport)


def _is_live(transport: Transport) -> bool:
    """A link to a real controller (UDP or serial), as opposed to a file or a capture."""
    return isinstance(transport, UdpTransport) or _is_serial(transport)


@dataclass(frozen=True)
class HoldUp:
    """One time the player found itself held up past ``resync_after_s`` and skipped ahead.

    Attributes
    ----------
    frame : int
        Index of the frame sent right after it among all frames of the run (0 = the first;
        the frame number SC-MBOX and IMAX frames carry on the wire).
    ride_s : float
        Ride time of that frame, the one due when the player went on (s).
    behind_s : float
        How late the player was for the frame it was waiting for (s): about how long it
        was held up.
    skipped : int
        Ride frames skipped (their time had passed).
    """

    frame: int
    ride_s: float
    behind_s: float
    skipped: int


@dataclass(frozen=True)
class PlayReport:
    """What ``play`` did: frames sent, clamped by the limiter, parking, timing, the link.

    Attributes
    ----------
    frames_sent, ride_frames_sent, park_frames : int
        All frames sent; those of the ride; those of the park (after the ride or its stop).
    clamped_frames : int
        Frames the limiter changed.
    interrupted : bool
        The ride was stopped before its end (``stop()``, a signal, an error).
    late_frames : int
        Frames sent more than half a period after their time.
    wall_s : float
        Wall time of the whole play, park included (s).
    signal : str or None
        The first stop signal received (``"SIGTERM"``), if any.
    refused_frames, frame_replies : int
        Frames the controller said it did not take (buffer full, e-stop...), out of the
        frame replies read (0 when the link cannot read replies).
    send_errors : int
        Transient send errors met and retried.
    notes : tuple of str
        Where the ride started and why, and similar remarks.
    error : str or None
        Why the ride stopped early, when an error stopped it (the platform was parked).
    skipped_frames, resyncs : int
        Ride frames skipped to stay on the ride's clock after the player was held up (a
        stopped process, a stalled machine), and how many times that happened.
    holdups : tuple of HoldUp
        Each of those times after which a frame was sent: where, how long, how many frames
        skipped (all of them unless an error stopped the ride at the frame after one).
    """

    frames_sent: int
    ride_frames_sent: int
    clamped_frames: int
    interrupted: bool
    park_frames: int
    late_frames: int
    wall_s: float
    signal: str | None = None
    refused_frames: int = 0
    frame_replies: int = 0
    send_errors: int = 0
    notes: tuple[str, ...] = ()
    error: str | None = None
    skipped_frames: int = 0
    resyncs: int = 0
    holdups: tuple[HoldUp, ...] = ()


RESYNC_AFTER_S = 0.1
"""A player on a live link held up longer than this (s) skips to where the ride's clock is
instead of sending the late frames back to back (:func:`play_ride`)."""


def play_ride(
    ride: Ride,
    platform: Platform,
    controller: Controller,
    limits: ActuatorLimits,
    transport: Transport,
    *,
    speed: float = 1.0,
    paced: bool = True,
    stop: Callable[[], object] | None = None,
    spin_s: float = 0.001,
    throttle: Callable[[int], object] | None = None,
    q_start: ArrayLike | Literal["auto"] | None = None,
    handle_signals: bool = True,
    on_start: Callable[[OutputStage], object] | None = None,
    resync_after_s: float | None = RESYNC_AFTER_S,
) -> PlayReport:
    """Stream a ride's frames on time, then park; every way out of the ride parks.

    Each frame passes the real-time limiter; a ride made by ``generate`` is feasible and
    starts at park, so the limiter changes nothing but rounding. A ride that starts
    elsewhere (or a platform that starts elsewhere, ``q_start``) is ramped into by the
    limiter. The ride ends at its last frame, when ``stop()`` returns True, on SIGINT,
    SIGTERM, SIGHUP or SIGQUIT (``handle_signals``, main thread), on ``KeyboardInterrupt``,
    or on any exception; in every case the platform is then parked at rest by the same
    limiter, effect outputs at zero. Signals during the park are recorded and ignored.

    The ride itself is not judged here: check it first with
    :func:`~motioncue.pipeline.check_ride_for` (``motioncue play`` does, before anything is
    sent), which refuses another rig's ride, a rate its controller cannot carry, outputs out
    of range and frames outside the current limits on the controller's clock. Whatever the
    ride holds, every frame sent here still passes the limiter.

    Parameters
    ----------
    speed : float
        Playback speed factor for the pacing (frames keep their own time stamps). Other
        than 1 on a live link (``udp://``, serial) only with a ``throttle``: a receiver
        in this process whose buffer holds the ride (the demo's emulator); a controller's
        buffer (``controller.buffer_frames``) would overflow.
    paced : bool
        False: send as fast as possible (``pcap:`` and ``file:`` targets only).
    stop : callable, optional
        Polled each frame; True stops the ride (then parks).
    spin_s : float
        Busy-wait before each deadline (s) for low jitter; 0 sleeps only (kinder to other
        threads of this process, such as an in-process emulator).
    throttle : callable, optional
        Called with the number of frames sent before each frame; may block (back-pressure
        from a receiver that reports its progress).
    q_start : array_like or "auto", optional
        Where the platform is at the start (see :class:`OutputStage`); default parked.
    handle_signals : bool
        Install flag-only handlers for the stop signals while playing (main thread only).
    on_start : callable, optional
        Called once with the :class:`OutputStage` before the first frame, for read-only
        observers (the live monitor reads its ``q``, ``v``, ``t_s``); it must not send.
    resync_after_s : float or None
        On a live link (paced, speed 1, no ``throttle``): when the player finds itself more
        than this late (s; default 0.1: the process was stopped, the machine stalled), it
        skips the ride frames whose time has passed and goes on with the frame due now, so
        that the ride stays on the film's clock instead of sending the late frames back to
        back. The jump to the new frame is made by the same real-time limiter as every
        frame (speed, acceleration and braking distance within the limits table): a limited
        transition that ends once the limiter has caught up with the ride (those frames
        count as clamped). The frames' own time stamps stay consecutive, one period apart.
        Counted in ``PlayReport.skipped_frames`` and ``resyncs``, each one described in
        ``PlayReport.holdups``. None: never skip (refused on a live link to a controller
        without a buffer, ``buffer_frames <= 1``).

    Returns
    -------
    PlayReport

    Raises
    ------
    PlayAborted
        An error stopped the ride; the platform was parked (``exc.report``).
    ParkFailed
        The park could not be sent: the platform may not be at rest at park.
    ConfigError
        ``speed`` or ``paced`` not allowed for this link (nothing sent).
    """
    if not (math.isfinite(speed) and speed > 0):
        raise ConfigError(f"speed = {speed!r} is invalid; allowed: a number > 0")
    live = _is_live(transport)
    if live and not paced:
        raise ConfigError("paced=False sends as fast as possible: only for pcap: and file: targets")
    if live and paced and resync_after_s is None and controller.buffer_frames <= 1:
        raise ConfigError(
            "never skipping late frames (--resync-after-ms 0, resync_after_s=None) sends them "
            f"back to back, and controller {controller.name} has no buffer to play them on its "
            "own clock (it moves as the frames arrive): give a number > 0"
        )
    if live and speed != 1.0 and throttle is None:
        raise ConfigError(
            f"speed {speed:g}: a controller plays frames at their own time stamps, so anything "
            f"but 1 overflows its buffer ({controller.buffer_frames} frames); "
            "other speeds are for pcap: and file: targets"
        )
    stage = OutputStage(platform, controller, limits, ride.rate_hz, transport, q_start=q_start)
    if on_start is not None:
        on_start(stage)
    replies = None if stage.watch is None else stage.watch.replies
    guard = SignalGuard()
    q_frames = platform.drives.from_pulses(ride.pulses)
    n = ride.n_frames
    late = sent = skipped = resyncs = 0
    holdups: list[HoldUp] = []
    resync = live and paced and speed == 1.0 and throttle is None
    resync_s = math.inf if resync_after_s is None or not resync else float(resync_after_s)
    ride_t = np.asarray(ride.t_s, dtype=float)
    interrupted = False
    failure: Exception | None = None
    park_error: ParkFailed | None = None
    park = 0
    t0 = time.perf_counter()
    try:
        if handle_signals:
            guard.__enter__()
        flagged = guard.event.is_set
        try:
            k = -1
            while k + 1 < n:
                k += 1
                if flagged() or (stop is not None and stop()):
                    interrupted = True
                    break
                if throttle is not None:
                    throttle(stage.frames)
                held: tuple[float, int] | None = None
                if paced:
                    deadline = t0 + float(ride_t[k]) / speed
                    behind = wait_until(deadline, spin_s)
                    if behind > 0.5 * stage.dt_s / speed:
                        late += 1
                    if behind > resync_s:
                        # held up: go on with the frame due now, not the ones passed
                        now_k = int(np.searchsorted(ride_t, time.perf_counter() - t0, "right"))
                        now_k = min(max(now_k - 1, k), n - 1)
                        if now_k > k:
                            held = (behind, now_k - k)
                            skipped += now_k - k
                            resyncs += 1
                            k = now_k
                stage.emit(
                    q_frames[k], int(ride.dout[k]), (int(ride.dacs[k, 0]), int(ride.dacs[k, 1]))
                )
                sent += 1
                if held is not None:
                    holdups.append(HoldUp(stage.frames - 1, float(ride_t[k]), *held))
        except KeyboardInterrupt:
            interrupted = True
        except Exception as exc:  # whatever stopped the ride, the platform is parked
            interrupted = True
            failure = exc
        t_park = time.perf_counter()

        def wait(slot: int) -> None:
            wait_until(t_park + slot * stage.dt_s / speed, spin_s)

        frames_before = stage.frames
        nothing_moved = None
        try:
            park_stage(stage, wait=wait if paced else None)
            nothing_moved = confirm_park(stage, paced=paced)
            end_run(stage)  # the park is confirmed: the stop string, if the kind has one
        except ParkFailed as exc:
            park_error = exc
        park = stage.frames - frames_before
    finally:
        if handle_signals:
            guard.__exit__(None, None, None)
    error = None if failure is None else f"{type(failure).__name__}: {failure}"
    report = PlayReport(
        frames_sent=stage.frames,
        ride_frames_sent=sent,
        clamped_frames=stage.clamped_frames,
        interrupted=interrupted,
        park_frames=park,
        late_frames=late,
        wall_s=time.perf_counter() - t0,
        signal=guard.first,
        refused_frames=0 if replies is None else replies.refused,
        frame_replies=0 if replies is None else replies.replies,
        send_errors=stage.send_errors,
        notes=tuple(stage.notes),
        error=error,
        skipped_frames=skipped,
        resyncs=resyncs,
        holdups=tuple(holdups),
    )
    if park_error is not None:
        if error is not None:
            park_error.args = (f"{park_error} (the ride had stopped at frame {sent}: {error})",)
        park_error.report = report
        raise park_error
    if nothing_moved is not None:
        raise PlayAborted(f"ride stopped at frame {sent} of {n}: {nothing_moved}", report)
    if failure is not None:
        parked = "confirmed by the controller" if stage.watch is not None else "sent"
        raise PlayAborted(
            f"ride stopped at frame {sent} of {n} ({error}); the platform was parked at rest "
            f"(park {parked})",
            report,
        ) from failure
    return report
