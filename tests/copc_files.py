"""A small COPC file written in code, for the tests (laspy reads COPC but does not write it).

:func:`write_copc` lays points on an octree as the COPC specification asks (copc.io): each point
in one node of some level (a node's cube holds it), each node one variable-size LAZ chunk
(lazrs), the COPC info VLR first, the hierarchy in an EVLR. Good enough for readers
(laspy's ``CopcReader`` and chunked reader, :mod:`curv.tiles.copc`), not a writer for users: a
point's level is drawn at random (each level four times as likely as the one above), not thinned
by spacing.
"""

from __future__ import annotations

import struct

import numpy as np

__all__ = ["write_copc"]


def write_copc(path, points: np.ndarray, normals: np.ndarray | None = None, *, scale: float = 1e-3,
               levels: int = 4, seed: int = 0) -> None:
    """Write ``points`` (n, 3) (and ``normals`` as the extra bytes ``nx``, ``ny``, ``nz``) to a COPC file."""
    import laspy
    import lazrs
    from laspy.vlrs.vlrlist import VLRList

    rng = np.random.default_rng(seed)
    points = np.asarray(points, np.float64)
    n = points.shape[0]
    lo, hi = points.min(axis=0), points.max(axis=0)
    half = float((hi - lo).max()) / 2.0 * 1.01 + scale
    centre = (lo + hi) / 2.0
    # a surface: each level holds about four times the points of the one above (as a spacing halved)
    share = 4.0 ** np.arange(levels + 1)
    level = rng.choice(levels + 1, size=n, p=share / share.sum())
    side = 2.0 * half / 2.0 ** level
    key = np.floor((points - (centre - half)) / side[:, None]).astype(np.int64)
    key = np.clip(key, 0, (2 ** level - 1)[:, None])
    order = np.lexsort((rng.permutation(n), key[:, 2], key[:, 1], key[:, 0], -level))  # deep nodes first

    header = laspy.LasHeader(point_format=6, version="1.4")
    if normals is not None:
        header.add_extra_dims([laspy.ExtraBytesParams(c, "f8") for c in ("nx", "ny", "nz")])
    header.scales = np.full(3, scale)
    header.offsets = np.floor(lo)
    las = laspy.LasData(header)
    las.x, las.y, las.z = points[order].T
    if normals is not None:
        las.nx, las.ny, las.nz = np.asarray(normals, np.float64)[order].T
    las.update_header()
    header = las.header
    raw = las.points.array
    node_keys = np.stack([level[order], *key[order].T], axis=1)
    cuts = np.flatnonzero((np.diff(node_keys, axis=0) != 0).any(axis=1)) + 1
    bounds = np.concatenate([[0], cuts, [n]])

    extra = header.point_format.num_extra_bytes
    laz = lazrs.LazVlr.new_for_compression(6, extra, True)
    info = laspy.VLR("copc", 1, "copc info", b"\0" * 160)
    header.vlrs = VLRList([info, laspy.VLR("laszip encoded", 22204, "lazrs", bytes(laz.record_data())),
                                 *[v for v in header.vlrs if v.user_id != "copc"]])
    header.set_compressed(True)
    with open(path, "w+b") as fh:
        header.write_to(fh)
        start = fh.tell()
        compressor = lazrs.LasZipCompressor(fh, laz)
        compressor.compress_chunks([raw[a:b].tobytes() for a, b in zip(bounds[:-1], bounds[1:])])
        compressor.done()
        end = fh.tell()
        fh.seek(start)
        table = lazrs.read_chunk_table(fh, laz)
        sizes = np.array([size for _, size in table], np.int64)
        offsets = start + 8 + np.concatenate([[0], np.cumsum(sizes)[:-1]])
        entries = b"".join(struct.pack("<iiiiQii", *map(int, node_keys[a]), int(o), int(s), int(b - a))
                           for a, b, o, s in zip(bounds[:-1], bounds[1:], offsets, sizes))
        # every ancestor of a node is in the hierarchy (empty ones with no points): readers walk down
        have = {tuple(map(int, node_keys[a])) for a in bounds[:-1]}
        empty = set()
        for d, x, y, z in have:
            while d > 0:
                d, x, y, z = d - 1, x >> 1, y >> 1, z >> 1
                if (d, x, y, z) not in have:
                    empty.add((d, x, y, z))
        entries += b"".join(struct.pack("<iiiiQii", *k, 0, 0, 0) for k in sorted(empty))
        fh.seek(end)
        fh.write(struct.pack("<H16sHQ32s", 0, b"copc", 1000, len(entries), b"EPT hierarchy"))
        fh.write(entries)
        header.start_of_first_evlr, header.number_of_evlrs = end, 1
        info.record_data = struct.pack("<5d2Q2d88x", *centre, half, half / 64.0, end + 60, len(entries), 0.0, 0.0)
        fh.seek(0)
        header.write_to(fh, ensure_same_size=True)
