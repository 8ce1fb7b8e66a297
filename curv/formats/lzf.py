"""LZF decompression (the codec of PCD's ``binary_compressed`` data), as one numba kernel.

An LZF stream is a sequence of runs, each opened by a control byte ``c``:
``c < 32``: the next ``c + 1`` bytes are literals; otherwise a back reference of length
``(c >> 5) + 2`` (when ``c >> 5 == 7`` a further byte adds to the length) to the bytes
``((c & 31) << 8) + next byte + 1`` positions back in the output (it may overlap the bytes it writes).
"""

from __future__ import annotations

import numpy as np

from ..core.jit import jit

__all__ = ["decompress"]


@jit
def _decompress(src, dst):
    """Decode ``src`` (uint8) into ``dst`` (uint8); the bytes written, or -1 on a malformed stream."""
    ip = 0
    op = 0
    n = src.size
    m = dst.size
    while ip < n:
        ctrl = np.int64(src[ip])
        ip += 1
        if ctrl < 32:  # literal run
            length = ctrl + 1
            if ip + length > n or op + length > m:
                return -1
            for i in range(length):
                dst[op + i] = src[ip + i]
            ip += length
            op += length
        else:  # back reference
            length = ctrl >> 5
            if length == 7:
                if ip >= n:
                    return -1
                length += np.int64(src[ip])
                ip += 1
            if ip >= n:
                return -1
            ref = op - ((ctrl & 31) << 8) - np.int64(src[ip]) - 1
            ip += 1
            length += 2
            if ref < 0 or op + length > m:
                return -1
            for i in range(length):  # byte by byte: the reference may overlap what it writes
                dst[op + i] = dst[ref + i]
            op += length
    return op


def decompress(data: bytes | np.ndarray, size: int) -> np.ndarray:
    """Decompress an LZF stream that holds exactly ``size`` bytes.

    Parameters
    ----------
    data : bytes or (c,) uint8 array
        The compressed stream.
    size : int
        The uncompressed size it must give.

    Returns
    -------
    (size,) uint8 array

    Raises
    ------
    ValueError
        The stream is malformed or does not decode to ``size`` bytes.
    """
    src = np.frombuffer(data, dtype=np.uint8) if isinstance(data, (bytes, bytearray, memoryview)) else data
    dst = np.empty(size, dtype=np.uint8)
    got = _decompress(np.ascontiguousarray(src, dtype=np.uint8), dst)
    if got < 0:
        raise ValueError("the LZF stream is malformed")
    if got != size:
        raise ValueError(f"the LZF stream gives {got} bytes, the header says {size}")
    return dst
