"""A minimal callback event: the model's only way to tell views that something changed."""

from __future__ import annotations

from typing import Callable

__all__ = ["Event"]


class Event:
    """A list of callbacks called in connection order with the emitted arguments.

    Examples
    --------
    >>> ev = Event()
    >>> seen = []
    >>> _ = ev.connect(seen.append)
    >>> ev.emit(3)
    >>> seen
    [3]
    """

    def __init__(self) -> None:
        self._callbacks: list[Callable] = []

    def connect(self, callback: Callable) -> Callable:
        """Subscribe ``callback``; returns it so the method works as a decorator."""
        if callback not in self._callbacks:
            self._callbacks.append(callback)
        return callback

    def emit(self, *args) -> None:
        """Call every subscriber with ``args``."""
        for cb in list(self._callbacks):
            cb(*args)
