"""Runs the slow work (loading, meshing, estimation) in worker threads and feeds the model."""

from .jobs import Controller
from .sources import Loaded, load_source, prepare_source

__all__ = ["Controller", "Loaded", "load_source", "prepare_source"]
