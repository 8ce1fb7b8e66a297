"""The orientation across the tiles of a file run (:mod:`curv.tiles.orient`'s rule), read tile by tile
from the scratch folder.

What it needs of the finished tiles: every tile's halo normals (its ``overlap`` file: the votes),
and of the points those halos hold, their own tile's normal, part and reason code. The overlap
files are read one at a time whenever they are needed (the votes, the points that still disagree),
and each tile's rows once in turn, keeping only those points: 37 bytes for each point some halo
holds (about a quarter of the points at tiles of a million), where reading every tile's rows and
halos at once held about 4 GB at 100M points. The roots of the groups of parts
(:func:`curv.tiles.orient.group_roots`) read the tiles' points and rows once more, one tile at a
time.
"""

from __future__ import annotations

import numpy as np

from .orient import Overlap, Parts, disagreeing, group_roots, part_signs
from .scratch import Scratch, point_dtype, read_rows

__all__ = ["file_part_signs"]


def file_part_signs(scratch: Scratch, n_tiles: int, has_normals: bool, orient: str):
    """Signs of the tiles' parts and the undecided points of a run oriented along spanning trees.

    Parameters
    ----------
    scratch : Scratch
        The run's folder, every tile finished (rows, overlap and points files).
    n_tiles : int
    has_normals : bool
        The tiles' point records carry the input's normals (:func:`curv.tiles.scratch.point_dtype`).
    orient : {"top", "outward"}

    Returns
    -------
    parts : Parts
    signs : (P,) int64
        +1 or -1 for each part of each tile.
    undecided : (k,) int64
        Ascending: the points whose two parts still disagree.
    was : (k,) uint8
        Their reason codes before.
    """
    def overlaps():
        for t in range(n_tiles):
            seen = read_rows(scratch.overlap_path(t))
            yield Overlap(t, seen["id"], seen["normal"], seen["part"])

    halo_parts = np.zeros(n_tiles, np.int64)
    seen_ids = []
    for ov in overlaps():
        halo_parts[ov.tile] = int(ov.parts.max(initial=-1)) + 1
        seen_ids.append(np.unique(ov.ids))
    wanted = np.unique(np.concatenate(seen_ids)) if seen_ids else np.empty(0, np.int64)
    del seen_ids
    node_at = np.full(wanted.size, -1, np.int64)
    normal_at = np.full((wanted.size, 3), np.nan, np.float32)
    reason_at = np.zeros(wanted.size, np.uint8)
    counts = np.zeros(n_tiles, np.int64)
    for t in range(n_tiles):
        rows = read_rows(scratch.rows_path(t))
        counts[t] = max(int(rows["part"].max(initial=-1)) + 1, int(halo_parts[t]))
        base = int(counts[:t].sum())
        at = np.minimum(np.searchsorted(wanted, rows["id"]), max(wanted.size - 1, 0))
        hit = np.flatnonzero(wanted[at] == rows["id"]) if wanted.size else np.empty(0, np.int64)
        node_at[at[hit]] = base + rows["part"][hit]
        normal_at[at[hit]] = rows["normals"][hit]
        reason_at[at[hit]] = rows["reason"][hit]
        del rows
    if (node_at < 0).any():
        raise RuntimeError("a tile's halo holds a point no tile's core holds (a bug in the plan)")
    parts = Parts(counts)

    def where(ids):
        return np.searchsorted(wanted, ids)

    def owner_of(ids):
        return node_at[where(ids)]

    def normal_of(ids):
        return normal_at[where(ids)].astype(np.float64)

    dtype = point_dtype(has_normals)

    def chunks():
        for t in range(n_tiles):
            rows = read_rows(scratch.rows_path(t))
            xyz = scratch.read_points(t, dtype)["xyz"]  # ascending numbers, as the rows
            yield parts.of(t, rows["part"]), xyz, rows["rooting"].astype(np.float64)

    signs = part_signs(parts, overlaps, owner_of, normal_of, lambda group: group_roots(group, orient, chunks))
    bad = disagreeing(overlaps, parts, signs, owner_of, normal_of)
    return parts, signs, bad, reason_at[where(bad)]
