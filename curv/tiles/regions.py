"""A large file read at full resolution around a point: the region and the halo its estimates read.

:class:`FileRegions` sorts a file's points into tiles once (:func:`curv.tiles.prepare.iter_prepare`,
in a scratch folder), after which :meth:`FileRegions.iter_around` reads the points within a radius
of a point (the **ball**) and around them a halo as wide as the estimates asked for read
(:func:`curv.tiles.support_reach`), widened until every ball point's reach is inside: estimating
that piece with ``vertices=`` the ball's points gives the whole file's values there
(:mod:`curv.tiles.engine`). The viewer opens such a piece when a preview's region is asked for
at full resolution.

A COPC file is not sorted into tiles: its octree is queried by the region's bounds
(:class:`curv.tiles.copc.CopcInput`), after one pass over its coordinates for the whole file's grid
(:func:`curv.tiles.copc.iter_whole_frame`); any other LAS/LAZ file or binary PLY is.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Generator

import numpy as np

from ..core.jit import Progress
from .copc import CopcInput, is_copc, iter_whole_frame
from .engine import Job, shape_of
from .plan import Region
from .prepare import FileInput, iter_prepare
from .scratch import Scratch
from .sources import open_source

__all__ = ["FileRegions", "Around", "REGION_TILE"]

REGION_TILE = 1_000_000
"""Points a tile of the region index holds (a region reads the few tiles it meets)."""


@dataclass
class Around:
    """A piece of a file around a point, at full resolution.

    Attributes
    ----------
    shape : PointCloud or Mesh
        The ball's points and their halo, as the whole file's estimate holds them.
    ball : (c,) int64
        The rows of ``shape`` within the radius (sorted): estimate them with ``vertices=ball``.
    ids : (m,) int64
        Each row's number in the file.
    halo : float
        The halo's width.
    """

    shape: object
    ball: np.ndarray
    ids: np.ndarray
    halo: float


class FileRegions:
    """Regions of one large file (module notes).

    Parameters
    ----------
    path : str or Path
        LAS/LAZ (COPC read by bounds) or a binary PLY of points, triangles or polygons.
    scratch : str or Path, optional
        Where the tiles are kept; default a folder per file in the system's temporary folder.
    """

    def __init__(self, path, scratch=None):
        self.path = Path(path)
        if scratch is None:
            st = self.path.stat()
            key = hashlib.blake2b(f"{self.path.resolve()}:{st.st_size}:{st.st_mtime_ns}".encode(), digest_size=8)
            scratch = Path(tempfile.gettempdir()) / f"curvlab-regions-{os.getuid()}" / key.hexdigest()
        self.scratch = Scratch(scratch)
        self._input = None
        self._bounds = self._frame = None
        self._is_mesh = False

    @property
    def ready(self) -> bool:
        return self._input is not None

    def iter_prepare(self) -> Generator[float, None, None]:
        """Sort the file's points into tiles, once (a generator of the fraction done)."""
        if self._input is not None:
            return
        if is_copc(self.path):
            copc = CopcInput(self.path)
            self._bounds, self._frame = yield from iter_whole_frame(self.path, copc.n)
            self._input = copc
            return
        source = open_source(self.path)
        if source is None:
            raise ValueError(f"{self.path}: is read whole (not LAS/LAZ or a PLY read a chunk at a time)")
        identity = self.scratch.identity(self.path, {"regions": True}, REGION_TILE)
        if self.scratch.open(identity):
            prepared = self.scratch.load_plan()
        else:
            prepared = yield from iter_prepare(source, self.scratch, REGION_TILE)
        self._bounds, self._frame, self._is_mesh = prepared.plan.bounds, prepared.frame, prepared.is_mesh
        self._input = FileInput(self.scratch, prepared, self.path)

    def iter_around(self, centre, radius: float, jobs) -> Generator[float, None, Around]:
        """The points within ``radius`` of ``centre`` and the halo the estimates ``jobs``
        (:class:`curv.tiles.engine.Job`, or ``(method, range, keywords)``) read there (module notes)."""
        if self._input is None:
            yield from self.iter_prepare()
        points = not self._is_mesh
        georeferenced = self.path.suffix.lower() in (".las", ".laz")  # as the LAS reader says (curv.PointCloud)
        jobs = [(j if isinstance(j, Job) else Job.checked(j[0], j[1], **dict(j[2])))
                .for_input(points=points, georeferenced=georeferenced) for j in jobs]
        centre = np.asarray(centre, np.float64).reshape(3)
        radius = float(radius)
        bounds = self._bounds
        lo, hi = centre - radius, centre + radius
        h = radius
        while True:
            yield Progress(0.5, "reading the region")
            region = Region.around(lo, hi, h, bounds)
            piece = self._input.fetch(region)
            shape, order = shape_of(piece, self._frame, points=points, georeferenced=georeferenced)
            inside = np.linalg.norm(shape.vertices - centre, axis=1) <= radius
            if not piece.ids.size or (not points and (piece.faces is None or not piece.faces.size)):
                return Around(shape, np.flatnonzero(inside), piece.ids[order], h)
            ball = np.flatnonzero(inside)
            if ball.size == 0:
                return Around(shape, ball, piece.ids[order], h)
            reach = np.max([job.reach(shape, ball) for job in jobs], axis=0)
            room = region.room(shape.vertices[ball])
            if np.all(reach <= room) or region.everything:
                return Around(shape, ball, piece.ids[order], h)
            wanted = reach[np.isfinite(reach)]
            h = max(2.0 * h, 1.5 * float(wanted.max(initial=0.0))) if np.isfinite(reach).all() else np.inf

    def close(self) -> None:
        """Remove the scratch folder."""
        self.scratch.clear()
        self._input = None
