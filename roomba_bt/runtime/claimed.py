"""An output file that one program writes at a time: ``run --record``, ``eval --out``.

Two runs given the same ``--record`` path in a classroom's shared folder each opened it with
``open(path, "w")``: the second truncated it under the first's descriptor, and the file held
the second run's record, then 34 KB of NUL bytes, then the end of the first's (whose record
was lost); ``replay`` then blamed "a line after the run's end line". Two ``eval --out`` into
one file both said "results written", and the file held one sweep's episodes.

:class:`ClaimedFile` opens the file without truncating it and takes an exclusive ``flock``
(``LOCK_EX | LOCK_NB``): a second writer is refused at once (:class:`FileInUse`), before it
has truncated anything, and its user is told which file and why. The file is emptied only
when its writer starts writing (:meth:`ClaimedFile.open_text`), so a run that fails before
(the port busy, an invalid mission) leaves an earlier record as it was, and removes a file it
made and never wrote. The lock is advisory: it stops every roomba-bt, not an editor that
writes the file; it goes with the descriptor, so a run killed outright lets go of it.
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path
from typing import IO

try:
    import fcntl
except ImportError:  # Windows: no flock; the file is written as before, unguarded
    fcntl = None  # type: ignore[assignment]

#: what a second writer is told (after ``--record FILE: ``)
IN_USE = (
    "another roomba-bt (a run or an eval) is writing it, and two writers corrupt it: give "
    "this one another file"
)
#: how often the file is opened again when it was replaced between the open and the lock
_ATTEMPTS = 3


class FileInUse(OSError):
    """Another process writes the file (it holds its lock); ``strerror`` says so."""


class ClaimedFile:
    """``path`` opened for writing by this process alone, not yet emptied.

    Raises :class:`FileInUse` when another process holds it, OSError when it cannot be
    opened. Either :meth:`open_text` (the writer takes the file, and the lock with it) or
    :meth:`release` (never written) ends the claim."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self._fd, self.created = _open_locked(self.path)
        self._handed = False

    def open_text(self, newline: str | None = None) -> IO[str]:
        """The file, emptied, as a text file for writing; closing it lets go of the lock."""
        return os.fdopen(self._handed_over(), "w", encoding="utf-8", newline=newline)

    def open_binary(self) -> IO[bytes]:
        """The file, emptied, for writing bytes (a compressed record, ``--record x.gz``);
        closing it lets go of the lock."""
        return os.fdopen(self._handed_over(), "wb")

    def _handed_over(self) -> int:
        """The descriptor, the file emptied, handed to its one writer."""
        if self._handed:
            raise RuntimeError(f"{self.path}: already handed to its writer")
        if stat.S_ISREG(os.fstat(self._fd).st_mode):  # a device (/dev/null) is not truncated
            os.ftruncate(self._fd, 0)
        self._handed = True
        return self._fd

    def make_room(self, size: int) -> None:
        """Make sure the disk takes ``size`` bytes more before a file that holds an earlier
        record is emptied (``run --require-record``, whose header is ``size`` bytes or fewer):
        they are written after its end and cut off again, the file as it was either way, and
        the disk's refusal (a full disk, a quota, a file size limit: an OSError) raised before
        anything of it is lost. Emptied first, an earlier record would be gone when the header
        then failed and the run refused to start. Nothing for a file this claim
        made or one that is empty (nothing to lose) or a device (never emptied)."""
        held = os.fstat(self._fd)
        if self._handed or not stat.S_ISREG(held.st_mode) or held.st_size == 0:
            return
        end = held.st_size
        try:
            written = self._write_at(b"\n" * size, end)
            if written < size:  # a short write: the disk took what it had room for
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(self.path))
        finally:
            os.ftruncate(self._fd, end)

    def _write_at(self, data: bytes, offset: int) -> int:
        """``data`` written at ``offset`` of the file; the bytes written."""
        return os.pwrite(self._fd, data, offset)

    def release(self) -> None:
        """Let go of a file that was never written: as it was, or gone if the claim made it
        (a run refused at its start left an empty record behind). Nothing once written."""
        if self._handed or self._fd < 0:
            return
        try:
            if self.created:  # removed while still locked: no other writer has it meanwhile
                self.path.unlink(missing_ok=True)
        finally:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> ClaimedFile:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.release()


def held_by_a_writer(path: str | Path) -> bool | None:
    """Whether a process writes ``path`` now, holding its :class:`ClaimedFile` lock (a ``run
    --record`` in progress): a shared ``flock`` that cannot be had at once says so. None
    when it cannot be told (no ``flock`` here, or none on the file's file system: some
    network mounts; the file unreadable): the caller falls back to another sign. A file's
    age said it before, and was wrong both ways: a record read 2 s after its run's ``kill
    -9`` was "still being written", and one read during a run that had written nothing for
    a while (a long stall ridden through) was "killed". The shared lock is let go at once;
    a writer starting in that instant would be refused (:class:`FileInUse`) and say so."""
    if fcntl is None:
        return None
    try:
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError as exc:
        return True if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN) else None
    finally:
        os.close(fd)  # and the shared lock with it
    return False


def _open_locked(path: Path) -> tuple[int, bool]:
    """A descriptor of ``path`` for writing, locked, and whether this open made the file.
    The name is checked to still be the locked file: one replaced meanwhile (a writer that
    removed the file it made) would be locked in vain, so it is opened again."""
    for _ in range(_ATTEMPTS):
        try:
            fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_CLOEXEC, 0o666)
            created = True
        except FileExistsError:
            try:
                fd = os.open(path, os.O_WRONLY | os.O_CLOEXEC)  # no O_TRUNC: not yet ours
            except FileNotFoundError:
                continue  # removed between the two opens
            created = False
        if fcntl is None:
            return fd, created
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                raise FileInUse(exc.errno, IN_USE, str(path)) from None
            raise
        if _same_file(fd, path):
            return fd, created
        os.close(fd)
    raise FileInUse(errno.EWOULDBLOCK, IN_USE, str(path))


def _same_file(fd: int, path: Path) -> bool:
    try:
        named = os.stat(path)
    except FileNotFoundError:
        return False
    held = os.fstat(fd)
    return (held.st_dev, held.st_ino) == (named.st_dev, named.st_ino)
