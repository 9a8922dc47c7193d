"""An emulated interface-string board: the firmware's parser, judged on the send clock.

Bytes (fed directly, or datagrams arriving on UDP, read as one stream as a serial port
would deliver them) go through the board's own parser (``_boards``); each complete target
set is one frame. The board has no clock of its own in the frames: frame ``k`` is taken to
arrive at ``k / rate_hz`` (the send clock; by default the config's ``frame_rate_hz``), and
every frame is judged with the controller's own numbers, in axis values:

- stroke: ``0 .. 2**bits - 1`` (the parser already drops larger values, counted);
- speed: ``|c[k] - c[k-1]| * rate`` within ``max_speed_counts_s`` plus one value of
  rounding per period;
- acceleration: ``|c[k] - 2 c[k-1] + c[k-2]| * rate**2`` within ``max_accel_counts_s2``
  plus two values of rounding; the board is at rest at the first target.
"""

from __future__ import annotations

import threading

import numpy as np

from ..._errors import ConfigError
from .._udp_emulator import Trace, UdpEmulatorBase, Violation
from ._boards import board_parser
from ._controller import IfaceController

__all__ = ["IfaceEmulator"]


class IfaceEmulator(UdpEmulatorBase):
    """Parses and judges one board's byte stream (module docstring).

    Parameters
    ----------
    controller : IfaceController
        With a ``firmware`` parser (not ``none``).
    host, port : str, int
        Where :meth:`start` listens on UDP (port 0: any free port).
    rate_hz : float, optional
        The send rate (default: the controller's ``frame_rate_hz``).
    """

    def __init__(
        self,
        controller: IfaceController,
        host: str = "127.0.0.1",
        port: int = 0,
        rate_hz: float | None = None,
    ) -> None:
        if controller.firmware == "none":
            raise ConfigError(f"controller {controller.name} names no firmware: no emulator")
        self.controller = controller
        self.rate_hz = float(controller.frame_rate_hz if rate_hz is None else rate_hz)
        controller.check_rate(self.rate_hz)
        self.parser = board_parser(controller.firmware)
        if self.parser.n_motors != controller.n_axes:
            raise ConfigError(
                f"firmware {controller.firmware} drives {self.parser.n_motors} motors, "
                f"{controller.name} has {controller.n_axes} axes"
            )
        self._lock = threading.Lock()
        self.frames: list[tuple[int, ...]] = []
        self._violations: list[Violation] = []
        self.bytes_received = 0
        self.datagrams = 0
        super().__init__(host, port)  # the UDP server loop: datagrams go to handle()

    # --- judging -------------------------------------------------------------------
    def feed(self, data: bytes) -> int:
        """Parse ``data`` (any split of the stream); returns the frames it completed."""
        with self._lock:
            self.bytes_received += len(data)
            new = self.parser.feed(data)
            for frame in new:
                self._judge(frame)
                self.frames.append(frame)
            return len(new)

    def _judge(self, frame: tuple[int, ...]) -> None:
        c = self.controller
        rate = self.rate_hz
        k = len(self.frames)
        t = k / rate
        full = self.parser.full_scale
        for i, value in enumerate(frame):
            if not 0 <= value <= full:
                self._violations.append(Violation(t, "stroke", i, f"{value} outside [0, {full}]"))
        if k == 0:
            return
        prev = self.frames[-1]
        before = self.frames[-2] if k >= 2 else prev  # at rest at the first target
        for i in range(len(frame)):
            v = abs(frame[i] - prev[i]) * rate
            if v > c.max_speed_counts_s + rate:
                self._violations.append(Violation(t, "speed", i, f"{v:.0f} values/s"))
            a = abs(frame[i] - 2 * prev[i] + before[i]) * rate * rate
            if a > c.max_accel_counts_s2 + 2.0 * rate * rate:
                self._violations.append(Violation(t, "accel", i, f"{a:.0f} values/s^2"))

    # --- Emulator protocol -----------------------------------------------------------
    @property
    def malformed(self) -> int:
        """Bytes or frames the parser dropped."""
        return self.parser.malformed

    @property
    def received(self) -> int:
        """Frames completed (the board reads a stream, not datagrams)."""
        with self._lock:
            return len(self.frames)

    @received.setter
    def received(self, datagrams: int) -> None:  # the server loop's datagram count
        self.datagrams = datagrams

    @property
    def frames_received(self) -> int:
        """The same as :attr:`received`: the board reads frames only."""
        return self.received

    def handle(self, data: bytes, now_s: float) -> list[bytes]:
        """One datagram into the stream; the board never answers."""
        self.feed(data)
        return []

    @property
    def violations(self) -> list[Violation]:
        """Every limit broken, and (one entry) what the parser dropped, counted."""
        with self._lock:
            out = list(self._violations)
            dropped = self.parser.malformed
            t = max(len(self.frames) - 1, 0) / self.rate_hz
        if dropped:
            out.append(Violation(t, "malformed", None, f"{dropped} bytes or frames dropped"))
        return out

    @property
    def trace(self) -> Trace:
        """Frames on the send clock, positions mapped back to pulses."""
        with self._lock:
            counts = np.array(self.frames, dtype=np.int64).reshape(-1, self.controller.n_axes)
        c = self.controller
        span = c.pulses_hi - c.pulses_lo
        pulses = c.pulses_lo + np.floor(counts * span / c.fmt.full_scale + 0.5).astype(np.int64)
        n = len(counts)
        return Trace(np.arange(n) / self.rate_hz, pulses, np.arange(n, dtype=np.int64))
