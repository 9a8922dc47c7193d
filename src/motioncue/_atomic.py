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
* Creating a temporary file and recording it for removal, publishing and discarding run with
  the stop signals blocked (:func:`_signals_held`), so that a signal cannot fall between the
  two and leak a file: it is delivered right after.
* :func:`interrupt_on_stop_signals` (installed by the command line before any verb runs)
  makes SIGTERM, SIGHUP and SIGQUIT raise :class:`Interrupted`, a ``KeyboardInterrupt``, as
  Ctrl-C does: the ``with`` blocks of the outputs discard them. A verb that must finish a
  park first replaces these handlers with its own (``pipeline._signals.SignalGuard``).
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
from collections.abc import Callable, Iterator
from pathlib import Path
from types import FrameType, TracebackType
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
    "atomic_write_bytes",
    "interrupt_on_stop_signals",
    "partial_name_prefix",
    "remove_stale_partials",
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


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Block the stop signals in this thread while the block runs; one that arrives
    meanwhile is delivered (its handler runs) right after."""
    try:
        old = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    except (OSError, ValueError):  # pragma: no cover - no signal masks here
        yield
        return
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


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


@contextlib.contextmanager
def interrupt_on_stop_signals() -> Iterator[None]:
    """While active, SIGTERM, SIGHUP and SIGQUIT raise :class:`Interrupted` (a
    ``KeyboardInterrupt``) in the main thread, as Ctrl-C does, so that the outputs being
    written are discarded and the command says it was interrupted. The previous handlers
    are restored on exit. Does nothing outside the main thread."""
    previous: dict[signal.Signals, Callable[[int, FrameType | None], object] | int | None] = {}
    if threading.current_thread() is threading.main_thread():
        for sig in STOP_SIGNALS:
            if sig == signal.SIGINT:
                continue
            try:
                previous[sig] = signal.signal(sig, _raise_interrupted)
            except (OSError, ValueError):  # pragma: no cover
                pass
    try:
        yield
    finally:
        for old_sig, handler in previous.items():
            signal.signal(old_sig, handler if handler is not None else signal.SIG_DFL)


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

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
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
                with _signals_held():  # created and recorded, or neither
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
        with _signals_held():
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
        with _signals_held():
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
    """Write ``data`` to ``path`` atomically (see the module docstring)."""
    with AtomicFile(path, what) as out:
        out.write(data)
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
        with _signals_held():  # created and recorded, or neither
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
        with _signals_held():  # created and recorded, or neither
            try:
                tmp = tempfile.mkdtemp(prefix=_own_prefix(final), dir=_folder(final))
            except OSError as exc:
                raise TransportError(f"cannot write {str(final)!r}: {exc}") from exc
            self._dirs.append((Path(tmp), final))
        return Path(tmp)

    def publish(self) -> None:
        with _signals_held():
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
        with _signals_held():
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
