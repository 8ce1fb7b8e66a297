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
from ..neighbourhood import DEFAULT_BLOCK_PAIRS, Neighbourhood, block_size_for, segment_sum
from ..result import Principal
from ..validity import Reason
from .registry import iter_blockwise

__all__ = ["LocalPairs", "run_fit", "normal_equations", "solve_normal_equations"]

MIN_TANGENT_LENGTH = 1e-9
"""Pairs whose tangent-plane offset is below this fraction of the support radius carry no direction."""


@dataclass
class LocalPairs:
    """The pairs of one neighbourhood block expressed in the centre's tangent frame.

    All per-pair arrays are 1-D (structure of arrays): gathers and arithmetic on contiguous 1-D
    arrays are several times faster than on rows of (k, 3) arrays.

    Attributes
    ----------
    nb : Neighbourhood
        The block.
    u, v, w : (nnz,) float64
        Offset ``q - p`` in the frame (U, V, N) of the centre p.
    usable : (nnz,) bool
        Pairs with a meaningful tangent offset.
    frame : (9, nnz) float64
        U, V, N of each pair's centre, components in rows ``Ux Uy Uz Vx Vy Vz Nx Ny Nz``.
    """

    nb: Neighbourhood
    u: np.ndarray
    v: np.ndarray
    w: np.ndarray
    usable: np.ndarray
    frame: np.ndarray

    def project(self, field) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Components of ``field[q]`` (e.g. normals) in each pair's centre frame: (a, b, c), each (nnz,).

        ``field`` is an (n, 3) array or, cheaper when called per block, its three contiguous (n,)
        columns.
        """
        q = self.nb.indices
        comps = [np.take(np.ascontiguousarray(field[k] if isinstance(field, tuple) else field[:, k]), q)
                 for k in range(3)]
        f = self.frame
        return tuple(comps[0] * f[3 * j] + comps[1] * f[3 * j + 1] + comps[2] * f[3 * j + 2] for j in range(3))


def local_pairs(xyz: tuple, nb: Neighbourhood, frames: np.ndarray) -> LocalPairs:
    """Express every support offset of the block in the centre's tangent frame.

    ``xyz`` are the three contiguous (n,) coordinate columns of the vertices; ``frames`` is (9, n):
    U, V, N components of every vertex (see :class:`LocalPairs`).
    """
    ids = nb.vertices
    frame = np.take(frames[:, ids], nb.rows, axis=1)
    d = [np.take(x, nb.indices) - nb.expand(np.take(x, ids)) for x in xyz]
    u, v, w = (d[0] * frame[3 * j] + d[1] * frame[3 * j + 1] + d[2] * frame[3 * j + 2] for j in range(3))
    tiny = MIN_TANGENT_LENGTH * nb.expand(nb.radius)
    usable = (u * u + v * v > tiny * tiny) & np.isfinite(u)
    return LocalPairs(nb, u, v, w, usable, frame)


def normal_equations(nb: Neighbourhood, equations: list[tuple[list, np.ndarray]]):
    """Sum the normal equations of every vertex of a block.

    Parameters
    ----------
    nb : Neighbourhood
        The block; pairs are grouped by row, so sums are contiguous segment sums.
    equations : list of (coefficients, rhs)
        One entry per kind of equation that each pair contributes (e.g. a height and two slopes).
        ``coefficients`` is a list of p arrays (nnz,) or ``None`` for an unknown absent from that
        equation; ``rhs`` is (nnz,).

    Returns
    -------
    ata : (c, p, p) float64
    atb : (c, p) float64
    """
    p = len(equations[0][0])
    ata = np.empty((nb.size, p, p))
    atb = np.empty((nb.size, p))

    def summed(terms: list) -> np.ndarray:
        # each column is reduced on its own: stacking them first costs a transposing copy
        if not terms:
            return np.zeros(nb.size)
        return segment_sum(sum(terms[1:], terms[0]), nb.indptr)

    for i in range(p):
        for j in range(i, p):
            col = summed([c[i] * c[j] for c, _ in equations if c[i] is not None and c[j] is not None])
            ata[:, i, j] = col
            ata[:, j, i] = col
        atb[:, i] = summed([c[i] * r for c, r in equations if c[i] is not None])
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
"""``fit(pairs, normals) -> (e, f, g, equation_count, singular)`` for one block; ``normals`` as the
three contiguous (n,) columns that :meth:`LocalPairs.project` takes."""


def run_fit(
    mesh: Mesh, normals: np.ndarray, factor: float, fit: FitBlock, *, min_pairs: int, block_size: int | None,
    pairs_per_block: int = DEFAULT_BLOCK_PAIRS,
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
        Vertices per block; default so that a block holds about ``pairs_per_block`` pairs.
    pairs_per_block : int
        Lower it for fits with many unknowns: their per-pair temporaries are wider.

    Yields
    ------
    float
        Fraction of vertices done.

    Returns
    -------
    Principal
    """
    U, V = tangent_frames(normals)
    frames = np.ascontiguousarray(np.concatenate([U, V, normals], axis=1).T)
    # contiguous columns once per run: every block gathers from them
    xyz = tuple(np.ascontiguousarray(mesh.vertices[:, k]) for k in range(3))
    normal_columns = tuple(frames[6:9])

    def solve_block(nb: Neighbourhood):
        pairs = local_pairs(xyz, nb, frames)
        e, f, g, used, singular = fit(pairs, normal_columns)
        ids = nb.vertices
        k1, k2, d1, d2 = principal_from_tensor(e, f, g, np.take(U, ids, axis=0), np.take(V, ids, axis=0))
        reason = np.full(ids.size, Reason.OK, np.uint8)
        reason[singular | ~np.isfinite(k1)] = Reason.SINGULAR
        reason[used < min_pairs] = Reason.TOO_FEW_NEIGHBOURS
        reason[~np.isfinite(normals[ids]).all(axis=1)] = Reason.DEGENERATE
        return k1, k2, d1, d2, reason

    block_size = block_size or block_size_for(mesh, factor, pairs=pairs_per_block)
    return (yield from iter_blockwise(mesh, factor, solve_block, block_size=block_size))
