"""Vertex normals from face geometry.

Max (1999) weights each face's normal at a corner by ``sin(angle) / (|e1| |e2|)``, i.e. the corner
cross product divided by both squared edge lengths; it is exact for vertices on a sphere and is the
normal the paper's study uses (§5.1). Area and angle weights are there for comparison.
"""

from __future__ import annotations

import enum
import math

from typing import TYPE_CHECKING

import numpy as np

from ..core.corner_normals import max_normal, max_weight, unit
from ..core.jit import jit_parallel, launch, prange

if TYPE_CHECKING:  # the mesh's corner pass uses this module's kernels: no import at run time
    from ..core.mesh import Mesh

__all__ = ["NormalWeighting", "vertex_normals", "normalize_rows", "unusable_normal_vertices", "max_normal",
           "max_weight", "unit", "KERNELS", "cached_max_normals"]


class NormalWeighting(str, enum.Enum):
    """How the faces around a vertex are weighted."""

    MAX = "max"
    AREA = "area"
    ANGLE = "angle"


def normalize_rows(v: np.ndarray) -> np.ndarray:
    """Return ``v`` (k, 3) with unit rows; rows of (near) zero length become NaN."""
    norm = np.linalg.norm(v, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = v / norm[:, None]
    out[~(norm > 1e-300)] = np.nan
    return out


def unusable_normal_vertices(mesh: Mesh) -> np.ndarray:
    """(n,) bool: vertices whose normal means nothing, so no estimate may use it.

    Where the faces around a vertex are not one consistently oriented fan (a non-manifold vertex,
    or an endpoint of an edge whose two faces disagree on orientation), the averaged normal mixes
    unrelated sheets. Computed once per mesh (read-only), so that an estimate over a small region
    does not combine the flags of the whole mesh again.
    """
    from .neighbourhood import cached_with_mesh

    def build():
        flags = mesh.nonmanifold_vertices | mesh.inconsistent_vertices
        flags.setflags(write=False)
        return flags

    return cached_with_mesh(mesh, "unusable_normals", build)


MAX, AREA, ANGLE = 0, 1, 2
"""Weighting codes of the kernel."""


@jit_parallel
def _vertex_normals(indptr, corners, indices, corner_next, corner_prev, corner_face, x, weighting, face_weight, out):
    for p in prange(indptr.size - 1):
        lo, hi = indptr[p], indptr[p + 1]
        if weighting == MAX:
            sx, sy, sz = max_normal(p, lo, hi, corners, indices, corner_next, corner_prev, x)
        else:
            sx, sy, sz = 0.0, 0.0, 0.0
            for i in range(lo, hi):
                c = corners[i]
                f = corner_face[c]
                w = 1.0
                if weighting == ANGLE:
                    # the corner angle atan2(|a x b|, a . b)
                    b, q = indices[corner_next[c]], indices[corner_prev[c]]
                    ax, ay, az = x[b, 0] - x[p, 0], x[b, 1] - x[p, 1], x[b, 2] - x[p, 2]
                    bx, by, bz = x[q, 0] - x[p, 0], x[q, 1] - x[p, 1], x[q, 2] - x[p, 2]
                    cx, cy, cz = ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx
                    w = math.atan2(math.sqrt(cx * cx + cy * cy + cz * cz), ax * bx + ay * by + az * bz)
                sx += face_weight[f, 0] * w
                sy += face_weight[f, 1] * w
                sz += face_weight[f, 2] * w
        out[p, 0], out[p, 1], out[p, 2] = unit(sx, sy, sz)


KERNELS = (_vertex_normals,)
"""The numba dispatchers of this module (for :func:`curv.core.jit.compile_pending`)."""


def vertex_normals(mesh: Mesh, *, weighting: NormalWeighting | str = NormalWeighting.MAX) -> np.ndarray:
    """Unit vertex normals.

    Parameters
    ----------
    mesh : Mesh
        Triangle or polygon mesh; orientation of the faces gives the side of the normal.
    weighting : {"max", "area", "angle"}
        Face weights: Max (1999), face area, or corner angle.

    Returns
    -------
    (n, 3) float64
        Unit normals; NaN rows for isolated vertices and vertices whose faces cancel or are all
        degenerate.
    """
    weighting = NormalWeighting(weighting)
    if weighting is NormalWeighting.AREA:
        code, face_weight = AREA, mesh.face_vector_areas
    elif weighting is NormalWeighting.ANGLE:
        code, face_weight = ANGLE, np.nan_to_num(mesh.face_normals)
    else:
        code, face_weight = MAX, np.zeros((0, 3))
    indptr, corners = mesh.vertex_corners
    out = np.empty((mesh.n_vertices, 3))
    launch(_vertex_normals, indptr, corners, mesh.face_indices, mesh.corner_next, mesh.corner_prev,
           mesh.corner_face, mesh.vertices, code, face_weight, out)
    return out


def cached_max_normals(mesh: Mesh) -> np.ndarray:
    """(n, 3) Max-weighted :func:`vertex_normals` of ``mesh``, computed once per mesh (read-only).

    They come from the mesh's one walk over its corners (:attr:`curv.Mesh.corner_pass`), which a fresh
    estimate makes anyway for the vertex flags and the neighbours. Column-major, so that a kernel's
    per-coordinate columns (``normals[:, 0]``) are views: an estimate over a small region copies
    nothing of the whole mesh's size.
    """
    return mesh.corner_pass.max_normals
