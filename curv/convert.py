"""Converters from other libraries' meshes and point clouds to :class:`curv.Mesh` and :class:`curv.PointCloud`.

``curv.estimate`` and the other entry points accept a trimesh ``Trimesh`` or ``PointCloud``, a
pyvista ``PolyData`` (with polygons, or only points), a meshio ``Mesh`` or an (n, 3) array as they
are, through :func:`as_input`; what needs faces asks :func:`as_mesh`. The objects are recognised by
their attributes, so curv imports none of those libraries (pyvista would bring VTK into the library).
"""

from __future__ import annotations

import numpy as np

from .core.errors import MeshError
from .core.mesh import Mesh
from .core.pointcloud import PointCloud

__all__ = ["as_input", "as_mesh", "ACCEPTED"]

_SURFACE_CELLS = ("triangle", "quad", "polygon")
"""meshio cell types that are surface faces."""

_POINT_CELLS = ("vertex",)
"""meshio cell types that are points alone."""

ACCEPTED = ("a curv.Mesh or curv.PointCloud, a trimesh.Trimesh or trimesh.PointCloud, a pyvista.PolyData, "
            "a meshio.Mesh or an (n, 3) array of points")
"""What :func:`as_input` takes, in words."""


def as_input(obj) -> Mesh | PointCloud:
    """``obj`` as a :class:`curv.Mesh` when it has faces, else as a :class:`curv.PointCloud`.

    Parameters
    ----------
    obj : Mesh, PointCloud, trimesh.Trimesh, trimesh.PointCloud, pyvista.PolyData, meshio.Mesh or (n, 3) array_like
        A mesh as in :func:`as_mesh`; points alone: a trimesh ``PointCloud`` (``vertices``), a
        pyvista ``PolyData`` without polygons, lines or strips (its ``points``, and its active
        point normals when it has them), a meshio ``Mesh`` with vertex cells only or none, or an
        (n, 3) array of positions (a numpy array, or a list of triples).

    Raises
    ------
    MeshError
        Anything else, naming the accepted kinds; a pyvista or meshio object whose cells are lines.
    """
    if isinstance(obj, (Mesh, PointCloud)):
        return obj
    points = _cloud_of(obj)
    return points if points is not None else as_mesh(obj)


def as_mesh(obj) -> Mesh:
    """``obj`` as a :class:`curv.Mesh` (the object itself when it is one already).

    Parameters
    ----------
    obj : curv.Mesh, trimesh.Trimesh, pyvista.PolyData or meshio.Mesh
        trimesh: ``vertices`` (n, 3) and ``faces`` (m, 3); pyvista: ``points`` (n, 3) and its
        ``regular_faces`` (m, k) or ``irregular_faces`` (polygons of any size); meshio: ``points``
        (n, 3) and its triangle, quad and polygon cell blocks, in their order.

    Raises
    ------
    MeshError
        Anything else, naming the accepted kinds; a point cloud (of curv or another library), or a
        pyvista or meshio object without faces, saying that this needs a mesh's faces.
    """
    if isinstance(obj, Mesh):
        return obj
    kind = type(obj).__name__
    if isinstance(obj, PointCloud) or _cloud_of(obj) is not None:
        raise MeshError(f"this needs a mesh's faces; got a point cloud ({kind} of {_count(obj)} points)")
    if hasattr(obj, "vertices") and hasattr(obj, "faces") and np.ndim(obj.faces) == 2:  # trimesh
        return Mesh(np.asarray(obj.vertices, np.float64), np.asarray(obj.faces))
    if hasattr(obj, "points") and isinstance(getattr(obj, "cells", None), (list, tuple)):  # meshio
        return Mesh(np.asarray(obj.points, np.float64)[:, :3], _meshio_faces(obj))
    if hasattr(obj, "points") and hasattr(obj, "irregular_faces"):  # pyvista PolyData
        return Mesh(np.asarray(obj.points, np.float64), _pyvista_faces(obj))
    raise MeshError(f"expected {ACCEPTED}; got {kind} "
                    f"(build one with curv.Mesh(vertices, faces) or curv.PointCloud(points), or read a file "
                    f"with curv.load)")


def _count(obj) -> str:
    """The number of points of a cloud-like object, for messages (``1,000``)."""
    cloud = obj if isinstance(obj, PointCloud) else _cloud_of(obj)
    return f"{cloud.n_points:,}"


def _cloud_of(obj) -> PointCloud | None:
    """A cloud-like ``obj`` as a :class:`PointCloud`, None when it is not one (a mesh, or unknown).

    The cloud is built anew on every call: callers keep what they get (a PointCloud caches its grid
    and neighbours)."""
    if isinstance(obj, PointCloud):
        return obj
    if isinstance(obj, (np.ndarray, list, tuple)):
        try:
            arr = np.asarray(obj)
        except (ValueError, TypeError):  # ragged: not an array of points
            return None
        if arr.ndim == 2 and arr.shape[1] == 3 and arr.dtype != object and np.issubdtype(arr.dtype, np.number):
            return PointCloud(np.asarray(arr, np.float64))
        if isinstance(obj, np.ndarray):
            raise MeshError(f"an array of points must have shape (n, 3); got {arr.shape}")
        return None
    if hasattr(obj, "vertices") and not hasattr(obj, "faces") and np.ndim(obj.vertices) == 2:  # trimesh PointCloud
        return PointCloud(np.asarray(obj.vertices, np.float64))
    if hasattr(obj, "points") and isinstance(getattr(obj, "cells", None), (list, tuple)):  # meshio
        types = {b.type for b in obj.cells}
        if types <= set(_POINT_CELLS):
            return PointCloud(np.asarray(obj.points, np.float64)[:, :3])
        return None
    if hasattr(obj, "points") and hasattr(obj, "irregular_faces"):  # pyvista PolyData
        if any(np.asarray(getattr(obj, cells, ())).size for cells in ("faces", "lines", "strips")):
            return None
        normals = getattr(getattr(obj, "point_data", None), "active_normals", None)
        return PointCloud(np.asarray(obj.points, np.float64),
                          normals=None if normals is None else np.asarray(normals, np.float64))
    return None


def _meshio_faces(obj) -> list:
    blocks = [np.asarray(b.data) for b in obj.cells if b.type in _SURFACE_CELLS]
    if not blocks:
        found = sorted({b.type for b in obj.cells}) or ["none"]
        raise MeshError(f"the meshio mesh has no surface faces (cell types: {', '.join(found)})")
    if len(blocks) == 1:
        return blocks[0]
    return [face for block in blocks for face in block.tolist()]


def _pyvista_faces(obj):
    if np.asarray(obj.faces).size == 0:
        raise MeshError("the pyvista object has no polygon faces, only lines or strips; triangulate it "
                        "(PolyData.triangulate()) or pass its points alone")
    try:
        return np.asarray(obj.regular_faces)
    except (ValueError, TypeError, AttributeError):  # faces of several sizes
        return list(obj.irregular_faces)
