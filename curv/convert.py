"""One converter from other libraries' mesh objects to :class:`curv.Mesh`.

``curv.estimate`` and the other entry points accept a trimesh ``Trimesh``, a pyvista ``PolyData``
or a meshio ``Mesh`` as they are, through :func:`as_mesh`. The objects are recognised by their
attributes, so curv imports none of those libraries (pyvista would bring VTK into the library).
"""

from __future__ import annotations

import numpy as np

from .core.errors import MeshError
from .core.mesh import Mesh

__all__ = ["as_mesh"]

_SURFACE_CELLS = ("triangle", "quad", "polygon")
"""meshio cell types that are surface faces."""


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
        Anything else, naming the accepted kinds; a pyvista or meshio object without faces.
    """
    if isinstance(obj, Mesh):
        return obj
    kind = type(obj).__name__
    if hasattr(obj, "vertices") and hasattr(obj, "faces") and np.ndim(obj.faces) == 2:  # trimesh
        return Mesh(np.asarray(obj.vertices, np.float64), np.asarray(obj.faces))
    if hasattr(obj, "points") and isinstance(getattr(obj, "cells", None), (list, tuple)):  # meshio
        return Mesh(np.asarray(obj.points, np.float64)[:, :3], _meshio_faces(obj))
    if hasattr(obj, "points") and hasattr(obj, "irregular_faces"):  # pyvista PolyData
        return Mesh(np.asarray(obj.points, np.float64), _pyvista_faces(obj))
    raise MeshError(f"expected a curv.Mesh, a trimesh.Trimesh, a pyvista.PolyData or a meshio.Mesh; got {kind} "
                    f"(build one with curv.Mesh(vertices, faces) or read a file with curv.load)")


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
        raise MeshError("the pyvista object has no polygon faces (points or lines only?)")
    try:
        return np.asarray(obj.regular_faces)
    except (ValueError, TypeError, AttributeError):  # faces of several sizes
        return list(obj.irregular_faces)
