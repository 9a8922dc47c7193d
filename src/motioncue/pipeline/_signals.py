"""Signals that end a ride only by a flag, so that the park after them cannot be cut short.

While a :class:`SignalGuard` is active (in the main thread), SIGINT (Ctrl-C), SIGTERM,
SIGHUP (terminal or SSH session closed) and SIGQUIT (Ctrl-\\) run a handler that only
records the signal and sets an event: no ``KeyboardInterrupt`` is raised into the frame
loop, and a second or third Ctrl-C during the park is recorded and otherwise ignored. Only
SIGKILL (and power loss) can stop the process during a park. In another thread the guard
does nothing (Python delivers signals to the main thread only).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable
from types import FrameType

from .._atomic import STOP_SIGNALS

__all__ = ["STOP_SIGNALS", "SignalGuard"]


class SignalGuard:
    """Context manager: flag-only handlers for :data:`STOP_SIGNALS`, restored on exit.

    Attributes
    ----------
    event : threading.Event
        Set at the first signal (a ride loop polls ``guard.event.is_set``).
    received : list of int
        Every signal received while active, in order.
    active : bool
        The handlers are installed (False outside the main thread).
    """

    def __init__(self) -> None:
        self.event = threading.Event()
        self.received: list[int] = []
        self.active = False
        self._previous: dict[int, Callable[[int, FrameType | None], object] | int | None] = {}

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        # nothing that could raise or block: no printing (the terminal may be gone)
        self.received.append(signum)
        self.event.set()

    @property
    def first(self) -> str | None:
        """Name of the first signal received (``"SIGTERM"``), or None."""
        if not self.received:
            return None
        try:
            return signal.Signals(self.received[0]).name
        except ValueError:
            return f"signal {self.received[0]}"

    def __enter__(self) -> SignalGuard:
        if threading.current_thread() is threading.main_thread():
            for sig in STOP_SIGNALS:
                try:
                    self._previous[sig] = signal.signal(sig, self._on_signal)
                except (OSError, ValueError):  # pragma: no cover - platform without it
                    pass
            self.active = True
        return self

    def __exit__(self, *exc: object) -> None:
        for sig, previous in self._previous.items():
            signal.signal(sig, previous if previous is not None else signal.SIG_DFL)
        self._previous.clear()
        self.active = False
