"""Exact principal curvatures from derivatives: Monge patches, level sets and parametrisations.

Every function is vectorised over points and ends in :func:`principal_from_shape`, which turns a
shape operator expressed in an orthonormal tangent frame into sorted curvatures and directions.

Sign convention (docs/ARCHITECTURE.md): ``dN = W t`` for a tangent ``t``. With the textbook second
fundamental form ``II_ij = X_ij . N`` (paper eq. 2.2) this gives ``W = -I^-1 II``, so an outward
sphere of radius r has ``k1 = k2 = +1/r``.
"""

from __future__ import annotations

import numpy as np

from ..core.result import Curvature

__all__ = [
    "tangent_frame",
    "principal_from_shape",
    "monge_principal",
    "implicit_principal",
    "exact_curvature",
]


def tangent_frame(normals: np.ndarray) -> np.ndarray:
    """An orthonormal tangent basis at each point.

    Parameters
    ----------
    normals : (n, 3) float64
        Unit normals.

    Returns
    -------
    (n, 3, 2) float64
        Columns ``U, V`` with ``(U, V, N)`` right-handed and orthonormal.
    """
    n = np.asarray(normals, dtype=np.float64)
    helper = np.zeros_like(n)
    use_x = np.abs(n[:, 0]) < 0.9
    helper[use_x, 0] = 1.0
    helper[~use_x, 1] = 1.0
    u = helper - np.einsum("ij,ij->i", helper, n)[:, None] * n
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.cross(n, u)
    return np.stack([u, v], axis=2)


def principal_from_shape(frame: np.ndarray, shape: np.ndarray, normals: np.ndarray):
    """Principal curvatures and directions of a symmetric shape operator.

    Parameters
    ----------
    frame : (n, 3, 2) float64
        Orthonormal tangent basis (columns) at each point.
    shape : (n, 2, 2) float64
        Symmetric shape operator ``W`` in that basis (``dN = W t``).
    normals : (n, 3) float64
        Unit normals; ``d2 = N x d1`` so that ``(d1, d2, N)`` is right-handed.

    Returns
    -------
    k1, k2 : (n,) float64
        ``k1 >= k2``.
    d1, d2 : (n, 3) float64
        Unit principal directions of ``k1`` and ``k2``.
    """
    sym = 0.5 * (shape + np.swapaxes(shape, 1, 2))
    vals, vecs = np.linalg.eigh(sym)  # ascending
    d1 = np.einsum("nij,nj->ni", frame, vecs[:, :, 1])
    d1 /= np.linalg.norm(d1, axis=1, keepdims=True)
    d2 = np.cross(normals, d1)
    return vals[:, 1].copy(), vals[:, 0].copy(), d1, d2


def monge_principal(gradient, hessian):
    """Exact geometry of a height field ``z = f(x, y)`` with the upward normal.

    Uses the fundamental forms of ``X(x, y) = (x, y, f)`` (paper eq. 2.1-2.3): ``X_x = (1, 0, fx)``,
    ``X_y = (0, 1, fy)``, ``N = (-fx, -fy, 1) / w`` with ``w = sqrt(1 + fx^2 + fy^2)``,
    ``I = [[1 + fx^2, fx fy], [fx fy, 1 + fy^2]]`` and ``II = Hess(f) / w``. The frame
    ``J L^-T`` (``I = L L^T``, Cholesky) is orthonormal, in which ``W = -L^-1 II L^-T``.

    Parameters
    ----------
    gradient : tuple of two (n,) float64
        ``fx, fy``.
    hessian : tuple of three (n,) float64
        ``fxx, fxy, fyy``.

    Returns
    -------
    k1, k2 : (n,) float64
    d1, d2, normals : (n, 3) float64
    """
    p, q = (np.asarray(a, dtype=np.float64).reshape(-1) for a in gradient)
    fxx, fxy, fyy = (np.asarray(a, dtype=np.float64).reshape(-1) for a in hessian)
    w = np.sqrt(1.0 + p * p + q * q)
    normals = np.stack([-p, -q, np.ones_like(p)], axis=1) / w[:, None]
    # Cholesky of I, in closed form: L = [[l11, 0], [l21, l22]]
    l11 = np.sqrt(1.0 + p * p)
    l21 = p * q / l11
    l22 = np.sqrt(1.0 + q * q - l21 * l21)  # = w / l11
    # M = L^-1 (rows of the inverse of a lower-triangular 2x2)
    m = np.zeros((p.size, 2, 2))
    m[:, 0, 0] = 1.0 / l11
    m[:, 1, 0] = -l21 / (l11 * l22)
    m[:, 1, 1] = 1.0 / l22
    jac = np.zeros((p.size, 3, 2))
    jac[:, 0, 0] = 1.0
    jac[:, 1, 1] = 1.0
    jac[:, 2, 0] = p
    jac[:, 2, 1] = q
    second = np.stack([np.stack([fxx, fxy], 1), np.stack([fxy, fyy], 1)], 1) / w[:, None, None]
    frame = jac @ np.swapaxes(m, 1, 2)
    shape = -(m @ second @ np.swapaxes(m, 1, 2))
    return (*principal_from_shape(frame, shape, normals), normals)


def implicit_principal(gradient: np.ndarray, hessian: np.ndarray):
    """Exact geometry of the level set of ``F`` through each point, normal along ``grad F``.

    For ``N = grad F / |grad F|`` and a tangent ``t``, ``dN = P Hess(F) t / |grad F|`` with ``P`` the
    tangent projector, so ``W = T^T Hess(F) T / |grad F|`` in an orthonormal tangent frame ``T``.
    A closed surface written ``F <= 0`` inside therefore gets the outward normal and ``+1/r`` on a
    sphere.

    Parameters
    ----------
    gradient : (n, 3) float64
        ``grad F`` at the points; must not vanish.
    hessian : (n, 3, 3) float64
        ``Hess F`` at the points.

    Returns
    -------
    k1, k2 : (n,) float64
    d1, d2, normals : (n, 3) float64
    """
    g = np.asarray(gradient, dtype=np.float64)
    norm = np.linalg.norm(g, axis=1)
    normals = g / norm[:, None]
    frame = tangent_frame(normals)
    shape = np.swapaxes(frame, 1, 2) @ hessian @ frame / norm[:, None, None]
    return (*principal_from_shape(frame, shape, normals), normals)


def exact_curvature(k1, k2, d1, d2, normals, **info) -> Curvature:
    """Wrap exact values as a :class:`curv.Curvature` (``method="exact"``, all valid)."""
    n = k1.shape[0]
    return Curvature(
        k1=k1, k2=k2, d1=d1, d2=d2, normals=normals,
        valid=np.ones(n, bool), reason=np.zeros(n, np.uint8),
        method="exact", range=None, info=dict(info),
    )
