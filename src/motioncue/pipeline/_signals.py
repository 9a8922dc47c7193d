"""Signals that end a ride only by a flag, so that the park after them cannot be cut short.

While a :class:`SignalGuard` is active (in the main thread), SIGINT (Ctrl-C), SIGTERM,
SIGHUP (terminal or SSH session closed) and SIGQUIT (Ctrl-\\) run a handler that only
records the signal and sets an event: no ``KeyboardInterrupt`` is raised into the frame
loop, and a second or third Ctrl-C during the park is recorded and otherwise ignored. Only
SIGKILL (and power loss) can stop the process during a park. In another thread the guard
does nothing (Python delivers signals to the main thread only).

The guard is the atomic writer's flag-only handlers (:class:`motioncue._atomic.StopSignalRecorder`,
also what a write that must not be cut defers the signals with): one mechanism for both.
"""

from __future__ import annotations

import signal

from .._atomic import STOP_SIGNALS, StopSignalRecorder

__all__ = ["STOP_SIGNALS", "SignalGuard"]


class SignalGuard(StopSignalRecorder):
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

    @property
    def first(self) -> str | None:
        """Name of the first signal received (``"SIGTERM"``), or None."""
        if not self.received:
            return None
        try:
            return signal.Signals(self.received[0]).name
        except ValueError:
            return f"signal {self.received[0]}"
