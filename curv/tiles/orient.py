"""One orientation across tiles for normals oriented along a spanning tree.

The rules per input kind (docs/LARGE_SCANS.md):

* **Aerial and terrestrial scans**: normals turned **up** (``orient="up"``, the default for a
  georeferenced cloud: a LAS/LAZ file) or **towards the scanner** (a viewpoint) are decided at each
  point from its own normal and its nearest points' (:mod:`curv.point_normals`), so a tile decides
  them as the whole call does: nothing to reconcile.
* **Objects** (``orient="top"``, the default for other clouds, and ``"outward"`` for closed ones)
  are oriented by propagation along a minimum spanning tree of the neighbour graph (Hoppe et al.
  1992), from one root per connected part (its highest point turned up; its point farthest from
  its centroid turned away from it): a global walk. Each tile propagates over its own region, one
  tree per connected part of the region (:func:`curv.point_normals.spanning_tree`); the parts of
  every tile are then made to agree (:func:`part_signs`): two parts share the points of the
  tiles' overlaps (one tile's core is the other's halo), their normals there vote whether the two
  parts agree, a spanning tree of the parts (strongest votes first) carries one sign to every
  part of a group from the part holding the point the whole call would root that group at,
  turned as the whole call turns it (:func:`group_roots`), and the parts whose sign is -1 are
  turned over (:func:`turned`). Turning whole tiles instead was wrong wherever a tile's region
  held several parts (a terrain's roofs and crowns apart from its ground): on 1M terrain points in
  six tiles, 18,000 points of one tile's roofs came out upside down, and the root of a group could
  be taken from another part's point. A point whose two parts still disagree after that (a fold or
  a thin sheet where the propagation went another way in each) has no decided orientation:
  ``Reason.ORIENTATION``.

Turning a part over negates its normals and turns its results with them: k1, k2 become -k2, -k1
and the directions swap (so (d1, d2, N) stays right-handed), as an estimate with the opposite
normals would give, to rounding.
"""

from __future__ import annotations

import numpy as np

from ..core.validity import Reason

__all__ = ["spans_tiles", "turned", "part_signs", "group_roots", "Parts", "Overlap", "AGREE", "TREE_ORIENTATIONS",
           "disagreeing", "undecided"]

AGREE = 0.5
"""Normals of one point from two tiles agree or disagree when |cos| between them is at least this."""


TREE_ORIENTATIONS = ("top", "outward")
"""The ``orient=`` choices :func:`curv.point_normals.orient_normals` propagates along a spanning tree
(from each part's highest point turned up, or its farthest from the part's centroid turned away);
``"up"`` and a viewpoint decide each point alone."""


def spans_tiles(job, has_normals: bool = False) -> bool:
    """Whether ``job``'s normals are estimated and oriented along a spanning tree
    (:data:`TREE_ORIENTATIONS`): then the tiles must be made to agree (module notes). A point cloud
    with normals of its own (``has_normals``) keeps them unless ``normals=`` asks otherwise."""
    kw = job.keywords
    orient = kw.get("orient")
    estimated = kw.get("normals") in ("fit", "pca") or (kw.get("normals") is None and not has_normals)
    return isinstance(orient, str) and orient in TREE_ORIENTATIONS and estimated


def turned(columns: dict) -> dict:
    """The rows of a tile turned over (module notes): normals negated, k1, k2 -> -k2, -k1, d1 <-> d2,
    the standard errors swapped with their values."""
    out = dict(columns)
    out["normals"] = -np.asarray(columns["normals"])
    out["k1"], out["k2"] = -np.asarray(columns["k2"]), -np.asarray(columns["k1"])
    out["d1"], out["d2"] = np.asarray(columns["d2"]), np.asarray(columns["d1"])
    out["k1_se"], out["k2_se"] = np.asarray(columns["k2_se"]), np.asarray(columns["k1_se"])
    if "rooting" in columns:
        out["rooting"] = -np.asarray(columns["rooting"])
    return out


class Overlap:
    """What one tile saw of the others: the normals it gave the points of its halo.

    Attributes
    ----------
    tile : int
    ids : (h,) int64
        Its halo points (ascending numbers in the whole input).
    normals : (h, 3) float
        The normals it estimated there, as it oriented them (a file run's as saved, float32).
    parts : (h,) int
        The part of its region each was oriented in (its label among the tile's parts,
        :func:`curv.tiles.engine.iter_run_tile`).
    """

    def __init__(self, tile: int, ids: np.ndarray, normals: np.ndarray, parts: np.ndarray):
        self.tile, self.ids, self.normals = int(tile), np.asarray(ids, np.int64), np.asarray(normals)
        self.parts = np.asarray(parts)


class Parts:
    """The parts of every tile numbered as one list: part ``j`` of tile ``t`` is ``base[t] + j``.

    Parameters
    ----------
    counts : (T,) int
        Each tile's parts (its labels are 0 .. count - 1).
    """

    def __init__(self, counts):
        counts = np.asarray(counts, np.int64)
        self.base = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        self.n = int(counts.sum())

    def of(self, tile, part) -> np.ndarray:
        """The numbers of the parts ``part`` of tiles ``tile`` (arrays of one shape, or scalars)."""
        return self.base[np.asarray(tile, np.int64)] + np.asarray(part, np.int64)


def _votes(overlaps, parts: Parts, owner_of, normal_of):
    """``(a, b, agree, disagree)`` arrays over the pairs of parts ``a < b`` that share points; the
    overlaps read one at a time, each summed into its pairs at once (memory: one tile's halo)."""
    pairs, yes, total = [], [], []
    for ov in overlaps():
        if ov.ids.size == 0:
            continue
        mine = parts.of(ov.tile, ov.parts)
        theirs = owner_of(ov.ids)
        cos = np.einsum("ij,ij->i", ov.normals, normal_of(ov.ids))
        vote = (cos >= AGREE) | (cos <= -AGREE)  # NaN and edge-on pairs say nothing
        a, b = np.minimum(mine, theirs)[vote], np.maximum(mine, theirs)[vote]
        keep = a != b
        key, inverse = np.unique(a[keep] * parts.n + b[keep], return_inverse=True)
        pairs.append(key)
        yes.append(np.bincount(inverse, weights=cos[vote][keep] >= AGREE, minlength=key.size))
        total.append(np.bincount(inverse, minlength=key.size))
    if not pairs:
        return (np.empty(0, np.int64),) * 4
    key, inverse = np.unique(np.concatenate(pairs), return_inverse=True)
    agree = np.bincount(inverse, weights=np.concatenate(yes), minlength=key.size).astype(np.int64)
    disagree = np.bincount(inverse, weights=np.concatenate(total), minlength=key.size).astype(np.int64) - agree
    return key // parts.n, key % parts.n, agree, disagree


def part_signs(parts: Parts, overlaps, owner_of, normal_of, roots) -> np.ndarray:
    """(P,) +1 or -1 for each part of each tile: the turn that makes every part agree with those it
    shares points with (module notes).

    Parameters
    ----------
    parts : Parts
    overlaps : callable
        ``overlaps()`` yields every :class:`Overlap` (read again at each call: a file run keeps
        them on disk).
    owner_of : callable
        ``owner_of(ids) -> (m,) int``: the part (a number of ``parts``) whose tile's core holds each point.
    normal_of : callable
        ``normal_of(ids) -> (m, 3)``: each point's normal as its own tile oriented it.
    roots : callable
        ``roots(group) -> (root (G,), sign (G,))``: given each part's group (``group`` (P,) int, the
        groups of parts that share points, 0 .. G-1), the part of each group that holds the whole
        call's root of that group's points and the sign that turns the root as the whole call would
        (:func:`group_roots`).
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

    a, b, yes, no = _votes(overlaps, parts, owner_of, normal_of)
    decided = yes != no
    a, b, yes, no = a[decided], b[decided], yes[decided], no[decided]
    n = parts.n
    # the strongest votes first: a maximum spanning tree is the minimum one of the negated weights
    weights = coo_matrix((1.0 / (1.0 + np.abs(yes - no)), (a, b)), shape=(n, n)).tocsr()
    tree = minimum_spanning_tree(weights)
    tree = (tree + tree.T).tocsr()
    count, group = connected_components(tree, directed=False)
    root, root_sign = roots(group)
    signs = np.ones(n, np.int64)
    signs[root] = root_sign
    if a.size == 0:
        return signs
    relation = coo_matrix((np.where(yes > no, 1, -1), (a, b)), shape=(n, n)).tocsr()
    relation = (relation + relation.T).tocsr()
    # one walk over every group's tree: a virtual part n joins each group's root
    ti, tj = tree.nonzero()
    hub = np.full(count, n)
    walk = coo_matrix((np.ones(ti.size + 2 * count), (np.concatenate([ti, hub, root]), np.concatenate([tj, root, hub]))),
                      shape=(n + 1, n + 1)).tocsr()
    order, parent = breadth_first_order(walk, n, directed=False, return_predecessors=True)
    inner = order[1:][parent[order[1:]] != n]  # every part but the roots, parents before children
    rel = np.asarray(relation[parent[inner], inner]).ravel()
    for t, r in zip(inner.tolist(), rel.tolist()):
        signs[t] = signs[parent[t]] * r
    return signs


def group_roots(group: np.ndarray, orient: str, chunks) -> tuple[np.ndarray, np.ndarray]:
    """``(root (G,), sign (G,))`` for :func:`part_signs`: in each group of parts, the part holding the
    point the whole call roots that group's points at (the highest point, or the farthest
    from the group's centroid, among those with a finite normal; as :func:`curv.point_normals.orient_normals` roots a part), and the
    turn that makes its normal point as that call turns it.

    ``chunks()`` yields ``(parts (m,), xyz (m, 3), rooting (m, 3))`` over every core point once:
    the normals each tile's propagation turned (:func:`curv.point_normals.spanning_tree`), as it
    turned them. The root is chosen and turned by those, not by the normals a result shows (a jet
    fit's may point the other way of the vertical at a crest); it is called once (``"top"``) or
    twice (``"outward"``: the centroids first).
    """
    g_count = int(group.max()) + 1 if group.size else 0
    centroid = None
    if orient != "top":
        sums, counts = np.zeros((g_count, 3)), np.zeros(g_count)
        for part, xyz, _ in chunks():
            g = group[part]
            counts += np.bincount(g, minlength=g_count)
            for c in range(3):
                sums[:, c] += np.bincount(g, weights=xyz[:, c], minlength=g_count)
        centroid = sums / np.maximum(counts, 1)[:, None]
    best = np.full(g_count, -np.inf)
    # a group none of whose points has a finite normal keeps its first part as the root, unturned
    root = np.zeros(g_count, np.int64)
    root[group[::-1]] = np.arange(group.size)[::-1]
    sign = np.ones(g_count, np.int64)
    for part, xyz, rooting in chunks():
        ok = np.isfinite(rooting).all(axis=1)
        part, xyz, rooting = part[ok], xyz[ok], rooting[ok]
        g = group[part]
        if orient == "top":
            key, turn = xyz[:, 2], rooting[:, 2]
        else:
            away = xyz - centroid[g]
            key, turn = np.linalg.norm(away, axis=1), np.einsum("ij,ij->i", rooting, away)
        top = np.full(g_count, -np.inf)
        np.maximum.at(top, g, key)
        at = np.flatnonzero((key == top[g]) & (key > best[g]))
        g_at, first_at = np.unique(g[at], return_index=True)
        at = at[first_at]
        best[g_at] = key[at]
        root[g_at] = part[at]
        sign[g_at] = np.where(turn[at] >= 0, 1, -1)
    return root, sign


def disagreeing(overlaps, parts: Parts, signs: np.ndarray, owner_of, normal_of) -> np.ndarray:
    """(k,) int64 ascending: the points whose normal, once every part is turned by ``signs``, points
    one way in their own tile and the other way in a tile that holds them in its halo
    (``overlaps()`` as in :func:`part_signs`)."""
    bad = []
    for ov in overlaps():
        if ov.ids.size == 0:
            continue
        cos = np.einsum("ij,ij->i", ov.normals, normal_of(ov.ids)) * signs[parts.of(ov.tile, ov.parts)]
        cos *= signs[owner_of(ov.ids)]
        bad.append(ov.ids[cos <= -AGREE])
    return np.unique(np.concatenate(bad)) if bad else np.empty(0, np.int64)


def undecided(columns: dict) -> dict:
    """Rows whose orientation the tiles did not agree on: ``Reason.ORIENTATION``, NaN (module notes)."""
    out = dict(columns)
    m = np.asarray(columns["k1"]).size
    out["valid"] = np.zeros(m, bool)
    out["reason"] = np.full(m, Reason.ORIENTATION, np.uint8)
    for name in ("k1", "k2", "k1_se", "k2_se"):
        out[name] = np.full(m, np.nan)
    for name in ("d1", "d2", "normals"):
        out[name] = np.full((m, 3), np.nan)
    return out
