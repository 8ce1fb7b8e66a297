"""The supports of a whole mesh as one sparse matrix: a tool of the tests (the library searches supports per vertex)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

import curv
from curv.core.ranges import Range, ball_radii
from curv.geometry.neighbourhood import supports


def neighbourhood_matrix(mesh: curv.Mesh, factor: float) -> sp.csr_matrix:
    """(n, n) boolean CSR matrix of all supports at range factor ``factor`` (centre excluded)."""
    if not factor > 0:
        raise ValueError(f"range factor must be positive, got {factor}")
    indptr, indices = supports(mesh, ball_radii(mesh, Range(k=float(factor)), uses_normals=False))
    n = mesh.n_vertices
    mat = sp.csr_matrix((np.ones(indices.size, bool), indices, indptr), shape=(n, n))
    mat.sort_indices()
    return mat
