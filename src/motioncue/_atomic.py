"""Atomic output files: written under a temporary name, renamed into place on success.

Every file motioncue produces (ride files, pcaps, raw ``file:`` targets, telemetry
recordings, reports) goes through :class:`AtomicFile` or :func:`atomic_write_bytes`. The data
is written to ``.NAME.partial-XXXXXXXX`` in the destination's own folder (so the final
``os.replace`` is atomic on every POSIX file system), flushed and fsynced, then renamed to
``NAME``. A refusal, an exception or Ctrl-C removes the temporary file; a process killed by
SIGKILL or a power loss can leave one behind, always with that obviously unfinished name,
never a valid-looking ``NAME``.

A destination that exists and is not a regular file (``/dev/null``, a FIFO, a terminal) is
written directly: it cannot be replaced, and nothing valid-looking is left there anyway. So is
a destination that is itself a temporary name (a file a :class:`Staging` handed out, which the
staging publishes or removes): no ``..NAME.partial-X.partial-Y`` nesting.

Interruptions:

* The temporary name carries the writer's process id, ``.NAME.partial-<pid>-XXXXXXXX``.
  Before writing ``NAME``, every writer removes the temporary files of ``NAME`` whose process
  is gone (a run killed by SIGKILL) and names them in a note on stderr
  (:func:`remove_stale_partials`); a temporary file of a live process is left to it, and one
  of unknown origin (another naming) is named, not removed.
* :func:`interrupt_on_stop_signals` (installed by the command line before any verb runs)
  makes SIGTERM, SIGHUP and SIGQUIT raise :class:`Interrupted`, a ``KeyboardInterrupt``, as
  Ctrl-C does: the ``with`` blocks of the outputs discard them. A verb that must finish a
  park first replaces these handlers with flag-only ones (:class:`StopSignalRecorder`, which
  ``pipeline._signals.SignalGuard`` is).
* A handler that raises at any bytecode can cut a write where nothing cleans up after it (a
  temporary file created but not yet armed for removal, a zip member open inside numpy's
  ``savez``: its close then raises ``ValueError`` over the interruption). Such writes run
  under :func:`stop_signals_deferred`: the stop signals are only recorded while they run and
  raised again right after, so their handlers run then. Creating a temporary file with its
  record, writing it whole (:func:`atomic_write_bytes`), publishing and discarding are such
  writes. (Blocking the signals in this thread instead is no guarantee: in a process with
  more threads the kernel hands a process-directed signal to one that does not block it, and
  Python runs the handler in the main thread all the same.)
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import stat
import sys
import tempfile
import threading
from collections.abc import Callable
from pathlib import Path
from types import FrameType
from typing import BinaryIO, Self

from ._errors import TransportError, one_line

__all__ = [
    "PARTIAL_MARK",
    "STOP_SIGNALS",
    "AtomicFile",
    "AtomicFileWriter",
    "Interrupted",
    "PublishOnExit",
    "Staging",
    "StopSignalRecorder",
    "atomic_write_bytes",
    "interrupt_on_stop_signals",
    "partial_name_prefix",
    "remove_stale_partials",
    "stop_signals_deferred",
]

_UMASK = os.umask(0o022)
os.umask(_UMASK)
_FILE_MODE = 0o666 & ~_UMASK
"""Mode of published files: what ``open(path, "w")`` would give (``mkstemp`` makes 0600)."""

PARTIAL_MARK = ".partial-"
"""Every temporary output file name contains this (``.r.ride.partial-1a2b3c4d``)."""


STOP_SIGNALS: tuple[signal.Signals, ...] = tuple(
    getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP", "SIGQUIT") if hasattr(signal, n)
)
"""The signals that ask a run to stop (Ctrl-C, kill, a closed terminal, Ctrl-\\), those this
platform has; a terminal sends them to the whole process group."""


def partial_name_prefix(path: str | os.PathLike[str]) -> str:
    """The name prefix of the temporary files of ``path`` (for tests and clean-up tools)."""
    return f".{Path(path).name}{PARTIAL_MARK}"


def _own_prefix(path: Path) -> str:
    """The prefix of this process's temporary files for ``path``."""
    return f"{partial_name_prefix(path)}{os.getpid()}-"


def _is_partial_name(path: Path) -> bool:
    """``path`` is a temporary name of this module (``.NAME.partial-...``)."""
    return path.name.startswith(".") and PARTIAL_MARK in path.name


def _note(line: str) -> None:
    try:
        print(one_line(f"motioncue: note: {line}"), file=sys.stderr, flush=True)
    except (OSError, ValueError):  # the terminal is gone
        pass


NOTE: Callable[[str], None] = _note
"""Where the notes of :func:`remove_stale_partials` go (one line each; stderr by default)."""

_OWNER = re.compile(r"(\d+)-")


def _owner_alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process (EPERM): alive
        return True
    return True


def remove_stale_partials(path: str | os.PathLike[str]) -> list[Path]:
    """Remove the temporary files of ``path`` left by writers that are gone; name them.

    A temporary file of ``path`` is a ``.NAME.partial-<pid>-...`` entry (or, from older
    versions, ``.NAME.partial-...`` and ``..NAME.partial-...``) in its folder. One whose
    process no longer runs (killed by SIGKILL, power loss) is removed (a folder with its
    files) and named in a :data:`NOTE`; one of a live process is left alone; one that names
    no process is named with the advice to remove it, and left.

    Returns
    -------
    list of Path
        The entries removed.
    """
    final = Path(path)
    folder = _folder(final)
    prefixes = (partial_name_prefix(final), "." + partial_name_prefix(final))
    removed: list[Path] = []
    try:
        entries = [e for e in os.scandir(folder) if e.name.startswith(prefixes)]
    except OSError:
        return removed
    for entry in sorted(entries, key=lambda e: e.name):
        stale = Path(entry.path)
        rest = entry.name.split(PARTIAL_MARK, 1)[1]
        owner = _OWNER.match(rest)
        if owner is None or entry.name.startswith(".."):
            NOTE(
                f"{str(stale)!r} is an unfinished temporary file of {str(final)!r} from an "
                "interrupted run; remove it if no other motioncue is writing that file"
            )
            continue
        pid = int(owner.group(1))
        if _owner_alive(pid):
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(stale)
            else:
                os.unlink(stale)
        except FileNotFoundError:
            continue
        except OSError as exc:
            NOTE(f"cannot remove the stale temporary file {str(stale)!r}: {exc}")
            continue
        removed.append(stale)
        NOTE(
            f"removed {str(stale)!r}, an unfinished {final.name} left by process {pid} "
            "(interrupted, no longer running)"
        )
    return removed


_Handler = Callable[[int, FrameType | None], object] | int | None


class _StopSignalHandlers:
    """Context manager: ``handler`` for the stop signals while active (main thread; elsewhere
    it does nothing, Python runs signal handlers in the main thread only), the previous
    handlers restored on exit.

    ``signal.signal`` first runs the handlers of signals already pending: one of them may
    raise while the handlers are being swapped. Then those already swapped are put back
    before the exception goes on (on entry), or the restoring goes on and the exception is
    raised once every handler is back (on exit).
    """

    def __init__(
        self,
        handler: Callable[[int, FrameType | None], object],
        signals: tuple[signal.Signals, ...] = STOP_SIGNALS,
        *,
        keep_ignored: bool = False,
    ) -> None:
        self._handler = handler
        self._signals = signals
        self._keep_ignored = keep_ignored
        self._previous: dict[int, _Handler] = {}
        self.active = False

    def __enter__(self) -> Self:
        if threading.current_thread() is not threading.main_thread():
            return self
        try:
            for sig in self._signals:
                try:
                    if self._keep_ignored and signal.getsignal(sig) == signal.SIG_IGN:
                        continue  # ignored (``nohup``): stays ignored
                    self._previous[sig] = signal.signal(sig, self._handler)
                except (OSError, ValueError):  # pragma: no cover - platform without it
                    pass
        except BaseException:
            self._restore()
            raise
        self.active = True
        return self

    def _restore(self) -> None:
        raised: BaseException | None = None
        while self._previous:
            sig, previous = next(iter(self._previous.items()))
            try:
                signal.signal(sig, previous if previous is not None else signal.SIG_DFL)
            except BaseException as exc:  # a pending signal's handler raised: not swapped yet
                raised = raised or exc
                continue
            del self._previous[sig]
        self.active = False
        if raised is not None:
            raise raised

    def __exit__(self, *exc: object) -> None:
        self._restore()


class StopSignalRecorder(_StopSignalHandlers):
    """Context manager: flag-only handlers for :data:`STOP_SIGNALS` (main thread), the
    previous handlers restored on exit. A signal is recorded and sets :attr:`event`; nothing
    is raised, nothing printed (the terminal may be gone).

    Attributes
    ----------
    event : threading.Event
        Set at the first signal (a loop polls ``event.is_set``).
    received : list of int
        Every signal received while active, in order.
    active : bool
        The handlers are installed (False outside the main thread).
    """

    def __init__(self, *, keep_ignored: bool = False) -> None:
        super().__init__(self._on_signal, keep_ignored=keep_ignored)
        self.event = threading.Event()
        self.received: list[int] = []

    def _on_signal(self, signum: int, frame: FrameType | None) -> None:
        # nothing that could raise or block
        self.received.append(signum)
        self.event.set()


class _Deferral(StopSignalRecorder):
    """See :func:`stop_signals_deferred`."""

    def __init__(self) -> None:
        super().__init__(keep_ignored=True)

    def __exit__(self, *exc: object) -> None:
        late: BaseException | None = None
        try:
            self._restore()
        except BaseException as exc:  # arrived as the handlers came back, and raised
            late = exc
        for sig in dict.fromkeys(self.received):
            # to this thread: its handler (the previous one, now back) runs here and now
            signal.raise_signal(sig)
        if late is not None:
            raise late


def stop_signals_deferred() -> StopSignalRecorder:
    """Context manager for a write that must not be cut: while the block runs (in the main
    thread) the stop signals are only recorded; on exit the previous handlers come back and
    each signal received is raised again (``signal.raise_signal``, in order, once each), so
    that its handler runs right after the block: an :class:`Interrupted` is raised there, a
    flag-only handler records it, the default action ends the process. Ignored signals stay
    ignored. Nests (an inner block hands its signals to the outer one). Outside the main
    thread it does nothing: a handler cannot interrupt that thread.

    Returns
    -------
    StopSignalRecorder
        Its ``received`` lists the signals deferred.
    """
    return _Deferral()


class Interrupted(KeyboardInterrupt):
    """A stop signal (SIGTERM, SIGHUP, SIGQUIT) handled like Ctrl-C.

    Attributes
    ----------
    signal_name : str
        ``"SIGTERM"``...
    """

    def __init__(self, signal_name: str) -> None:
        super().__init__(signal_name)
        self.signal_name = signal_name


def _raise_interrupted(signum: int, frame: FrameType | None) -> None:
    try:
        name = signal.Signals(signum).name
    except ValueError:  # pragma: no cover
        name = f"signal {signum}"
    raise Interrupted(name)


def interrupt_on_stop_signals() -> contextlib.AbstractContextManager[object]:
    """While active, SIGTERM, SIGHUP and SIGQUIT raise :class:`Interrupted` (a
    ``KeyboardInterrupt``) in the main thread, as Ctrl-C does, so that the outputs being
    written are discarded and the command says it was interrupted. The previous handlers
    are restored on exit. Does nothing outside the main thread."""
    return _StopSignalHandlers(
        _raise_interrupted, tuple(s for s in STOP_SIGNALS if s != signal.SIGINT)
    )


def _is_special(path: Path) -> bool:
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return False
    return not stat.S_ISREG(mode)


class PublishOnExit:
    """Mixin: a ``with`` block that ends normally publishes (:meth:`_publish`), one that
    raises (or Ctrl-C) discards (:meth:`discard`): nothing half-written is left."""

    def _publish(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def discard(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def __enter__(self) -> Self:
        return self

    def __exit__(self, exc_type: object = None, *rest: object) -> None:
        if exc_type is None:
            self._publish()
        else:
            self.discard()


class AtomicFile(PublishOnExit):
    """A binary file published under its name only by :meth:`commit`.

    Parameters
    ----------
    path : str or os.PathLike
        Final name. Its folder must exist.
    what : str
        What the file is, for error messages (``"pcap"``).

    Use as a context manager: a normal exit commits, an exception (including
    ``KeyboardInterrupt``) discards. :meth:`commit` and :meth:`discard` are idempotent, and
    after one of them the other does nothing.

    Raises
    ------
    TransportError
        The temporary file cannot be created, written or renamed (the OS error is named).
    """

    def __init__(self, path: str | os.PathLike[str], what: str = "file") -> None:
        self.path = Path(path)
        self.what = what
        self._done = False
        self._special = _is_special(self.path)
        # a special file, or a temporary name already (a Staging's): written in place
        self.direct = self._special or _is_partial_name(self.path)
        try:
            if self.direct:
                self.tmp_path = self.path
                self._fh: BinaryIO = open(self.path, "wb")
            else:
                remove_stale_partials(self.path)
                made = False
                try:
                    with stop_signals_deferred():  # created and recorded, or neither
                        fd, tmp = tempfile.mkstemp(
                            prefix=_own_prefix(self.path), suffix="", dir=_folder(self.path)
                        )
                        self.tmp_path = Path(tmp)
                        try:
                            os.fchmod(fd, _FILE_MODE)
                            self._fh = os.fdopen(fd, "wb")
                        except OSError:
                            os.close(fd)
                            os.unlink(tmp)
                            raise
                        made = True
                except BaseException:
                    if made:  # a stop signal came meanwhile and raised right after: no file
                        self._done = True
                        self._remove_tmp()
                    raise
        except OSError as exc:
            raise TransportError(f"cannot write {what} {str(self.path)!r}: {exc}") from exc

    @property
    def fh(self) -> BinaryIO:
        """The open temporary file."""
        return self._fh

    def write(self, data: bytes) -> None:
        try:
            self._fh.write(data)
        except (OSError, ValueError) as exc:
            raise TransportError(f"cannot write {self.what} {str(self.path)!r}: {exc}") from exc

    def commit(self) -> Path:
        """Flush, fsync and rename the temporary file to its final name."""
        if self._done:
            return self.path
        with stop_signals_deferred():
            return self._commit()

    def _commit(self) -> Path:
        self._done = True
        try:
            self._fh.flush()
            if not self._special:
                os.fsync(self._fh.fileno())
            self._fh.close()
            if not self.direct:
                os.replace(self.tmp_path, self.path)
        except BaseException as exc:
            self._remove_tmp()
            if isinstance(exc, OSError | ValueError):
                raise TransportError(f"cannot write {self.what} {str(self.path)!r}: {exc}") from exc
            raise
        return self.path

    def discard(self) -> None:
        """Close and remove the temporary file; the final name is left untouched."""
        if self._done:
            return
        with stop_signals_deferred():
            self._done = True
            self._remove_tmp()

    def _remove_tmp(self) -> None:
        try:
            self._fh.close()
        except (OSError, ValueError):
            pass
        if not self.direct:
            try:
                os.unlink(self.tmp_path)
            except FileNotFoundError:
                pass
            except OSError:  # pragma: no cover - nothing more can be done
                pass

    @property
    def closed(self) -> bool:
        return self._done

    def _publish(self) -> None:
        self.commit()


class AtomicFileWriter(PublishOnExit):
    """Mixin: a writer of one :class:`AtomicFile` ``_out`` (set by the subclass), published
    by :meth:`close` or a normal exit, discarded by :meth:`discard` or an exception."""

    _out: AtomicFile

    def close(self) -> None:
        """Publish the file under its name (nothing happens after :meth:`discard`)."""
        self._out.commit()

    def discard(self) -> None:
        """Remove what was written; no file is left under the name."""
        self._out.discard()

    def _publish(self) -> None:
        self.close()


def atomic_write_bytes(path: str | os.PathLike[str], data: bytes, what: str = "file") -> Path:
    """Write ``data`` to ``path`` atomically (see the module docstring).

    The temporary file is created and written whole with the stop signals deferred
    (:func:`stop_signals_deferred`); one received meanwhile is handled before the file is
    published: if its handler raises, the file is discarded and nothing is left.
    """
    out: AtomicFile | None = None
    try:
        with stop_signals_deferred():
            out = AtomicFile(path, what)
            out.write(data)
        out.commit()
    except BaseException:
        if out is not None:
            out.discard()
        raise
    return Path(path)


class Staging(PublishOnExit):
    """Several outputs prepared under temporary names and published together.

    :meth:`file` and :meth:`directory` return temporary paths next to the final ones; write
    there. :meth:`publish` renames every file into place (and moves every file of a staged
    directory into its final directory, created if needed); :meth:`discard` removes them
    all. As a context manager: a normal exit publishes, an exception (or Ctrl-C) discards.
    """

    def __init__(self) -> None:
        self._files: list[tuple[Path, Path]] = []
        self._dirs: list[tuple[Path, Path]] = []

    def file(self, final: str | os.PathLike[str]) -> Path:
        """A temporary path for the file ``final`` (in the same folder, which must exist)."""
        final = Path(final)
        if _is_special(final):
            self._files.append((final, final))
            return final
        remove_stale_partials(final)
        with stop_signals_deferred():  # created and recorded, or neither
            try:
                fd, tmp = tempfile.mkstemp(prefix=_own_prefix(final), dir=_folder(final))
            except OSError as exc:
                raise TransportError(f"cannot write {str(final)!r}: {exc}") from exc
            self._files.append((Path(tmp), final))
            try:
                os.fchmod(fd, _FILE_MODE)
            finally:
                os.close(fd)
        return Path(tmp)

    def directory(self, final: str | os.PathLike[str]) -> Path:
        """A temporary folder whose files go to the folder ``final`` (parents created)."""
        final = Path(final)
        try:
            _folder(final).mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise TransportError(f"cannot write {str(final)!r}: {exc}") from exc
        remove_stale_partials(final)
        with stop_signals_deferred():  # created and recorded, or neither
            try:
                tmp = tempfile.mkdtemp(prefix=_own_prefix(final), dir=_folder(final))
            except OSError as exc:
                raise TransportError(f"cannot write {str(final)!r}: {exc}") from exc
            self._dirs.append((Path(tmp), final))
        return Path(tmp)

    def publish(self) -> None:
        with stop_signals_deferred():
            self._publish_all()

    def _publish_all(self) -> None:
        try:
            for tmp, final in self._files:
                if tmp != final:
                    os.replace(tmp, final)
            for tmp, final in self._dirs:
                final.mkdir(parents=True, exist_ok=True)
                for entry in sorted(tmp.iterdir()):
                    os.replace(entry, final / entry.name)
                tmp.rmdir()
        except OSError as exc:
            self._discard_all()
            raise TransportError(f"cannot publish the outputs: {exc}") from exc
        self._files, self._dirs = [], []

    def discard(self) -> None:
        with stop_signals_deferred():
            self._discard_all()

    def _discard_all(self) -> None:
        for tmp, final in self._files:
            if tmp != final:
                try:
                    os.unlink(tmp)
                except OSError:
                    pass
        for tmp, _ in self._dirs:
            shutil.rmtree(tmp, ignore_errors=True)
        self._files, self._dirs = [], []

    def _publish(self) -> None:
        self.publish()


def _folder(path: Path) -> Path:
    return path.parent if str(path.parent) else Path(".")
