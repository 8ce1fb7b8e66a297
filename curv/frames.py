"""Tangent frames and the eigen-decomposition of 2x2 shape operators, vectorised over vertices."""

from __future__ import annotations

import numpy as np

__all__ = ["tangent_frames", "principal_from_tensor", "solve_sym3"]


def tangent_frames(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal tangent bases ``(U, V)`` with ``U x V = N``.

    Parameters
    ----------
    normals : (n, 3) float64
        Unit normals (NaN rows give NaN frames).

    Returns
    -------
    U, V : (n, 3) float64
    """
    n = normals
    # cross with the coordinate axis least aligned with N: never near-parallel
    axis = np.zeros_like(n)
    axis[np.arange(n.shape[0]), np.argmin(np.abs(np.nan_to_num(n)), axis=1)] = 1.0
    u = np.cross(n, axis)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(n, u)
    return u, v


def principal_from_tensor(e, f, g, U, V):
    """Principal curvatures and directions of the symmetric tensor ``[[e, f], [f, g]]`` in frame (U, V).

    Parameters
    ----------
    e, f, g : (n,) float64
        Shape operator entries in the tangent basis (U, V).
    U, V : (n, 3) float64
        Tangent basis.

    Returns
    -------
    k1, k2 : (n,) float64
        Eigenvalues, ``k1 >= k2``.
    d1, d2 : (n, 3) float64
        Unit eigenvectors in 3-D; ``d2 = N x d1`` keeps (d1, d2, N) right-handed.
    """
    half = 0.5 * (e - g)
    mean = 0.5 * (e + g)
    rad = np.hypot(half, f)
    theta = 0.5 * np.arctan2(f, half)
    c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
    d1 = c * U + s * V
    d2 = -s * U + c * V
    return mean + rad, mean - rad, d1, d2


def solve_sym3(a00, a01, a02, a11, a12, a22, b0, b1, b2, *, rcond=1e-10):
    """Solve many symmetric 3x3 systems ``A x = b`` in closed form (Cramer's rule).

    Parameters
    ----------
    a00 ... a22 : (n,) float64
        Upper triangle of each symmetric matrix.
    b0, b1, b2 : (n,) float64
        Right-hand sides.
    rcond : float
        A system is called singular when ``|det A| <= rcond * ||A||_max^3``.

    Returns
    -------
    x : (n, 3) float64
        Solutions (NaN rows where singular).
    singular : (n,) bool
    """
    c00 = a11 * a22 - a12 * a12
    c01 = a02 * a12 - a01 * a22
    c02 = a01 * a12 - a02 * a11
    c11 = a00 * a22 - a02 * a02
    c12 = a01 * a02 - a00 * a12
    c22 = a00 * a11 - a01 * a01
    det = a00 * c00 + a01 * c01 + a02 * c02
    scale = np.max(np.abs(np.stack([a00, a01, a02, a11, a12, a22])), axis=0)
    singular = ~(np.abs(det) > rcond * scale**3)
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = 1.0 / det
        x = np.stack(
            [
                (c00 * b0 + c01 * b1 + c02 * b2) * inv,
                (c01 * b0 + c11 * b1 + c12 * b2) * inv,
                (c02 * b0 + c12 * b1 + c22 * b2) * inv,
            ],
            axis=1,
        )
    x[singular] = np.nan
    return x, singular
