"""Orienting a point cloud's normals (module notes, 2 and 3): up point by point, Hoppe's spanning
tree, a viewpoint; the undecided points.

"up": each normal turned by its own nz, the edge-on ones and those their nearest oppose undecided
(:func:`_orient_up`, :func:`_opposed`). The propagation: the neighbour graph's edges weighted
``1 - |n_p . n_q|``, ranked by a stable parallel radix sort (:func:`_stable_rank`), Kruskal's spanning forest
(:func:`_spanning_forest`), a breadth-first walk of each part's tree from its root
(:func:`_propagate`) and the neighbours' agreement (:func:`_agreement`).
"""

from __future__ import annotations

import weakref

import numpy as np

from ..core.connectivity import find_root
from ..core.errors import EstimatorError
from ..core.jit import jit, jit_parallel, launch, prange
from ..core.pointcloud import PointCloud
from ..core.radix import stable_order

__all__ = ["orient_normals", "default_orientation", "describe_orientation", "keep_tree", "spanning_tree", "AGREE_COSINE",
           "GRAZING_COSINE", "ORIENTATIONS"]

AGREE_COSINE = 0.5
"""Neighbours whose normals are within 60 degrees (or opposed within 60) count as agreeing (or not)."""

GRAZING_COSINE = 0.05
"""Orienting towards a viewpoint, or up, fails for normals within ~3 degrees of perpendicular to the
view ray (to the vertical): the side is then within the normals' own error (a jet normal at R2
errs by about a degree on a clean sample, several on a scan's noise). A side that noise flips
above this shows up as neighbours that oppose each other (module notes, step 3), which are left
undecided too. On ``autzen_trim.laz`` (110,000 aerial points: ground, roofs, walls, trees) 0.5 %
of the jet normals are within it, 1.0 % within 0.1 and 2.6 % within 0.25: a wider band would
leave out steep roofs and slopes whose up side is clear."""

ORIENTATIONS = ("up", "top", "outward")
"""The named orientation rules (module notes, step 2); a viewpoint (x, y, z) is the fourth."""

_KEEP_TREE: "weakref.WeakSet[PointCloud]" = weakref.WeakSet()
_TREES: "weakref.WeakKeyDictionary[PointCloud, tuple]" = weakref.WeakKeyDictionary()
_TRUSTED: "weakref.WeakKeyDictionary[PointCloud, np.ndarray]" = weakref.WeakKeyDictionary()


@jit_parallel
def _edge_counts(indptr, neighbours, finite, count):
    """``count[p + 1]``: the edges ``p < q`` of row p of the graph between finite normals."""
    for p in prange(indptr.size - 1):
        m = 0
        if finite[p]:
            for j in range(indptr[p], indptr[p + 1]):
                q = neighbours[j]
                if q > p and finite[q]:
                    m += 1
        count[p + 1] = m


@jit_parallel
def _edge_fill(indptr, neighbours, normal, finite, start, out):
    """Write row p's edges of :func:`_tree_edges` from ``start[p]`` on; ``out`` is (rows, cols, weight)."""
    rows, cols, weight = out
    for p in prange(indptr.size - 1):
        if not finite[p]:
            continue
        m = start[p]
        for j in range(indptr[p], indptr[p + 1]):
            q = neighbours[j]
            if q > p and finite[q]:
                rows[m] = p
                cols[m] = q
                c = normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2]
                # kept positive (a sparse MST once read zero as no edge), so the tree and its ties stay as they were
                weight[m] = 1.0 - abs(c) + 1e-9
                m += 1


def _tree_edges(indptr: np.ndarray, neighbours: np.ndarray, normal: np.ndarray,
                finite: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The neighbour graph's edges ``p < q`` between finite normals, row by row, and their weights.

    Each row's edges are counted, then written from its place in the counts' running sum, both in
    parallel: the same order as one serial pass over the rows.

    Parameters
    ----------
    indptr : (n+1,) int64
        The graph's CSR row starts.
    neighbours : (nnz,) int
        Its column indices.
    normal : (n, 3) float64
        The normals, zero where not finite.
    finite : (n,) bool
        The rows whose normal takes part.

    Returns
    -------
    rows, cols : (m,) int32
        The edges' ends, ``rows < cols``.
    weight : (m,) float64
        ``1 - |n_p . n_q| + 1e-9``.
    """
    count = np.zeros(indptr.size, np.int64)
    launch(_edge_counts, indptr, neighbours, finite, count)
    start = np.cumsum(count)
    m = int(start[-1])
    out = (np.empty(m, np.int32), np.empty(m, np.int32), np.empty(m))
    launch(_edge_fill, indptr, neighbours, normal, finite, start, out)
    return out


def _stable_rank(weight: np.ndarray) -> np.ndarray:
    """(m,) ``np.argsort(weight, kind="stable")`` of non-negative finite floats (int32 below 2^31
    weights), by a parallel radix sort of their bit patterns (:func:`curv.core.radix.stable_order`),
    which order such floats as their values: ties keep their order."""
    weight = np.ascontiguousarray(weight, dtype=np.float64)
    dtype = np.int32 if weight.size < 2 ** 31 else np.int64
    return stable_order(weight.view(np.int64), 64, dtype)


@jit_parallel
def _ranked_ends(rank, rows, cols, ends):
    """``ends[i] = rows[rank[i]], cols[rank[i]]``."""
    for i in prange(rank.size):
        e = rank[i]
        ends[i, 0] = rows[e]
        ends[i, 1] = cols[e]


@jit
def _kruskal(n, ends, take):
    """Kruskal over the edges ``ends`` (lightest first): ``take[i]`` for those of the spanning
    forest; returns the union-find forest ``parent`` (n,) (every ``parent[p] <= p``) and the
    points' degrees in the spanning forest, shifted by one, (n+1,)."""
    parent = np.arange(n).astype(np.int32)
    degree = np.zeros(n + 1, np.int64)
    for i in range(ends.shape[0]):
        a = find_root(parent, ends[i, 0])
        b = find_root(parent, ends[i, 1])
        if a != b:
            parent[max(a, b)] = min(a, b)
            take[i] = True
            degree[ends[i, 0] + 1] += 1
            degree[ends[i, 1] + 1] += 1
    return parent, degree


@jit_parallel
def _taken_by_edge(rank, take, taken):
    """``taken[rank[i]] = take[i]``: the forest's edges flagged in the edges' own order."""
    for i in prange(rank.size):
        if take[i]:
            taken[rank[i]] = True


@jit
def _forest_csr(ptr, rows, cols, taken, parent):
    """The forest's CSR adjacency (each row's neighbours in the edges' order) and each point's part:
    the smallest index of its tree, read off ``parent`` in one ascending pass (a union joins the
    larger root under the smaller and path halving only shortens, so ``parent[p] <= p`` and p's part
    is its parent's, already known)."""
    n = parent.size
    adj = np.empty(ptr[n], np.int64)
    fill = ptr[:n].copy()
    for e in range(taken.size):
        if taken[e]:
            adj[fill[rows[e]]] = cols[e]
            fill[rows[e]] += 1
            adj[fill[cols[e]]] = rows[e]
            fill[cols[e]] += 1
    part = np.empty(n, np.int64)
    for p in range(n):
        part[p] = p if parent[p] == p else part[parent[p]]
    return adj, part


def _spanning_forest(n: int, rank: np.ndarray, rows: np.ndarray,
                     cols: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Kruskal's minimum spanning forest of the edges ``rows[e] - cols[e]`` taken in the order ``rank``.

    The edges' ends are first gathered in that order in parallel: Kruskal's serial loop then reads
    them in a row. Fetched one by one inside the loop, each random read waited on the union-find's
    before it, and the loop cost 0.43-0.55 s at 1M points (5.7M edges); on the gathered ends
    0.07-0.12 s, the gather 0.07 (measured 2026-12-05, 2 cores, load 2-3).

    Parameters
    ----------
    n : int
        Points.
    rank : (m,) int
        The edges, lightest first (:func:`_stable_rank` of the weights).
    rows, cols : (m,) int32
        The edges' ends.

    Returns
    -------
    ptr : (n+1,) int64
        The forest's CSR row starts.
    adj : (ptr[n],) int64
        Each point's neighbours in the forest, in the edges' order.
    part : (n,) int64
        Each point's part: the smallest index of its tree.
    """
    ends = np.empty((rank.size, 2), np.int32)
    launch(_ranked_ends, rank, rows, cols, ends)
    take = np.zeros(rank.size, np.bool_)
    parent, degree = _kruskal(n, ends, take)
    del ends
    taken = np.zeros(rank.size, np.bool_)
    launch(_taken_by_edge, rank, take, taken)
    ptr = np.cumsum(degree)
    adj, part = _forest_csr(ptr, rows, cols, taken, parent)
    return ptr, adj, part


@jit
def _propagate(ptr, adj, part, key, root_sign, normal):
    """Walk each part's tree breadth first from its root (the greatest ``key``, the smallest index
    on ties), turning the root by ``root_sign`` (its value < 0: flip) and every other normal to
    agree with its tree parent."""
    n = part.size
    root = np.full(n, -1, np.int64)
    for p in range(n):
        r = part[p]
        if root[r] < 0 or key[p] > key[root[r]]:
            root[r] = p
    seen = np.zeros(n, np.bool_)
    queue = np.empty(n, np.int64)
    for r in range(n):
        s = root[r]
        if s < 0:
            continue
        if root_sign[s] < 0.0:
            normal[s, 0] = -normal[s, 0]
            normal[s, 1] = -normal[s, 1]
            normal[s, 2] = -normal[s, 2]
        seen[s] = True
        queue[0] = s
        head, tail = 0, 1
        while head < tail:
            p = queue[head]
            head += 1
            for j in range(ptr[p], ptr[p + 1]):
                q = adj[j]
                if seen[q]:
                    continue
                seen[q] = True
                if normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2] < 0.0:
                    normal[q, 0] = -normal[q, 0]
                    normal[q, 1] = -normal[q, 1]
                    normal[q, 2] = -normal[q, 2]
                queue[tail] = q
                tail += 1


@jit
def _votes(p, indptr, neighbours, normal, cosine):
    """How many of p's neighbours ``neighbours[indptr[p]:indptr[p + 1]]`` (-1 entries skipped) agree
    with its normal (cos >= ``cosine``) and how many oppose it (cos <= -``cosine``)."""
    agree = 0
    oppose = 0
    for j in range(indptr[p], indptr[p + 1]):
        q = neighbours[j]
        if q < 0:
            continue
        c = normal[p, 0] * normal[q, 0] + normal[p, 1] * normal[q, 1] + normal[p, 2] * normal[q, 2]
        if c >= cosine:
            agree += 1
        elif c <= -cosine:
            oppose += 1
    return agree, oppose


@jit_parallel
def _agreement(indptr, neighbours, normal, cosine, ambiguous):
    """``ambiguous[p]``: p's normal agrees with none of its neighbours (:func:`_votes`), or with no
    more of them than disagree."""
    for p in prange(indptr.size - 1):
        agree, oppose = _votes(p, indptr, neighbours, normal, cosine)
        ambiguous[p] = agree == 0 or oppose >= agree


@jit_parallel
def _opposed(indptr, neighbours, normal, cosine, ambiguous):
    """``ambiguous[p]``: as many of p's neighbours disagree with its normal as agree with it
    (:func:`_votes`), and at least one does."""
    for p in prange(indptr.size - 1):
        agree, oppose = _votes(p, indptr, neighbours, normal, cosine)
        ambiguous[p] = oppose > 0 and oppose >= agree


def default_orientation(cloud: PointCloud) -> str:
    """The orientation rule of a cloud's estimated normals when none is asked for (module notes, 2):
    ``"up"`` for a georeferenced scan (:attr:`curv.PointCloud.georeferenced`), else ``"top"``."""
    return "up" if cloud.georeferenced else "top"


def describe_orientation(orient) -> str:
    """The orientation rule in words, e.g. ``up (nz >= 0 at every point)`` (the summaries' wording)."""
    if isinstance(orient, str):
        return {"up": "up (nz >= 0 at every point)",
                "top": "by propagation from each part's top, turned up (Hoppe)",
                "outward": "outward (propagated from each part's farthest point, Hoppe)"}.get(orient, orient)
    return "towards " + " ".join(f"{v:g}" for v in np.asarray(orient, dtype=np.float64).reshape(-1))


def _orient_up(cloud: PointCloud, out: np.ndarray, finite: np.ndarray) -> np.ndarray:
    """``"up"``, point by point, in place: flip every normal with nz < 0; the edge-on ones and those
    their nearest points oppose (module notes, step 3) are undecided (NaN). Returns those (n,) bool."""
    out[out[:, 2] < 0.0] *= -1.0
    nearest = cloud.nearest[0]
    k = nearest.shape[1]
    indptr = np.arange(0, k * nearest.shape[0] + 1, k, dtype=np.int64)
    ambiguous = np.zeros(out.shape[0], bool)
    # a grazing normal's sign is the fit's free choice, not a decision: it does not vote on its
    # neighbours (a zero vector agrees and opposes nobody), so no point's verdict depends on it
    grazing = ~(np.abs(out[:, 2]) >= GRAZING_COSINE)
    voters = finite & ~grazing
    launch(_opposed, indptr, nearest.reshape(-1), np.where(voters[:, None], out, 0.0), AGREE_COSINE, ambiguous)
    ambiguous |= grazing
    ambiguous &= finite
    out[ambiguous] = np.nan
    return ambiguous


def keep_tree(cloud: PointCloud, trusted: np.ndarray | None = None) -> None:
    """Ask every later propagation along a spanning tree on ``cloud`` to keep its forest and the
    normals it turned (:func:`spanning_tree`; kept only where asked, it is 48 bytes a point).

    ``trusted`` (n,) bool: the points whose neighbour-graph edges and unoriented normals the caller
    knows to be a larger cloud's (a tile's region: :func:`curv.tiles.reach.tree_reach`). Kruskal
    then takes every edge with an untrusted end after all the others: the forest over the trusted
    points is the minimum one of their own edges, so a part of the larger cloud that they hold whole
    gets the larger cloud's tree, and so its relative orientation, whatever the region's edge adds.
    """
    _KEEP_TREE.add(cloud)
    if trusted is None:
        _TRUSTED.pop(cloud, None)
    else:
        _TRUSTED[cloud] = np.asarray(trusted, bool)


def spanning_tree(cloud: PointCloud) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """``(ptr (n+1,), adj (ptr[n],), rooting (n, 3))``: the forest the last propagation on ``cloud``
    walked (CSR, both directions; its trees are the parts one root each decided) and the normals
    it turned along it (the unoriented ones it was given, before the undecided are left out: the
    root of a part is its highest point, or farthest from its centroid, with a finite one, and that
    normal is turned up, or away), when :func:`keep_tree` asked for it; None when the last
    orientation decided each point alone (up, a viewpoint) or none ran.

    An estimate of a whole cloud orients its twin in grid order
    (:func:`curv.point_normals.grid_ordered`); a cloud already in its grid's order (a tile's
    region) is oriented itself. The tiles ask it: the parts of a tile's region are turned over one
    by one to agree with the others, and rooted as the whole call roots them (:mod:`curv.tiles.orient`).
    """
    return _TREES.get(cloud)


def orient_normals(cloud: PointCloud, normals: np.ndarray, *, orient=None) -> tuple[np.ndarray, np.ndarray]:
    """Orient unoriented normals (module notes, step 2) and find the undecided ones (step 3).

    Parameters
    ----------
    cloud : PointCloud
    normals : (n, 3) float64
        Unit normals, either sign; NaN rows take no part.
    orient : {"up", "top", "outward"} or (3,) array_like, optional
        Every normal up (nz >= 0), propagation from each connected part's top turned up or from its
        farthest point turned away from its centroid, or every normal towards this viewpoint;
        default :func:`default_orientation`.

    Returns
    -------
    normals : (n, 3) float64
        Oriented copy; NaN at undecided points.
    ambiguous : (n,) bool
        Points whose orientation could not be decided (module notes, step 3).
    """
    out = np.array(normals, dtype=np.float64, copy=True)
    n = out.shape[0]
    finite = np.isfinite(out).all(axis=1)
    _TREES.pop(cloud, None)
    if orient is None:
        orient = default_orientation(cloud)
    if not isinstance(orient, str):
        view = np.asarray(orient, dtype=np.float64).reshape(3)
        ray = view - cloud.points
        ray /= np.linalg.norm(ray, axis=1, keepdims=True)
        cosine = np.einsum("ij,ij->i", out, ray)
        out[cosine < 0] *= -1.0
        ambiguous = finite & ~(np.abs(cosine) >= GRAZING_COSINE)
        out[ambiguous] = np.nan
        return out, ambiguous
    if orient not in ORIENTATIONS:
        raise EstimatorError(f"orient must be 'up', 'top', 'outward' or a viewpoint (x, y, z); got {orient!r}")
    if orient == "up":
        return out, _orient_up(cloud, out, finite)
    graph = cloud.adjacency
    indptr, neighbours = graph.indptr, graph.indices
    safe = np.where(finite[:, None], out, 0.0)
    rows, cols, weight = _tree_edges(indptr, neighbours, safe, finite)
    trusted = _TRUSTED.get(cloud) if cloud in _KEEP_TREE else None
    if trusted is not None:  # weights lie in [0, 1]: these come after every other edge (keep_tree)
        weight[~(trusted[rows] & trusted[cols])] += 2.0
    # Kruskal in the order of the weights (stable: ties keep the edges' order)
    ptr, adj, part = _spanning_forest(n, _stable_rank(weight), rows, cols)
    del rows, cols, weight
    # one root per part: its highest point (turned up), or the point farthest from its centroid (turned away)
    if orient == "top":
        key = cloud.points[:, 2].copy()
        root_sign = out[:, 2].copy()
    else:
        centroid = np.stack([np.bincount(part, cloud.points[:, c], n) for c in range(3)], axis=1)
        centroid /= np.maximum(np.bincount(part, minlength=n), 1)[:, None]
        away = cloud.points - centroid[part]
        key = np.linalg.norm(away, axis=1)
        root_sign = np.einsum("ij,ij->i", out, away)
    key[~finite] = -np.inf
    root_sign[~finite] = 0.0
    _propagate(ptr, adj, part, key, root_sign, out)
    if cloud in _KEEP_TREE:
        _TREES[cloud] = (ptr, adj, out.copy())
    ambiguous = np.zeros(n, bool)
    safe = np.where(finite[:, None], out, 0.0)
    launch(_agreement, indptr, neighbours, safe, AGREE_COSINE, ambiguous)
    ambiguous &= finite
    out[ambiguous] = np.nan
    return out, ambiguous
