"""Small text helpers shared by the views' messages (the library owns the counting rule)."""

from __future__ import annotations

from curv.core.wording import count_text

__all__ = ["count_text"]
