"""Small dense linear algebra for per-vertex kernels: the one 2x2 eigen step, symmetric 3x3 systems,
the one Jacobi-scaled Cholesky, and the 3x3 symmetric eigen-decomposition (by Jacobi rotations, and
in closed form).

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
           "scaled_norm_bound", "reciprocal_condition", "sym3_eigen", "sym3_eigen_closed"]

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
def _inverse_iteration(factor, size, vec, row):
    """``1 / |A⁻¹ v|`` after :data:`INVERSE_STEPS` steps of inverse iteration from ``v = vec[row]``
    (normalised on the way; A from its factor): an upper bound of A's smallest eigenvalue, reached
    when the start has a part along its eigenvector. 0 when the iteration breaks down."""
    norm = 0.0
    for i in range(size):
        norm += vec[row, i] * vec[row, i]
    lam_min = 0.0
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
    return lam_min


@jit
def reciprocal_condition(factor, size, lam_max, vec, row, signs):
    """The reciprocal condition number of ``D A D`` estimated from its factor: the smallest
    eigenvalue by a few steps of inverse iteration (:data:`INVERSE_STEPS`), over ``lam_max``
    (:func:`scaled_norm_bound`); ``vec[row]`` is scratch. 0 when an iteration breaks down.

    ``signs`` (at least ``size``,) of +1 and -1: the estimate is the same, bit for bit, for ``S A S``
    with ``S = diag(signs)`` as for A (a fit whose frame has a free sign: turning an axis over turns
    the unknowns odd in it, ``S``). Two starts, each on one side of ``signs`` (the entries of a
    fixed vector with no other symmetry where ``signs`` is +1, then where it is -1; ``S`` maps each
    onto plus or minus itself, and the factor of ``S A S`` is ``S L S`` to the bit), and the smaller
    estimate: a start with parts on both sides would give ``S A S`` another estimate than A.
    """
    lam_min = lam_max
    for side in (1.0, -1.0):
        norm = 0.0
        for i in range(size):
            vec[row, i] = 1.0 + (0.37 * i if i % 2 == 0 else -0.37 * i) if signs[i] == side else 0.0
            norm += vec[row, i] * vec[row, i]
        if norm > 0.0:
            lam_min = min(lam_min, _inverse_iteration(factor, size, vec, row))
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
    _sort_pairs(vecs)


@jit
def _sort_pairs(vecs):
    """Insertion sort of the three eigenpairs of ``vecs`` (:func:`sym3_eigen`), ascending."""
    for i in range(1, 3):
        j = i
        while j > 0 and vecs[3, j - 1] > vecs[3, j]:
            for k in range(4):
                vecs[k, j - 1], vecs[k, j] = vecs[k, j], vecs[k, j - 1]
            j -= 1


@jit
def _null_vector(a, lam, vecs, col):
    """``vecs[:3, col]``: the unit vector that ``a - lam I`` maps nearest to zero, from the longest
    cross product of two of its rows (``a`` symmetric 3x3). Returns False when every cross product
    vanishes (``lam`` is at least a double eigenvalue: any vector of a plane would do)."""
    r00, r01, r02 = a[0, 0] - lam, a[0, 1], a[0, 2]
    r11, r12 = a[1, 1] - lam, a[1, 2]
    r22 = a[2, 2] - lam
    # the three cross products of the rows (r00 r01 r02), (r01 r11 r12), (r02 r12 r22)
    c0x, c0y, c0z = r01 * r12 - r02 * r11, r02 * r01 - r00 * r12, r00 * r11 - r01 * r01
    c1x, c1y, c1z = r01 * r22 - r02 * r12, r02 * r02 - r00 * r22, r00 * r12 - r01 * r02
    c2x, c2y, c2z = r11 * r22 - r12 * r12, r12 * r02 - r01 * r22, r01 * r12 - r11 * r02
    d0 = c0x * c0x + c0y * c0y + c0z * c0z
    d1 = c1x * c1x + c1y * c1y + c1z * c1z
    d2 = c2x * c2x + c2y * c2y + c2z * c2z
    if d0 >= d1 and d0 >= d2:
        cx, cy, cz, d = c0x, c0y, c0z, d0
    elif d1 >= d2:
        cx, cy, cz, d = c1x, c1y, c1z, d1
    else:
        cx, cy, cz, d = c2x, c2y, c2z, d2
    if not d > 0.0:
        return False
    inv = 1.0 / math.sqrt(d)
    vecs[0, col], vecs[1, col], vecs[2, col] = cx * inv, cy * inv, cz * inv
    return True


@jit
def _plane_pairs(a, vecs, known, lo, hi):
    """The two eigenpairs of ``a`` in the plane orthogonal to the eigenvector ``vecs[:3, known]``:
    the smaller into column ``lo``, the larger into ``hi``, from the 2x2 restriction of ``a`` to
    that plane (its eigenvector by the larger of two cancellation-free forms; the plane's first
    basis vector when the restriction is a multiple of the identity)."""
    wx, wy, wz = vecs[0, known], vecs[1, known], vecs[2, known]
    # an orthonormal basis (u, v) of the plane orthogonal to w, u from w's two largest components
    if abs(wx) > abs(wy):
        inv = 1.0 / math.sqrt(wx * wx + wz * wz)
        ux, uy, uz = -wz * inv, 0.0, wx * inv
    else:
        inv = 1.0 / math.sqrt(wy * wy + wz * wz)
        ux, uy, uz = 0.0, wz * inv, -wy * inv
    vx, vy, vz = wy * uz - wz * uy, wz * ux - wx * uz, wx * uy - wy * ux
    aux = a[0, 0] * ux + a[0, 1] * uy + a[0, 2] * uz
    auy = a[0, 1] * ux + a[1, 1] * uy + a[1, 2] * uz
    auz = a[0, 2] * ux + a[1, 2] * uy + a[2, 2] * uz
    avx = a[0, 0] * vx + a[0, 1] * vy + a[0, 2] * vz
    avy = a[0, 1] * vx + a[1, 1] * vy + a[1, 2] * vz
    avz = a[0, 2] * vx + a[1, 2] * vy + a[2, 2] * vz
    m00 = ux * aux + uy * auy + uz * auz
    m01 = ux * avx + uy * avy + uz * avz
    m11 = vx * avx + vy * avy + vz * avz
    half = 0.5 * (m00 - m11)
    rad = math.sqrt(half * half + m01 * m01)
    mean = 0.5 * (m00 + m11)
    # the larger eigenvalue's vector (s, t) in (u, v): (half + rad, m01) or (m01, rad - half), whichever adds
    if half >= 0.0:
        s, t = half + rad, m01
    else:
        s, t = m01, rad - half
    norm = s * s + t * t
    if norm > 0.0:
        inv = 1.0 / math.sqrt(norm)
        s *= inv
        t *= inv
    else:
        s, t = 1.0, 0.0
    vecs[0, hi], vecs[1, hi], vecs[2, hi] = s * ux + t * vx, s * uy + t * vy, s * uz + t * vz
    vecs[0, lo], vecs[1, lo], vecs[2, lo] = -t * ux + s * vx, -t * uy + s * vy, -t * uz + s * vz
    vecs[3, hi] = mean + rad
    vecs[3, lo] = mean - rad


@jit
def _outer_root(h):
    """The largest root of ``b^3 - 3 b - 2 h`` for ``h`` in [0, 1] (in [sqrt 3, 2], a simple root):
    Newton's steps from 2, which fall monotonically onto it (the cubic is convex there)."""
    b = 2.0
    for _ in range(8):
        step = ((b * b - 3.0) * b - 2.0 * h) / (3.0 * (b * b - 1.0))
        b -= step
        if not step > 1e-16 * b:
            break
    return b


@jit
def sym3_eigen_closed(a, vecs):
    """Eigen-decomposition of a symmetric 3x3 matrix without iterating rotations: the best separated
    eigenvalue from the characteristic cubic, its vector from cross products of the rows of
    ``A - lambda I``, the other two from the 2x2 restriction of A to the plane orthogonal to it.
    The same arrays and conventions as :func:`sym3_eigen` (``a`` is not changed here).

    The best separated eigenvalue is the smallest when the other two are closer together (a plane's
    covariance) and the largest otherwise (a line's); it is a simple root of the cubic, found by a
    few Newton steps (:func:`_outer_root`), no trigonometric call. The other two pairs come from a
    2x2 eigen-problem (:func:`_plane_pairs`), so the three vectors are orthonormal even for repeated
    eigenvalues (any orthonormal pair of a double eigenvalue's plane). The first eigenvalue is the
    Rayleigh quotient of its vector. Cases: a multiple of the identity (the zero matrix included) gives the
    identity's columns as :func:`sym3_eigen` does; a matrix with a NaN or infinite entry gives NaN.
    The vectors agree with :func:`sym3_eigen`'s to rounding up to sign wherever the eigenvalue is
    simple (to about ``eps * |A| / gap`` radians).
    """
    a00, a01, a02, a11, a12, a22 = a[0, 0], a[0, 1], a[0, 2], a[1, 1], a[1, 2], a[2, 2]
    scale = max(abs(a00), abs(a01), abs(a02), abs(a11), abs(a12), abs(a22))
    if not (math.isfinite(a00) and math.isfinite(a01) and math.isfinite(a02) and math.isfinite(a11)
            and math.isfinite(a12) and math.isfinite(a22)):
        for i in range(4):
            for j in range(3):
                vecs[i, j] = math.nan
        return
    q = (a00 + a11 + a22) / 3.0
    off = a01 * a01 + a02 * a02 + a12 * a12
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    p2 = (b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0
    if not p2 > 1e-30 * scale * scale:
        # a multiple of the identity (to rounding): every vector is an eigenvector
        for i in range(3):
            for j in range(3):
                vecs[i, j] = 1.0 if i == j else 0.0
            vecs[3, i] = a[i, i]
        _sort_pairs(vecs)
        return
    p = math.sqrt(p2)
    # B = (A - q I) / p has trace 0 and eigenvalues b with b^3 - 3 b = det(B): the outer root on the
    # side of det(B)'s sign is simple (the best separated eigenvalue), found by Newton's steps
    inv = 1.0 / p
    c00, c01, c02, c11, c12, c22 = b00 * inv, a01 * inv, a02 * inv, b11 * inv, a12 * inv, b22 * inv
    half_det = 0.5 * (c00 * (c11 * c22 - c12 * c12) - c01 * (c01 * c22 - c12 * c02) + c02 * (c01 * c12 - c11 * c02))
    half_det = min(max(half_det, -1.0), 1.0)
    root = _outer_root(abs(half_det))
    # the smallest eigenvalue's vector first when det(B) < 0 (the other two closer: a plane's covariance)
    first, lo, hi = (0, 1, 2) if half_det < 0.0 else (2, 0, 1)
    lam = q - p * root if half_det < 0.0 else q + p * root
    if not _null_vector(a, lam, vecs, first):
        vecs[0, first], vecs[1, first], vecs[2, first] = (1.0, 0.0, 0.0) if first == 0 else (0.0, 0.0, 1.0)
    _plane_pairs(a, vecs, first, lo, hi)
    x, y, z = vecs[0, first], vecs[1, first], vecs[2, first]
    vecs[3, first] = (x * (a00 * x + a01 * y + a02 * z) + y * (a01 * x + a11 * y + a12 * z)
                      + z * (a02 * x + a12 * y + a22 * z))
    _sort_pairs(vecs)  # rounding may leave two nearly equal Rayleigh quotients out of order
