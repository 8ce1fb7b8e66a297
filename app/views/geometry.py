"""Building VTK geometry from a :class:`curv.Mesh` (shared by every pane) and direction glyphs."""

from __future__ import annotations

from functools import cached_property

import numpy as np
from curv import prepare
from curv.core.quantities import anisotropy
import pyvista as pv
from vtkmodules.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
from vtkmodules.vtkCommonDataModel import vtkCellArray

from app.model.camera import is_georeferenced
from app.model.inputs import is_points, unit_length

from .viewport import grey_colours

__all__ = ["mesh_polydata", "cloud_polydata", "prepare_geometry", "direction_glyphs", "glyph_subsample", "edge_lines",
           "Geometry"]


def mesh_polydata(mesh, normals: np.ndarray | None = None) -> pv.PolyData:
    """A PolyData of ``mesh`` (triangles or polygons) with point normals for smooth shading.

    The points and the faces are the mesh's own arrays, not copies (VTK reads the numpy memory and
    the PolyData keeps the arrays alive): one copy of the geometry between the library and the
    display. At 10M vertices a deep copy of the faces alone was 640 MB.

    Parameters
    ----------
    mesh : curv.Mesh
    normals : (n, 3) float, optional
        Vertex normals, stored as the active normals (as float32, the precision VTK shades with)
        so VTK shades smoothly.
    """
    poly = pv.PolyData()
    poly.points = np.ascontiguousarray(mesh.vertices, dtype=np.float64)
    cells = vtkCellArray()
    offsets = numpy_to_vtkIdTypeArray(np.ascontiguousarray(mesh.face_offsets, dtype=np.int64), deep=False)
    conn = numpy_to_vtkIdTypeArray(np.ascontiguousarray(mesh.face_indices, dtype=np.int64), deep=False)
    cells.SetData(offsets, conn)
    poly.SetPolys(cells)
    if normals is not None:
        arr = numpy_to_vtk(np.ascontiguousarray(normals, dtype=np.float32), deep=True)
        arr.SetName("Normals")
        poly.GetPointData().SetNormals(arr)
    return poly


class Geometry:
    """What the views draw of a mesh or point cloud: its PolyData and grey colours (built off the GUI
    thread), and on first use its length unit.

    The length unit (mean edge length of a mesh, median spacing of a point cloud) needs a mesh's
    edge table, which neither an estimate nor the first picture needs (at 10M vertices 2.5 GB and
    15-30 s): it is computed when something asks for it (direction glyphs, a default radius). The
    overlay edges (borders, creases) are the controller's, found in a worker.

    Parameters
    ----------
    mesh : curv.Mesh or curv.PointCloud
    base : pyvista.PolyData
        ``mesh`` as drawn (:func:`mesh_polydata` or :func:`cloud_polydata`).
    """

    def __init__(self, mesh, base: pv.PolyData) -> None:
        self.mesh, self.base = mesh, base

    @cached_property
    def grey(self) -> np.ndarray:
        """(n, 4) uint8: the colours of a pane without a result, shared by every viewport."""
        return grey_colours(self.base.n_points)

    @cached_property
    def bounds(self) -> tuple:
        """``(xmin, xmax, ymin, ymax, zmin, zmax)`` of the points, as VTK orders them (what the camera frames)."""
        points = np.asarray(self.base.points)
        if points.shape[0] == 0:
            return (0.0, 1.0, 0.0, 1.0, 0.0, 1.0)
        lo, hi = points.min(axis=0), points.max(axis=0)
        return tuple(float(v) for pair in zip(lo, hi) for v in pair)

    @cached_property
    def georeferenced(self) -> bool:
        """Whether a point cloud is a scan in map coordinates: the reader said so
        (``PointCloud.georeferenced``, LAS/LAZ) or it looks like one
        (:func:`app.model.camera.is_georeferenced`); False for a mesh. It is first seen from above."""
        return self.points_only and (bool(getattr(self.mesh, "georeferenced", False))
                                     or is_georeferenced(np.asarray(self.base.points)))

    @cached_property
    def edge_length(self) -> float:
        """The length unit (:func:`app.model.inputs.unit_length`)."""
        return unit_length(self.mesh)

    @property
    def points_only(self) -> bool:
        """Whether this is a point cloud (vertex cells only)."""
        return self.base.n_cells == self.base.n_verts and self.base.n_verts > 0


def edge_lines(mesh, edges: np.ndarray) -> pv.PolyData:
    """``edges`` (k, 2) vertex pairs of ``mesh`` as line cells (an empty PolyData for none)."""
    if edges.size == 0:
        return pv.PolyData()
    lines = np.column_stack([np.full(len(edges), 2), edges]).ravel()
    return pv.PolyData(np.ascontiguousarray(mesh.vertices, dtype=np.float64), lines=lines)


def cloud_polydata(cloud) -> pv.PolyData:
    """A PolyData of a :class:`curv.PointCloud`: its points, one vertex cell each (nothing to shade)."""
    return pv.PolyData(np.ascontiguousarray(cloud.points, dtype=np.float64))


def prepare_geometry(mesh) -> Geometry:
    """Render geometry of ``mesh``; safe to run in a worker thread.

    A point cloud is drawn as its points. A mesh is shaded with its default normals
    (:func:`curv.prepare`), the ones a default estimate uses too: computed once for both. A point cloud's length unit is asked here (its neighbour search, which the cloud
    keeps and its estimates reuse); a mesh's waits until something needs it (:class:`Geometry`).
    """
    if is_points(mesh):
        geometry = Geometry(mesh, cloud_polydata(mesh))
        geometry.edge_length  # noqa: B018 (computed here, off the GUI thread)
    else:
        geometry = Geometry(mesh, mesh_polydata(mesh, prepare(mesh)))
    geometry.grey  # noqa: B018 (here too)
    geometry.bounds  # noqa: B018
    geometry.georeferenced  # noqa: B018
    return geometry


def glyph_subsample(n: int, *, count: int = 2000, seed: int = 0) -> np.ndarray:
    """A fixed, spread-out subset of at most ``count`` vertex indices (same on every pane)."""
    if n <= count:
        return np.arange(n)
    return np.sort(np.random.default_rng(seed).choice(n, size=count, replace=False))


def direction_glyphs(points: np.ndarray, result, *, length: float, index: np.ndarray,
                     min_anisotropy: float = 0.02, lift: float | None = None) -> tuple[pv.PolyData, pv.PolyData]:
    """Line glyphs along d1 and d2 at ``index``, centred on the vertices.

    Parameters
    ----------
    points : (n, 3) float
    result : curv.Curvature
    length : float
        Full length of a glyph line (a multiple of the mean edge length).
    index : (m,) int
        Subsample of vertices to draw.
    min_anisotropy : float
        Glyphs are hidden where ``|k1 - k2| / (|k1| + |k2|)`` is below this (umbilics: no direction).
    lift : float, optional
        How far along the normal the glyphs float (default 2 % of ``length``; above a point's
        sphere on a point cloud).

    Returns
    -------
    (d1_lines, d2_lines) : pyvista.PolyData
    """
    k1, k2 = result.k1[index], result.k2[index]
    aniso = anisotropy(k1, k2)
    keep = index[np.isfinite(aniso) & (aniso >= min_anisotropy)]
    out = []
    lift = (0.02 * length if lift is None else lift) * result.normals[keep]
    for d in (result.d1, result.d2):
        half = 0.5 * length * d[keep]
        centre = points[keep] + lift
        pts = np.empty((2 * keep.size, 3))
        pts[0::2] = centre - half
        pts[1::2] = centre + half
        lines = np.column_stack([np.full(keep.size, 2), np.arange(0, 2 * keep.size, 2),
                                 np.arange(1, 2 * keep.size, 2)]).ravel()
        out.append(pv.PolyData(pts, lines=lines) if keep.size else pv.PolyData())
    return out[0], out[1]
