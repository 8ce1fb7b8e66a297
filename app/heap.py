"""Giving freed memory back to the system (glibc's allocator; elsewhere these do nothing).

A large mesh passes through many short-lived buffers: the estimate's numpy temporaries, VTK's
vertex and index buffers while it uploads a frame, the report's arrays. glibc's allocator keeps
what is freed in its heaps for reuse, and after the first large buffer is freed it raises its
threshold for serving requests from fresh pages (up to 32 MB), so the buffers of the next phase
also land in the heaps and their pages stay with the process after they are freed: measured at
1M vertices, 100 MB of the viewer's resident memory after its first frame was free heap.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import sys

__all__ = ["tune_allocator", "release_free_memory"]

_M_MMAP_THRESHOLD = -3
MMAP_THRESHOLD = 1 << 20
"""Allocations of at least this many bytes get pages of their own, returned to the system when
freed (glibc's default starts at 128 KiB and rises with every larger buffer freed)."""


def _libc():
    if not sys.platform.startswith("linux"):
        return None
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
    except OSError:
        return None
    return libc if hasattr(libc, "malloc_trim") and hasattr(libc, "mallopt") else None


_LIBC = _libc()


def tune_allocator() -> bool:
    """Fix the allocator's threshold for own-pages allocations at :data:`MMAP_THRESHOLD`.

    Call it once, before the first large buffer (``curvlab`` does, before the file's read starts).

    Returns
    -------
    bool
        Whether the allocator took the setting (False off glibc).
    """
    if _LIBC is None:
        return False
    return bool(_LIBC.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD))


def release_free_memory() -> bool:
    """Return the free pages of the allocator's heaps to the system (``malloc_trim(0)``).

    At most a few milliseconds (0.1 ms measured in the viewer at 1M vertices); the controller calls it after a mesh loads, after its first coloured frame
    and after its report.

    Returns
    -------
    bool
        Whether any memory was released (False off glibc).
    """
    if _LIBC is None:
        return False
    return bool(_LIBC.malloc_trim(0))
