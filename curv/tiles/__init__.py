"""Inputs larger than memory: tiles with halos, run here or on a Dask cluster, file to file.

- :mod:`curv.tiles.plan`: tiles sized by point count, the regions (tile plus halo) they read.
- :mod:`curv.tiles.reach`: how far an estimate at a point reads (the halo rule's one owner).
- :mod:`curv.tiles.frame`: the whole input's order and grid, which every tile keeps.
- :mod:`curv.tiles.engine`: one tile: estimate its region, keep what its halo covered, redo the rest.
- :mod:`curv.tiles.memory`: tiles over an input held in memory (:func:`estimate_tiled`).
- :mod:`curv.tiles.files`: file to file, a chunk at a time (:func:`estimate_file`): the passes of
  :mod:`curv.tiles.prepare`, the tasks of :mod:`curv.tiles.tasks` run by :mod:`curv.tiles.driver`,
  the output from :mod:`curv.tiles.merge` through :mod:`curv.formats.laswrite` or :mod:`curv.tiles.plyout`.
"""

from __future__ import annotations

from .files import FileRun, estimate_file, iter_estimate_file, output_suffixes
from .memory import estimate_tiled, iter_estimate_tiled
from .reach import support_reach

__all__ = ["estimate_file", "iter_estimate_file", "FileRun", "output_suffixes", "estimate_tiled", "iter_estimate_tiled",
           "support_reach"]
