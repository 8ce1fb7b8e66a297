"""Shared machinery of the per-vertex least-squares estimators (nc, qs, an, mru).

Each of them writes, for every (vertex p, neighbour q) pair of the support, a few linear equations
in the unknowns of a local fit. The normal equations ``A^T A x = A^T b`` of every vertex are summed
with ``np.bincount`` over the pairs and solved all at once: closed form for 3 unknowns, a batched
``np.linalg.solve`` (after Jacobi scaling) for more.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Generator

import numpy as np

from ..frames import principal_from_tensor, solve_sym3, tangent_frames
from ..mesh import Mesh
from ..neighbourhood import Neighbourhood, iter_neighbourhoods
from ..result import Principal
from ..validity import Reason
from .registry import empty_principal

__all__ = ["LocalPairs", "run_fit", "normal_equations", "solve_normal_equations"]

MIN_TANGENT_LENGTH = 1e-9
"""Pairs whose tangent-plane offset is below this fraction of the support radius carry no direction."""


@dataclass
class LocalPairs:
    """The pairs of one neighbourhood block expressed in the centre's tangent frame.

    Attributes
    ----------
    nb : Neighbourhood
        The block.
    u, v, w : (nnz,) float64
        Offset ``q - p`` in the frame (U, V, N) of the centre p.
    usable : (nnz,) bool
        Pairs with a meaningful tangent offset.
    """

    nb: Neighbourhood
    u: np.ndarray
    v: np.ndarray
    w: np.ndarray
    usable: np.ndarray
    frame_u: np.ndarray
    frame_v: np.ndarray
    frame_n: np.ndarray
    centres: np.ndarray


def local_pairs(mesh: Mesh, nb: Neighbourhood, U, V, N) -> LocalPairs:
    """Express every support offset of the block in the centre's tangent frame."""
    centres = nb.centres
    d = mesh.vertices[nb.indices] - mesh.vertices[centres]
    fu, fv, fn = U[centres], V[centres], N[centres]
    u = np.einsum("ij,ij->i", d, fu)
    v = np.einsum("ij,ij->i", d, fv)
    w = np.einsum("ij,ij->i", d, fn)
    tiny = MIN_TANGENT_LENGTH * nb.radius[nb.rows]
    usable = (u * u + v * v > tiny * tiny) & np.isfinite(u)
    return LocalPairs(nb, u, v, w, usable, fu, fv, fn, centres)


def normal_equations(rows: np.ndarray, size: int, design: list[np.ndarray], rhs: np.ndarray):
    """Sum the normal equations of equations grouped by row.

    Parameters
    ----------
    rows : (k,) int64
        Local row (vertex of the block) of each equation.
    size : int
        Number of rows in the block.
    design : list of p arrays of shape (k,)
        Coefficients of each unknown in every equation (zero weight equations may be included).
    rhs : (k,) float64

    Returns
    -------
    ata : (size, p, p) float64
    atb : (size, p) float64
    """
    p = len(design)
    ata = np.empty((size, p, p))
    atb = np.empty((size, p))
    for i in range(p):
        atb[:, i] = np.bincount(rows, weights=design[i] * rhs, minlength=size)
        for j in range(i, p):
            s = np.bincount(rows, weights=design[i] * design[j], minlength=size)
            ata[:, i, j] = s
            ata[:, j, i] = s
    return ata, atb


def solve_normal_equations(ata: np.ndarray, atb: np.ndarray, *, rcond: float = 1e-10):
    """Solve batched symmetric systems; flag (near-)singular ones.

    Parameters
    ----------
    ata : (c, p, p) float64
    atb : (c, p) float64

    Returns
    -------
    x : (c, p) float64
        NaN rows where singular.
    singular : (c,) bool
    """
    if ata.shape[1] == 3:
        a = ata
        return solve_sym3(a[:, 0, 0], a[:, 0, 1], a[:, 0, 2], a[:, 1, 1], a[:, 1, 2], a[:, 2, 2],
                          atb[:, 0], atb[:, 1], atb[:, 2], rcond=rcond)
    diag = np.einsum("cii->ci", ata)
    ok = np.all(diag > 0, axis=1) & np.all(np.isfinite(ata), axis=(1, 2))
    scale = np.zeros_like(diag)
    scale[ok] = 1.0 / np.sqrt(diag[ok])
    scaled = ata * scale[:, :, None] * scale[:, None, :]
    x = np.full(atb.shape, np.nan)
    if ok.any():
        sign, logdet = np.linalg.slogdet(scaled[ok])
        good = (sign > 0) & (logdet > np.log(rcond) * 2)
        idx = np.flatnonzero(ok)[good]
        if idx.size:
            y = np.linalg.solve(scaled[idx], (atb[idx] * scale[idx])[:, :, None])[:, :, 0]
            x[idx] = y * scale[idx]
        ok[np.flatnonzero(ok)[~good]] = False
    return x, ~ok


FitBlock = Callable[[LocalPairs, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]
"""``fit(pairs, normals) -> (e, f, g, equation_count, singular)`` for one block."""


def run_fit(
    mesh: Mesh, normals: np.ndarray, factor: float, fit: FitBlock, *, min_pairs: int, block_size: int | None
) -> Generator[float, None, Principal]:
    """Drive a per-vertex fit over all neighbourhood blocks.

    Parameters
    ----------
    mesh, normals : Mesh, (n, 3) float64
    factor : float
        Support radius in longest-1-ring-edge units.
    fit : FitBlock
        Computes the shape-operator entries (e, f, g) in the centre frame for one block.
    min_pairs : int
        Fewer usable neighbours than this make the vertex ``TOO_FEW_NEIGHBOURS``.
    block_size : int or None

    Yields
    ------
    float
        Fraction of vertices done.

    Returns
    -------
    Principal
    """
    n = mesh.n_vertices
    out = empty_principal(n)
    U, V = tangent_frames(normals)
    done = 0
    for nb in iter_neighbourhoods(mesh, factor, block_size=block_size):
        pairs = local_pairs(mesh, nb, U, V, normals)
        e, f, g, used, singular = fit(pairs, normals)
        ids = nb.vertices
        k1, k2, d1, d2 = principal_from_tensor(e, f, g, U[ids], V[ids])
        reason = np.full(ids.size, Reason.OK, np.uint8)
        reason[singular | ~np.isfinite(k1)] = Reason.SINGULAR
        reason[used < min_pairs] = Reason.TOO_FEW_NEIGHBOURS
        reason[~np.isfinite(normals[ids]).all(axis=1)] = Reason.DEGENERATE
        out.k1[ids], out.k2[ids], out.d1[ids], out.d2[ids] = k1, k2, d1, d2
        out.reason[ids] = reason
        done += ids.size
        yield done / n
    return out
