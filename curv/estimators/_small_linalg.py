"""Small dense linear algebra for per-vertex kernels: 3x3 symmetric eigen, scaled Cholesky solves.

Everything here is a serial ``@jit`` helper that works in caller-owned scratch arrays, so a
parallel kernel can call it once per vertex without allocating.
"""

from __future__ import annotations

import math

import numpy as np

from ..core.jit import jit

__all__ = ["sym3_eigen", "sym2_eigen", "solve_spd_scaled"]

JACOBI_SWEEPS = 12
"""Most cyclic Jacobi sweeps of :func:`sym3_eigen`; a 3x3 matrix converges in 3-5."""

INVERSE_STEPS = 3
"""Inverse-iteration steps of the condition estimate of :func:`solve_spd_scaled`."""


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


@jit
def sym2_eigen(e, f, g):
    """Eigenpairs of the symmetric 2x2 matrix ``[[e, f], [f, g]]``.

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
def solve_spd_scaled(m, vec, size):
    """Solve the symmetric positive (semi)definite system ``m x = b`` with Jacobi scaling.

    The system is scaled to unit diagonal, ``D m D y = D b`` with ``D = diag(m)^(-1/2)``, factored
    by Cholesky, and its reciprocal condition number estimated: the smallest eigenvalue by a few
    steps of inverse iteration with the factor, the largest bounded by the largest absolute row sum.

    Parameters
    ----------
    m : (K, K) float64
        The matrix in its upper triangle (``m[i, j]``, ``i <= j``); the lower triangle and the
        diagonal are overwritten by the Cholesky factor of the scaled matrix.
    vec : (5, K) float64
        Row 0: the right-hand side b (kept); row 1: output, the solution x; rows 2-4: scratch.
    size : int
        The system's order (``size <= K``); only the leading block is used.

    Returns
    -------
    float
        Estimated reciprocal condition number of the scaled matrix; 0 when the factorisation
        broke down (a zero diagonal entry or a non-positive pivot).
    """
    for i in range(size):
        if not m[i, i] > 0.0:
            return 0.0
        vec[2, i] = 1.0 / math.sqrt(m[i, i])
    # row sums of the scaled matrix bound its largest eigenvalue
    lam_max = 0.0
    for i in range(size):
        row = 0.0
        for j in range(size):
            mij = m[i, j] if i <= j else m[j, i]
            row += abs(mij) * vec[2, i] * vec[2, j]
        lam_max = max(lam_max, row)
    for j in range(size):
        s = 1.0  # the scaled diagonal
        for k in range(j):
            s -= m[j, k] * m[j, k]
        if not s > 1e-300:
            return 0.0
        ljj = math.sqrt(s)
        m[j, j] = ljj
        for i in range(j + 1, size):
            t = m[j, i] * vec[2, i] * vec[2, j]
            for k in range(j):
                t -= m[i, k] * m[j, k]
            m[i, j] = t / ljj
    for i in range(size):
        vec[3, i] = vec[0, i] * vec[2, i]
    _cholesky_solve(m, vec, 3, size)
    for i in range(size):
        vec[1, i] = vec[3, i] * vec[2, i]
    # inverse iteration for the smallest eigenvalue, from a start vector with no special symmetry
    norm = 0.0
    for i in range(size):
        vec[4, i] = 1.0 + (0.37 * i if i % 2 == 0 else -0.37 * i)
        norm += vec[4, i] * vec[4, i]
    lam_min = lam_max
    for _ in range(INVERSE_STEPS):
        norm = math.sqrt(norm)
        for i in range(size):
            vec[4, i] /= norm
        _cholesky_solve(m, vec, 4, size)
        norm = 0.0
        for i in range(size):
            norm += vec[4, i] * vec[4, i]
        if not norm > 0.0 or not math.isfinite(norm):
            return 0.0
        lam_min = 1.0 / math.sqrt(norm)  # |A^-1 v| with |v| = 1 bounds 1 / lambda_min from below
    return lam_min / lam_max


@jit
def _cholesky_solve(l, vec, row, size):
    """Overwrite ``b = vec[row]`` with ``(L L^T)^-1 b``; ``L`` in the lower triangle and diagonal of ``l``."""
    for i in range(size):
        t = vec[row, i]
        for k in range(i):
            t -= l[i, k] * vec[row, k]
        vec[row, i] = t / l[i, i]
    for i in range(size - 1, -1, -1):
        t = vec[row, i]
        for k in range(i + 1, size):
            t -= l[k, i] * vec[row, k]
        vec[row, i] = t / l[i, i]
