"""Real-time building blocks of the live loop: a deadline ticker, a cue gate, loop statistics,
and a short scheduler slice for the loop thread.

The first three are small explicit-state objects on plain floats so that a loop iteration
stays in the tens of microseconds.

Short slice (:func:`request_short_slice`)
-----------------------------------------
Without real-time priority a frame loop that sleeps until its deadline competes, when it
wakes, with whatever else runs on that core. Linux's fair scheduler (EEVDF, Linux >= 6.6)
lets the waking thread preempt a running CPU hog only when its virtual deadline comes first,
which depends on the *slice* each task asks for: with the default slice (about 3 ms on this
2-core machine) the loop often waits the rest of the hog's slice, milliseconds. Since Linux
6.12 any thread may ask for a shorter slice of its own (``sched_setattr`` with
``SCHED_OTHER`` and ``sched_runtime``; no privilege, no change of priority or share of the
CPU): its deadline then comes first and it runs at once when it wakes. Measured on this
machine, a bare sleep-and-spin 250 Hz loop beside a busy core: jitter p99 0.00-0.92 ms (3 runs)
with the default slice, 0.001 ms with a 0.1 ms slice (``benchmarks/bench_bridge.py``
measures the bridge both ways). Before 6.12 the kernel ignores ``sched_runtime`` of a
fair task (the call succeeds; not tried on such a kernel here).
"""

from __future__ import annotations

import math
import struct
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from .._errors import ConfigError

__all__ = ["CueGate", "GateConfig", "LoopStats", "Ticker", "request_short_slice", "wait_until"]

_SCHED_ATTR = struct.Struct("=IIQiIQQQII")  # struct sched_attr, SCHED_ATTR_SIZE_VER1 (56 B)
_SYS_SCHED_SETATTR = {"x86_64": 314, "aarch64": 274, "armv7l": 380, "riscv64": 274}
SLICE_MIN_S = 1e-4  # the kernel's bounds on a requested slice
SLICE_MAX_S = 0.1


def request_short_slice(slice_s: float) -> str | None:
    """Ask the scheduler for a ``slice_s`` slice for the calling thread (Linux; module
    docstring, *Short slice*). Policy stays ``SCHED_OTHER`` at the thread's nice value.

    Parameters
    ----------
    slice_s : float
        Requested slice (s), in [1e-4, 0.1].

    Returns
    -------
    str or None
        None when the kernel took the request, else a one-line note saying why not (not
        Linux, unknown architecture, refused); the caller reports it and runs anyway.
    """
    if not (math.isfinite(slice_s) and SLICE_MIN_S <= slice_s <= SLICE_MAX_S):
        raise ConfigError(
            f"slice_s = {slice_s!r} is invalid; allowed: [{SLICE_MIN_S}, {SLICE_MAX_S}] s"
        )
    import platform
    import sys

    if not sys.platform.startswith("linux"):
        return f"short scheduler slice not available on {sys.platform}"
    nr = _SYS_SCHED_SETATTR.get(platform.machine())
    if nr is None:
        return f"short scheduler slice: sched_setattr unknown on {platform.machine()}"
    import ctypes
    import os

    try:
        libc = ctypes.CDLL(None, use_errno=True)
        nice = os.getpriority(os.PRIO_PROCESS, 0)
        attr = _SCHED_ATTR.pack(_SCHED_ATTR.size, 0, 0, nice, 0, round(slice_s * 1e9), 0, 0, 0, 0)
        buf = ctypes.create_string_buffer(attr, len(attr))
        if libc.syscall(nr, 0, buf, 0) != 0:  # pid 0: this thread
            err = ctypes.get_errno()
            return f"short scheduler slice refused ({os.strerror(err)}); default slice"
    except (OSError, AttributeError) as exc:
        return f"short scheduler slice unavailable ({exc}); default slice"
    return None


def wait_until(deadline: float, spin_s: float = 0.001) -> float:
    """Sleep, then spin, until ``perf_counter() >= deadline``; return how late we already were.

    Returns
    -------
    float
        ``max(0, now - deadline)`` at entry (s): 0 when the deadline was still ahead.
    """
    now = time.perf_counter()
    if now >= deadline:
        return now - deadline
    remaining = deadline - now
    if remaining > spin_s:
        time.sleep(remaining - spin_s)
    while time.perf_counter() < deadline:
        pass
    return 0.0


class Ticker:
    """Absolute ``perf_counter`` deadlines at a fixed period: sleep, then spin the last part.

    Deadlines are ``t0 + k * period_s``, never ``now + period_s``, so errors do not
    accumulate. If the loop overruns a whole period the missed deadlines are skipped (and
    counted in ``missed``) instead of being fired back to back.

    Parameters
    ----------
    period_s : float
        Tick period (s), > 0.
    spin_s : float
        How long before a deadline to stop sleeping and busy-wait (s). ``time.sleep`` on
        Linux wakes ~50-100 us late; 1 ms of spinning keeps jitter well under 1 ms.
    """

    def __init__(self, period_s: float, spin_s: float = 0.001) -> None:
        if not (math.isfinite(period_s) and period_s > 0):
            raise ConfigError(f"period_s = {period_s!r} must be > 0")
        self.period_s = float(period_s)
        self.spin_s = float(spin_s)
        self.t0 = time.perf_counter()
        self.k = 0
        self.missed = 0

    def wait(self) -> float:
        """Block until the next deadline; return the deadline (perf_counter seconds)."""
        self.k += 1
        deadline = self.t0 + self.k * self.period_s
        now = time.perf_counter()
        if now - deadline > self.period_s:
            skipped = int((now - deadline) // self.period_s)
            self.missed += skipped
            self.k += skipped
            deadline = self.t0 + self.k * self.period_s
        wait_until(deadline, self.spin_s)
        return deadline


@dataclass(frozen=True)
class GateConfig:
    """How the live loop fades the cue in and out.

    Attributes
    ----------
    timeout_s : float
        No new telemetry for this long counts as lost (the game stopped sending).
    fade_out_s : float
        Time to fade the cue to the parked pose after loss or pause.
    fade_in_s : float
        Time to fade the cue in at start and on resume.
    """

    timeout_s: float = 0.25
    fade_out_s: float = 2.0
    fade_in_s: float = 2.0

    def __post_init__(self) -> None:
        for name in ("timeout_s", "fade_out_s", "fade_in_s"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"{name} = {value!r} must be a finite number > 0")


@dataclass
class CueGate:
    """Cue gain in [0, 1] with smooth (raised-cosine) fades; 0 means parked.

    ``update(now_s, last_packet_s, paused)`` advances the state: fresh, unpaused telemetry
    fades in; telemetry older than ``timeout_s`` or a pause fades out. The gain's time
    derivative is bounded by ``pi / (2 * fade_s)`` and is continuous at the ends of a fade.
    """

    config: GateConfig = field(default_factory=GateConfig)
    phase: float = 0.0  # 0 = parked, 1 = live; gain = (1 - cos(pi * phase)) / 2
    last_s: float | None = None
    fade_outs: int = 0
    fade_ins: int = 0
    _was_live: bool = False

    @property
    def gain(self) -> float:
        return 0.5 * (1.0 - math.cos(math.pi * self.phase))

    @property
    def parked(self) -> bool:
        return self.phase == 0.0

    def update(self, now_s: float, last_packet_s: float | None, paused: bool) -> float:
        dt = 0.0 if self.last_s is None else max(0.0, now_s - self.last_s)
        self.last_s = now_s
        live = (
            last_packet_s is not None
            and not paused
            and now_s - last_packet_s <= self.config.timeout_s
        )
        if live != self._was_live:
            if live:
                self.fade_ins += 1
            else:
                self.fade_outs += 1
            self._was_live = live
        if live:
            self.phase = min(1.0, self.phase + dt / self.config.fade_in_s)
        else:
            self.phase = max(0.0, self.phase - dt / self.config.fade_out_s)
        return self.gain


@dataclass
class LoopStats:
    """Rolling statistics of a live loop (the last ``window`` ticks)."""

    window: int = 20000
    periods_s: deque[float] = field(default_factory=deque)
    latencies_s: deque[float] = field(default_factory=deque)
    frames_out: int = 0
    packets_in: int = 0
    _last_tick: float | None = None

    def tick(self, now_s: float) -> None:
        if self._last_tick is not None:
            self.periods_s.append(now_s - self._last_tick)
            if len(self.periods_s) > self.window:
                self.periods_s.popleft()
        self._last_tick = now_s
        self.frames_out += 1

    def latency(self, latency_s: float) -> None:
        self.latencies_s.append(latency_s)
        if len(self.latencies_s) > self.window:
            self.latencies_s.popleft()

    def summary(self, period_s: float) -> dict[str, float]:
        """p50/p99 latency (ms), p99 |period - nominal| jitter (ms), output rate (Hz)."""
        out: dict[str, float] = {}
        if self.periods_s:
            p = np.asarray(self.periods_s)
            out["rate_hz"] = float(1.0 / np.mean(p))
            out["jitter_p99_ms"] = float(np.percentile(np.abs(p - period_s), 99) * 1e3)
        if self.latencies_s:
            lat = np.asarray(self.latencies_s)
            out["latency_p50_ms"] = float(np.percentile(lat, 50) * 1e3)
            out["latency_p99_ms"] = float(np.percentile(lat, 99) * 1e3)
        return out
