"""Runs the slow work (loading, meshing, estimation) in worker threads and feeds the model."""

from .jobs import Controller
from .sources import load_source

__all__ = ["Controller", "load_source"]
