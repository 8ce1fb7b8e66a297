"""Words for counts in messages: ``1 vertex``, ``2 vertices`` (the library's and the viewer's)."""

from __future__ import annotations

__all__ = ["count_text"]


def count_text(n: int, singular: str, plural: str) -> str:
    """``1 vertex``, ``0 vertices``, ``2 vertices``: a count with the noun in the right number."""
    return f"{n} {singular if n == 1 else plural}"
