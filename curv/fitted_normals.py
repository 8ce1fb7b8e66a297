"""Vertex normals from a local fit instead of an average of face normals.

Each vertex normal is the normal at the origin of the osculating jet (Cazals & Pouget 2003)
fitted over the vertex's range support, the same fit as the ``jet`` estimator
(:mod:`curv.estimators.jet`): a PCA frame of the support, the least-squares height polynomial
with its constant and linear terms, and ``n = (-J_u, -J_v, 1) / |.|``. The linear terms let the fit
find its own tangent plane, so the normal does not inherit the bias of the face-angle weighting on
irregular meshes nor, at a larger range, as much of the noise of the 1-ring.

Orientation comes from the default Max-weighted normals (:func:`curv.geometry.normals.vertex_normals`): a
fitted normal points to the same side. Where there is no fit (fewer than ``(d+1)(d+2)/2`` support
points, a singular system) or no Max normal to orient it, the normal is NaN.
"""

from __future__ import annotations

import numpy as np

from .core.jit import run_to_end
from .estimators.jet import jet_normals
from .core.errors import EstimatorError
from .core.mesh import Mesh
from .geometry.normals import unusable_normal_vertices, vertex_normals
from .estimators import get_spec
from .core.ranges import ball_radii, resolve

__all__ = ["fitted_normals", "DEFAULT_FIT_RANGE", "DEFAULT_FIT_DEGREE"]

DEFAULT_FIT_RANGE = 2
"""Range Rk of the fit unless told otherwise."""

DEFAULT_FIT_DEGREE = 2
"""Jet degree of the fit unless told otherwise."""


def fitted_normals(mesh: Mesh, *, range=None, degree: int = DEFAULT_FIT_DEGREE,
                   radius: float | None = None, features=None, vertices=None) -> np.ndarray:
    """Unit vertex normals of local jet fits.

    Parameters
    ----------
    mesh : Mesh
        Any polygon mesh.
    range : int, float or str
        k of the range Rk of the support (a ball of ``k`` times the vertex's longest 1-ring edge,
        :mod:`curv.core.ranges`); ``2``, ``2.5`` or ``"R2"``; default :data:`DEFAULT_FIT_RANGE`.
    degree : {2, 3, 4}
        Degree of the fitted jet.
    radius : float, optional
        Instead of ``range``: the same ball radius in mesh units at every vertex.
    features : curv.core.features.FeatureSet, optional
        The fits do not reach across a crease; a vertex on one keeps its Max normal (its curvature
        is ``FEATURE`` anyway, and neighbours never use it).
    vertices : (c,) int array_like, optional
        Fit only at these vertices (default every vertex). A fit reads only its own vertex's
        support, so the normals there are those of the whole call, bit for bit; the other rows are
        NaN. For a caller that reads the normals at a few of the vertices (an estimate at a few
        centres: the vertices their supports reach).

    Returns
    -------
    (n, 3) float64
        Unit normals on the side of the Max normals; NaN where the fit is undefined (and at the
        vertices not asked for).

    Raises
    ------
    EstimatorError
        A range below 1, or a degree other than 2, 3, 4.
    """
    # the normals come from the jet's own fit, so the jet's range rule applies (curv.core.ranges owns it)
    if range is None and radius is None:
        range = DEFAULT_FIT_RANGE
    rng = resolve(get_spec("jet"), range, radius)
    reference = vertex_normals(mesh)
    bad = unusable_normal_vertices(mesh)
    if bad.any():
        reference = reference.copy()
        reference[bad] = np.nan
    radii = ball_radii(mesh, rng, uses_normals=False)
    on_crease = features is not None and features.any
    if vertices is not None:
        vertices = _vertex_indices(vertices, mesh.n_vertices)
    normals, _ = run_to_end(jet_normals(mesh, reference, radii, degree=degree,
                                        features=features if on_crease else None, centres=vertices))
    # the jet normal lies within 90 degrees of the PCA axis, which was turned towards the Max
    # normal; a strongly tilted fit may still end up on the other side
    normals[np.einsum("ij,ij->i", normals, reference) < 0] *= -1.0
    if on_crease:
        crease = features.vertices
        if vertices is not None:
            crease = crease & np.isin(np.arange(mesh.n_vertices), vertices)
        normals[crease] = reference[crease]
    return normals


def _vertex_indices(vertices, n: int) -> np.ndarray:
    """``vertices`` as (c,) int64 indices below ``n``; a one-line error otherwise."""
    arr = np.asarray(vertices)
    if arr.ndim != 1 or (arr.size and (not np.issubdtype(arr.dtype, np.integer) or arr.min() < 0 or arr.max() >= n)):
        raise EstimatorError(f"vertices must be a 1-D array of vertex indices from 0 to {n - 1}")
    return np.ascontiguousarray(arr, dtype=np.int64)
