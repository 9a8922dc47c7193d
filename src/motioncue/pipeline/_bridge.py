"""The live bridge: telemetry -> washout -> cue gate -> workspace -> IK -> output, in real time.

One :class:`Bridge` runs the loop in its own thread on absolute ``perf_counter`` deadlines
(:class:`~motioncue.pipeline._realtime.Ticker`: sleep, then spin the last part). Telemetry is
received apart, in the telemetry source's own thread; each tick reads only its newest sample.
Per tick:

1. newest sample (``source.latest()``, never blocks);
2. cue gate (:class:`~motioncue.pipeline._realtime.CueGate`): live when the newest sample
   is younger than ``gate.timeout_s`` and not paused, else the gain fades to 0 (parked). The
   bridge starts parked and ramps in; while parked the washout state is reset so a resume
   starts clean;
3. up-sampling (:mod:`~motioncue.pipeline._upsample`, ``BridgeConfig.upsample``): the
   telemetry at the frame's time, from the samples so far (held, interpolated, or
   extrapolated and corrected on the next sample), then the washout step (streaming,
   explicit :class:`~motioncue.cueing.WashoutState`; the washout runs at the frame rate);
4. blend ``pose = pose_park + gain * (cue - pose_park)``, plus ``gain`` x the effect layer's
   offsets when effects are on (:mod:`~motioncue.pipeline._effects`: engine, road, shift);
5. workspace limiting (:func:`motioncue.trajectory.limit_pose`, which also returns the
   inverse kinematics of the pose it keeps: ``platform.inverse``'s single-pose fast path);
6. :meth:`OutputStage.emit <motioncue.pipeline._stream.OutputStage.emit>`: real-time
   actuator limiter (limits tightened by the pulse rounding), pulses, frame encoder, send.
   While parked the stage is driven to the park position itself.

Every frame passes the limiter, whatever the telemetry carries, so every frame respects the
limits table of ``motioncue limits``. On :meth:`Bridge.stop`, or when the source reports
``finished`` (the end of a replayed recording), the gate fades out, the stage parks at rest,
then the loop ends. One frame's work is :meth:`Bridge.step`, which tests and
simulations may call by hand on their own clock instead of starting the thread.

*Frames on arrival* (``BridgeConfig(frame_clock="arrival")``, SC-MBOX and IMAX: whole-ms
time stamps): instead of waiting for the next slot, the loop sends a frame at the next whole
ms after a telemetry sample arrives, else one every period; when the game's next packet is
due just after a regular slot, that frame waits for it (up to ``period + min_interval_ms``),
so the frames lock on to the packets (60 Hz into 250 Hz: 4, 4, 4, 5 ms). The stage
(:class:`~motioncue.pipeline._arrival.ArrivalOutputStage`) keeps the limits on the
controller's clock for any whole-ms intervals; the cueing runs per ms.

*Lead*: a controller moves to a frame's position over the interval after the frame
arrives, so a frame holding the cue of the moment it is sent is felt one interval late (a
step in the telemetry shows in the frames' acceleration only one frame later). Each frame
therefore carries the cue for the end of the interval it starts (``BridgeConfig.lead_ms``,
default one period on arrival): the cueing runs that far ahead of the wall clock on the
up-sampler's extrapolation, which is corrected smoothly from the last value used when the
next sample arrives. Measured on loopback (``benchmarks/bench_latency.py``): a lateral-g
step reaches the first frame after its packet, 0.8-0.9 ms p50 instead of 4.7-4.9 ms.

On a busy PC the scheduler may hold the loop back by several milliseconds. The loop thread
asks for a short scheduler slice (``BridgeConfig.slice_s``, no privilege needed: see
:mod:`~motioncue.pipeline._realtime`), which on Linux >= 6.12 lets it run as soon as it
wakes, beside a busy core. ``BridgeConfig(rt_priority=...)`` (``--rt-priority``) runs the
loop thread under ``SCHED_FIFO`` where the system allows it (``benchmarks/bench_bridge.py``
measures each).

Timing figures (:class:`BridgeStats`):

* *added latency*: for each frame that uses a sample for the first time, the time from
  ``max(sample arrival stamp, tick deadline)`` to the return of the last ``transport.send``:
  what the bridge adds once both the datagram and the frame slot are there;
* *sample age*: from the datagram's arrival stamp to the same send, which also contains the
  sample-and-hold wait for the next frame slot (between 0 and one frame period: inherent to
  a fixed frame rate, since the game sends at its own rate and phase);
* *jitter*: ``|interval between consecutive sends - period|`` (frames on arrival: minus the
  interval between the two frames' own time stamps);
* *frame age*: for every frame, from the arrival stamp of the newest sample it used to
  the return of its send (``BridgeStats.frame_age_ms`` for the last frame, percentiles
  over the window).
"""

from __future__ import annotations

import gc
import math
import os
import sys
import threading
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Literal, Protocol, runtime_checkable

import numpy as np

from .._errors import ConfigError, MotioncueError
from ..cueing import Rig, cueing_algorithms, cueing_entry, make_cueing
from ..trajectory import limit_pose
from ._effects import EffectGains, EffectsState, make_effects
from ._realtime import CueGate, GateConfig, Ticker
from ._stream import OutputStage

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..cueing import CueingParams, CueingState
    from ..kinematics import Platform
    from ..output import Controller, Transport
    from ..telemetry import TelemetrySample
    from ..trajectory import ActuatorLimits
    from ._arrival import ArrivalOutputStage

__all__ = [
    "CLAMP_WARN_FRACTION",
    "CLAMP_WARN_MIN_POSES",
    "Bridge",
    "BridgeConfig",
    "BridgeStats",
    "FinishingInput",
    "ReportsCueingStats",
    "TelemetryInput",
]

CLAMP_WARN_FRACTION = 0.01
"""Share of clamped poses above which the bridge warns (live and at the end)."""

CLAMP_WARN_MIN_POSES = 100
"""Poses before the clamp share is judged (the first few ticks say little)."""


class TelemetryInput(Protocol):
    """What the bridge needs from a telemetry source (``motioncue.telemetry.open_source``).

    ``latest()`` returns the newest :class:`~motioncue.telemetry.TelemetrySample` (or None)
    without blocking; ``stats`` maps outcome reasons (``"skipped: truncated"``...) and the
    counters ``datagrams``, ``samples``, ``receive errors`` to counts. A source that can end
    also has :class:`FinishingInput`'s ``finished``; one without it never finishes.
    """

    def latest(self) -> TelemetrySample | None: ...

    @property
    def stats(self) -> Mapping[str, int]: ...


@runtime_checkable
class FinishingInput(Protocol):
    """The optional capability of a :class:`TelemetryInput` that can end.

    ``finished`` (the telemetry sources have it: False for live receivers, True at the end
    of a replayed file) tells the bridge that nothing more will come: it then fades out,
    parks and ends as on :meth:`Bridge.stop`. The bridge looks for it once, when it is
    made.
    """

    @property
    def finished(self) -> bool: ...


@runtime_checkable
class ReportsCueingStats(Protocol):
    """The optional capability of a cueing design that reports on its run (MPC: solve times,
    fallbacks): ``stats(state)``, names to numbers, copied into :attr:`BridgeStats.cueing`.
    """

    def stats(self, state: CueingState) -> Mapping[str, float]: ...


@dataclass(frozen=True)
class BridgeConfig:
    """How the live loop runs.

    Attributes
    ----------
    rate_hz : float
        Frame rate (and washout sample rate), in (0, 1000] Hz.
    gate : GateConfig
        Telemetry timeout and fade times.
    spin_s : float
        Busy-wait before each deadline (s), in [0, 0.01].
    stats_window : int
        Ticks kept for the percentiles (>= 10).
    rt_priority : int or None
        If given (1..99), the loop thread asks for the ``SCHED_FIFO`` real-time policy at
        this priority (Linux; needs root or ``CAP_SYS_NICE``). On a busy machine this keeps
        other processes from delaying the frames; if it is refused the loop runs anyway
        and ``BridgeStats.notes`` says why. None: the normal policy.
    switch_interval_s : float or None
        While running, the interpreter's thread switch interval is lowered to this (s) so
        that another Python thread (the telemetry receiver, an in-process emulator) holds
        the GIL for at most this long when the loop wakes; restored on stop. None: leave it.
    upsample : str
        How telemetry slower than the frame rate is brought to each frame's time
        (the names ``motioncue bridge --upsample`` takes): ``"hold"`` (the newest sample,
        a step per sample), ``"interpolate"`` (one telemetry period late, no steps) or
        ``"extrapolate"`` (no steps and no lag for smooth motion; bounded overshoot on a
        step in the telemetry).
    frame_clock : str
        ``"fixed"``: a frame every period. ``"arrival"`` (SC-MBOX, IMAX: whole-ms time
        stamps): a frame as soon as a telemetry sample arrives (at the next whole ms, at
        least ``min_interval_ms`` after the previous frame), else every period; the frame
        clock locks on to the game's packets (module docstring, *Frames on arrival*).
    min_interval_ms : int
        Shortest interval between frames on arrival (ms), 1..period.
    slice_s : float or None
        The loop thread asks the scheduler for this short slice (s, [1e-4, 0.1]; Linux >=
        6.12, no privilege, same priority: :func:`~motioncue.pipeline._realtime.
        request_short_slice`) so that it runs as soon as it wakes beside a busy core; if
        it is refused ``BridgeStats.notes`` says why. None: the default slice.
    lead_ms : int or None
        How far ahead of its send time each frame's cue is computed (ms, 0..period; None:
        one frame period with frames on arrival, 0 with fixed frames). The controller moves
        to a frame's position over the interval after it receives the frame, so a frame
        that holds the cue of the moment it is sent is felt one interval late; computed for
        the end of that interval (the telemetry brought there by the up-sampler,
        ``upsample``), the motion reaches the rider when the game sent it. The gate
        (timeouts, fades) keeps the wall clock; with ``upsample = "hold"`` the lead changes
        nothing.
    """

    rate_hz: float = 100.0
    gate: GateConfig = field(default_factory=GateConfig)
    spin_s: float = 0.001
    stats_window: int = 20000
    rt_priority: int | None = None
    switch_interval_s: float | None = 0.0005
    upsample: str = "hold"
    frame_clock: str = "fixed"
    min_interval_ms: int = 2
    lead_ms: int | None = None
    slice_s: float | None = 1e-4

    def __post_init__(self) -> None:
        if self.frame_clock not in ("fixed", "arrival"):
            raise ConfigError(
                f"frame_clock = {self.frame_clock!r} is unknown; allowed: fixed, arrival"
            )
        from ._upsample import UPSAMPLERS

        if self.upsample not in UPSAMPLERS:
            raise ConfigError(
                f"upsample = {self.upsample!r} is unknown; allowed: "
                + ", ".join(sorted(UPSAMPLERS))
            )
        if not (math.isfinite(self.rate_hz) and 0.0 < self.rate_hz <= 1000.0):
            raise ConfigError(f"rate_hz = {self.rate_hz!r} is invalid; allowed: (0, 1000] Hz")
        if not (math.isfinite(self.spin_s) and 0.0 <= self.spin_s <= 0.01):
            raise ConfigError(f"spin_s = {self.spin_s!r} is invalid; allowed: [0, 0.01] s")
        if self.stats_window < 10:
            raise ConfigError(f"stats_window = {self.stats_window!r} is invalid; allowed: >= 10")
        p = self.rt_priority
        if p is not None and not (isinstance(p, int) and 1 <= p <= 99):
            raise ConfigError(f"rt_priority = {p!r} is invalid; allowed: None or 1..99")
        s = self.switch_interval_s
        if s is not None and not (math.isfinite(s) and 1e-5 <= s <= 0.1):
            raise ConfigError(
                f"switch_interval_s = {s!r} is invalid; allowed: None or [1e-5, 0.1] s"
            )
        sl = self.slice_s
        if sl is not None and not (math.isfinite(sl) and 1e-4 <= sl <= 0.1):
            raise ConfigError(f"slice_s = {sl!r} is invalid; allowed: None or [1e-4, 0.1] s")
        lead = self.lead_ms
        period_ms = 1000.0 / self.rate_hz
        if lead is not None and not (isinstance(lead, int) and 0 <= lead <= period_ms):
            raise ConfigError(
                f"lead_ms = {lead!r} is invalid; allowed: None or 0..{period_ms:g} ms (whole)"
            )


@dataclass(frozen=True)
class BridgeStats:
    """A snapshot of the bridge (see the module docstring for the timing definitions).

    Attributes
    ----------
    state : str
        ``"new"``; ``"parked"`` (at the park position, at rest); ``"parking"`` (gate closed,
        the limiter still on its way to park); ``"fading in"``, ``"live"``, ``"fading out"``;
        ``"stopping"``, ``"stopped"``; ``"failed, parking"`` (a frame failed: parking at
        once), then ``"failed"``.
    gain : float
        Cue gate gain in [0, 1] (0 = parked).
    frames_sent : int
        Frames encoded and sent.
    missed_deadlines : int
        Frame slots skipped because the loop overran a whole period.
    samples_in, datagrams_in : int
        Telemetry samples and datagrams the source received.
    rate_in_hz, rate_out_hz : float
        Telemetry sample rate and frame rate over about the last second (nan if unknown).
    jitter_p99_ms, latency_p50_ms, latency_p99_ms, latency_max_ms, age_p99_ms : float
        Over the last ``stats_window`` ticks; nan before there is data.
    limiter_clamped_frames : int
        Frames the actuator limiter changed (beyond a feasible target stream).
    pose_clamped, pose_invalid : int
        Ticks whose pose the workspace limiting scaled back / found non-finite.
    poses : int
        Ticks whose pose went through the workspace limiting (the denominator of
        ``pose_clamped``; see :meth:`clamp_warning`).
    cueing_bad_samples : int
        Telemetry samples the cueing held since the start (NaN, inf, spikes).
    bad_packets : int
        Datagrams the decoder skipped (truncated, foreign, non-finite...) plus receive errors.
    packet_reasons : dict[str, int]
        The source's counters by reason.
    fade_ins, fade_outs : int
        Times the gate started fading in / out.
    park_q_error : float
        ``max |q - q_park|`` of the last frame (SI); 0 when parked.
    error : str or None
        Why the loop stopped, if it failed.
    notes : tuple of str
        Things the user should know that did not stop the loop (a refused real-time
        priority, where the platform started).
    send_errors : int
        Transient send errors met and retried within their frame.
    status_requests : int
        Status requests (register reads) the link watch sent while the controller was
        silent for its probe interval (0.2 s by default; a busy controller or machine).
        Datagrams on the link besides the frames, never counted in ``frames_sent`` (the
        others: the start-position query of ``q_start="auto"``, a kind's end-of-run
        messages).
    frame_age_ms, frame_age_p50_ms, frame_age_p99_ms : float
        Age of the newest sample a frame used, at the return of its send: the last
        frame's, and percentiles over the window (nan before there is data).
    cueing : dict[str, float]
        The cueing algorithm's own figures when it reports any (``stats(state)``; the MPC:
        ``solves``, ``failed``, ``late``, ``fallbacks``, ``p50_ms``, ``p99_ms``, ``max_ms``
        of its solves); empty for the classical washout.
    """

    state: str
    gain: float
    frames_sent: int
    missed_deadlines: int
    samples_in: int
    datagrams_in: int
    rate_in_hz: float
    rate_out_hz: float
    jitter_p99_ms: float
    latency_p50_ms: float
    latency_p99_ms: float
    latency_max_ms: float
    age_p99_ms: float
    limiter_clamped_frames: int
    pose_clamped: int
    pose_invalid: int
    cueing_bad_samples: int
    bad_packets: int
    packet_reasons: dict[str, int]
    fade_ins: int
    fade_outs: int
    park_q_error: float
    error: str | None
    notes: tuple[str, ...] = ()
    send_errors: int = 0
    status_requests: int = 0
    frame_age_ms: float = math.nan
    frame_age_p50_ms: float = math.nan
    frame_age_p99_ms: float = math.nan
    cueing: dict[str, float] = field(default_factory=dict)
    poses: int = 0

    @property
    def pose_clamped_fraction(self) -> float:
        """``pose_clamped / poses`` (0 before any pose)."""
        return self.pose_clamped / self.poses if self.poses else 0.0

    def clamp_warning(self) -> str | None:
        """A warning when more than :data:`CLAMP_WARN_FRACTION` of the poses so far were
        clamped (after :data:`CLAMP_WARN_MIN_POSES` poses), else None.

        Clamped poses are cues the platform cannot give: the preset asks more than this
        platform's workspace (a preset tuned for another platform, or gains too high).
        """
        if self.poses < CLAMP_WARN_MIN_POSES or self.pose_clamped_fraction <= CLAMP_WARN_FRACTION:
            return None
        return (
            f"the workspace limit clamped {self.pose_clamped} of {self.poses} poses "
            f"({100 * self.pose_clamped_fraction:.1f} %, more than "
            f"{100 * CLAMP_WARN_FRACTION:g} %): the cues ask more than this platform can "
            "move; use the platform's own preset (its default_preset) or lower the gains"
        )

    def status_line(self) -> str:
        """One line for a terminal status display."""
        bad = ", ".join(
            f"{k.split(': ', 1)[-1]} {v}"
            for k, v in sorted(self.packet_reasons.items())
            if v and (k.startswith("skipped") or k == "receive errors")
        )

        def f(x: float, fmt: str) -> str:
            return "-" if math.isnan(x) else format(x, fmt)

        return (
            f"{self.state:<10} gain {self.gain:4.2f} | in {f(self.rate_in_hz, '5.1f')}/s"
            f" out {f(self.rate_out_hz, '5.1f')}/s | jitter p99 {f(self.jitter_p99_ms, '.2f')}"
            f" ms | latency p99 {f(self.latency_p99_ms, '.2f')} ms | age"
            f" {f(self.frame_age_ms, '.1f')} ms | limiter {self.limiter_clamped_frames} frames"
            f" | workspace {self.pose_clamped} poses | bad"
            f" {self.bad_packets}{f' ({bad})' if bad else ''} | missed {self.missed_deadlines}"
            + ("".join(f" | {k}" for k, v in sorted(self.packet_reasons.items())
                       if v and k.startswith("note: ")))
            + (f" | solve p99 {self.cueing['p99_ms']:.2f} ms fallback"
               f" {int(self.cueing['fallbacks'])}" if "p99_ms" in self.cueing else "")
            + (f" | WARNING {100 * self.pose_clamped_fraction:.0f} % of poses clamped"
               if self.clamp_warning() is not None else "")
        )  # fmt: skip


class _Ring:
    """Fixed-size float ring written by the loop thread, read by others.

    Readers never reorder the whole window: percentiles do not depend on the order
    (:meth:`percentiles_ms`), and the few values needed in order are read by index
    (:meth:`last`). A value written while a reader copies is read either old or new.
    """

    __slots__ = ("buf", "n", "prev")

    def __init__(self, size: int) -> None:
        self.buf = np.full(size, np.nan)
        self.n = 0
        self.prev = math.nan  # the last value added (the loop thread's own, for differences)

    def add(self, x: float) -> None:
        self.buf[self.n % self.buf.size] = x
        self.n += 1
        self.prev = x

    def values(self, last: int | None = None) -> np.ndarray:
        """The last ``last`` (default: all kept) finite values, oldest first (a copy)."""
        n, size = self.n, self.buf.size
        data = self.buf.copy()
        k = min(n, size) if last is None else min(n, size, last)
        if k == 0:
            return data[:0]
        idx = (np.arange(n - k, n)) % size
        v = data[idx]
        finite: np.ndarray = v[np.isfinite(v)]
        return finite

    def last(self, k: int) -> list[float]:
        """The last ``k`` finite values kept, oldest first (``values()[-k:]``, read by index
        from the newest back instead of copying the window)."""
        n, size = self.n, self.buf.size
        buf = self.buf
        out: list[float] = []
        for j in range(n - 1, n - 1 - min(n, size), -1):
            if len(out) == k:
                break
            x = float(buf[j % size])
            if math.isfinite(x):
                out.append(x)
        out.reverse()
        return out

    def percentiles_ms(self, qs: tuple[float, ...]) -> tuple[list[float], float]:
        """Percentiles ``qs`` (0-100) of the finite values kept and their maximum, in ms
        (x 1e3; nan without data): numpy's default (linear) percentile, ``x[i] + f (x[i+1]
        - x[i])`` at ``i + f = (m - 1) q / 100``, from the order statistics themselves.

        One single-index partition per percentile, highest first and each within the part
        below the last (numpy's partition with several indices at once, or a sort, costs
        about seven times as much on 20000 values); ``x[i]`` is the maximum of the part
        below ``x[i+1]``."""
        v = self.buf[: min(self.n, self.buf.size)]
        v = v[np.isfinite(v)]  # a copy: the loop thread may go on writing the ring
        m = v.size
        if m == 0:
            return [math.nan] * len(qs), math.nan
        top = float(v.max())
        out = [math.nan] * len(qs)
        bound = m  # v[:bound] not yet ordered; v[bound] (if any) is in its place
        for j in sorted(range(len(qs)), key=lambda j: -qs[j]):
            h = (m - 1) * (qs[j] / 100.0)
            lo = math.floor(h)
            k = min(lo + 1, m - 1)  # the upper order statistic
            if k < bound:
                v[:bound].partition(k)
                bound = k
            x_hi = float(v[k])
            x_lo = float(v[:k].max()) if lo < k else x_hi
            out[j] = _lerp(x_lo, x_hi, h - lo) * 1e3
        return out, top * 1e3


def _telemetry_notes(reasons: Mapping[str, int], finished: bool) -> tuple[str, ...]:
    """Notes from the source: its ``note: ...`` counters (e.g. F1 angular velocity derived
    from the orientation) and the end of a replay."""
    notes = tuple(
        f"telemetry: {k[len('note: ') :]} ({v} samples)"
        for k, v in sorted(reasons.items())
        if k.startswith("note: ") and v
    )
    if finished:
        notes += ("telemetry: the source finished (end of the replay); faded out and parked",)
    return notes


def _lerp(a: float, b: float, t: float) -> float:
    """``a + t (b - a)``, written from the end nearer to ``t`` as numpy's percentile does."""
    d = b - a
    return b - d * (1.0 - t) if t >= 0.5 else a + d * t


class Bridge:
    """The live loop, usable in-process (tests) and from ``motioncue bridge``.

    Parameters
    ----------
    platform : motioncue.kinematics.Platform
    controller
        From :func:`motioncue.output.load_controller`.
    cueing : motioncue.cueing.CueingParams
        Cueing preset (``load_cueing("racing")``); its ``algorithm`` picks the cueing
        algorithm (:func:`motioncue.cueing.make_cueing`), stepped with an explicit state.
    source : TelemetryInput
        A started telemetry source (``motioncue.telemetry.open_source("f1:20777")``) or any
        object with ``latest()`` and ``stats``. Not closed by the bridge.
    transport : motioncue.output.Transport
        Where frames go (anything with ``send(data, *, t_s=None)``). Not closed by the bridge.
    limits : motioncue.trajectory.ActuatorLimits
        The limits table in SI (``ActuatorLimits.from_platform(platform, controller, ...)``).
    config : BridgeConfig, optional

    q_start : array_like or "auto", optional
        Where the platform is (at rest) at the start: default parked (as after homing);
        ``"auto"`` asks the controller (see :class:`~motioncue.pipeline.OutputStage`).
    effects : EffectGains, optional
        Effect layer gains (engine, road, shift): small heave/roll/pitch added to the cued
        pose before workspace limiting, faded with the cue. Refused (``ConfigError``) below
        100 Hz. None or all gains 0: no effects.

    Notes
    -----
    Use ``bridge.start()``, read ``bridge.stats`` at will, ``bridge.stop()`` to park and end
    (``with Bridge(...) as b:`` does both). If a frame fails (an exception anywhere in
    :meth:`step`, a link that keeps failing) the loop parks at once by the same limiter and
    ends in state ``"failed"`` with ``stats.error`` set; if even the park cannot be sent,
    ``stats.error`` starts with ``PARK FAILED``. Over ``udp://`` a controller silent for
    longer than the target's ``silence_ms`` (default 500 ms), or refusing frames for a
    reason waiting does not cure, fails the loop the same way
    (the link watch of the output stage); the park is sent all the same, and the
    loop ends ``"stopped"`` only once the controller answered the final park frame
    (otherwise ``stats.error`` starts with ``PARK NOT CONFIRMED``).
    """

    def __init__(
        self,
        platform: Platform,
        controller: Controller,
        cueing: CueingParams,
        source: TelemetryInput,
        transport: Transport,
        limits: ActuatorLimits,
        config: BridgeConfig | None = None,
        *,
        q_start: ArrayLike | Literal["auto"] | None = None,
        effects: EffectGains | None = None,
    ) -> None:
        self.platform = platform
        self.controller = controller
        self.source = source
        self._finishing = source if isinstance(source, FinishingInput) else None
        self.transport = transport
        self.limits = limits
        self.config = BridgeConfig() if config is None else config
        cfg = self.config
        if limits.n_actuators != platform.n_actuators:
            raise ConfigError(
                f"limits have {limits.n_actuators} actuators; platform {platform.name!r} has "
                f"{platform.n_actuators}"
            )
        self._arrival = cfg.frame_clock == "arrival"
        if self._arrival and not cueing_entry(cueing.algorithm).frames_on_arrival:
            raise ConfigError(
                f"frames on arrival step the cueing every millisecond; algorithm "
                f"{cueing.algorithm!r} is meant for the frame rate: use fixed frames "
                "(BridgeConfig frame_clock='fixed', --frames fixed)"
            )
        if not cueing_entry(cueing.algorithm).streaming:
            raise ConfigError(
                f"cueing algorithm {cueing.algorithm!r} needs the whole recording; the live "
                "bridge needs a streaming one (algorithm = "
                + " or ".join(repr(a) for a in cueing_algorithms() if cueing_entry(a).streaming)
                + ")"
            )
        # on arrival the frame intervals vary: the cueing runs on the 1 ms grid instead,
        # stepped once per ms of each frame interval
        rig = Rig(platform, limits)
        self.cueing = make_cueing(cueing, 1000.0 if self._arrival else cfg.rate_hz, rig)
        self.cueing_state = self.cueing.initial_state()
        # effect layer (``effects``: an EffectGains; None or all gains 0: none); refused below
        # 100 Hz. It adds to the blended pose before workspace limiting: limits see the sum.
        self.effects = None if effects is None else make_effects(effects, cfg.rate_hz)
        self.effects_state = EffectsState()
        self.gate = CueGate(cfg.gate)
        # built here so that configuration errors surface before start()
        # (the arrival stage also kept as its own type: its emit takes the ticks)
        self._arrival_stage: ArrivalOutputStage | None = None
        if self._arrival:
            from ._arrival import ArrivalOutputStage

            self._arrival_stage = ArrivalOutputStage(
                platform, controller, limits, cfg.rate_hz, transport, q_start=q_start,
                min_interval_ms=cfg.min_interval_ms,
            )  # fmt: skip
            self.stage: OutputStage = self._arrival_stage
        else:
            self.stage = OutputStage(
                platform, controller, limits, cfg.rate_hz, transport, q_start=q_start
            )
        self.period_s = 1.0 / cfg.rate_hz
        self._pose_park = [float(v) for v in platform.pose_park]
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._state = "new"
        self._error: str | None = None
        self._bad_total = 0  # washout bad samples from states reset since the start
        self._pose_clamped = 0
        self._poses = 0
        self._pose_invalid = 0
        self._missed = 0
        self._park_err = 0.0
        w = cfg.stats_window
        self._sent_at = _Ring(w)  # perf_counter when each frame's send returned
        # |send interval - period| (on arrival: - the stamped interval), one per interval
        # of the send times kept (w - 1), written by the loop thread as frames go out
        self._jitter = _Ring(w - 1)
        self._latency = _Ring(w)
        self._age = _Ring(w)
        self._frame_age = _Ring(w)
        self._stamps = _Ring(w)  # frames on arrival: the stamp of each frame (s)
        self._period_ms = round(1000.0 / cfg.rate_hz)
        # each frame's cue is for the end of the interval it starts (BridgeConfig.lead_ms)
        if cfg.lead_ms is None:
            self.lead_s = self._period_ms * 1e-3 if self._arrival else 0.0
        else:
            self.lead_s = cfg.lead_ms * 1e-3
        from ._upsample import make_upsampler

        self._upsampler = make_upsampler(cfg.upsample)
        self._fw = [0.0] * 6  # telemetry at the frame's time: f (3), then w (3)
        self._fed_t = math.nan  # stamp of the last sample given to the upsampler
        self._t_cue = math.nan  # the time the cueing was last run up to (lead_s ahead)
        self._rate_in_prev: tuple[float, int] | None = None
        self._rate_in = math.nan
        self._old_switch: float | None = None
        self._notes: list[str] = list(self.stage.notes)
        # per-frame state of step()
        self._limit_pose = limit_pose
        self._q_park = [float(v) for v in platform.q_park]
        self._cue = [0.0] * 6
        self._pose = [0.0] * 6
        # newest sample seen (a source may forget it; the cue fades)
        self._held: TelemetrySample | None = None
        self._clean = True  # washout state fresh (reset while parked)
        self._last_sample_t = math.nan

    # ------------------------------------------------------------------ control
    def start(self) -> Bridge:
        """Start the loop thread (once). Returns self."""
        if self._thread is not None:
            raise MotioncueError("this bridge was already started; make a new one")
        s = self.config.switch_interval_s
        if s is not None:
            self._old_switch = sys.getswitchinterval()
            sys.setswitchinterval(min(s, self._old_switch))
        self._state = "parked"
        # not a daemon: the interpreter waits for the park to finish before exiting
        self._thread = threading.Thread(target=self._run, name="motioncue-bridge")
        self._thread.start()
        return self

    def stop(self, timeout_s: float | None = None) -> BridgeStats:
        """Fade out, park at rest, end the loop; returns the final stats.

        Parameters
        ----------
        timeout_s : float, optional
            How long to wait for the park (default: the fade-out time plus an upper bound
            of the park from anywhere, plus 2 s). A loop still parking after that (a loaded
            machine) goes on parking: the stats' state is then not yet ``"stopped"`` or
            ``"failed"``, and :meth:`wait` waits for the end.
        """
        self._stop.set()
        if self._thread is not None:
            if timeout_s is None:
                timeout_s = (
                    self.config.gate.fade_out_s
                    + self.stage.park_frames_bound() * self.period_s
                    + 2.0
                )
            self._thread.join(timeout_s)
            if self._thread.is_alive():
                return self.stats  # still parking: the switch interval is restored at the end
        self._restore_switch()
        return self.stats

    def wait(self, timeout_s: float | None = None) -> bool:
        """Block until the loop thread ends (or the timeout); True if it ended."""
        if self._thread is None:
            return True
        self._thread.join(timeout_s)
        return not self._thread.is_alive()

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    @property
    def cue(self) -> tuple[float, ...]:
        """The cueing algorithm's last pose ``[x, y, z, roll, pitch, yaw]`` (m, rad), before
        the gate's blend and the workspace limiting (a copy; read by monitors)."""
        return tuple(self._cue)

    @property
    def source_finished(self) -> bool:
        """True once the telemetry source reports ``finished`` (end of a replay; a source
        without :class:`FinishingInput`'s ``finished`` never finishes).

        The loop then fades out, parks and ends by itself, as after :meth:`stop`.
        """
        return self._finishing is not None and self._finishing.finished is True

    def __enter__(self) -> Bridge:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _restore_switch(self) -> None:
        if self._old_switch is not None:
            sys.setswitchinterval(self._old_switch)
            self._old_switch = None

    # ------------------------------------------------------------------ the loop
    def _run(self) -> None:
        if self.config.slice_s is not None:
            from ._realtime import request_short_slice

            note = request_short_slice(self.config.slice_s)
            if note is not None:
                self._notes.append(note)
        # the objects alive now (the whole application's) leave the cyclic collector's view:
        # a full collection of them takes milliseconds in a process that imported numpy,
        # scipy and the rest, and it would come in the middle of a frame
        gc.freeze()
        prio = self.config.rt_priority
        if prio is not None:
            try:  # pid 0 = this thread on Linux
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(prio))
            except (AttributeError, OSError) as exc:
                self._notes.append(f"real-time priority {prio} refused ({exc}); normal policy")
        try:
            if self._arrival:
                self._loop_arrival()
            else:
                self._loop()
        except BaseException as exc:  # recorded, reported by stats/stop; then park
            self._error = f"{type(exc).__name__}: {exc}"
            self._state = "failed, parking"
            self._park_after_failure()
            self._state = "failed"
        else:
            # "parked" only once the controller confirmed it (where the link can tell)
            from ._stream import ParkFailed, confirm_park

            try:
                confirm_park(self.stage)
                self._end_run()
                self._state = "stopped"
            except ParkFailed as exc:
                self._error = str(exc)
                self._state = "failed"
        finally:
            gc.unfreeze()
            if self._stop.is_set():  # stop() may have stopped waiting for the park
                self._restore_switch()

    def _park_after_failure(self) -> None:
        """Park from wherever the last frame the link took left the platform, on time."""
        from ._stream import confirm_park, park_stage

        ticker = Ticker(self.period_s, self.config.spin_s)
        try:
            park_stage(self.stage, wait=lambda slot: ticker.wait())
            nothing_moved = confirm_park(self.stage)
            self._end_run()
            if nothing_moved is not None:
                self._error = f"{self._error}; {nothing_moved}"
        except BaseException as exc:
            self._error = f"{exc}; the loop had failed with {self._error}"
        self._missed = ticker.missed
        self._park_err = float(np.max(np.abs(self.stage.q - np.asarray(self._q_park))))

    def _end_run(self) -> None:
        """After the confirmed park: the controller kind's end-of-run messages (the stop
        string of an interface-string board); a failure to send them is noted."""
        from ._stream import end_run

        before = len(self.stage.notes)
        end_run(self.stage)
        self._notes.extend(self.stage.notes[before:])

    def _parked_after_stop(self, stop_ticks: int) -> bool:
        """Both loops after a stop: True once the gate and the stage are parked; an error
        when that takes more frames than the fade-out and the longest park need."""
        if self.gate.parked and self.stage.parked:
            return True
        bound = (
            math.ceil(self.config.gate.fade_out_s / self.period_s)
            + self.stage.park_frames_bound()
            + 10
        )
        if stop_ticks > bound:
            raise MotioncueError(f"could not park within {bound} frames after stop")
        return False

    def _loop(self) -> None:
        cfg = self.config
        period = self.period_s
        stop = self._stop
        step = self.step
        stop_ticks = 0
        ticker = Ticker(period, cfg.spin_s)
        while True:
            deadline = ticker.wait()
            stopping = stop.is_set() or self.source_finished
            step(deadline, stopping)
            self._missed = ticker.missed
            if stopping:
                stop_ticks += 1
                if self._parked_after_stop(stop_ticks):
                    return

    def _loop_arrival(self) -> None:
        """Frames on arrival: wait for the next period or a new sample, whichever is first.

        Frame ``k`` carries the whole-ms stamp ``s_k`` and is sent at ``wall0 + s_k``: the
        loop polls the source every ~0.2 ms while it sleeps and spins the last 0.3 ms. A new
        sample moves the next frame to the next whole ms (at least ``min_interval_ms`` after
        the previous frame). When the next sample is due within ``min_interval_ms`` after a
        regular frame's slot (the game's period estimated from the arrivals), that frame
        waits for the sample, up to ``period + min_interval_ms`` after the previous frame:
        the frames lock on to the packets instead of beating with them.
        """
        from ._upsample import _PeriodEstimate

        cfg = self.config
        stop = self._stop
        period_ms = round(1000.0 / cfg.rate_hz)
        h_min = cfg.min_interval_ms
        h_max = period_ms + h_min
        tick = 1e-3
        clock = time.perf_counter
        stop_ticks = 0
        est = _PeriodEstimate()
        seen_t = math.nan
        wall0 = clock()
        last = 0  # stamp of the last frame (ms); the stage opens the run at 0
        while True:
            due = last + period_ms
            if est.n >= 3 and est.period_s == est.period_s:
                pred = (est.ref_s + est.period_s - wall0) / tick
                if pred - due < h_min and pred < last + h_max - 0.5:
                    due = last + h_max  # the sample is expected first: wait for it
            while True:  # wait for the due stamp, or a sample that moves it earlier
                s = self.source.latest()
                if s is not None and s.t_s != seen_t:
                    seen_t = s.t_s
                    est.update(s.t_s)
                    due = min(due, max(last + h_min, math.ceil((s.t_s - wall0) / tick - 1e-9)))
                left = wall0 + due * tick - clock()
                if left <= 0.0:
                    break
                if left > 0.0005:
                    time.sleep(min(0.0002, left - 0.0003))
            late = (clock() - wall0) / tick - due
            if late > period_ms:  # overran a whole period: skip ahead, counted
                skip = int(late // period_ms)
                self._missed += skip
                due += skip * period_ms
            stopping = stop.is_set() or self.source_finished
            self.step(wall0 + due * tick, stopping, ticks=due - last)
            sent = self._sent_at
            if self._stamps.n and sent.n >= 2:  # the send interval against the stamped one
                interval = sent.prev - float(sent.buf[(sent.n - 2) % sent.buf.size])
                self._jitter.add(abs(interval - (due * tick - self._stamps.prev)))
            self._stamps.add(due * tick)
            last = due
            if stopping:
                stop_ticks += 1
                if self._parked_after_stop(stop_ticks):
                    return

    def step(self, deadline_s: float, stopping: bool = False, ticks: int | None = None) -> None:
        """One frame: newest sample -> gate -> washout -> blend -> workspace -> IK -> emit.

        The loop thread calls this once per frame slot. Tests and simulations may call it
        directly instead of :meth:`start` (never both), on ``perf_counter`` times (the
        gate compares ``deadline_s`` with the samples' arrival stamps).

        Parameters
        ----------
        deadline_s : float
            The frame slot's deadline (``perf_counter`` s). In the loop the gate is advanced
            to the current time (the deadline or just after it); when stepped by hand, to
            ``deadline_s`` itself.
        stopping : bool
            Close the gate (fade out and park) whatever the telemetry says; also done when
            the source reports ``finished``.
        ticks : int, optional
            Frames on arrival only: this frame comes ``ticks`` ms after the previous one
            (default: the period).
        """
        stopping = stopping or self.source_finished
        sample = self.source.latest()
        now = max(time.perf_counter(), deadline_s) if self._thread is not None else deadline_s
        if sample is not None:
            self._held = sample
        held = self._held
        gate = self.gate
        if held is None:
            gain = gate.update(now, None, True)
        else:
            gain = gate.update(now, held.t_s, held.paused or stopping)
        stage = self.stage
        arrival = self._arrival_stage
        if gate.parked:
            if not self._clean:
                wstate = self.cueing_state
                self._bad_total += wstate.bad_samples
                self.cueing.reset(wstate)
                if self.effects is not None:
                    self.effects.reset(self.effects_state)
                self._clean = True
            if arrival is not None:
                arrival.emit(self.platform.q_park, ticks=ticks)
            else:
                stage.park_step()
        else:
            # the gate leaves park only on a sample, and a sample once held stays held
            assert held is not None
            cue = self._cue
            # on arrival the cueing runs on the 1 ms grid: one step per ms of the interval
            reps = (self._period_ms if ticks is None else ticks) if self._arrival else 1
            up = self._upsampler
            fresh = held.t_s != self._fed_t
            # the cue is for the end of the interval this frame starts (lead_s): the cueing
            # runs up to t_cue; the ms of this interval before the new sample arrived are
            # what the telemetry was then (the up-sampler before the sample), the later ones
            # after it
            t_cue = now + self.lead_s
            early: list[list[float]] = []
            recent = held.t_s - self._fed_t <= self.config.gate.timeout_s  # False for nan
            if fresh and reps > 1 and recent:
                for j in range(reps):
                    t_j = t_cue - (reps - 1 - j) * 1e-3
                    if t_j >= held.t_s:
                        break
                    v6 = [0.0] * 6
                    up.value_at(t_j, v6)
                    early.append(v6)
            raw = False
            if fresh:
                self._fed_t = held.t_s
                fw = (*held.f, *held.w)
                if all(map(math.isfinite, fw)):
                    up.update(held.t_s, fw, self._t_cue)
                else:  # the washout counts and holds a bad sample; the upsampler never sees it
                    raw = True
            fw6 = self._fw
            for j in range(reps):
                if raw and j == reps - 1:
                    self.cueing.step(self.cueing_state, held.f, held.w, cue)
                elif j < len(early):
                    v6 = early[j]
                    self.cueing.step(self.cueing_state, v6[:3], v6[3:], cue)
                else:
                    up.value_at(t_cue - (reps - 1 - j) * 1e-3, fw6)
                    self.cueing.step(self.cueing_state, fw6[:3], fw6[3:], cue)
            self._t_cue = t_cue
            self._clean = False
            park = self._pose_park
            pose = self._pose
            for i in range(6):
                pose[i] = park[i] + gain * (cue[i] - park[i])
            if self.effects is not None:
                self.effects.add(self.effects_state, held, gain, pose)
            res = self._limit_pose(self.platform, pose, limits=self.limits)
            self._poses += 1
            if res.status != "ok":
                if res.status == "invalid":
                    self._pose_invalid += 1
                else:
                    self._pose_clamped += 1
            if arrival is not None:
                arrival.emit(res.q, ticks=ticks)
            else:
                stage.emit(res.q)
        done = time.perf_counter()
        if not self._arrival and self._sent_at.n:
            self._jitter.add(abs((done - self._sent_at.prev) - self.period_s))
        self._sent_at.add(done)
        if held is not None:
            self._frame_age.add(done - held.t_s)
        if sample is not None and sample.t_s != self._last_sample_t:
            self._last_sample_t = sample.t_s
            self._age.add(done - sample.t_s)
            self._latency.add(done - max(sample.t_s, deadline_s))
        err = 0.0
        for a, b in zip(stage.q.tolist(), self._q_park, strict=True):
            d = abs(a - b)
            if d > err:
                err = d
        self._park_err = err
        if stopping:
            self._state = "stopping"
        elif gate.parked:
            self._state = "parked" if stage.parked else "parking"
        elif gate.phase >= 1.0:
            self._state = "live"
        else:
            self._state = "fading in" if gate._was_live else "fading out"

    # ------------------------------------------------------------------ reporting
    @property
    def stats(self) -> BridgeStats:
        """A snapshot of the counters and timing figures.

        Cheap: the jitter is kept per frame by the loop, and each window's percentiles come
        from partial sorts of the unordered window (:meth:`_Ring.percentiles_ms`) instead of
        ordered copies and ``np.percentile``; the same figures (tests/test_bridge_stats.py).
        ``benchmarks/bench_monitor.py`` prints its cost with full windows.
        """
        src: dict[str, int] = {}
        try:
            src = dict(self.source.stats)
        except Exception as exc:  # a foreign source; report, do not fail the reader
            src = {"receive errors": 0, f"stats unavailable: {type(exc).__name__}": 1}
        samples = int(src.get("samples", 0))
        now = time.perf_counter()
        if self._rate_in_prev is not None:
            t_prev, n_prev = self._rate_in_prev
            if now - t_prev >= 0.25:
                self._rate_in = (samples - n_prev) / (now - t_prev)
                self._rate_in_prev = (now, samples)
        else:
            self._rate_in_prev = (now, samples)
        rate = self.config.rate_hz
        recent = self._sent_at.last(int(rate) + 1)
        rate_out = math.nan
        if len(recent) > 1 and recent[-1] > recent[0]:
            rate_out = (len(recent) - 1) / (recent[-1] - recent[0])
        (jit_p99,), _ = self._jitter.percentiles_ms((99.0,))
        (lat_p50, lat_p99), lat_max = self._latency.percentiles_ms((50.0, 99.0))
        (age_p99,), _ = self._age.percentiles_ms((99.0,))
        (fage_p50, fage_p99), _ = self._frame_age.percentiles_ms((50.0, 99.0))
        fage_last = self._frame_age.last(1)
        bad = sum(v for k, v in src.items() if k.startswith("skipped")) + int(
            src.get("receive errors", 0)
        )
        gate = self.gate
        return BridgeStats(
            state=self._state,
            gain=gate.gain,
            frames_sent=self.stage.frames,
            missed_deadlines=self._missed,
            samples_in=samples,
            datagrams_in=int(src.get("datagrams", 0)),
            rate_in_hz=self._rate_in,
            rate_out_hz=rate_out,
            jitter_p99_ms=jit_p99,
            latency_p50_ms=lat_p50,
            latency_p99_ms=lat_p99,
            latency_max_ms=lat_max,
            age_p99_ms=age_p99,
            limiter_clamped_frames=self.stage.clamped_frames,
            pose_clamped=self._pose_clamped,
            pose_invalid=self._pose_invalid,
            cueing_bad_samples=self._bad_total + self.cueing_state.bad_samples,
            bad_packets=bad,
            packet_reasons=src,
            fade_ins=gate.fade_ins,
            fade_outs=gate.fade_outs,
            park_q_error=self._park_err,
            error=self._error,
            notes=tuple(self._notes) + _telemetry_notes(src, self.source_finished),
            send_errors=self.stage.send_errors,
            status_requests=0 if self.stage.watch is None else self.stage.watch.probes,
            frame_age_ms=fage_last[0] * 1e3 if fage_last else math.nan,
            frame_age_p50_ms=fage_p50,
            frame_age_p99_ms=fage_p99,
            cueing=self._cueing_stats(),
            poses=self._poses,
        )

    def _cueing_stats(self) -> dict[str, float]:
        """The cueing algorithm's ``stats(state)`` (MPC solve times, fallbacks), if it has it
        (:class:`ReportsCueingStats`)."""
        design = self.cueing
        if not isinstance(design, ReportsCueingStats):
            return {}
        try:
            return {str(k): float(v) for k, v in dict(design.stats(self.cueing_state)).items()}
        except Exception as exc:  # a plug-in's report must not stop the bridge
            return {f"stats unavailable: {type(exc).__name__}": 1.0}
