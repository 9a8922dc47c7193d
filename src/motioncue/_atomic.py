"""Atomic output files: written under a temporary name, renamed into place on success.

Every file motioncue produces (ride files, pcaps, raw ``file:`` targets, telemetry
recordings, reports) goes through :class:`AtomicFile` or :func:`atomic_write_bytes`. The data
is written to ``.NAME.partial-XXXXXXXX`` in the destination's own folder (so the final
``os.replace`` is atomic on every POSIX file system), flushed and fsynced, then renamed to
``NAME``. A refusal, an exception or Ctrl-C removes the temporary file; a process killed by
SIGKILL or a power loss can leave one behind, always with that obviously unfinished name,
never a valid-looking ``NAME``.

A destination that exists and is not a regular file (``/dev/null``, a FIFO, a terminal) is
written directly: it cannot be replaced, and nothing valid-looking is left there anyway.
"""

from __future__ import annotations

import os
import shutil
import stat
import tempfile
from pathlib import Path
from types import TracebackType
from typing import BinaryIO, Self

from ._errors import TransportError

__all__ = [
    "PARTIAL_MARK",
    "AtomicFile",
    "PublishOnExit",
    "Staging",
    "atomic_write_bytes",
    "partial_name_prefix",
]

_UMASK = os.umask(0o022)
os.umask(_UMASK)
_FILE_MODE = 0o666 & ~_UMASK
"""Mode of published files: what ``open(path, "w")`` would give (``mkstemp`` makes 0600)."""

PARTIAL_MARK = ".partial-"
"""Every temporary output file name contains this (``.r.ride.partial-1a2b3c4d``)."""


def partial_name_prefix(path: str | os.PathLike[str]) -> str:
    """The name prefix of the temporary files of ``path`` (for tests and clean-up tools)."""
    return f".{Path(path).name}{PARTIAL_MARK}"


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
        self.direct = _is_special(self.path)
        try:
            if self.direct:
                self.tmp_path = self.path
                self._fh: BinaryIO = open(self.path, "wb")
            else:
                folder = self.path.parent if str(self.path.parent) else Path(".")
                fd, tmp = tempfile.mkstemp(
                    prefix=partial_name_prefix(self.path), suffix="", dir=folder
                )
                self.tmp_path = Path(tmp)
                os.fchmod(fd, _FILE_MODE)
                self._fh = os.fdopen(fd, "wb")
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
        self._done = True
        try:
            self._fh.flush()
            if not self.direct:
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
        try:
            fd, tmp = tempfile.mkstemp(prefix=partial_name_prefix(final), dir=_folder(final))
        except OSError as exc:
            raise TransportError(f"cannot write {str(final)!r}: {exc}") from exc
        try:
            os.fchmod(fd, _FILE_MODE)
        finally:
            os.close(fd)
        self._files.append((Path(tmp), final))
        return Path(tmp)

    def directory(self, final: str | os.PathLike[str]) -> Path:
        """A temporary folder whose files go to the folder ``final`` (parents created)."""
        final = Path(final)
        try:
            _folder(final).mkdir(parents=True, exist_ok=True)
            tmp = tempfile.mkdtemp(prefix=partial_name_prefix(final), dir=_folder(final))
        except OSError as exc:
            raise TransportError(f"cannot write {str(final)!r}: {exc}") from exc
        self._dirs.append((Path(tmp), final))
        return Path(tmp)

    def publish(self) -> None:
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
            self.discard()
            raise TransportError(f"cannot publish the outputs: {exc}") from exc
        self._files, self._dirs = [], []

    def discard(self) -> None:
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
