"""``csm`` and ``icc`` in one pass: per vertex and range, one search, one rim and one exact clip of
each face crossing the sphere, fed to both estimators' sums.

The two estimators sum different terms over the same ball: csm the edges' dihedral terms and the
area, icc the faces' corrected measures, each face weighted by the fraction of its area inside.
What costs is the same for both: the support walk, finding the faces that cross the sphere and
clipping them (their exits and exact areas, :func:`~curv.estimators._ball_clipping.crossing_faces`).
:func:`iter_csm_icc` builds both estimators' per-mesh terms (:func:`curv.estimators.csm.csm_terms`,
:func:`curv.estimators.icc.icc_terms`) and runs the one kernel that sums both
(:func:`curv.estimators._clipped_sums.run_clipping`). Each estimator's sums are added in the order
of a run of it alone: the results are those of :func:`~curv.estimators.csm.iter_csm` and
:func:`~curv.estimators.icc.iter_icc` at the same levels, bit for bit.
"""

from __future__ import annotations

import numpy as np

from ..core.mesh import Mesh
from ._ball_clipping import clipping_inputs, corner_rings
from ._clipped_sums import CLIPPING_PASS, run_clipping
from .csm import csm_terms
from .icc import icc_terms
from .registry import register_pass

__all__ = ["iter_csm_icc"]


def iter_csm_icc(mesh: Mesh, normals: np.ndarray, radii: np.ndarray, methods=("csm", "icc"), *,
                 chunk: int | None = None, centres: np.ndarray | None = None, features=None,
                 options: dict | None = None):
    """csm and icc over the balls of every level of ``radii`` around every vertex, in one pass.

    Parameters
    ----------
    mesh : Mesh
        Triangle mesh.
    normals : (n, 3) float64
        Unit vertex normals (csm picks its normal eigenvector with them, icc interpolates them).
    radii : (levels, n) or (n,) float64
        Ball radii, ascending per vertex (:func:`curv.estimators.csm.iter_csm`).
    methods : sequence of str
        ``"csm"``, ``"icc"`` or both.
    chunk, centres, features :
        As in :func:`~curv.estimators.csm.iter_csm`.
    options : dict, optional
        ``{name: estimator options}``: icc's ``from_measures``.

    Yields
    ------
    float
        Fraction done.

    Returns
    -------
    dict
        ``{name: [Principal per level]}`` for each of ``methods``.
    """
    options = options or {}
    tri, centres, x, y, z, indptr, indices, cut, crease, radii, touched = yield from clipping_inputs(
        mesh, centres, radii, features)
    normals = np.asarray(normals, dtype=np.float64)  # the cached normals are column-major: read as they are
    csm = (yield from csm_terms(mesh, centres, radii, indptr, indices, touched[0], crease)) if "csm" in methods else None
    icc = (icc_terms(mesh, normals, touched, crease, **options.get("icc", {})) if "icc" in methods else None)
    after, link = corner_rings(mesh, touched[0])
    yield 0.0
    csm_out, icc_out = yield from run_clipping(
        mesh, centres, radii, (tri, x, y, z, indptr, indices, cut, crease, after, link), normals, csm, icc, chunk=chunk)
    levels = range(radii.shape[0])
    out = {}
    if csm_out is not None:
        out["csm"] = [csm_out.principal(level) for level in levels]
    if icc_out is not None:
        out["icc"] = [icc_out[0].principal(level) for level in levels]
    return out


register_pass(CLIPPING_PASS, iter_csm_icc)
