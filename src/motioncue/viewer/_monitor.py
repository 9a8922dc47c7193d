"""The live monitor: a local web page of a running bridge, play or emulator.

A :class:`Monitor` serves one page (plotly.js served by the monitor itself, from the
``plotly`` package: no CDN) and pushes a snapshot over a WebSocket a few times a second: the
platform in 3D, each actuator's use of stroke, speed and acceleration as bars (fractions of
the limits the frames are held to), the cue, the telemetry rate, delay and jitter, and the
state. Its stop button asks the job to stop, which parks by the job's own stop path.

The server is tornado (https://www.tornadoweb.org/): HTTP and WebSocket in one small,
dependency-free, long-maintained library, run on its own asyncio loop in a daemon thread.

The frame loop is never delayed by the monitor: a started monitor serves from a process of
its own (the server, forward kinematics for the pose, fractions, acceleration as the change
of speed between two snapshots, JSON and WebSocket I/O), so none of that holds the job's
interpreter lock. In the job's process one small thread only *reads* the
:class:`MonitorSource` (attribute reads of the running job, no lock the loop waits on) when
the server asks for a snapshot (at most :attr:`Monitor.rate_hz` times a second while a page
is open, and for ``/snapshot``) and hands the raw mapping over a pipe. A slow browser only
misses snapshots: a snapshot is not sent to a client while its previous one is still in
flight.
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING, Any, Protocol, SupportsFloat, TypedDict

import numpy as np

from .._errors import ConfigError, TransportError
from ..telemetry._source import is_loopback
from ._page import frame_json, html_page, scene_layout
from ._scene import Scene, scene_from_q

if TYPE_CHECKING:
    import socket
    import subprocess
    from asyncio import Future
    from multiprocessing.connection import Connection

    import tornado.web

    from ..kinematics import Platform
    from ..output import EmulatorReadout
    from ..pipeline._bridge import Bridge, BridgeStats
    from ..pipeline._stream import OutputStage
    from ..trajectory import ActuatorLimits

__all__ = [
    "BridgeSource",
    "EmulatorSource",
    "Monitor",
    "MonitorSource",
    "PlaySource",
    "SourceSnapshot",
    "parse_monitor",
]

DEFAULT_MONITOR_PORT = 8765
"""Port of ``--monitor`` without a value (loopback)."""

_START_TIMEOUT_S = 60.0  # the server process imports numpy and motioncue (slow when loaded)
_REPLY_TIMEOUT_S = 5.0  # the job's process answers a snapshot request within this


class _SourceError(Exception):
    """The job's source failed to give a snapshot; ``str()`` is the one-line error text
    (``"Type: message"``), already counted in the job's process."""


class _Client(Protocol):
    """A page's WebSocket as the monitor uses it."""

    def push(self, msg: str) -> None: ...

    def close(self) -> None: ...

    def write_message(self, message: str) -> Future[None]: ...


class SourceSnapshot(TypedDict, total=False):
    """What a :class:`MonitorSource` reports, every key optional (without ``q`` the page
    shows no actuators); the monitor checks each value it reads (the snapshot may come over
    a pipe from another process).

    Attributes
    ----------
    q : sequence of float
        Actuator positions from neutral (SI, ``n`` numbers) of the last frame.
    v : sequence of float
        Their speeds (SI).
    t_s : float
        The frame clock of ``q`` (s), for the acceleration.
    state : str
        ``"parked"``, ``"running"``, ``"fading in"``... (the job's words).
    cue : sequence of float or None
        The cue pose ``[x, y, z, roll, pitch, yaw]`` (m, rad).
    telemetry : mapping of str to float or None
        ``{"rate_hz", "delay_ms", "jitter_ms"}``.
    info : mapping of str to str
        ``{label: text}`` shown as is (frames sent, ride time...).
    """

    q: Sequence[float]
    v: Sequence[float]
    t_s: float
    state: str
    cue: Sequence[float | None]
    telemetry: Mapping[str, float | None]
    info: Mapping[str, str]


class MonitorSource(Protocol):
    """What a monitor reads from a running job (called in the job's process, by the
    monitor's reader thread when its server asks, or by the caller of :meth:`Monitor.snapshot`).

    ``snapshot()`` returns a :class:`SourceSnapshot` (a plain dict of those keys).
    ``request_stop()`` asks the job to stop and park; ``can_stop`` says if it can.
    """

    can_stop: bool

    def snapshot(self) -> SourceSnapshot: ...

    def request_stop(self) -> None: ...


def _num(x: SupportsFloat | str | None) -> float | None:
    """``x`` as a finite float, or None (unknown, not a number, NaN or inf)."""
    if x is None:
        return None
    try:
        v = float(x)
    except (TypeError, ValueError):
        return None
    return v if math.isfinite(v) else None


class BridgeSource:
    """Reads a :class:`~motioncue.pipeline.Bridge` (its stats at most twice a second)."""

    can_stop = True

    def __init__(self, bridge: Bridge, info: Mapping[str, str] | None = None) -> None:
        """``info``: fixed lines shown first in the page's table (e.g. ``{"cueing": "P at
        intensity 50 %"}``)."""
        self.bridge = bridge
        self.info = dict(info or {})
        self._stats: BridgeStats | None = None
        self._stats_at = -math.inf

    def snapshot(self) -> SourceSnapshot:
        b = self.bridge
        now = time.monotonic()
        st = self._stats
        if st is None or now - self._stats_at >= 0.5 or not b.running:  # the final at once
            st = self._stats = b.stats
            self._stats_at = now
        stage = b.stage
        state = str(st.state)
        if state in ("stopped", "failed") and stage.parked:
            # the loop has ended with the platform at its park position: say so
            state = "parked" if state == "stopped" else "failed, parked"
        return {
            "q": stage.q.tolist(),
            "v": stage.v.tolist(),
            "t_s": float(stage.t_s),
            "state": state,
            "cue": list(b.cue),
            "telemetry": {
                "rate_hz": st.rate_in_hz,
                "delay_ms": st.latency_p50_ms,
                "jitter_ms": st.jitter_p99_ms,
            },
            "info": {
                **self.info,
                "frames sent": str(st.frames_sent),
                "gain": f"{st.gain:.2f}",
                "bad packets": str(st.bad_packets),
                "delay p99": f"{st.latency_p99_ms:.1f} ms",
            },
        }

    def request_stop(self) -> None:
        # Bridge.stop() sets the loop's stop flag, then waits for the park: run it in a
        # thread of its own so the monitor's loop goes on serving while the platform parks.
        threading.Thread(target=self.bridge.stop, name="monitor-stop", daemon=True).start()


class PlaySource:
    """Reads the output stage of :func:`~motioncue.pipeline.play_ride` (``on_start``).

    Pass :meth:`attach` as ``play_ride(..., on_start=...)`` and :meth:`stopped` as (part
    of) its ``stop`` callable.
    """

    can_stop = True

    def __init__(self, duration_s: float, info: Mapping[str, str] | None = None) -> None:
        """``info``: fixed lines shown first in the page's table (e.g. the ride's cueing)."""
        self.duration_s = float(duration_s)
        self.info = dict(info or {})
        self.stage: OutputStage | None = None
        self._stop = threading.Event()
        self.finished = False

    def attach(self, stage: OutputStage) -> None:
        self.stage = stage

    def stopped(self) -> bool:
        return self._stop.is_set()

    def request_stop(self) -> None:
        self._stop.set()

    def snapshot(self) -> SourceSnapshot:
        stage = self.stage
        if stage is None:
            return {"state": "starting", "info": dict(self.info)}
        parked = bool(stage.parked)
        if parked and (stage.frames > 0 or self.finished):
            state = "parked"
        elif self._stop.is_set() or self.finished:
            state = "parking"
        else:
            state = "running"
        return {
            "q": stage.q.tolist(),
            "v": stage.v.tolist(),
            "t_s": float(stage.t_s),
            "state": state,
            "info": {
                **self.info,
                "frames sent": str(stage.frames),
                "ride time": f"{min(stage.t_s, self.duration_s):.1f} of {self.duration_s:.1f} s",
                "limiter changed": f"{stage.clamped_frames} frames",
            },
        }


class EmulatorSource:
    """Reads an emulator's trace (what the controller plays), in pulses -> SI.

    The emulator is the controller: it has no park of its own to give, so ``can_stop`` is
    False (stop the sender; it parks).
    """

    can_stop = False

    def __init__(self, emulator: EmulatorReadout, platform: Platform) -> None:
        self.emulator = emulator
        self.platform = platform
        self._last: tuple[float, np.ndarray] | None = None
        self._v = np.zeros(platform.n_actuators)

    def request_stop(self) -> None:
        raise ConfigError("the emulator cannot park: stop the program that sends it frames")

    def snapshot(self) -> SourceSnapshot:
        emu = self.emulator
        trace = emu.trace
        n = self.platform.n_actuators
        if len(trace) == 0:
            q = np.asarray(self.platform.q_park, dtype=float)
            t = 0.0
        else:
            pulses = np.asarray(trace.positions[-1], dtype=float)[:n]
            q = self.platform.drives.from_pulses(pulses[None])[0]
            t = float(trace.t_s[-1])
        v = np.zeros(n)
        if self._last is not None and t > self._last[0]:
            v = (q - self._last[1]) / (t - self._last[0])
        elif self._last is not None:
            v = self._v
        self._last, self._v = (t, q), v
        state = "parked" if np.allclose(q, self.platform.q_park, atol=1e-9) else "running"
        return {
            "q": q.tolist(),
            "v": v.tolist(),
            "t_s": t,
            "state": state,
            "info": {
                "datagrams": str(emu.received),
                "trace points": str(len(trace)),
                "violations": str(len(emu.violations)),
            },
        }


def parse_monitor(value: str | None) -> tuple[str, int]:
    """``--monitor [[HOST:]PORT]`` -> ``(host, port)``; loopback and 8765 by default.

    Raises
    ------
    ConfigError
        A port outside 0..65535 or not a number, an empty host.
    """
    if value is None or value == "":
        return "127.0.0.1", DEFAULT_MONITOR_PORT
    host, _, port_s = value.rpartition(":")
    host = host.strip("[]") or "127.0.0.1"
    try:
        port = int(port_s)
    except ValueError:
        raise ConfigError(
            f"--monitor {value!r} is invalid; allowed: PORT or HOST:PORT (port 0..65535)"
        ) from None
    if not 0 <= port <= 65535:
        raise ConfigError(f"--monitor port {port} is invalid; allowed: 0..65535")
    return host, port


class Monitor:
    """Serve the live page of one job.

    Parameters
    ----------
    source : MonitorSource
    platform : Platform
        For the 3D drawing (forward kinematics of the snapshot's ``q``).
    limits : ActuatorLimits, optional
        Stroke, speed and acceleration the bars are fractions of; default the platform's
        stroke, and no speed or acceleration bars.
    host, port : str, int
        Where to listen (port 0: any free port; see :attr:`url`). Loopback by default.
    rate_hz : float
        Snapshots a second pushed to each page, in ``[1, 60]``.
    title : str
        What the page says it shows.

    Raises
    ------
    ConfigError
        ``rate_hz`` out of range.
    TransportError
        The address cannot be listened on (in :meth:`start`).
    """

    def __init__(
        self,
        source: MonitorSource,
        platform: Platform,
        limits: ActuatorLimits | None = None,
        *,
        host: str = "127.0.0.1",
        port: int = DEFAULT_MONITOR_PORT,
        rate_hz: float = 10.0,
        title: str = "",
    ) -> None:
        if not (math.isfinite(rate_hz) and 1.0 <= rate_hz <= 60.0):
            raise ConfigError(f"monitor rate_hz = {rate_hz!r} is invalid; allowed: 1 .. 60")
        self.source = source
        self.platform = platform
        self.host, self.port = host, int(port)
        self.rate_hz = float(rate_hz)
        self.title = title
        n = platform.n_actuators
        lim = limits
        self._q_lo = np.asarray(platform.q_min if lim is None else lim.q_min, dtype=float)
        self._q_hi = np.asarray(platform.q_max if lim is None else lim.q_max, dtype=float)
        self._v_max = None if lim is None else np.asarray(lim.v_max, dtype=float)
        self._a_max = None if lim is None else np.asarray(lim.a_max, dtype=float)
        self._names = list(platform.actuator_names)
        self._first_spare = n - platform.spare_axes
        self._rotary = [k == "rotary" for k in platform.actuator_kinds]
        park = scene_from_q(platform, [0.0], np.asarray(platform.q_park, dtype=float)[None])
        # a box that holds the platform anywhere in its stroke
        ends = np.array([self._q_lo, self._q_hi, np.zeros(n), platform.q_park])
        reach = [park]
        for qq in ends:
            try:
                reach.append(scene_from_q(platform, [0.0], qq[None]))
            except ConfigError:
                pass
        self._box = scene_layout(_merge(reach))
        self._pose_guess: np.ndarray | None = None
        self._prev: tuple[float, np.ndarray] | None = None
        self._acc = np.zeros(n)
        self.snapshots = 0
        self.errors = 0
        self.stop_requests = 0
        self._ended = False
        self._last: dict[str, Any] = {}
        self._thread: threading.Thread | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._clients: set[_Client] = set()
        self._sockets: list[socket.socket] = []
        # started: the server process, the pipes to it and the job-side reader thread
        self._proc: subprocess.Popen[bytes] | None = None
        self._requests: Connection | None = None  # the server's snapshot/stop requests
        self._control: Connection | None = None  # "end" to the server
        self._reader: threading.Thread | None = None
        self._server_errors = 0  # errors counted by the server process (not the source's)

    # ------------------------------------------------------------------ snapshots
    def snapshot(self) -> dict[str, Any]:
        """Read the source once and derive what the page shows (JSON-ready, no NaN)."""
        raw = self.source.snapshot()
        n = len(self._names)
        out: dict[str, Any] = {
            "state": str(raw.get("state", "?")),
            "can_stop": bool(self.source.can_stop),
            "stop_requests": self.stop_requests,
            "info": {str(k): str(v) for k, v in dict(raw.get("info", {})).items()},
        }
        q_raw = raw.get("q")
        if q_raw is not None:
            q = np.asarray(q_raw, dtype=float)
            if q.shape == (n,) and np.all(np.isfinite(q)):
                out.update(self._actuators(q, raw))
        cue = raw.get("cue")
        if cue is not None:
            c = [_num(v) for v in cue]
            out["cue"] = [
                None if v is None else round(v * (1e3 if i < 3 else 180.0 / math.pi), 2)
                for i, v in enumerate(c)
            ]
        tel = raw.get("telemetry")
        if tel is not None:
            out["telemetry"] = {k: _num(v) for k, v in dict(tel).items()}
        self.snapshots += 1
        self._last = out
        return out

    def _actuators(self, q: np.ndarray, raw: SourceSnapshot) -> dict[str, Any]:
        from ._scene import _scene, at_rest, fk_miss, stroke_use

        plat = self.platform
        fk = plat.forward(q, self._pose_guess)
        if not fk.ok and self._pose_guess is not None:
            fk = plat.forward(q)
        self._pose_guess = fk.pose if fk.ok else None
        # the nearest rigid pose is drawn whatever happens; the page says when it is not one
        scene = _scene(plat, np.zeros(1), np.asarray(fk.pose, dtype=float)[None], q[None])
        frame = frame_json(scene, 0)
        frac = np.where(q >= 0.0, q / self._q_hi, -q / self._q_lo)
        rest = at_rest(plat, q)
        v = np.asarray(raw.get("v", np.zeros_like(q)), dtype=float)
        t = _num(raw.get("t_s"))
        if t is not None and self._prev is not None and t > self._prev[0]:
            self._acc = (v - self._prev[1]) / (t - self._prev[0])
        if t is not None:
            self._prev = (t, v)
        speed = None if self._v_max is None else v / self._v_max
        accel = None if self._a_max is None else self._acc / self._a_max
        acts = []
        for i, name in enumerate(self._names):
            rot = self._rotary[i]
            scale = 180.0 / math.pi if rot else 1e3
            a_scale = 180.0 / math.pi if rot else 1.0  # m/s^2: mm/s^2 reads as thousands
            acts.append(
                {
                    "name": name,
                    "q": round(float(q[i]) * scale, 2),
                    "unit": "deg" if rot else "mm",
                    "stroke": round(float(frac[i]), 4),
                    "rest": bool(rest[i]),
                    "spare": i >= self._first_spare,
                    "speed": None if speed is None else _num(round(float(speed[i]), 4)),
                    "accel": None if accel is None else _num(round(float(accel[i]), 4)),
                    # the values themselves, in the units the page prints beside the bars
                    "v": _num(round(float(v[i]) * scale, 1)),
                    "v_unit": "deg/s" if rot else "mm/s",
                    "v_max": None if self._v_max is None else _num(float(self._v_max[i]) * scale),
                    "a": _num(round(float(self._acc[i]) * a_scale, 2)),
                    "a_unit": "deg/s²" if rot else "m/s²",
                    "a_max": None if self._a_max is None else _num(float(self._a_max[i]) * a_scale),
                }
            )
        pose = fk.pose
        moving = ~rest[: len(q)]
        extra = {} if fk.ok else {"error": fk_miss(plat, q, fk)}
        return {
            **extra,
            "frame": frame,
            # the largest stroke use of an actuator not at its park position (0: all parked)
            "use": float(np.max(stroke_use(plat, q)[moving], initial=0.0)),
            "pose": [
                round(float(pose[i]) * (1e3 if i < 3 else 180.0 / math.pi), 2) for i in range(6)
            ],
            "actuators": acts,
        }

    def stop_pressed(self) -> None:
        """The page's stop button: ask the source to stop (it parks)."""
        self.stop_requests += 1
        self.source.request_stop()

    # ------------------------------------------------------------------ server
    @property
    def url(self) -> str:
        host = self.host if ":" not in self.host else f"[{self.host}]"
        return f"http://{host}:{self.port}/"

    def start(self) -> Monitor:
        """Listen (errors raised here) and serve from a process of its own (module
        docstring); this process keeps one daemon thread that reads the source on request.

        Raises
        ------
        TransportError
            The address cannot be listened on, or the server process does not start.
        """
        from tornado.netutil import bind_sockets

        try:
            self._sockets = bind_sockets(self.port, self.host)
        except (OSError, ValueError) as exc:
            raise TransportError(
                f"monitor: cannot listen on {self.host}:{self.port}: {exc}"
            ) from exc
        self.port = int(self._sockets[0].getsockname()[1])
        import pickle
        import socket
        import subprocess
        import sys
        from multiprocessing.connection import Connection

        # a fresh interpreter (not a fork of a process with threads, and not multiprocessing's
        # spawn, which would run the job's own __main__ again), this process' module path
        # first; the pipes are socket pairs and the listening sockets are passed as fds
        req_job_s, req_server_s = socket.socketpair()
        ctl_job_s, ctl_server_s = socket.socketpair()
        fds = [req_server_s.fileno(), ctl_server_s.fileno()] + [s.fileno() for s in self._sockets]
        config = {
            "platform": self.platform,
            "bars": (self._q_lo, self._q_hi, self._v_max, self._a_max),
            "host": self.host,
            "port": self.port,
            "rate_hz": self.rate_hz,
            "title": self.title,
            "can_stop": bool(self.source.can_stop),
            "families": [s.family for s in self._sockets],
        }
        req_job = Connection(req_job_s.detach())
        ctl_job = Connection(ctl_job_s.detach())
        try:
            blob = pickle.dumps(config)
            proc = subprocess.Popen(
                [sys.executable, "-c", _SERVER_CODE, repr(sys.path), *map(str, fds)],
                pass_fds=fds,
                stdin=subprocess.DEVNULL,
            )
        except Exception as exc:  # e.g. an unpicklable platform: no monitor, one line
            for c in (req_job, ctl_job):
                c.close()
            req_server_s.close()
            ctl_server_s.close()
            self._close_sockets()
            raise TransportError(f"monitor: cannot start its server: {exc}") from exc
        req_server_s.close()
        ctl_server_s.close()
        self._proc, self._requests, self._control = proc, req_job, ctl_job
        try:
            ctl_job.send_bytes(blob)
            ready = req_job.poll(_START_TIMEOUT_S) and req_job.recv() == ("ready",)
        except (EOFError, OSError):
            ready = False
        if not ready:
            self.stop()
            raise TransportError("monitor: its server process did not start")
        self._reader = threading.Thread(
            target=self._answer, args=(req_job,), name="motioncue-monitor-source", daemon=True
        )
        self._reader.start()
        return self

    def _answer(self, conn: Connection) -> None:
        """The job-side thread: answer the server process' requests until it ends."""
        while True:
            try:
                msg = conn.recv()
            except (EOFError, OSError):
                return
            try:
                if msg[0] == "snapshot":
                    # the server's counters: snapshots made before this one, errors other
                    # than the source's
                    self.errors += int(msg[2]) - self._server_errors
                    self._server_errors = int(msg[2])
                    try:
                        reply: tuple[str, Any] = ("ok", dict(self.source.snapshot()))
                        self.snapshots = int(msg[1]) + 1  # this one is being made
                    except Exception as exc:  # a torn read: the server shows it, counted
                        self.errors += 1
                        reply = ("error", f"{type(exc).__name__}: {exc}")
                elif msg[0] == "stop":
                    try:
                        self.stop_pressed()
                        reply = ("ok", None)
                    except Exception as exc:  # e.g. the emulator has nothing to park
                        reply = ("error", str(exc))
                else:
                    continue
                conn.send(reply)
            except Exception:  # a raw snapshot that does not pickle: an error shown
                self.errors += 1
                try:
                    conn.send(("error", "the job's snapshot could not be passed on"))
                except (OSError, ValueError):
                    return

    def stop(self) -> None:
        """Stop serving (idempotent), after a last snapshot flagged ``"ended": true`` to each
        page, so that a page shows the job's final state (``parked``) instead of a stale one.
        """
        import subprocess

        proc, control = self._proc, self._control
        if proc is not None and control is not None:
            try:
                control.send(("end",))
            except (OSError, ValueError):
                pass
            try:
                proc.wait(5.0)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait(2.0)
            control.close()
            if self._requests is not None:
                self._requests.close()  # the reader thread ends on it
            if self._reader is not None:
                self._reader.join(2.0)
            self._proc = self._control = self._requests = self._reader = None
        loop = self._loop
        if loop is not None and loop.is_running():
            if self._clients:
                try:
                    asyncio.run_coroutine_threadsafe(self._final_push(), loop).result(2.0)
                except Exception:  # the pages only miss the last word
                    pass
            loop.call_soon_threadsafe(loop.stop)
        if self._thread is not None:
            self._thread.join(5.0)
            self._thread = None
        self._close_sockets()

    def _close_sockets(self) -> None:
        for s in self._sockets:
            try:
                s.close()
            except OSError:
                pass
        self._sockets = []

    def __enter__(self) -> Monitor:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def local_only(self) -> bool:
        return is_loopback(self.host)

    def _serve(
        self,
        ready: threading.Event,
        on_start: Callable[[asyncio.AbstractEventLoop], object] | None = None,
    ) -> None:
        import tornado.web
        from tornado.httpserver import HTTPServer
        from tornado.ioloop import PeriodicCallback

        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        self._loop = loop
        app = tornado.web.Application(_handlers(self), log_function=_no_access_log)
        server = HTTPServer(app)
        server.add_sockets(self._sockets)
        tick = PeriodicCallback(self._tick, 1000.0 / self.rate_hz)
        tick.start()
        if on_start is not None:
            on_start(loop)
        ready.set()
        try:
            loop.run_forever()
        finally:
            tick.stop()
            server.stop()
            for c in list(self._clients):
                c.close()
            loop.run_until_complete(asyncio.sleep(0))
            loop.close()

    async def _final_push(self) -> None:
        self._ended = True  # no regular snapshot after this one (the page keeps this state)
        snap = self._snapshot_or_error()
        snap["ended"] = True
        msg = json.dumps(snap, allow_nan=False)
        for client in list(self._clients):
            try:
                await client.write_message(msg)
            except Exception:  # a page that went away
                self._clients.discard(client)

    def _snapshot_or_error(self) -> dict[str, Any]:
        """:meth:`snapshot`, or ``{"state": "?", "error": "..."}`` (counted) when it fails."""
        try:
            snap = self.snapshot()
            json.dumps(snap, allow_nan=False)  # a NaN is an error too, not a broken page
            return snap
        except _SourceError as exc:  # counted where the source was read
            return {"state": "?", "error": str(exc)}
        except Exception as exc:  # a torn read of a running job: skip this snapshot, count it
            self.errors += 1
            return {"state": "?", "error": f"{type(exc).__name__}: {exc}"}

    def snapshot_json(self) -> str:
        """:meth:`snapshot` as JSON; a snapshot that fails is counted and answered with
        ``{"state": "?", "error": "..."}`` (which the page shows), never an HTTP error."""
        return json.dumps(self._snapshot_or_error(), allow_nan=False)

    def _tick(self) -> None:
        if not self._clients or self._ended:
            return
        msg = self.snapshot_json()
        for client in list(self._clients):
            client.push(msg)


class _JobSource:
    """The job's source as the server process sees it: each snapshot and stop request is
    a round trip over the pipe to the job's process (``Monitor._answer``)."""

    def __init__(self, conn: Connection, can_stop: bool) -> None:
        self.conn = conn
        self.can_stop = can_stop
        self.monitor: Monitor | None = None  # its counters go with each request

    def _ask(self, msg: tuple[Any, ...]) -> Any:
        self.conn.send(msg)
        if not self.conn.poll(_REPLY_TIMEOUT_S):
            raise TimeoutError(f"the job did not answer within {_REPLY_TIMEOUT_S:g} s")
        kind, value = self.conn.recv()
        if kind == "error":
            raise _SourceError(value)
        return value

    def snapshot(self) -> SourceSnapshot:
        mon = self.monitor
        counts = (0, 0) if mon is None else (mon.snapshots, mon.errors)
        raw: SourceSnapshot = self._ask(("snapshot", *counts))  # checked where it is read
        return raw

    def request_stop(self) -> None:
        try:
            self._ask(("stop",))
        except _SourceError as exc:  # the job's refusal, as the page shows it
            raise ConfigError(str(exc)) from None


# the server process' entry: SIGINT ignored before anything else (Ctrl-C reaches the whole
# process group: the job stops and parks by its own path, then says "end" here; no
# traceback), the job's module path, then _server_main on the passed descriptors
#: how much lower than the job's the server process' scheduling priority is (``os.nice``):
#: its snapshots, forward kinematics and JSON never hold a core the frame loop waits for
SERVER_NICE = 10

_SERVER_CODE = (
    "import signal, sys; signal.signal(signal.SIGINT, signal.SIG_IGN); "
    "import ast; sys.path[:] = ast.literal_eval(sys.argv[1]); "
    "from motioncue.viewer._monitor import _server_main; "
    "_server_main(*(int(a) for a in sys.argv[2:]))"
)


def _server_main(req_fd: int, ctl_fd: int, *socket_fds: int) -> None:
    """The monitor's server process: a :class:`Monitor` on a :class:`_JobSource`, served
    on this process' main thread until the job's process says "end" (or goes away)."""
    import pickle
    import socket
    from multiprocessing.connection import Connection

    try:  # below the job's frame loop: on a busy 2-core machine the loop must win a core
        os.nice(SERVER_NICE)
    except (AttributeError, OSError):  # no os.nice (Windows) or not allowed: serve as is
        pass
    requests = Connection(req_fd)
    control = Connection(ctl_fd, writable=False)
    config = pickle.loads(control.recv_bytes())
    sockets = [
        socket.socket(family, socket.SOCK_STREAM, fileno=fd)
        for family, fd in zip(config["families"], socket_fds, strict=True)
    ]
    source = _JobSource(requests, config["can_stop"])
    mon = Monitor(
        source, config["platform"], host=config["host"], port=config["port"],
        rate_hz=config["rate_hz"], title=config["title"],
    )  # fmt: skip
    # the bars are fractions of the job's monitor's limits
    mon._q_lo, mon._q_hi, mon._v_max, mon._a_max = config["bars"]
    source.monitor = mon
    mon._sockets = sockets

    def on_control() -> None:
        try:
            msg = control.recv()
        except (EOFError, OSError):
            msg = ("end",)
        if msg[0] == "end":
            loop = mon._loop
            assert loop is not None
            loop.remove_reader(control.fileno())
            if mon._clients:
                loop.create_task(_end(mon, loop))
            else:
                loop.stop()

    def on_start(loop: asyncio.AbstractEventLoop) -> None:
        loop.add_reader(control.fileno(), on_control)
        requests.send(("ready",))

    mon._serve(threading.Event(), on_start)
    for s in sockets:
        s.close()


async def _end(mon: Monitor, loop: asyncio.AbstractEventLoop) -> None:
    """The last snapshot (``"ended"``) to each page, then the server's loop stops."""
    try:
        await asyncio.wait_for(mon._final_push(), 2.0)
    except Exception:  # the pages only miss the last word
        pass
    loop.stop()


def _no_access_log(handler: tornado.web.RequestHandler) -> None:
    """Tornado's access log off: the terminal shows the job's own lines only."""


def _merge(scenes: list[Scene]) -> Scene:
    """One scene of the frames of ``scenes`` (a drawing's bounding box)."""

    def opt(name: str) -> np.ndarray | None:
        parts = [getattr(s, name) for s in scenes]
        if any(p is None for p in parts):
            return None
        return np.concatenate(parts)

    def cat(name: str) -> np.ndarray:
        return np.concatenate([getattr(s, name) for s in scenes])

    return Scene(
        np.arange(len(scenes), dtype=float), cat("poses"), cat("q"), cat("base"),
        opt("joint"), cat("top"), cat("centre"), cat("forward"), cat("use"), opt("rest"),
        scenes[0].order, opt("seat"), opt("rail"),
    )  # fmt: skip


def _handlers(mon: Monitor) -> list[tuple[str, type[tornado.web.RequestHandler]]]:
    import tornado.web
    import tornado.websocket

    from ._page import plotly_js

    class Page(tornado.web.RequestHandler):
        def get(self) -> None:
            self.set_header("Content-Type", "text/html; charset=utf-8")
            self.set_header("Cache-Control", "no-store")
            self.write(_page(mon))

    class PlotlyJs(tornado.web.RequestHandler):
        def get(self) -> None:
            self.set_header("Content-Type", "application/javascript; charset=utf-8")
            self.set_header("Cache-Control", "max-age=3600")
            self.write(plotly_js())

    class Snapshot(tornado.web.RequestHandler):
        def get(self) -> None:
            self.set_header("Content-Type", "application/json")
            self.write(mon.snapshot_json())

    class Live(tornado.websocket.WebSocketHandler):
        _busy: Future[None] | None = None

        def open(self, *args: str, **kwargs: str) -> None:
            mon._clients.add(self)

        def on_close(self) -> None:
            mon._clients.discard(self)

        def on_message(self, message: str | bytes) -> None:
            if message == "stop":
                try:
                    mon.stop_pressed()
                    reply = {"stop": "requested"}
                except Exception as exc:  # e.g. the emulator has nothing to park
                    reply = {"stop": f"refused: {exc}"}
                self.write_message(json.dumps(reply))

        def push(self, msg: str) -> None:
            busy = self._busy
            if busy is not None and not busy.done():
                return  # the browser is behind: drop this snapshot
            try:
                self._busy = self.write_message(msg)
            except tornado.websocket.WebSocketClosedError:
                mon._clients.discard(self)

    class NoIcon(tornado.web.RequestHandler):
        def get(self) -> None:
            self.set_status(204)

    return [
        (r"/", Page),
        (r"/plotly.js", PlotlyJs),
        (r"/snapshot", Snapshot),
        (r"/ws", Live),
        (r"/favicon.ico", NoIcon),
    ]


def _page(mon: Monitor) -> str:
    import html

    data = json.dumps(
        {"box": mon._box, "title": mon.title, "names": mon._names, "rate_hz": mon.rate_hz}
    )
    return html_page("monitor", html.escape(mon.title), _HEAD, _BODY, data, _SCRIPT)


_HEAD = """<script src="/plotly.js"></script>
<style>
body { font-family: sans-serif; margin: 8px; }
#wrap { display: flex; gap: 12px; }
#scene { flex: 1 1 50%; min-width: 420px; height: 600px; }
#side { flex: 0 0 auto; max-width: 700px; }
#state { font-size: 22px; font-weight: bold; padding: 4px 10px; border-radius: 4px;
          display: inline-block; }
.running, .live { background: #b7e4c7; } .parked { background: #ddd; }
.fading, .parking, .stopping { background: #ffe08a; } .failed { background: #f4a3a3; }
#stop { font-size: 20px; padding: 6px 24px; background: #d73027; color: #fff;
         border: none; border-radius: 4px; margin-left: 16px; }
#stop:disabled { background: #aaa; }
table { border-collapse: collapse; margin-top: 8px; font-size: 13px; }
td, th { padding: 2px 6px; text-align: left; }
.bar { position: relative; width: 80px; height: 12px; background: #eee; }
#acts td { white-space: nowrap; }
.bar div { position: absolute; top: 0; height: 12px; }
.bar .mid { left: 50%; width: 1px; background: #666; }
.bar, .num { display: inline-block; vertical-align: middle; }
.num { width: 84px; text-align: right; font-variant-numeric: tabular-nums;
        font-size: 12px; }
.bar.rest { background: #d9d9d9; }
</style>"""

_BODY = """<div style="margin:6px 0"><span id="state">connecting</span>
<button id="stop" disabled>stop (park)</button> <span id="msg"></span></div>
<div id="error" style="color:#b00;font-weight:bold"></div>
<div id="wrap"><div id="scene"></div><div id="side">
<table id="acts"><thead><tr><th>actuator</th><th>position</th><th>stroke used</th>
<th>speed</th><th>acceleration</th></tr></thead><tbody></tbody></table>
<div style="font-size:11px;color:#555">bars: share of each limit the frames are held to
(centre = 0, edge = the limit, either sign; amber from 70 %, red from 90 %), the value
beside each bar; stroke used = distance from mid-stroke over the usable half stroke;
grey "at park": the actuator rests at its park position (near its bottom end by
design)</div>
<table id="cue"></table>
<table id="info"></table>
</div></div>"""

_SCRIPT = """
const M = JSON.parse(document.getElementById('mc-data').textContent);
const sceneDiv = document.getElementById('scene');
const stateEl = document.getElementById('state');
const stopBtn = document.getElementById('stop');
const msgEl = document.getElementById('msg');
window.mcMonitor = {snapshots: 0, last: null, drawn: null, connected: false};
function bar(f, rest) {
  if (rest) return '<div class="bar rest" title="at its park position"></div>';
  if (f === null || f === undefined) return '<div class="bar"></div>';
  const a = Math.min(1, Math.abs(f));
  const colour = a < 0.7 ? '#1a9850' : (a < 0.9 ? '#fdae61' : '#d73027');
  const left = f >= 0 ? 50 : 50 - 50 * a;
  return '<div class="bar" title="' + (100 * f).toFixed(0) + ' %"><div style="left:' + left +
         '%;width:' + (50 * a) + '%;background:' + colour + '"></div><div class="mid"></div></div>';
}
// one 3D redraw at a time, the newest pose: a slow machine shows fewer poses, never old ones
let pending = null, drawing = false;
function schedule() {
  if (drawing || pending === null) return;
  drawing = true;
  requestAnimationFrame(() => {
    const f = pending; pending = null;
    mcDraw(sceneDiv, f, M.box, 'platform (legs coloured by stroke use)').then(() => {
      window.mcMonitor.drawn = f; window.mcMonitor.draws = (window.mcMonitor.draws || 0) + 1;
      drawing = false; setTimeout(schedule, 0);
    });
  });
}
function esc(x) {
  return String(x).replace(/[&<>"']/g, c => ({'&': '&amp;', '<': '&lt;', '>': '&gt;',
                                              '"': '&quot;', "'": '&#39;'})[c]);
}
function fmt(x, d) { return (x === null || x === undefined) ? 'n/a' : x.toFixed(d); }
function render(s) {
  const st = s.state || '?';
  stateEl.textContent = s.ended ? st + ' (job ended)' : st;
  stateEl.className = st.split(' ')[0].replace(',', '');
  stopBtn.disabled = !s.can_stop || !!s.ended;
  document.getElementById('error').textContent = s.error ? 'error: ' + s.error : '';
  if (s.frame) { pending = s.frame; schedule(); }
  if (s.actuators) {
    const num = (x, d, unit) => '<span class="num">' + fmt(x, d) + ' ' + unit + '</span>';
    const lim = (x, d, unit) => (x === null || x === undefined) ? '' :
      ' title="limit ' + x.toFixed(d) + ' ' + unit + '"';
    const rows = s.actuators.map(a => '<tr><td>' + a.name + '</td><td>' + a.q.toFixed(1) +
      ' ' + a.unit + '</td><td>' + bar(a.stroke, a.rest) + (a.rest
        ? '<span class="num">' + (a.spare ? 'spare axis' : 'at park') + '</span>'
        : '<span class="num">' + (100 * Math.abs(a.stroke)).toFixed(0) + ' %</span>') +
      '</td><td' + lim(a.v_max, 0, a.v_unit) + '>' + bar(a.speed) + num(a.v, 0, a.v_unit) +
      '</td><td' + lim(a.a_max, 1, a.a_unit) + '>' + bar(a.accel) + num(a.a, 2, a.a_unit) +
      '</td></tr>');
    document.querySelector('#acts tbody').innerHTML = rows.join('');
  }
  const names = ['x mm', 'y mm', 'z mm', 'roll deg', 'pitch deg', 'yaw deg'];
  let cue = '';
  if (s.pose) cue += '<tr><th>pose</th>' + s.pose.map((v, i) => '<td>' + names[i] + ' ' +
                     fmt(v, 1) + '</td>').join('') + '</tr>';
  const parked = st.startsWith('parked') || st.startsWith('failed');
  if (s.cue && !parked) cue += '<tr><th>cue</th>' + s.cue.map((v, i) => '<td>' + names[i] +
                               ' ' + fmt(v, 1) + '</td>').join('') + '</tr>';
  document.getElementById('cue').innerHTML = cue;
  let info = '';
  if (s.telemetry) {
    info += '<tr><th>telemetry rate</th><td>' + fmt(s.telemetry.rate_hz, 1) + ' Hz</td></tr>';
    info += '<tr><th>delay (p50)</th><td>' + fmt(s.telemetry.delay_ms, 1) + ' ms</td></tr>';
    info += '<tr><th>jitter (p99)</th><td>' + fmt(s.telemetry.jitter_ms, 2) + ' ms</td></tr>';
  }
  // info lines are the job's words (a preset's path among them): shown as text, not markup
  for (const [k, v] of Object.entries(s.info || {})) info += '<tr><th>' + esc(k) + '</th><td>' +
                                                             esc(v) + '</td></tr>';
  document.getElementById('info').innerHTML = info;
}
function connect() {
  const ws = new WebSocket('ws://' + location.host + '/ws');
  window.mcMonitor.ws = ws;
  ws.onopen = () => { window.mcMonitor.connected = true; };
  ws.onmessage = (ev) => {
    const s = JSON.parse(ev.data);
    if (s.stop !== undefined) { msgEl.textContent = 'stop ' + s.stop; return; }
    if (window.mcMonitor.ended && !s.ended) return;  // the final state stays
    window.mcMonitor.snapshots += 1;
    window.mcMonitor.last = s;
    if (s.ended) window.mcMonitor.ended = true;
    render(s);
  };
  ws.onclose = () => {
    window.mcMonitor.connected = false;
    stopBtn.disabled = true;
    if (window.mcMonitor.ended) return;  // the job's final state stays on the page
    stateEl.textContent = 'disconnected'; stateEl.className = '';
    setTimeout(connect, 1000);
  };
}
stopBtn.onclick = () => {
  if (window.mcMonitor.ws) window.mcMonitor.ws.send('stop');
  msgEl.textContent = 'stop sent';
};
connect();
"""
