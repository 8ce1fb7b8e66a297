"""Estimates that run on a twin in grid order and map their rows back (caches read neighbours near each other).

A point cloud's twin is :func:`curv.point_normals.grid_ordered`; a whole mesh numbered too scattered
for the caches runs on :func:`locality_ordered`. :func:`rows_of` takes a caller's per-row input into
the twin's order, :func:`rows_back` a result back into the input's.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .core.jit import jit_parallel, launch, prange
from .core.mesh import Mesh
from .core.result import Curvature
from .core.support import support_of
from .geometry.neighbourhood import cached_with_mesh

__all__ = ["cloud_twin", "locality_ordered", "rank", "rows_of", "rows_back"]


def cloud_twin(mesh):
    """A point cloud's twin in grid order and that order (:func:`curv.point_normals.grid_ordered`);
    None for a mesh (an input whose provider runs it in its own order,
    :attr:`curv.core.support.Support.grid_twin`) or a twin."""
    if not support_of(mesh).grid_twin:
        return None
    from .point_normals import grid_ordered

    return grid_ordered(mesh)


def locality_ordered(mesh: Mesh, centres, features):
    """A whole-mesh estimate of a mesh numbered too scattered for the caches
    (:meth:`curv.Mesh.scattered_order`) runs on its twin in grid order (the point clouds' order,
    :func:`curv.core.grid.build_grid`): ``(twin, order)``, kept with the mesh; None otherwise (a
    region costs what the region costs, and a caller's feature mask is in the mesh's own numbering).
    """
    if centres is not None or (features is not None and np.ndim(features) != 0) or not mesh.scattered_order():
        return None

    def build():
        from .core.grid import build_grid

        order = np.ascontiguousarray(build_grid(mesh.vertices)[0][3], dtype=np.int64)
        order.setflags(write=False)
        return mesh.renumbered(order), order

    return cached_with_mesh(mesh, "locality order", build)


def rank(order: np.ndarray) -> np.ndarray:
    """(n,) int64: the position of each row in ``order`` (its inverse)."""
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    return rank


def rows_of(normals, order: np.ndarray):
    """Given (n, 3) normals in ``order``; anything else as it is (its checks say the same)."""
    if normals is None or isinstance(normals, str) or np.shape(normals) != (order.size, 3):
        return normals
    return np.asarray(normals)[order]


@jit_parallel
def _rows_to(order, rows, out):
    """``out[order[i]] = rows[i]``, rows of (n, m) arrays, in parallel."""
    for i in prange(order.size):
        at = order[i]
        for c in range(rows.shape[1]):
            out[at, c] = rows[i, c]


def rows_back(res: Curvature, order: np.ndarray) -> Curvature:
    """A result computed on rows in ``order``, in the cloud's own order."""
    order = np.ascontiguousarray(order, dtype=np.int64)

    def back(a):
        a = np.ascontiguousarray(a)
        out = np.empty_like(a)
        # numpy's scatter is one thread; a million rows of seven fields cost more than a phase
        launch(_rows_to, order, a.reshape(a.shape[0], -1), out.reshape(a.shape[0], -1))
        return out

    fields = ("k1", "k2", "d1", "d2", "normals", "valid", "reason") + (
        ("k1_se", "k2_se") if res.has_standard_errors else ())  # else NaN everywhere, in any order
    return replace(res, **{f: back(getattr(res, f)) for f in fields})
