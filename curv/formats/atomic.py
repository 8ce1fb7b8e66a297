"""Writing a file atomically: a temporary file beside the target, renamed over it when complete.

A failure (a full disk, a bad input found half way, Ctrl-C) removes the temporary file, so the
target is either the complete new file or whatever was there before: never a partial output.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path", "atomic_write", "plain_mode"]


def plain_mode(path: Path) -> int:
    """The permission bits ``open(path, "w")`` would leave: the old file's, else 0666 minus the umask."""
    try:
        return path.stat().st_mode & 0o7777
    except OSError:
        mask = os.umask(0)
        os.umask(mask)
        return 0o666 & ~mask


@contextlib.contextmanager
def atomic_path(path):
    """A temporary path beside ``path`` to write to; renamed over ``path`` when the block ends cleanly.

    The caller writes and closes the temporary file inside the block. On leaving it the file gets the
    permissions of a plain write (``mkstemp`` makes 0600 files), is synced to disk and renamed over
    ``path``; on any exception (``KeyboardInterrupt`` included) it is deleted and the exception
    goes on.

    Yields
    ------
    Path
        The temporary file (created empty, hidden: ``.NAME.XXXX.tmp``).
    """
    path = Path(path)
    folder = path.parent if str(path.parent) else Path(".")
    mode = plain_mode(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    os.close(fd)
    tmp = Path(tmp)
    try:
        yield tmp
        os.chmod(tmp, mode)
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def atomic_write(path: Path, write) -> Path:
    """Write through ``write(fh)`` into a temporary file beside ``path``, then rename it over ``path``.

    A failure never leaves a partial file; the result has the permissions of a plain write
    (``mkstemp`` creates 0600 files).
    """
    folder = path.parent if str(path.parent) else Path(".")
    mode = plain_mode(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fchmod(fh.fileno(), mode)
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path
