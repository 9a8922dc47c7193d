"""A toy controller kind registered from outside motioncue: one UDP datagram per frame.

Wire format (big-endian), declared once as a ``struct.Struct`` beside its dataclass::

    b"TOY1", frame u32, time_ms u32 (absolute, since the first frame), n x i32 positions

The toy answers nothing (no replies, no position query). Its emulator listens on UDP,
records every frame and judges it with its own numbers: stroke, speed (finite difference
over the stamped period) and acceleration (change of that speed over the mean of the two
periods), from rest at the first frame. Importing this module registers kind ``toy``
(``MOTIONCUE_PLUGINS=toys.toy_controller`` does it for the command line).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

import numpy as np

from motioncue import ConfigError, ProtocolError
from motioncue._config import ConfigReader
from motioncue.output import (
    Controller,
    ControllerKind,
    DriveExpectations,
    FrameEncoder,
    Inspection,
    PulseLimits,
    Trace,
    TransportURL,
    UdpEmulatorBase,
    Violation,
    register_controller_kind,
)
from motioncue.output._controller_api import check_whole_ms_rate

MAGIC = b"TOY1"


@cache
def frame_struct(n_axes: int) -> struct.Struct:
    """Layout of a frame of ``n_axes`` positions."""
    return struct.Struct(f">4sII{n_axes}i")


@dataclass(frozen=True)
class ToyFrame:
    """One toy frame: number, absolute time stamp (ms) and positions (pulses)."""

    frame: int
    time_ms: int
    positions: tuple[int, ...]

    def encode(self) -> bytes:
        try:
            return frame_struct(len(self.positions)).pack(
                MAGIC, self.frame, self.time_ms, *self.positions
            )
        except struct.error as exc:
            raise ProtocolError(f"toy frame out of range: {exc}") from None

    @classmethod
    def decode(cls, data: bytes) -> ToyFrame:
        n, rest = divmod(len(data) - 12, 4)
        if rest or n < 1 or data[:4] != MAGIC:
            raise ProtocolError(f"not a toy frame ({len(data)} bytes, {data[:4]!r})")
        _magic, frame, time_ms, *positions = frame_struct(n).unpack(data)
        return cls(frame, time_ms, tuple(positions))


class ToyEncoder:
    """Frames of one run: numbers from 0, times in whole ms from the first frame.

    Its ``clock`` is None (a ``FrameEncoder`` declares one): the toy numbers its frames
    itself and is not rolled back by the output stage."""

    clock: None = None

    def __init__(self, n_axes: int) -> None:
        self.n_axes = n_axes
        self.frame = 0
        self.t0_s: float | None = None

    def encode(
        self, t_s: float, pulses: Sequence[int], dout: int = 0, dacs: tuple[int, int] = (0, 0)
    ) -> list[bytes]:
        if len(pulses) != self.n_axes:
            raise ProtocolError(f"{len(pulses)} positions for a {self.n_axes}-axis toy")
        if self.t0_s is None:
            self.t0_s = t_s
        ms = round((t_s - self.t0_s) * 1000.0)
        data = ToyFrame(self.frame, ms, tuple(int(p) for p in pulses)).encode()
        self.frame += 1
        return [data]


@dataclass(frozen=True)
class ToyController:
    """The frozen description the registry's reader returns (satisfies ``Controller``)."""

    name: str
    n_axes: int
    default_target: str
    stroke_pulses: tuple[int, int]
    max_speed_pulses_s: float
    max_accel_pulses_s2: float
    kind: str = "toy"
    buffer_frames: int = 1 << 20
    max_frame_rate_hz: float | None = 1000.0
    time_resolution_s: float | None = 1e-3
    catch_up_factor: float = 1.0
    dout_max: int = 0
    dac_max: tuple[int, int] = (0, 0)
    link_kind: str = "udp"
    replies_to_frames: bool = False

    def pulse_limits(self, rate_hz: float | None = None) -> PulseLimits:
        n = self.n_axes
        return PulseLimits(
            n,
            [self.stroke_pulses[0]] * n,
            [self.stroke_pulses[1]] * n,
            [self.max_speed_pulses_s] * n,
            [self.max_accel_pulses_s2] * n,
            {"stroke": "toy stroke_pulses", "v_max": "toy", "a_max": "toy"},
        )

    def drive_expectations(self) -> DriveExpectations:
        return DriveExpectations()

    def check_rate(self, rate_hz: float) -> None:
        check_whole_ms_rate(rate_hz, self.max_frame_rate_hz, f"toy {self.name}", "1 ms stamps")

    def position_query(self) -> None:
        return None

    def command_streamer(self, transport: object, rate_hz: float) -> None:
        return None

    def run_encoder(
        self, rate_hz: float, start_pulses: Sequence[int] | None = None
    ) -> FrameEncoder:
        self.check_rate(rate_hz)
        return ToyEncoder(self.n_axes)


def read_config(reader: ConfigReader, name: str) -> ToyController:
    """Every key of a toy TOML besides ``kind``."""
    lo = reader.integer("stroke_lo_pulses")
    hi = reader.integer("stroke_hi_pulses")
    if lo >= hi:
        raise reader.error("stroke_hi_pulses", hi, f"> stroke_lo_pulses = {lo}")
    return ToyController(
        name,
        reader.integer("axes", lo=1, hi=64),
        reader.string("default_target", "udp://127.0.0.1:7499"),
        (lo, hi),
        reader.number("max_speed_pulses_s", lo=0, lo_open=True),
        reader.number("max_accel_pulses_s2", lo=0, lo_open=True),
    )


class ToyEmulator(UdpEmulatorBase):
    """Records and judges every toy frame (module docstring); the UDP server loop, its
    thread and the datagram count (``received``) are motioncue's :class:`UdpEmulatorBase`."""

    def __init__(self, controller: ToyController, host: str = "127.0.0.1", port: int = 0) -> None:
        super().__init__(host, port)
        self.controller = controller
        self.frames: list[ToyFrame] = []
        self._violations: list[Violation] = []

    @property
    def trace(self) -> Trace:
        with self.lock:
            frames = list(self.frames)
        n = self.controller.n_axes
        return Trace(
            np.array([f.time_ms / 1000.0 for f in frames]),
            np.array([f.positions for f in frames], dtype=np.int64).reshape(-1, n),
            np.array([f.frame for f in frames], dtype=np.int64),
        )

    @property
    def violations(self) -> list[Violation]:
        with self.lock:
            return list(self._violations)

    def handle(self, data: bytes, now_s: float) -> list[bytes]:
        """Judge and keep one datagram (called under ``self.lock``); the toy never replies."""
        try:
            frame = ToyFrame.decode(data)
        except ProtocolError as exc:
            self._violations.append(Violation(0.0, "malformed", None, str(exc)))
            return []
        self._judge(frame)
        self.frames.append(frame)
        return []

    def _judge(self, frame: ToyFrame) -> None:
        """Stroke, speed and acceleration of ``frame`` after the ones before it."""
        c = self.controller
        t = frame.time_ms / 1000.0
        if len(frame.positions) != c.n_axes:
            self._violations.append(Violation(t, "malformed", None, "axis count"))
            return
        lo, hi = c.stroke_pulses
        for i, p in enumerate(frame.positions):
            if not lo <= p <= hi:
                self._violations.append(Violation(t, "stroke", i, f"{p} outside [{lo}, {hi}]"))
        if not self.frames:
            return
        prev = self.frames[-1]
        dt = (frame.time_ms - prev.time_ms) / 1000.0
        if dt <= 0:
            self._violations.append(Violation(t, "sequence", None, f"period {dt} s"))
            return
        before = self.frames[-2] if len(self.frames) > 1 else None
        dt0 = (prev.time_ms - before.time_ms) / 1000.0 if before is not None else dt
        for i in range(c.n_axes):
            v1 = (frame.positions[i] - prev.positions[i]) / dt
            v0 = 0.0 if before is None else (prev.positions[i] - before.positions[i]) / dt0
            # one pulse of rounding on each position is allowed for
            if abs(v1) > c.max_speed_pulses_s + 1.0 / dt:
                self._violations.append(Violation(t, "speed", i, f"{v1:.0f} pulses/s"))
            accel = (v1 - v0) / ((dt + dt0) / 2.0)
            if abs(accel) > c.max_accel_pulses_s2 + 4.0 / (dt * (dt + dt0)):
                self._violations.append(Violation(t, "accel", i, f"{accel:.0f} pulses/s^2"))


def _emulator(controller: Controller, url: TransportURL, homing_time_s: float) -> ToyEmulator:
    if not isinstance(controller, ToyController):
        raise ConfigError(f"the toy emulator needs a toy controller, not {controller.kind}")
    return ToyEmulator(controller, url.host, url.port)


def _split(blob: bytes) -> list[bytes]:
    """A raw capture of toy frames of one axis count, back to back (first frame's size)."""
    if len(blob) < 16 or blob[:4] != MAGIC:
        raise ProtocolError("not a toy capture")
    size = blob.find(MAGIC, 4)
    size = len(blob) if size < 0 else size
    if len(blob) % size:
        raise ProtocolError("toy capture of uneven frames")
    return [blob[i : i + size] for i in range(0, len(blob), size)]


def _describe(data: bytes) -> str:
    f = ToyFrame.decode(data)
    return f"toy frame {f.frame} t={f.time_ms} ms positions={list(f.positions)}"


KIND = ControllerKind(
    "toy",
    read_config,
    title="toy UDP controller (tests)",
    links=("udp", "file"),
    emulator=_emulator,
    inspect=Inspection(_split, _describe),
)
register_controller_kind("toy", KIND, replace=True)


def write_config(
    path: Path, *, axes: int = 3, stroke_pulses: tuple[int, int] = (-1000, 201000)
) -> Path:
    """A toy controller TOML, by default for a seat3-like rig (100 mm stroke at 2000
    pulses/mm, 200 mm/s, 10 m/s^2 in pulses, with room above the platform's own limits);
    ``stroke_pulses`` (lo, hi) for another rig's pulse range."""
    path.write_text(
        'kind = "toy"\n'
        f"axes = {axes}\n"
        'default_target = "udp://127.0.0.1:7499"\n'
        f"stroke_lo_pulses = {stroke_pulses[0]}\n"
        f"stroke_hi_pulses = {stroke_pulses[1]}\n"
        f"max_speed_pulses_s = {250.0 * 2000:.1f}\n"
        f"max_accel_pulses_s2 = {12000.0 * 2000:.1f}\n"
    )
    return path


__all__ = ["KIND", "MAGIC", "ToyController", "ToyEmulator", "ToyFrame", "write_config"]
