"""What every file reader checks first, and how it words a library's exception in one line."""

from __future__ import annotations

import os
from pathlib import Path

from .errors import LoadError

__all__ = ["check_readable", "one_line", "read_with", "is_panic"]


def one_line(exc: BaseException) -> str:
    """``exc``'s message on one line of at most 200 characters (its type name when it has none)."""
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) < 200 else text[:197] + "..."


def check_readable(path: Path) -> None:
    """A :class:`LoadError` naming ``path`` when it is missing, a folder, unreadable or empty."""
    if not path.exists():
        raise LoadError(f"{path}: no such file")
    if path.is_dir():
        raise LoadError(f"{path}: is a directory, not a mesh file")
    if not os.access(path, os.R_OK):
        raise LoadError(f"{path}: permission denied")
    if path.stat().st_size == 0:
        raise LoadError(f"{path}: file is empty")


def read_with(reader, path: Path, kind: str):
    """``reader(path)``, with whatever else it raises turned into one :class:`LoadError` line naming
    ``path`` as a ``kind`` file (a LoadError of the reader's own passes as it is).

    Each format's library has its own exceptions (struct, unicode, parser, index errors ...); a user
    gets "PATH: not a readable PLY file (the library's message)" for all of them.
    """
    try:
        return reader(path)
    except LoadError:
        raise
    except MemoryError:
        raise LoadError(f"{path}: not enough memory to read the file") from None
    except Exception as exc:  # noqa: BLE001 (see above)
        raise LoadError(f"{path}: not a readable {kind} file ({one_line(exc)})") from None
    except BaseException as exc:  # a Rust library's panic (pyo3's PanicException) is no Exception
        if not is_panic(exc):
            raise
        raise LoadError(f"{path}: not a readable {kind} file (the reader failed: {one_line(exc)})") from None


def is_panic(exc: BaseException) -> bool:
    """True for pyo3's ``PanicException`` (lazrs, a Rust library, raises it when it panics)."""
    return type(exc).__name__ == "PanicException"
