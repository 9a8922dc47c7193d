"""The package's UDP controller emulator (IMAX, SC-MBOX) served in a process of its own.

An emulator thread inside the test process shares the interpreter lock and the process's
share of the CPU with the player, the monitor, the browser driver and the telemetry
sender; on a machine at load 15-25 it was held up for 500-620 ms, and the player (rightly)
stopped as "controller silent". In a process of its own the emulator only waits for the
scheduler, which wakes a sleeping process promptly, as ``test_liveness`` runs it.

:class:`EmulatorProcess` starts the emulator (``spawn``: nothing of the test process is
inherited, no fork of a threaded process) and reads it over a pipe: the counters cheaply
(``received``, ``frames_received``), the trace, violations and internal errors as copies.
The emulator itself is unchanged: the same class ``emulate`` and the in-process tests use,
chosen by the controller kind's registry entry.
"""

from __future__ import annotations

import multiprocessing as mp
import os
import signal
import threading
from typing import Any, Self

__all__ = ["EmulatorProcess"]


def _serve(controller: str, conn: Any) -> None:
    """In the child: start the emulator of ``controller``, send its port, then answer
    requests (``"counts"``, ``"state"``) until ``"stop"`` or the pipe closes."""
    from motioncue.output import controller_kind, load_controller
    from motioncue.output._transport import parse_target

    ctrl = load_controller(controller)
    emu: Any = controller_kind(ctrl.kind).open_emulator(ctrl, parse_target("udp://127.0.0.1:0"))
    emu.start()
    try:
        conn.send(emu.port)
        while True:
            try:
                request = conn.recv()
            except EOFError:
                break
            if request == "stop":
                break
            if request == "counts":
                conn.send((emu.received, emu.frames_received))
            elif request == "state":
                conn.send(
                    {
                        "received": emu.received,
                        "frames_received": emu.frames_received,
                        "trace": emu.trace,
                        "violations": list(emu.violations),
                        "internal_errors": list(emu.internal_errors),
                    }
                )
            else:
                conn.send(ValueError(f"unknown request {request!r}"))
    finally:
        emu.stop()
        conn.close()


class EmulatorProcess:
    """The emulator of controller ``controller`` (``"mbox6"``, ``"imax3"``) in its own
    process, started and stopped by a ``with`` block.

    Attributes read from the running emulator: ``received`` (every datagram),
    ``frames_received`` (frame datagrams), ``trace``, ``violations``, ``internal_errors``;
    ``port`` and ``pid`` once started. After the block they keep what the emulator held
    when it was stopped, as an emulator object does. :meth:`pause` / :meth:`resume` stop
    and continue the process (SIGSTOP / SIGCONT): datagrams wait in its socket, stamped by
    the kernel on arrival, as for a controller that stops answering for a while.
    """

    def __init__(self, controller: str, start_timeout_s: float = 120.0) -> None:
        self.controller = controller
        self.start_timeout_s = start_timeout_s
        self.port = 0
        self.pid = 0
        self._conn: Any = None
        self._proc: Any = None
        self._lock = threading.Lock()
        self._final: dict[str, Any] | None = None  # what it held when stopped

    def __enter__(self) -> Self:
        ctx = mp.get_context("spawn")
        parent, child = ctx.Pipe()
        self._proc = ctx.Process(target=_serve, args=(self.controller, child), daemon=True)
        self._proc.start()
        child.close()
        self._conn = parent
        if not parent.poll(self.start_timeout_s):
            self._kill()
            raise AssertionError(
                f"the {self.controller} emulator process did not start in {self.start_timeout_s} s"
            )
        try:
            self.port = int(parent.recv())
        except EOFError:
            self._proc.join(10.0)
            raise AssertionError(
                f"the {self.controller} emulator process ended before it listened "
                f"(exit code {self._proc.exitcode})"
            ) from None
        self.pid = int(self._proc.pid)
        return self

    def __exit__(self, *exc: object) -> None:
        self.resume()
        try:
            self._final = self.state()
            with self._lock:
                self._conn.send("stop")
        except (OSError, EOFError):
            pass
        self._proc.join(10.0)
        if self._proc.is_alive():
            self._kill()
        self._conn.close()

    def _kill(self) -> None:
        self._proc.kill()
        self._proc.join(10.0)

    def _ask(self, request: str) -> Any:
        if self._final is not None:  # stopped: what it held then
            return (
                self._final
                if request == "state"
                else (self._final["received"], self._final["frames_received"])
            )
        with self._lock:
            self._conn.send(request)
            answer = self._conn.recv()
        if isinstance(answer, Exception):
            raise answer
        return answer

    @property
    def received(self) -> int:
        return int(self._ask("counts")[0])

    @property
    def frames_received(self) -> int:
        return int(self._ask("counts")[1])

    def state(self) -> dict[str, Any]:
        """Counters, trace, violations and internal errors read at one moment."""
        return dict(self._ask("state"))

    @property
    def trace(self) -> Any:
        return self.state()["trace"]

    @property
    def violations(self) -> list[Any]:
        return list(self.state()["violations"])

    @property
    def internal_errors(self) -> list[str]:
        return list(self.state()["internal_errors"])

    def pause(self) -> None:
        """Stop the emulator's process (SIGSTOP): it neither reads nor answers."""
        os.kill(self.pid, signal.SIGSTOP)

    def resume(self) -> None:
        """Continue it (SIGCONT); it then reads what waited in its socket."""
        if self.pid:
            os.kill(self.pid, signal.SIGCONT)
