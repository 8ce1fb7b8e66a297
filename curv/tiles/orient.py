"""One orientation across tiles for normals oriented along a spanning tree.

The rules per input kind (docs/LARGE_SCANS.md):

* **Aerial and terrestrial scans**: normals turned **up** (``orient="up"``, the default for a
  georeferenced cloud: a LAS/LAZ file) or **towards the scanner** (a viewpoint) are decided at each
  point from its own normal and its nearest points' (:mod:`curv.point_normals`), so a tile decides
  them as the whole call does: nothing to reconcile.
* **Objects** (``orient="top"``, the default for other clouds, and ``"outward"`` for closed ones)
  are oriented by propagation along a minimum spanning tree of the neighbour graph (Hoppe et al.
  1992), from one root per connected part (its highest point turned up; its point farthest from
  its centroid turned away from it): a global walk. Each tile propagates over its own region; the tiles are then made to agree
  (:func:`tile_signs`): two tiles share the points of their overlaps (one's core is the other's
  halo), each pair's normals there vote whether the two tiles agree, a spanning tree of the tiles
  (strongest votes first) carries one sign to every tile from a root tile, and the tiles whose
  sign is -1 are turned over as a whole (:func:`turned`). The root tile is the one holding the
  point the whole call would root at, turned as the whole call turns it (away from the centroid
  of its part); parts that share no point with each other are oriented each from its own root.
  A point whose two tiles still disagree after that (a fold or a thin sheet where the
  propagation went another way in each) has no decided orientation: ``Reason.ORIENTATION``.

Turning a tile over negates its normals and turns its results with them: k1, k2 become -k2, -k1
and the directions swap (so (d1, d2, N) stays right-handed), as an estimate with the opposite
normals would give, to rounding.
"""

from __future__ import annotations

import numpy as np

from ..core.validity import Reason

__all__ = ["spans_tiles", "turned", "tile_signs", "Overlap", "AGREE", "root_choice", "TREE_ORIENTATIONS", "disagreeing", "undecided"]

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


def root_choice(points: np.ndarray, normals: np.ndarray, orient: str, centroid: np.ndarray | None = None):
    """``(row, sign)``: where the whole call roots a part whose points (m, 3) and normals (m, 3) are
    these, and the turn (+1 or -1) that makes the normal there point as that call turns it: the
    highest point up, or the point farthest from the part's ``centroid`` away from it. Rows without a
    finite normal are never the root; ``(None, 1)`` when none has one."""
    ok = np.flatnonzero(np.isfinite(normals).all(axis=1))
    if ok.size == 0:
        return None, 1
    if orient == "top":
        row = ok[int(np.argmax(points[ok, 2]))]
        return int(row), 1 if normals[row, 2] >= 0 else -1
    away = points[ok] - centroid
    far = int(np.argmax(np.linalg.norm(away, axis=1)))
    row = ok[far]
    return int(row), 1 if float(normals[row] @ away[far]) >= 0 else -1


def turned(columns: dict) -> dict:
    """The rows of a tile turned over (module notes): normals negated, k1, k2 -> -k2, -k1, d1 <-> d2,
    the standard errors swapped with their values."""
    out = dict(columns)
    out["normals"] = -np.asarray(columns["normals"])
    out["k1"], out["k2"] = -np.asarray(columns["k2"]), -np.asarray(columns["k1"])
    out["d1"], out["d2"] = np.asarray(columns["d2"]), np.asarray(columns["d1"])
    out["k1_se"], out["k2_se"] = np.asarray(columns["k2_se"]), np.asarray(columns["k1_se"])
    return out


class Overlap:
    """What one tile saw of the others: the normals it gave the points of its halo.

    Attributes
    ----------
    tile : int
    ids : (h,) int64
        Its halo points (ascending numbers in the whole input).
    normals : (h, 3) float64
        The normals it estimated there, as it oriented them.
    """

    def __init__(self, tile: int, ids: np.ndarray, normals: np.ndarray):
        self.tile, self.ids, self.normals = int(tile), np.asarray(ids, np.int64), np.asarray(normals, np.float64)


def _votes(overlaps, owner_of, normal_of):
    """``{(a, b): (agree, disagree)}`` over the shared points of tile pairs."""
    votes = {}
    for ov in overlaps:
        if ov.ids.size == 0:
            continue
        owners = owner_of(ov.ids)
        theirs = normal_of(ov.ids)
        cos = np.einsum("ij,ij->i", ov.normals, theirs)
        ok = np.isfinite(cos)
        for other in np.unique(owners[ok]):
            if other == ov.tile:
                continue
            c = cos[ok & (owners == other)]
            key = (min(ov.tile, int(other)), max(ov.tile, int(other)))
            a, d = votes.get(key, (0, 0))
            votes[key] = (a + int((c >= AGREE).sum()), d + int((c <= -AGREE).sum()))
    return votes


def tile_signs(n_tiles: int, overlaps, owner_of, normal_of, roots) -> np.ndarray:
    """(T,) +1 or -1 for each tile: the turn that makes every tile agree with the others (module notes).

    Parameters
    ----------
    n_tiles : int
    overlaps : sequence of Overlap
    owner_of : callable
        ``owner_of(ids) -> (m,) int``: the tile whose core holds each point.
    normal_of : callable
        ``normal_of(ids) -> (m, 3)``: each point's normal as its own tile oriented it.
    roots : callable
        ``roots(groups) -> list of (tile, sign)``: for each group of tiles that share points (a list
        of tile-index arrays), the tile holding that part's root and the sign that turns the root as
        the whole call would.
    """
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import breadth_first_order, connected_components, minimum_spanning_tree

    votes = _votes(overlaps, owner_of, normal_of)
    pairs = [(a, b, ag, dis) for (a, b), (ag, dis) in votes.items() if ag != dis]
    signs = np.ones(n_tiles, np.int64)
    if pairs:
        a, b, ag, dis = (np.array(c) for c in zip(*pairs))
        relation = np.where(ag > dis, 1, -1)
        # the strongest votes first: a maximum spanning tree is the minimum one of the negated weights
        strength = np.abs(ag - dis).astype(np.float64)
        weights = coo_matrix((1.0 / (1.0 + strength), (a, b)), shape=(n_tiles, n_tiles)).tocsr()
        tree = minimum_spanning_tree(weights)
        tree = (tree + tree.T).tocsr()
        rel = {(int(x), int(y)): int(r) for x, y, r in zip(a, b, relation)}
        rel.update({(y, x): r for (x, y), r in list(rel.items())})
        count, labels = connected_components(tree, directed=False)
    else:
        tree, rel = None, {}
        count, labels = n_tiles, np.arange(n_tiles)
    groups = [np.flatnonzero(labels == g) for g in range(count)]
    for group, (root, sign) in zip(groups, roots(groups)):
        signs[root] = sign
        if tree is None or group.size == 1:
            continue
        order, parent = breadth_first_order(tree, root, directed=False, return_predecessors=True)
        for t in order[1:]:
            signs[t] = signs[parent[t]] * rel[(int(parent[t]), int(t))]
    return signs


def disagreeing(overlaps, signs: np.ndarray, owner_of, normal_of) -> np.ndarray:
    """(k,) int64 ascending: the points whose normal, once every tile is turned by ``signs``, points
    one way in their own tile and the other way in a tile that holds them in its halo."""
    bad = []
    for ov in overlaps:
        if ov.ids.size == 0:
            continue
        owners = owner_of(ov.ids)
        cos = np.einsum("ij,ij->i", ov.normals, normal_of(ov.ids)) * signs[ov.tile] * signs[owners]
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
