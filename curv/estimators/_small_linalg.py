"""Small dense linear algebra for per-vertex kernels: 3x3 symmetric eigen, scaled Cholesky solves.

Everything here is a serial ``@jit`` helper that works in caller-owned scratch arrays, so a
parallel kernel can call it once per vertex without allocating.
"""

from __future__ import annotations

import math

import numpy as np

from ..jit import jit

__all__ = ["sym3_eigen", "sym2_eigen", "solve_spd_scaled"]

JACOBI_SWEEPS = 12
"""Cyclic Jacobi sweeps of :func:`sym3_eigen`; a 3x3 matrix converges in 4-6."""


@jit
def sym3_eigen(a, vals, vecs):
    """Eigen-decomposition of a symmetric 3x3 matrix by cyclic Jacobi rotations.

    Parameters
    ----------
    a : (3, 3) float64
        The matrix; overwritten (it ends up nearly diagonal).
    vals : (3,) float64
        Output: eigenvalues in ascending order.
    vecs : (3, 3) float64
        Output: ``vecs[:, i]`` is the unit eigenvector of ``vals[i]``.
    """
    for i in range(3):
        for j in range(3):
            vecs[i, j] = 1.0 if i == j else 0.0
    for _ in range(JACOBI_SWEEPS):
        off = a[0, 1] * a[0, 1] + a[0, 2] * a[0, 2] + a[1, 2] * a[1, 2]
        diag = a[0, 0] * a[0, 0] + a[1, 1] * a[1, 1] + a[2, 2] * a[2, 2]
        if off <= 1e-30 * diag or off == 0.0:
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
                for k in range(3):
                    akp = a[k, p]
                    akq = a[k, q]
                    a[k, p] = c * akp - s * akq
                    a[k, q] = s * akp + c * akq
                for k in range(3):
                    apk = a[p, k]
                    aqk = a[q, k]
                    a[p, k] = c * apk - s * aqk
                    a[q, k] = s * apk + c * aqk
                for k in range(3):
                    vkp = vecs[k, p]
                    vkq = vecs[k, q]
                    vecs[k, p] = c * vkp - s * vkq
                    vecs[k, q] = s * vkp + c * vkq
    for i in range(3):
        vals[i] = a[i, i]
    # insertion sort of three eigenpairs, ascending
    for i in range(1, 3):
        j = i
        while j > 0 and vals[j - 1] > vals[j]:
            vals[j - 1], vals[j] = vals[j], vals[j - 1]
            for k in range(3):
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
def solve_spd_scaled(m, rhs, size, x, work, scale):
    """Solve the symmetric positive (semi)definite system ``m x = rhs`` with Jacobi scaling.

    The system is scaled to unit diagonal, ``D m D y = D rhs`` with ``D = diag(m)^(-1/2)``, factored
    by Cholesky, and its reciprocal condition number estimated: the smallest eigenvalue by a few
    steps of inverse iteration with the factor, the largest bounded by the largest absolute row sum.

    Parameters
    ----------
    m : (K, K) float64
        The matrix in its upper triangle (``m[i, j]``, ``i <= j``); the lower triangle is
        overwritten by the Cholesky factor of the scaled matrix.
    rhs : (K,) float64
        Right-hand side (not modified).
    size : int
        The system's order (``size <= K``); only the leading block is used.
    x : (K,) float64
        Output: the solution in ``x[:size]``.
    work : (2, K) float64
        Scratch.
    scale : (K,) float64
        Scratch (the Jacobi scaling).

    Returns
    -------
    float
        Estimated reciprocal condition number of the scaled matrix; 0 when the factorisation
        broke down (a zero diagonal entry or a non-positive pivot).
    """
    for i in range(size):
        if not m[i, i] > 0.0:
            return 0.0
        scale[i] = 1.0 / math.sqrt(m[i, i])
    # lower triangle L of the scaled matrix; row sums bound its largest eigenvalue
    lam_max = 0.0
    for i in range(size):
        row = 0.0
        for j in range(size):
            mij = m[i, j] if i <= j else m[j, i]
            row += abs(mij) * scale[i] * scale[j]
        lam_max = max(lam_max, row)
    for j in range(size):
        s = 1.0  # the scaled diagonal
        for k in range(j):
            s -= m[j, k] * m[j, k]
        if not s > 1e-300:
            return 0.0
        ljj = math.sqrt(s)
        m[j, j] = ljj  # the diagonal now holds L (the scaled diagonal is 1 by construction)
        for i in range(j + 1, size):
            t = m[j, i] * scale[i] * scale[j]
            for k in range(j):
                t -= m[i, k] * m[j, k]
            m[i, j] = t / ljj
    y = work[0]
    for i in range(size):
        y[i] = rhs[i] * scale[i]
    _cholesky_solve(m, y, size)
    for i in range(size):
        x[i] = y[i] * scale[i]
    # inverse iteration for the smallest eigenvalue, from a start vector with no special symmetry
    v = work[1]
    norm = 0.0
    for i in range(size):
        v[i] = 1.0 + 0.37 * i * (-1.0) ** i
        norm += v[i] * v[i]
    lam_min = lam_max
    for _ in range(4):
        norm = math.sqrt(norm)
        for i in range(size):
            v[i] /= norm
        _cholesky_solve(m, v, size)
        norm = 0.0
        for i in range(size):
            norm += v[i] * v[i]
        if not norm > 0.0 or not math.isfinite(norm):
            return 0.0
        lam_min = 1.0 / math.sqrt(norm)  # |A^-1 v| with |v| = 1 bounds 1 / lambda_min from below
    return lam_min / lam_max


@jit
def _cholesky_solve(l, b, size):
    """Overwrite ``b`` with ``(L L^T)^-1 b``; ``L`` in the lower triangle and diagonal of ``l``."""
    for i in range(size):
        t = b[i]
        for k in range(i):
            t -= l[i, k] * b[k]
        b[i] = t / l[i, i]
    for i in range(size - 1, -1, -1):
        t = b[i]
        for k in range(i + 1, size):
            t -= l[k, i] * b[k]
        b[i] = t / l[i, i]
