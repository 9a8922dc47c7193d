"""Machinery shared by the IMAX and SC-MBOX emulators: the UDP server thread, Who
addressing, the playback timeline with its buffer, the per-axis trace and violations.

An emulator is usable in two ways:

* in-process and deterministic: ``replies = emu.handle(datagram, now_s)``;
* as a UDP server: ``emu.start()`` (port 0 picks a free port, see ``emu.port``), then
  ``emu.stop()``; or ``with emu: ...``.

The *timeline* is the controller's playback time in seconds: 0 at the first frame after
start-up or homing; each later frame is reached ``duration`` after the previous one, where
``duration`` is the frame's time step, or the manual's jog / rewind / fast-forward time.
The trace records ``(timeline time, commanded positions)`` for every frame played, so it
can be compared directly with the positions the host meant at the frame times.

Limits: each frame is judged with the numbers the controller description implies
(``controller.pulse_limits()``: stroke, speed and, where finite, acceleration, in pulses),
on the controller's own clock: the timeline step divided by the controller's catch-up
factor (MBOX Fn012/1000, always; IMAX 1.5 with PA06 = 1), acceleration by the second
divided difference on that clock (see :class:`Playback`). A frame that moves although it
carries the previous frame's millisecond stamp is flagged ``jog``: the controller moves it
over its own jog time (MBOX Fn013, IMAX PA59), not at once as the host meant.
"""

from __future__ import annotations

import collections
import math
import socket
import struct
import sys
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import ClassVar, Generic, Protocol, Self, TypeVar

import numpy as np

from .._errors import MotioncueError, ProtocolError, TransportError
from ._controller_api import Controller, PulseLimits
from ._udp_common import CONFIRM_MAIN, F_ABS, F_REL, Header, WireMessage, decode_header

__all__ = [
    "STATE_ESTOP",
    "STATE_HOMING",
    "STATE_READY",
    "ControllerEmulator",
    "Playback",
    "Trace",
    "UdpEmulatorBase",
    "Violation",
    "wall_clock",
    "who_matches",
]

# controller states both emulators share (the MBOX adds a fault state)
STATE_HOMING, STATE_READY, STATE_ESTOP = 0, 1, 2

# kernel receive time stamps (struct timespec); Python does not name the option, Linux's
# generic value is 35 (also the control-message type SCM_TIMESTAMPNS)
_SO_TIMESTAMPNS = getattr(socket, "SO_TIMESTAMPNS", 35 if sys.platform == "linux" else None)
_TIMESPEC = struct.Struct("@ll")


def wall_clock() -> float:
    """The emulators' clock: seconds of wall time (comparable with kernel receive stamps)."""
    return time.time()


@dataclass(frozen=True)
class Violation:
    """Something a real controller would refuse or a platform would not survive.

    Attributes
    ----------
    t_s : float
        Timeline time (s) of the frame concerned (or of the last frame for malformed data).
    kind : str
        ``stroke``, ``speed``, ``accel`` (judged on the controller's clock, see
        :class:`Playback`), ``jog`` (a moving frame stamped with the previous frame's ms, which
        the controller moves over its own jog time), ``period`` (IMAX PA59 / PA0b),
        ``malformed``, ``sequence``, ``buffer`` or ``config`` (parameters written that
        imply no usable limits).
    axis : int or None
        Axis index (0-based) for stroke, speed and accel.
    detail : str
        Human-readable description with the values.
    """

    t_s: float
    kind: str
    axis: int | None
    detail: str


@dataclass(frozen=True)
class Trace:
    """Commanded positions in time, one row per frame played.

    Attributes
    ----------
    t_s : numpy.ndarray, shape (N,)
        Timeline times (s).
    positions : numpy.ndarray, shape (N, n_axes), int64
        Commanded motor positions (pulses).
    frames : numpy.ndarray, shape (N,), int64
        Frame numbers as sent (-1 for points the controller made itself: e-stop, homing).
    """

    t_s: np.ndarray
    positions: np.ndarray
    frames: np.ndarray

    def axis(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """``(t_s, positions)`` of axis ``i``."""
        return self.t_s, self.positions[:, i]

    def __len__(self) -> int:
        return len(self.t_s)


def who_matches(who: int, node: int) -> bool:
    """Does Who code ``who`` (0xFFFF all, XX.FF column, FF.YY row, XX.YY node, 0 none)
    select the controller whose node is ``node`` (``XX.YY``)?"""
    if who == 0:
        return False
    if who == 0xFFFF:
        return True
    hi, lo = who >> 8, who & 0xFF
    return (hi == 0xFF or hi == node >> 8) and (lo == 0xFF or lo == node & 0xFF)


# a segment on the controller's clock: per-axis speed (pulses/s), duration (s), stamped
_Motion = tuple[tuple[float, ...], float, bool]


class Playback:
    """Timeline, buffer, trace and limit checks of one emulated controller (explicit state).

    Every frame is judged on the clock the controller really plays it on: its duration is
    its timeline step (the stamp difference, or the controller's own jog / rewind /
    fast-forward time) divided by ``catch_up``, the factor by which the controller plays
    faster than the stamps. On that clock an axis's speed is its step over the duration,
    and its acceleration the change of speed over the mean of the two durations (twice the
    second divided difference of position over time). Where the previous segment was timed
    by the controller itself (a jog, including the first frame of a run, a rewind, a
    fast-forward, the move after an e-stop) the new segment's own duration is used instead
    of the mean: the motor is taken to have moved at the previous speed until one segment
    before (at rest before the first frame), as a planner starting from rest assumes.
    A new run (frame number 0 after other frames) starts from rest too. The frames are
    judged as the contiguous stream they describe: when the buffer runs dry the motors stop
    at the drives' own ramp, which no frame describes, so underruns are not judged here.

    Parameters
    ----------
    n_axes : int
    capacity : int
        Frames the buffer holds (FIFO) before refusing with buffer-full.
    fifo : bool
        ``True``: every frame is played in order. ``False``: only the latest frame; a frame
        not yet started is replaced by a newer one.
    limits : PulseLimits or None
        Stroke, speed and acceleration the frames must keep, in pulses on the controller's
        clock (``controller.pulse_limits()``; ``inf`` = none; ``None``: no checks). Frames
        outside give ``stroke``, ``speed`` and ``accel`` violations.
    catch_up : float
        How much faster than the timeline (the stamps) the controller plays, >= 1.
    catch_up_above : int
        The controller plays at ``catch_up`` while more than this many frames are queued
        (0: always). The checks always divide by ``catch_up``: any frame may be played fast.
    """

    def __init__(
        self,
        n_axes: int,
        capacity: int,
        fifo: bool,
        limits: PulseLimits | None = None,
        *,
        catch_up: float = 1.0,
        catch_up_above: int = 0,
    ) -> None:
        self.n_axes = n_axes
        self.capacity = capacity
        self.fifo = fifo
        self.catch_up = 1.0
        self.catch_up_above = 0
        self.set_catch_up(catch_up, catch_up_above)
        self._lo: tuple[float, ...] | None = None
        self._hi: tuple[float, ...] | None = None
        self._vmax: tuple[float, ...] | None = None
        self._amax: tuple[float, ...] | None = None
        self._vlim: tuple[float, ...] | None = None
        self._alim: tuple[float, ...] | None = None
        self.limits: PulseLimits | None = None
        self.set_limits(limits)
        self.rows_t: list[float] = []
        self.rows_p: list[tuple[int, ...]] = []
        self.rows_f: list[int] = []
        self.violations: list[Violation] = []
        self.position: tuple[int, ...] = (0,) * n_axes  # last commanded (end of timeline)
        self.t_end = 0.0  # timeline time of the last frame
        self.play_t = 0.0  # timeline time the controller has reached
        self.started = False
        self.last_wall: float | None = None
        self.pending: collections.deque[float] = collections.deque()  # end times not reached
        self.last_frame_no: int | None = None
        self.frames_played = 0
        self.frames_dropped = 0
        # the last segment on the controller's clock: per-axis speed (pulses/s), duration
        # (s), whether the duration came from the stamps; and the same before the last
        # frame (restored when a latest-frame controller replaces that frame)
        self._rest: _Motion = ((0.0,) * n_axes, 0.0, False)
        self._motion: _Motion = self._rest
        self._motion_before: _Motion = self._rest

    def set_catch_up(self, catch_up: float, above: int = 0) -> None:
        """Play (and judge) frames ``catch_up`` times as fast as stamped, while more than
        ``above`` frames are queued."""
        if not (math.isfinite(catch_up) and catch_up >= 1.0):
            raise ValueError(f"catch_up = {catch_up!r}; allowed: a finite number >= 1")
        self.catch_up = float(catch_up)
        self.catch_up_above = int(above)

    def set_limits(self, limits: PulseLimits | None) -> None:
        """Judge later frames against ``limits`` (``None``: no checks)."""
        self.limits = limits
        if limits is None:
            self._lo = self._hi = self._vmax = self._amax = self._vlim = self._alim = None
            return
        if limits.n_axes != self.n_axes:
            raise ValueError(f"limits for {limits.n_axes} axes; the controller has {self.n_axes}")

        def per_axis(values: np.ndarray) -> tuple[float, ...] | None:
            out = tuple(float(v) for v in values)
            return out if any(math.isfinite(v) for v in out) else None

        self._lo = per_axis(limits.stroke_lo)
        self._hi = per_axis(limits.stroke_hi)
        self._vmax = per_axis(limits.max_speed_pulses_s)
        self._amax = per_axis(limits.max_accel_pulses_s2)
        # what is compared (a rounding's worth above the limits)
        self._vlim = None if self._vmax is None else tuple(v * (1 + 1e-9) for v in self._vmax)
        self._alim = None if self._amax is None else tuple(a * (1 + 1e-9) for a in self._amax)

    # -- time ---------------------------------------------------------------------------
    def advance(self, now_s: float) -> None:
        """Move the controller's playback clock to wall time ``now_s``."""
        if self.last_wall is None:
            self.last_wall = now_s
            return
        dt = max(0.0, now_s - self.last_wall)
        self.last_wall = now_s
        if not self.started:
            return
        rate = self.catch_up if len(self.pending) > self.catch_up_above else 1.0
        self.play_t = min(self.t_end, self.play_t + dt * rate)
        while self.pending and self.pending[0] <= self.play_t + 1e-9:
            self.pending.popleft()

    @property
    def depth(self) -> int:
        """Frames received and not yet completely played."""
        return len(self.pending)

    @property
    def full(self) -> bool:
        return len(self.pending) >= self.capacity

    # -- frames -------------------------------------------------------------------------
    def play(
        self, frame_no: int, duration_s: float, positions: Sequence[int], *, stamped: bool = True
    ) -> None:
        """Append a frame reached ``duration_s`` (timeline) after the previous one (or at 0
        if first). ``stamped``: the duration is the frames' stamp difference, not a time the
        controller chose itself (jog, rewind, fast-forward, e-stop release)."""
        positions = tuple(int(p) for p in positions)
        base = None
        if not self.fifo and len(self.pending) > 1 and self.rows_t:
            # latest-frame mode: the frame not yet started is replaced by this one, which
            # keeps its own place in time (the replaced frame's time + this step)
            self.pending.pop()
            base = self.rows_t.pop()
            self.rows_p.pop()
            self.rows_f.pop()
            self.frames_dropped += 1
            self.t_end = self.rows_t[-1] if self.rows_t else 0.0
            self.position = self.rows_p[-1] if self.rows_p else (0,) * self.n_axes
            self._motion = self._motion_before
        if not self.started:
            self.started = True
            t = 0.0
            self.play_t = 0.0
            move_s = duration_s
        else:
            t = (self.t_end if base is None else base) + duration_s
            move_s = t - self.t_end if self.rows_t else duration_s
        if frame_no == 0 and self.last_frame_no is not None:
            self._motion = self._rest  # a new run (a new encoder) starts from rest
        self._motion_before = self._motion
        self._check(t, move_s, positions, frame_no, stamped)
        # frame numbers count up by one; 0 starts a new run (a new encoder)
        expected = None if self.last_frame_no is None else (self.last_frame_no + 1) & 0xFFFFFFFF
        if expected is not None and frame_no not in (expected, 0):
            self.violations.append(
                Violation(
                    t,
                    "sequence",
                    None,
                    f"frame {frame_no} after frame {self.last_frame_no} (lost or reordered)",
                )
            )
        self.last_frame_no = frame_no
        self.rows_t.append(t)
        self.rows_p.append(positions)
        self.rows_f.append(frame_no)
        self.pending.append(t)
        self.t_end = t
        self.position = positions
        self.frames_played += 1

    def jump(self, duration_s: float, positions: Sequence[int]) -> None:
        """A move the controller makes by itself (e-stop, homing): clears the buffer; the
        motors are at rest afterwards."""
        positions = tuple(int(p) for p in positions)
        self.pending.clear()
        t = (self.play_t if self.started else 0.0) + duration_s
        self.started = True
        self.rows_t.append(t)
        self.rows_p.append(positions)
        self.rows_f.append(-1)
        self.t_end = self.play_t = t
        self.position = positions
        self._motion = self._motion_before = self._rest

    def restart(self) -> None:
        """After homing the next frame starts a new run (its time is the new origin)."""
        self.last_frame_no = None

    def _check(
        self, t: float, move_s: float, positions: tuple[int, ...], frame: int, stamped: bool
    ) -> None:
        """Judge the move to ``positions`` over ``move_s`` of timeline on the controller's
        clock, and remember its speeds for the next frame's acceleration."""
        lo, hi, vmax = self._lo, self._hi, self._vmax
        if lo is not None or hi is not None:
            for i, p in enumerate(positions):
                a_lo = -math.inf if lo is None else lo[i]
                a_hi = math.inf if hi is None else hi[i]
                if not a_lo <= p <= a_hi:
                    self.violations.append(
                        Violation(
                            t,
                            "stroke",
                            i,
                            f"frame {frame}: axis {i + 1} at {p} pulses, allowed "
                            f"[{_num(a_lo)}, {_num(a_hi)}]",
                        )
                    )
        prev_v, prev_dur, prev_stamped = self._motion
        q = self.position
        if move_s <= 0.0:  # a move in no time (IMAX PA0a = 1 with PA09 = 0)
            for i, (p, r) in enumerate(zip(positions, q, strict=True)):
                if p != r and vmax is not None:
                    self.violations.append(
                        Violation(
                            t, "speed", i, f"frame {frame}: axis {i + 1} moves {p - r} in 0 ms"
                        )
                    )
            self._motion = self._rest
            return
        dur = move_s / self.catch_up
        inv = 1.0 / dur
        speeds = tuple([(p - r) * inv for p, r in zip(positions, q, strict=True)])
        self._motion = (speeds, dur, stamped)
        vlim, alim = self._vlim, self._alim
        if vlim is not None:
            for i, (v, lim) in enumerate(zip(speeds, vlim, strict=True)):
                if v > lim or -v > lim:
                    self._speed_violation(t, frame, i, positions[i] - q[i], move_s)
        if alim is not None:
            h = 0.5 * (dur + prev_dur) if stamped and prev_stamped else dur
            inv_h = 1.0 / h
            for i, (v, u, lim) in enumerate(zip(speeds, prev_v, alim, strict=True)):
                if abs(v - u) * inv_h > lim:
                    self._accel_violation(t, frame, i, u, v, h)

    def _speed_violation(self, t: float, frame: int, i: int, step: int, move_s: float) -> None:
        assert self._vmax is not None
        dur = move_s / self.catch_up
        clock = (
            f" ({move_s * 1e3:.1f} ms / catch-up {self.catch_up:g})" if self.catch_up != 1 else ""
        )
        self.violations.append(
            Violation(
                t,
                "speed",
                i,
                f"frame {frame}: axis {i + 1} moves {step} pulses in {dur * 1e3:.3f} ms{clock} "
                f"= {abs(step) / dur:.0f} pulses/s > {self._vmax[i]:.0f}",
            )
        )

    def _accel_violation(self, t: float, frame: int, i: int, u: float, v: float, h: float) -> None:
        assert self._amax is not None
        self.violations.append(
            Violation(
                t,
                "accel",
                i,
                f"frame {frame}: axis {i + 1} speed {u:.0f} -> {v:.0f} pulses/s over {h * 1e3:.3f} "
                f"ms on the controller's clock = {abs(v - u) / h:.4g} pulses/s^2 "
                f"> {self._amax[i]:.4g}",
            )
        )

    def trace(self) -> Trace:
        n = self.n_axes
        return Trace(
            np.asarray(self.rows_t, dtype=float),
            np.asarray(self.rows_p, dtype=np.int64).reshape(-1, n),
            np.asarray(self.rows_f, dtype=np.int64),
        )


ERR_ADDRESS = 1
"""Error code of a register access to an address the controller does not have (both kinds:
the manuals define none, a decision)."""
ERR_VALUE = 2
"""Error code of a register write of a value outside the parameter's range."""


def parameter_changes(
    start: int,
    words: Sequence[int],
    by_address: Mapping[int, str],
    spec: Mapping[str, tuple[int, int, int, str]],
) -> tuple[dict[str, int], int | None]:
    """The parameter values a register write of ``words`` from address ``start`` sets, and
    ``None``; or ``({}, code)`` for the first word the controller refuses (:data:`ERR_ADDRESS`
    no parameter there, :data:`ERR_VALUE` out of its ``spec`` range). A parameter whose range
    goes below 0 reads its word as signed 16-bit."""
    changes = {}
    for i, word in enumerate(words):
        name = by_address.get(start + i)
        if name is None:
            return {}, ERR_ADDRESS
        lo, hi, _, _ = spec[name]
        value = word - 0x10000 if lo < 0 and word & 0x8000 else word
        if not lo <= value <= hi:
            return {}, ERR_VALUE
        changes[name] = value
    return changes, None


def _num(x: float) -> str:
    """A limit for a message: whole pulses, or +-inf."""
    return f"{x:.0f}" if math.isfinite(x) else str(x)


class EmulatedController(Controller, Protocol):
    """What the shared emulator state needs of a UDP controller description: a
    :class:`~._controller_api.Controller` with parameters by name, a Who node and copies
    with changed parameters."""

    @property
    def parameters(self) -> Mapping[str, int]: ...

    @property
    def node(self) -> int: ...

    def with_parameters(self, **changes: int) -> EmulatedController: ...


C = TypeVar("C", bound=EmulatedController)
"""The controller description type of a :class:`ControllerEmulator`."""


class StampedFrame(Protocol):
    """What :meth:`ControllerEmulator._stamp_step` reads of a timed frame (both kinds)."""

    @property
    def absolute(self) -> bool:
        """``True``: ``time_ms`` is the frame's time stamp; ``False``: its time step."""
        ...

    @property
    def time_ms(self) -> int:
        """Time stamp or step (ms)."""
        ...


Handler = Callable[..., WireMessage | None]
"""A :attr:`ControllerEmulator.HANDLERS` entry: ``handler(emulator, msg, now_s)`` -> the
reply (``None``: none)."""


class UdpEmulatorBase:
    """The UDP server loop and thread shared by both emulators.

    Subclasses implement :meth:`handle` (one datagram -> reply datagrams) and
    :meth:`periodic` (status reports due at wall time ``now_s``).

    Attributes
    ----------
    received : int
        Every datagram the server read, whatever it is: frames, and the status requests a
        host's link watch sends while the controller seems silent, parameter reads and
        writes. Not a frame count (a controller emulator's ``frames_received`` is).
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0) -> None:
        self._host = host
        self._port = port
        self._sock: socket.socket | None = None
        self._thread: threading.Thread | None = None
        self._stop = threading.Event()
        self.lock = threading.RLock()
        self.last_peer: tuple[str, int] | None = None
        self.received = 0
        self._stamped = False
        self.internal_errors: list[str] = []  # emulator bugs met while serving (none expected)

    # -- subclass hooks -----------------------------------------------------------------
    def handle(self, data: bytes, now_s: float) -> list[bytes]:  # pragma: no cover - abstract
        raise NotImplementedError

    def periodic(self, now_s: float) -> list[bytes]:
        return []

    # -- server -------------------------------------------------------------------------
    @property
    def port(self) -> int:
        """The UDP port the emulator listens on (after :meth:`start`)."""
        return self._port

    @property
    def where(self) -> str:
        """``udp://HOST:PORT`` it listens on (the port known after :meth:`start`)."""
        return f"udp://{self._host}:{self._port}"

    def start(self) -> Self:
        """Bind and serve in a daemon thread."""
        try:
            sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 21)
            sock.bind((self._host, self._port))
        except OSError as exc:
            raise TransportError(
                f"emulator cannot listen on {self._host}:{self._port}: {exc}"
            ) from exc
        self._stamped = False
        if _SO_TIMESTAMPNS is not None:
            try:
                sock.setsockopt(socket.SOL_SOCKET, _SO_TIMESTAMPNS, 1)
                self._stamped = True
            except OSError:
                pass
        sock.settimeout(0.02)
        self._port = int(sock.getsockname()[1])
        self._sock = sock
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name="motioncue-emulator", daemon=True)
        self._thread.start()
        return self

    def serve_forever(self) -> None:
        """Serve in the calling thread until :meth:`stop` (or Ctrl-C)."""
        if self._sock is None:
            self.start()
        assert self._thread is not None
        try:
            while self._thread.is_alive():
                self._thread.join(0.2)
        finally:
            self.stop()

    def _serve(self) -> None:
        sock = self._sock
        assert sock is not None
        while not self._stop.is_set():
            try:
                data, peer, now = self._receive(sock)
            except TimeoutError:
                data, peer, now = b"", None, wall_clock()
            except OSError:
                break
            with self.lock:
                try:
                    if peer is not None:
                        self.last_peer = peer
                        self.received += 1
                        replies = self.handle(data, now)
                    else:
                        replies = []
                    reports = self.periodic(now)
                except Exception as exc:  # keep serving; the error is reported
                    self.internal_errors.append(f"{type(exc).__name__}: {exc}")
                    replies, reports = [], []
            target = peer or self.last_peer
            if target is None:
                continue
            for out in (*replies, *reports):
                try:
                    sock.sendto(out, target)
                except OSError:
                    pass

    def _receive(self, sock: socket.socket) -> tuple[bytes, tuple[str, int], float]:
        """One datagram, its sender and its arrival time: the kernel's receive stamp when
        the OS gives one (so a busy emulator thread does not distort the playback model),
        else the time it is read."""
        if not self._stamped:
            data, peer = sock.recvfrom(65536)
            return data, peer, wall_clock()
        data, ancillary, _flags, peer = sock.recvmsg(65536, 64)
        for level, kind, cdata in ancillary:
            if level == socket.SOL_SOCKET and kind == _SO_TIMESTAMPNS and len(cdata) >= 8:
                sec, nsec = _TIMESPEC.unpack_from(cdata.ljust(_TIMESPEC.size, b"\0"))
                return data, peer, sec + nsec * 1e-9
        return data, peer, wall_clock()

    def stop(self) -> None:
        """Stop serving and close the socket (idempotent)."""
        self._stop.set()
        if self._thread is not None and self._thread is not threading.current_thread():
            self._thread.join(2.0)
        if self._sock is not None:
            self._sock.close()
        self._sock = None
        self._thread = None

    def __enter__(self) -> Self:
        if self._sock is None:
            self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


class ControllerEmulator(UdpEmulatorBase, Generic[C]):
    """State and views both controller emulators keep on top of the server loop.

    The controller description, a mutable copy of its parameters, the homing / ready /
    e-stop state, frame counters, the violations met while decoding, and the
    :class:`Playback` of ``controller.buffer_frames`` frames (FIFO or latest-frame as
    :meth:`_fifo` says).

    Parameters
    ----------
    controller : C
        The description (an ``ImaxController``, ``MboxController``).
    host, port : str, int
        Where to listen when started (port 0 = any free port; see :attr:`port`).
    homing_time_s : float
        How long initial positioning takes (s).
    start_homed : bool
        ``True``: ready at once; ``False``: homing first, as after power-up.

    Attributes
    ----------
    frames_received : int
        Frame datagrams (header function in :attr:`FRAME_FUNCTIONS`) addressed to this
        controller's node, counted by :meth:`handle` whether they are played, refused or
        malformed: what a host's frame counter must equal. Other datagrams (status
        requests, parameter reads and writes) are in ``received`` only.
    """

    playback: Playback
    LABEL: ClassVar[str]
    """The controller's name in messages (``"IMAX"``, ``"MBOX"``)."""
    FRAME_FUNCTIONS: ClassVar[frozenset[int]] = frozenset({F_ABS, F_REL})
    """Header functions of the frames the host sends (0x1301 absolute, 0x1401 relative
    time); a kind with more frame messages (IMAX vibration frames) adds them."""
    HANDLERS: ClassVar[tuple[tuple[type | tuple[type, ...], Handler], ...]]
    """What the controller does with each decoded message it receives: ``(message
    type(s), handler)`` pairs, the first whose type matches is called as ``handler(self,
    msg, now_s)`` and returns the reply (subclasses first where one message subclasses
    another); a message that matches none is one the controller sends, not receives."""
    LIMIT_PARAMS: ClassVar[frozenset[str]]
    """The parameters ``controller.pulse_limits()`` comes from (a write of one of them
    changes the limits frames are judged with)."""

    def __init__(
        self,
        controller: C,
        host: str = "127.0.0.1",
        port: int = 0,
        *,
        homing_time_s: float = 1.0,
        start_homed: bool = True,
    ) -> None:
        super().__init__(host, port)
        self.controller: C = controller
        self.n_axes: int = controller.n_axes
        self.params: dict[str, int] = dict(controller.parameters)
        self.homing_time_s = float(homing_time_s)
        self.state = STATE_READY if start_homed else STATE_HOMING
        # -1: homing starts at the first datagram's wall time
        self._homing_until: float | None = None if start_homed else -1.0
        self.ignored_frames = 0
        self.refused_frames = 0
        self.frames_received = 0
        self._last_time_ms: int | None = None
        self._next_report: float | None = None
        self._violations: list[Violation] = []
        self.playback = Playback(self.n_axes, controller.buffer_frames, self._fifo())
        self._init_kind()
        self._set_limits()
        self._set_rate()

    # -- subclass hooks -----------------------------------------------------------------
    def _init_kind(self) -> None:  # pragma: no cover - abstract
        """The kind's own state."""
        raise NotImplementedError

    def _fifo(self) -> bool:
        """Whether the buffer plays every frame in order (``False``: only the latest)."""
        return True

    def _set_rate(self) -> None:  # pragma: no cover - abstract
        """Playback rate from the current parameters."""
        raise NotImplementedError

    def _tick(self, now_s: float) -> None:  # pragma: no cover - abstract
        """Advance playback, homing and timers to wall time ``now_s``."""
        raise NotImplementedError

    def _header(self, data: bytes) -> Header:
        """The header of a datagram sent to the controller (:class:`ProtocolError` if none)."""
        return decode_header(data)

    def _replies_enabled(self) -> bool:
        """Whether the controller answers at all (a parameter may turn replies off)."""
        return True

    def _decode(self, data: bytes, h: Header, reply: bool) -> WireMessage | list[bytes]:
        """The message in ``data`` (header ``h``), or, when it cannot be decoded, what the
        controller sends back instead (the malformed datagram recorded)."""
        raise NotImplementedError  # pragma: no cover - abstract

    def _answer(self, msg: WireMessage, now_s: float) -> WireMessage | None:
        """Act on a decoded message with its :attr:`HANDLERS` entry; the reply to send (if
        replies are asked for). A message the controller only sends is recorded malformed."""
        for types, handler in self.HANDLERS:
            if isinstance(msg, types):
                return handler(self, msg, now_s)
        self._not_to_it(msg)
        return None

    # -- datagrams ----------------------------------------------------------------------
    def handle(self, data: bytes, now_s: float) -> list[bytes]:
        """Process one datagram at wall time ``now_s``; return the reply datagrams.

        A datagram whose header does not decode is recorded as malformed; one whose Who
        accept field does not select this controller's node is ignored; the others are
        decoded (:meth:`_decode`) and acted on (:meth:`_answer`), and the reply is sent
        when the Who reply field selects the node and :meth:`_replies_enabled`.
        """
        self._tick(now_s)
        try:
            h = self._header(data)
        except ProtocolError as exc:
            return self._malformed(str(exc))
        node = self.controller.node
        if not who_matches(h.who_accept, node):
            return []
        if h.confirm == CONFIRM_MAIN and h.function in self.FRAME_FUNCTIONS:
            self.frames_received += 1
        reply = who_matches(h.who_reply, node) and self._replies_enabled()
        msg = self._decode(data, h, reply)
        if isinstance(msg, list):
            return msg
        out = self._answer(msg, now_s)
        return [out.encode()] if reply and out is not None else []

    def _not_to_it(self, msg: WireMessage) -> None:
        """Record a message the controller sends but never receives; no reply."""
        self._malformed(f"{type(msg).__name__} is sent by an {self.LABEL}, not to it")

    @property
    def trace(self) -> Trace:
        with self.lock:
            return self.playback.trace()

    @property
    def violations(self) -> list[Violation]:
        with self.lock:
            return [*self._violations, *self.playback.violations]

    @property
    def estop(self) -> bool:
        return self.state == STATE_ESTOP

    def _same_stamp(self, frame: int, positions: Sequence[int], jog_s: float, source: str) -> None:
        """Flag a frame carrying the previous frame's ms stamp (or relative time 0 within a
        run) that moves: the host meant it to follow at once, the controller moves over
        its jog time ``jog_s`` (``source`` names the parameter) instead."""
        pb = self.playback
        if tuple(positions) != pb.position:
            pb.violations.append(
                Violation(
                    pb.t_end + jog_s,
                    "jog",
                    None,
                    f"frame {frame} has the previous frame's ms stamp but moves: the "
                    f"controller moves it over {source} = {jog_s * 1e3:g} ms",
                )
            )

    def _stamp_step(self, msg: StampedFrame) -> int | None:
        """The time step (ms) of frame ``msg`` after the previous frame of the run: its
        relative time, or its stamp minus the previous stamp (``None`` for the first
        absolute frame of a run); remembers an absolute frame's stamp for the next."""
        if not msg.absolute:
            return msg.time_ms
        step = None if self._last_time_ms is None else msg.time_ms - self._last_time_ms
        self._last_time_ms = msg.time_ms
        return step

    def _set_limits(self) -> None:
        """Judge later frames with the limits of the description with the current values
        of :attr:`LIMIT_PARAMS` (as written by the host). Parameters that imply no usable
        limits (a stroke of less than a pulse) are flagged ``config`` and the limits stay
        as they were."""
        base = self.controller.parameters
        changed = {k: self.params[k] for k in self.LIMIT_PARAMS if self.params[k] != base[k]}
        try:
            ctrl = self.controller.with_parameters(**changed) if changed else self.controller
            limits = ctrl.pulse_limits()
        except MotioncueError as exc:
            self._violations.append(
                Violation(self.playback.t_end, "config", None, f"limits unchanged: {exc}")
            )
            return
        self.playback.set_limits(limits)

    def _refuse_full(self, frame: int, note: str = "") -> None:
        """Count and record frame ``frame`` refused because the buffer is full (``note``:
        the controller's error, appended to the detail)."""
        pb = self.playback
        self.refused_frames += 1
        self._violations.append(
            Violation(
                pb.t_end,
                "buffer",
                None,
                f"frame {frame} refused: buffer full ({pb.depth} frames{note})",
            )
        )

    def _begin_homing(self, now_s: float) -> None:
        """Start initial positioning at wall time ``now_s``: the platform goes to zero over
        ``homing_time_s`` (the buffer cleared) and the next frame starts a new run."""
        self.state = STATE_HOMING
        self._homing_until = now_s + self.homing_time_s
        self.playback.jump(self.homing_time_s, [0] * self.n_axes)
        self.playback.restart()
        self._last_time_ms = None

    def _malformed(self, detail: str) -> list[bytes]:
        """Record a datagram the controller cannot use; no reply."""
        self._violations.append(Violation(self.playback.t_end, "malformed", None, detail))
        return []

    def _homing_done(self, now_s: float) -> bool:
        """Advance homing to ``now_s``; ``True`` when it has just finished."""
        if self.state != STATE_HOMING:
            return False
        if self._homing_until is not None and self._homing_until < 0:
            self._homing_until = now_s + self.homing_time_s
        if self._homing_until is not None and now_s >= self._homing_until:
            self.state = STATE_READY
            self._homing_until = None
            return True
        return False

    def _position_now(self) -> tuple[int, ...]:
        """Commanded position at the playback clock (linear between frames)."""
        pb = self.playback
        if not pb.rows_t:
            return (0,) * self.n_axes
        t = pb.play_t
        rows_t = pb.rows_t
        k = len(rows_t) - 1
        while k > 0 and rows_t[k - 1] >= t:
            k -= 1
        if k == 0 or rows_t[k] <= t:
            return pb.rows_p[k]
        t0, t1 = rows_t[k - 1], rows_t[k]
        w = (t - t0) / (t1 - t0) if t1 > t0 else 1.0
        return tuple(
            round(a + (b - a) * w) for a, b in zip(pb.rows_p[k - 1], pb.rows_p[k], strict=True)
        )
