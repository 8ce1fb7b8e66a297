"""Small dense linear algebra for per-vertex kernels: the one 2x2 eigen step, symmetric 3x3 systems,
the one Jacobi-scaled Cholesky, and the 3x3 symmetric eigen-decomposition.

Everything here is a serial ``@jit`` helper working on scalars or in caller-owned scratch, so a
parallel kernel can call it once per vertex without allocating. Conventions:

- a symmetric 3x3 matrix travels as the 6-tuple of its upper triangle ``(a00, a01, a02, a11, a12,
  a22)`` (or as those six scalars where a caller has them apart), a 3-vector as a 3-tuple;
- a larger symmetric matrix A of order ``size`` lives in a ``(K + 1, K)`` array, A in its **upper**
  triangle (``a[i, j]``, ``i <= j``). :func:`cholesky_scaled` factors ``D A D = L Lᵀ`` with
  ``D = diag(A)^(-1/2)`` in place: L goes to the lower triangle and the diagonal, D to the row
  ``srow`` (= K); A's strict upper triangle is left as it was. :func:`cholesky_solve_scaled`,
  :func:`factor_whiten` and :func:`reciprocal_condition` read that factor.
"""

from __future__ import annotations

import math

from .jit import jit

__all__ = ["RCOND", "sym2_eigen", "sym3_cofactors", "solve_sym3", "sym3_inverse", "sym3_bilinear", "cholesky_scaled",
           "factor_solve", "cholesky_solve_scaled", "scaled_determinant", "factor_whiten", "row_dot",
           "scaled_norm_bound", "reciprocal_condition", "sym3_eigen"]

RCOND = 1e-10
"""A 3x3 system is singular when its determinant is at most this times the cube of its largest
entry (:func:`solve_sym3`); a scaled one when the determinant of ``D A D`` is at most its square."""

JACOBI_SWEEPS = 12
"""Most cyclic Jacobi sweeps of :func:`sym3_eigen`; a 3x3 matrix converges in 3-5."""

INVERSE_STEPS = 3
"""Inverse-iteration steps of :func:`reciprocal_condition`."""


@jit
def sym2_eigen(e, f, g):
    """Eigenpairs of the symmetric 2x2 matrix ``[[e, f], [f, g]]``: the one eigen step of a shape
    operator written in a tangent basis.

    ``k1, k2 = (e + g) / 2 ± rad`` with ``rad = |((e - g) / 2, f)|``; the eigenvector of k1 makes
    the angle ``theta = atan2(f, (e - g) / 2) / 2`` with the first basis vector.

    Returns
    -------
    k1, k2 : float
        Eigenvalues, ``k1 >= k2``.
    c, s : float
        ``(c, s)`` is the unit eigenvector of ``k1``; ``(-s, c)`` that of ``k2``.
    """
    half = 0.5 * (e - g)
    mean = 0.5 * (e + g)
    rad = math.hypot(half, f)
    theta = 0.5 * math.atan2(f, half)
    return mean + rad, mean - rad, math.cos(theta), math.sin(theta)


@jit
def sym3_cofactors(a00, a01, a02, a11, a12, a22):
    """The cofactors of a symmetric 3x3 A (the upper triangle of ``det(A) A⁻¹``) and det(A).

    Returns
    -------
    c00, c01, c02, c11, c12, c22, det : float
    """
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    return c00, c01, c02, c11, c12, c22, a00 * c00 + a01 * c01 + a02 * c02


@jit
def solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2):
    """Solve a symmetric 3x3 system by Cramer's rule.

    Returns
    -------
    x0, x1, x2 : float
    singular : bool
        ``|det A| <= RCOND * max|a_ij|^3`` (the x are then NaN).
    """
    c00, c01, c02, c11, c12, c22, det = sym3_cofactors(a00, a01, a02, a11, a12, a22)
    scale = max(abs(a00), abs(a01), abs(a02), abs(a11), abs(a12), abs(a22))
    if not abs(det) > RCOND * scale * scale * scale:
        return math.nan, math.nan, math.nan, True
    inv = 1.0 / det
    return ((c00 * b0 + c01 * b1 + c02 * b2) * inv,
            (c01 * b0 + c11 * b1 + c12 * b2) * inv,
            (c02 * b0 + c12 * b1 + c22 * b2) * inv,
            False)


@jit
def sym3_inverse(a00, a01, a02, a11, a12, a22):
    """The upper triangle of A⁻¹ for a symmetric 3x3 A, by its cofactors (inf/NaN when A is singular)."""
    c00, c01, c02, c11, c12, c22, det = sym3_cofactors(a00, a01, a02, a11, a12, a22)
    inv = 1.0 / det
    return c00 * inv, c01 * inv, c02 * inv, c11 * inv, c12 * inv, c22 * inv


@jit
def sym3_bilinear(s, g, h):
    """``gᵀ S h`` for the symmetric 3x3 S (6-tuple, upper triangle) and the 3-vectors g, h."""
    i00, i01, i02, i11, i12, i22 = s
    g0, g1, g2 = g
    h0, h1, h2 = h
    return (g0 * (i00 * h0 + i01 * h1 + i02 * h2) + g1 * (i01 * h0 + i11 * h1 + i12 * h2)
            + g2 * (i02 * h0 + i12 * h1 + i22 * h2))


@jit
def cholesky_scaled(a, size, srow):
    """Jacobi-scaled Cholesky ``D A D = L Lᵀ`` of the symmetric A in the upper triangle of ``a``'s
    leading ``size`` block, in place (module notes: L below and on the diagonal, D in row ``srow``).

    Returns
    -------
    bool
        False when A is not positive definite (a diagonal entry or a pivot not positive).
    """
    for i in range(size):
        d = a[i, i]
        if not d > 0.0:
            return False
        a[srow, i] = 1.0 / math.sqrt(d)
    for j in range(size):
        acc = 1.0  # the scaled diagonal
        for k in range(j):
            acc -= a[j, k] * a[j, k]
        if not acc > 1e-300:
            return False
        ljj = math.sqrt(acc)
        a[j, j] = ljj
        for i in range(j + 1, size):
            t = a[j, i] * a[srow, i] * a[srow, j]
            for k in range(j):
                t -= a[i, k] * a[j, k]
            a[i, j] = t / ljj
    return True


@jit
def factor_solve(factor, size, vec, row):
    """Overwrite ``vec[row]`` with ``(L Lᵀ)⁻¹ vec[row]`` (L from :func:`cholesky_scaled`)."""
    for i in range(size):
        t = vec[row, i]
        for k in range(i):
            t -= factor[i, k] * vec[row, k]
        vec[row, i] = t / factor[i, i]
    for i in range(size - 1, -1, -1):
        t = vec[row, i]
        for k in range(i + 1, size):
            t -= factor[k, i] * vec[row, k]
        vec[row, i] = t / factor[i, i]


@jit
def cholesky_solve_scaled(factor, srow, size, vec):
    """``vec[1] = A⁻¹ vec[0] = D (L Lᵀ)⁻¹ D vec[0]`` from :func:`cholesky_scaled`'s factor (``vec[0]`` kept)."""
    for i in range(size):
        vec[1, i] = vec[0, i] * factor[srow, i]
    factor_solve(factor, size, vec, 1)
    for i in range(size):
        vec[1, i] *= factor[srow, i]


@jit
def scaled_determinant(factor, size):
    """``det(D A D) = Π L_ii²`` (at most 1: ``D A D`` has a unit diagonal)."""
    det = 1.0
    for i in range(size):
        det *= factor[i, i] * factor[i, i]
    return det


@jit
def factor_whiten(factor, srow, size, rows):
    """Replace each row v of ``rows`` by ``L⁻¹ D v`` (:func:`cholesky_scaled`'s factor), so that
    ``gᵀA⁻¹h`` is the dot product of the whitened g and h (:func:`row_dot`).

    Parameters
    ----------
    factor : (K + 1, K) float64
        L and D (module notes).
    srow, size : int
    rows : (r, K) float64
        Overwritten in their first ``size`` columns.
    """
    for r in range(rows.shape[0]):
        for i in range(size):
            # forward substitution in place: rows[r, :i] already hold (L⁻¹ D v)[:i]
            t = rows[r, i] * factor[srow, i]
            for k in range(i):
                t -= factor[i, k] * rows[r, k]
            rows[r, i] = t / factor[i, i]


@jit
def row_dot(rows, i, j, size):
    """``rows[i, :size] . rows[j, :size]``."""
    acc = 0.0
    for k in range(size):
        acc += rows[i, k] * rows[j, k]
    return acc


@jit
def scaled_norm_bound(a, size, srow):
    """An upper bound of the largest eigenvalue of ``D A D`` (A in ``a``'s upper triangle, before
    :func:`cholesky_scaled`): its largest absolute row sum. Writes D to row ``srow`` on the way
    (as :func:`cholesky_scaled` does)."""
    for i in range(size):
        a[srow, i] = 1.0 / math.sqrt(a[i, i])
    lam_max = 0.0
    for i in range(size):
        row = 0.0
        for j in range(size):
            aij = a[i, j] if i <= j else a[j, i]
            row += abs(aij) * a[srow, i] * a[srow, j]
        lam_max = max(lam_max, row)
    return lam_max


@jit
def reciprocal_condition(factor, size, lam_max, vec, row):
    """The reciprocal condition number of ``D A D`` estimated from its factor: the smallest
    eigenvalue by a few steps of inverse iteration (:data:`INVERSE_STEPS`) from a start vector with
    no special symmetry, over ``lam_max`` (:func:`scaled_norm_bound`); ``vec[row]`` is scratch.
    0 when the iteration breaks down."""
    norm = 0.0
    for i in range(size):
        vec[row, i] = 1.0 + (0.37 * i if i % 2 == 0 else -0.37 * i)
        norm += vec[row, i] * vec[row, i]
    lam_min = lam_max
    for _ in range(INVERSE_STEPS):
        norm = math.sqrt(norm)
        for i in range(size):
            vec[row, i] /= norm
        factor_solve(factor, size, vec, row)
        norm = 0.0
        for i in range(size):
            norm += vec[row, i] * vec[row, i]
        if not norm > 0.0 or not math.isfinite(norm):
            return 0.0
        lam_min = 1.0 / math.sqrt(norm)  # |A^-1 v| with |v| = 1 bounds 1 / lambda_min from below
    return lam_min / lam_max


@jit
def _rotate_columns(m, p, q, c, s):
    """Rotate columns p and q of the first three rows of ``m`` by the angle with cosine c and sine s."""
    for k in range(3):
        mkp = m[k, p]
        mkq = m[k, q]
        m[k, p] = c * mkp - s * mkq
        m[k, q] = s * mkp + c * mkq


@jit
def sym3_eigen(a, vecs):
    """Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations.

    Parameters
    ----------
    a : (3, 3) float64
        The matrix; overwritten (it ends up nearly diagonal).
    vecs : (4, 3) float64
        Output: ``vecs[3, i]`` are the eigenvalues in ascending order and ``vecs[:3, i]`` the unit
        eigenvector of ``vecs[3, i]``. (One array, no row views: views made per vertex inside a
        parallel loop cost an atomic reference count each.)
    """
    for i in range(3):
        for j in range(3):
            vecs[i, j] = 1.0 if i == j else 0.0
    for _ in range(JACOBI_SWEEPS):
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        diag = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= 1e-28 * diag:
            break
        for p in range(2):
            for q in range(p + 1, 3):
                apq = a[p, q]
                if apq == 0.0:
                    continue
                # rotation angle that zeroes a[p, q] (the smaller of the two solutions)
                theta = (a[q, q] - a[p, p]) / (2.0 * apq)
                t = 1.0 / (abs(theta) + math.sqrt(theta * theta + 1.0))
                if theta < 0.0:
                    t = -t
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                # A <- Jᵀ A J and V <- V J with the rotation J in the plane (p, q)
                _rotate_columns(a, p, q, c, s)
                for k in range(3):
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                _rotate_columns(vecs, p, q, c, s)
    for i in range(3):
        vecs[3, i] = a[i, i]
    # insertion sort of three eigenpairs, ascending
    for i in range(1, 3):
        j = i
        while j > 0 and vecs[3, j - 1] > vecs[3, j]:
            for k in range(4):
                vecs[k, j - 1], vecs[k, j] = vecs[k, j], vecs[k, j - 1]
            j -= 1
