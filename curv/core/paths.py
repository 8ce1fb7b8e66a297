"""What every file reader checks first, and how it words a library's exception in one line."""

from __future__ import annotations

import os
from pathlib import Path

from .errors import LoadError

__all__ = ["check_readable", "one_line"]


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
