"""Shared machinery of the per-vertex least-squares estimators (nc, qs, an, mru).

Each of them writes, for every (vertex p, neighbour q) pair of the support, a few linear equations
in the unknowns of a local fit. The supports of a block of vertices are laid out padded, one row
per vertex (:class:`LocalPairs`, grouped by support size so padding stays below 1/8); the normal
equations ``A^T A x = A^T b`` of every vertex are row sums, solved all at once: closed form for 3
unknowns, a batched ``np.linalg.solve`` (after Jacobi scaling) for more.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Generator

import numpy as np

from ..frames import principal_from_tensor, solve_sym3, tangent_frames
from ..mesh import Mesh
from .._legacy_neighbourhood import DEFAULT_BLOCK_PAIRS, Neighbourhood, block_size_for
from ..result import Principal
from ..validity import Reason
from .registry import iter_blockwise

__all__ = ["LocalPairs", "run_fit", "normal_equations", "solve_normal_equations", "padded_groups", "local_pairs"]

MIN_TANGENT_LENGTH = 1e-9
"""Pairs whose tangent-plane offset is below this fraction of the support radius carry no direction."""


@dataclass
class LocalPairs:
    """The supports of a group of centres in a padded layout, in each centre's tangent frame.

    Row i holds the support of centre i in ``K`` slots; rows with fewer neighbours are padded
    with the centre itself. A padded slot has a zero offset, so it is never ``usable`` and adds
    nothing to any fit. The padded layout lets every per-centre quantity (frame, radius) broadcast
    over its row instead of being copied to every pair, and the per-centre sums are plain row sums.

    Attributes
    ----------
    neighbours : (c, K) int64
        Support vertices (padding: the centre).
    radius : (c,) float64
        Support radius of each centre.
    frame : (c, 9) float64
        U, V, N of each centre, components ``Ux Uy Uz Vx Vy Vz Nx Ny Nz``.
    u, v, w : (c, K) float64
        Offset ``q - p`` in the frame (U, V, N) of the centre p.
    usable : (c, K) bool
        Pairs with a meaningful tangent offset (never a padded slot).
    """

    neighbours: np.ndarray
    radius: np.ndarray
    frame: np.ndarray
    u: np.ndarray
    v: np.ndarray
    w: np.ndarray
    usable: np.ndarray

    @staticmethod
    def row_sum(values: np.ndarray) -> np.ndarray:
        """Sum (c, K) per-pair values (bool counts as 0/1) over each centre's row: (c,) float64."""
        return values.sum(axis=1, dtype=np.float64)

    def project(self, columns: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Components of a per-vertex vector field at the neighbours, in each centre's frame.

        ``columns`` are the field's three contiguous (n,) component arrays (e.g. of the normals).
        Returns (a, b, c), each (c, K).
        """
        comps = [np.take(col, self.neighbours) for col in columns]
        f = self.frame
        return tuple(comps[0] * f[:, 3 * j, None] + comps[1] * f[:, 3 * j + 1, None] + comps[2] * f[:, 3 * j + 2, None]
                     for j in range(3))


def padded_groups(counts: np.ndarray, *, min_group: int = 256) -> list[tuple[np.ndarray, int]]:
    """Split centres into groups of similar support size for the padded layout.

    Each centre's size is rounded up to a cap with at most 1/8 of it padding (steps of 1 below 16,
    then 8 caps per doubling); groups smaller than ``min_group`` join the next larger cap, which
    bounds the number of groups (and the per-group overhead) on irregular meshes.

    Parameters
    ----------
    counts : (c,) int
        Support size of every centre.

    Returns
    -------
    list of (rows, K)
        ``rows`` (r,) int64 indices into ``counts``; ``K`` the row length of the group.
    """
    size = np.maximum(counts, 1)
    step = 2 ** np.maximum(0, np.floor(np.log2(size)).astype(np.int64) - 3)
    cap = -(-size // step) * step
    order = np.argsort(cap, kind="stable")
    caps, starts = np.unique(cap[order], return_index=True)
    bounds = list(starts) + [order.size]
    groups = []
    pending_start = 0
    for i, k in enumerate(caps):
        stop = bounds[i + 1]
        if stop - pending_start >= min_group or i == caps.size - 1:
            groups.append((order[pending_start:stop], int(k)))
            pending_start = stop
    return groups


def local_pairs(xyz: tuple, nb: Neighbourhood, rows: np.ndarray, width: int,
                frames: np.ndarray) -> LocalPairs:
    """Express the supports of some centres of a block in their tangent frames, padded to ``width``.

    Parameters
    ----------
    xyz : three (n,) float64
        Contiguous vertex coordinate columns.
    nb : Neighbourhood
        The block.
    rows : (c,) int64
        Centres of the block (local row numbers) to take; every support has at most ``width`` entries.
    width : int
        Slots per row.
    frames : (n, 9) float64
        U, V, N of every vertex.
    """
    ids = np.take(nb.vertices, rows)
    start = np.take(nb.indptr, rows)
    slot = np.arange(width)
    real = slot[None, :] < np.take(nb.counts, rows)[:, None]
    if nb.indices.size == 0:  # a block made only of isolated vertices: no support to gather
        gathered = np.broadcast_to(ids[:, None], (ids.size, width))
    else:
        gathered = np.take(nb.indices, start[:, None] + slot[None, :], mode="clip")
    neighbours = np.where(real, gathered, ids[:, None])
    frame = np.take(frames, ids, axis=0)
    d = [np.take(x, neighbours) - np.take(x, ids)[:, None] for x in xyz]
    u, v, w = (d[0] * frame[:, 3 * j, None] + d[1] * frame[:, 3 * j + 1, None] + d[2] * frame[:, 3 * j + 2, None]
               for j in range(3))
    radius = np.take(nb.radius, rows)
    tiny = MIN_TANGENT_LENGTH * radius[:, None]
    usable = (u * u + v * v > tiny * tiny) & np.isfinite(u)
    return LocalPairs(neighbours, radius, frame, u, v, w, usable)


def normal_equations(pairs: LocalPairs, equations: list[tuple[list, np.ndarray]]):
    """Sum the normal equations of every centre of a group.

    Parameters
    ----------
    pairs : LocalPairs
        The group (c centres, K slots).
    equations : list of (coefficients, rhs)
        One entry per kind of equation that each pair contributes (e.g. a height and two slopes).
        ``coefficients`` is a list of p arrays (c, K) or ``None`` for an unknown absent from that
        equation; ``rhs`` is (c, K).

    Returns
    -------
    ata : (c, p, p) float64
    atb : (c, p) float64
    """
    p = len(equations[0][0])
    c = pairs.radius.size
    ata = np.empty((c, p, p))
    atb = np.empty((c, p))

    def summed(terms: list) -> np.ndarray:
        if not terms:
            return np.zeros(c)
        return pairs.row_sum(sum(terms[1:], terms[0]))

    for i in range(p):
        for j in range(i, p):
            col = summed([c_[i] * c_[j] for c_, _ in equations if c_[i] is not None and c_[j] is not None])
            ata[:, i, j] = col
            ata[:, j, i] = col
        atb[:, i] = summed([c_[i] * r for c_, r in equations if c_[i] is not None])
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

    frames_by_vertex = np.ascontiguousarray(frames.T)  # (n, 9): one row gathered per centre

    def solve_block(nb: Neighbourhood):
        c = nb.size
        e, f, g, used = (np.empty(c) for _ in range(4))
        singular = np.empty(c, bool)
        for rows, width in padded_groups(nb.counts):
            pairs = local_pairs(xyz, nb, rows, width, frames_by_vertex)
            e[rows], f[rows], g[rows], used[rows], singular[rows] = fit(pairs, normal_columns)
        ids = nb.vertices
        k1, k2, d1, d2 = principal_from_tensor(e, f, g, np.take(U, ids, axis=0), np.take(V, ids, axis=0))
        reason = np.full(ids.size, Reason.OK, np.uint8)
        reason[singular | ~np.isfinite(k1)] = Reason.SINGULAR
        reason[used < min_pairs] = Reason.TOO_FEW_NEIGHBOURS
        reason[~np.isfinite(normals[ids]).all(axis=1)] = Reason.DEGENERATE
        return k1, k2, d1, d2, reason

    block_size = block_size or block_size_for(mesh, factor, pairs=pairs_per_block)
    return (yield from iter_blockwise(mesh, factor, solve_block, block_size=block_size))
