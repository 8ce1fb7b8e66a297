"""What the controller's workers run around a library call, and how their failures read."""

from __future__ import annotations

import numpy as np

__all__ = ["counted", "one_line"]


def counted(call, *args, **kwargs):
    """Run the estimate generator ``call(*args, **kwargs)`` (yielding its progress) and return its
    result with its count of invalid vertices, counted here in the worker (O(n): 5M points)."""
    result = yield from call(*args, **kwargs)
    return result, int(np.count_nonzero(~np.asarray(result.valid)))


def one_line(exc: Exception) -> str:
    """The first line of an exception's message (its type's name when it has none), for the status bar."""
    text = str(exc).strip().splitlines()
    return text[0] if text else type(exc).__name__
