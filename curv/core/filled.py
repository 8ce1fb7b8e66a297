"""Full-length arrays of one value that cost only the rows written into them.

An estimate over a region of a large mesh returns full-length arrays, NaN (or ``NOT_COMPUTED``)
outside the region. Filling 10M rows of k1, k2, d1, d2 and the reason writes 660 MB: far more
than estimating 1,000 vertices. :func:`filled` instead maps, copy-on-write, a shared buffer that
already holds the value (made once per process and value, grown when a larger array is asked
for): the operating system hands out the buffer's pages for reading, and copies a page only when
a row on it is written. The array is an ordinary writeable ndarray.

Where the system has no anonymous shared files (``os.memfd_create``: Linux), and for small arrays,
:func:`filled` is ``np.full``.
"""

from __future__ import annotations

import math
import mmap
import os
import threading

import numpy as np

__all__ = ["filled", "MIN_MAPPED_BYTES"]

MIN_MAPPED_BYTES = 1 << 22
"""Arrays smaller than this (4 MiB) are filled the ordinary way: a mapping would save nothing."""

_LOCK = threading.Lock()
_TEMPLATES: dict[bytes, tuple[int, int]] = {}
"""The fill pattern (one item's bytes) -> (descriptor of the shared buffer holding it, its size)."""


def filled(shape, fill, dtype=np.float64, *, most_written: bool = False) -> np.ndarray:
    """``np.full(shape, fill, dtype)``, writeable, at the cost of the pages later written.

    Parameters
    ----------
    shape : int or tuple of int
    fill : scalar
        The value of every element (NaN, a reason code, ...).
    dtype : numpy dtype
    most_written : bool
        The caller will write most rows (a whole-mesh estimate): then ``np.full`` is cheaper, since a
        mapped page costs a copy when it is written (10M x 3 float64 written whole: 0.17 s mapped,
        0.05 s plain).

    Returns
    -------
    ndarray of ``shape`` and ``dtype``, C-contiguous
    """
    dtype = np.dtype(dtype)
    shape = (shape,) if np.ndim(shape) == 0 else tuple(shape)
    count = math.prod(shape)
    nbytes = count * dtype.itemsize
    if most_written or nbytes < MIN_MAPPED_BYTES or not hasattr(os, "memfd_create"):
        return np.full(shape, fill, dtype)
    pattern = np.array(fill, dtype).tobytes()
    try:
        fd = _template(pattern, dtype, nbytes)
        view = mmap.mmap(fd, nbytes, flags=mmap.MAP_PRIVATE, prot=mmap.PROT_READ | mmap.PROT_WRITE)
    except OSError:  # no shared memory to spare: the ordinary way
        return np.full(shape, fill, dtype)
    return np.frombuffer(view, dtype=dtype, count=count).reshape(shape)


def _template(pattern: bytes, dtype: np.dtype, nbytes: int) -> int:
    """The descriptor of a shared buffer of at least ``nbytes`` filled with ``pattern``."""
    with _LOCK:
        fd, size = _TEMPLATES.get(pattern, (-1, 0))
        if size >= nbytes:
            return fd
        size = max(nbytes, 2 * size)
        size += -size % mmap.PAGESIZE
        new = os.memfd_create("curv-filled", os.MFD_CLOEXEC)
        try:
            os.ftruncate(new, size)
            with mmap.mmap(new, size, flags=mmap.MAP_SHARED) as shared:
                template = np.frombuffer(shared, dtype=dtype, count=size // dtype.itemsize)
                template[...] = np.frombuffer(pattern, dtype=dtype)[0]
                del template
        except BaseException:
            os.close(new)
            raise
        if fd >= 0:
            os.close(fd)  # arrays mapped from it keep their pages
        _TEMPLATES[pattern] = (new, size)
        return new
