"""Writing a tiled run's PLY a block at a time: the file :func:`curv.save_ply` writes, for an input
that never was in memory whole.

The vertex records are :func:`curv.save_ply`'s (coordinates, colours, k1, k2, H, K, standard
errors, directions, valid, reason, the shown values, and for points the normals the estimate
used), then a mesh's faces copied from the input (a polygon mesh's polygons as they are, as
:func:`curv.save_ply` writes them: a uchar count, then that many int32 corners). The colours' limits are
:func:`curv.colors.colour_choice`'s, from the values of every ``stride``-th point when there are
more than :data:`LIMIT_SAMPLE` (robust percentiles hardly move; say so when comparing colours
with an in-memory export). Written atomically (:func:`curv.formats.atomic.atomic_path`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Generator

import numpy as np

from ..colors import colour_choice, map_colors
from ..core.quantities import compute
from ..core.result import Curvature
from ..core.validity import reason_legend
from ..formats.atomic import atomic_path

__all__ = ["iter_write_ply", "LIMIT_SAMPLE", "colour_limits", "face_records"]

LIMIT_SAMPLE = 4_000_000
"""Values the colour limits of a tiled PLY are chosen from, at most (every k-th point)."""

_BLOCK = 1 << 18


def colour_limits(n: int, read_block: Callable[[int, int], dict], quantity: str, cmap, clim):
    """``(cmap, (lo, hi))`` of :func:`curv.colors.colour_choice` over every ``stride``-th point's value
    (all of them up to :data:`LIMIT_SAMPLE`), read through ``read_block(start, stop)``."""
    stride = max(1, -(-n // LIMIT_SAMPLE))
    values, valid = [], []
    for start in range(0, n, _BLOCK * stride):
        stop = min(n, start + _BLOCK * stride)
        cols = read_block(start, stop)
        values.append(compute(quantity, cols["k1"], cols["k2"])[::stride])
        valid.append(np.asarray(cols["valid"])[::stride])
    return colour_choice(np.concatenate(values), np.concatenate(valid), quantity, cmap=cmap, clim=clim)


def face_records(faces: np.ndarray) -> np.ndarray:
    """The binary little-endian PLY list records of (m, k) faces padded with -1: (b,) uint8, each
    face a uchar count and that many int32 corners (:func:`curv.save_ply`'s records)."""
    real = faces >= 0
    sizes = real.sum(axis=1)
    flat = faces[real]  # row by row: each face's corners in order (the padding trails)
    h = flat.size
    offsets = np.cumsum(sizes) - sizes
    out = np.empty(faces.shape[0] + 4 * h, np.uint8)
    out[np.arange(faces.shape[0]) + 4 * offsets] = sizes
    first = np.repeat(np.arange(faces.shape[0]), sizes) + 1 + 4 * np.arange(h)
    out[first[:, None] + np.arange(4)] = flat.astype("<i4").view(np.uint8).reshape(h, 4)
    return out


def iter_write_ply(path, n: int, coordinates, open_rows, *, n_faces: int = 0, face_blocks=None, points: bool,
                   label: Curvature, quantity: str = "mean", cmap=None, clim=None,
                   face_width: int = 3) -> Generator[float, None, Path]:
    """Write the PLY (module notes) a block at a time: yields the fraction written, returns the path.

    Parameters
    ----------
    path : str or Path
    n : int
        Points (vertices).
    coordinates : callable
        ``coordinates(start, stop) -> (m, 3) float64``: the input's positions, in order.
    open_rows : callable
        ``open_rows()`` returns a new reader of the result rows (:class:`curv.tiles.merge.Rows`),
        read block by block in order: one for the colours' limits (when automatic), one to write.
    n_faces : int
    face_blocks : callable, optional
        ``face_blocks()`` yields a mesh's faces in order, (m, k) int blocks (-1 pads a polygon).
    points : bool
        A point cloud (its normals are written, and no face element).
    label : Curvature
        A result whose ``method``, ``range`` and ``info`` name the estimate in the header comment.
    quantity, cmap, clim
        As in :func:`curv.save_ply`.
    face_width : int
        The longest face's corners (k); at most 255, as :func:`curv.save_ply` writes.
    """
    from plyfile import PlyData, PlyElement

    from ..formats.plywrite import DIR_PROPS as _DIR_PROPS, describe_colours, float_props as _float_props

    if face_width > 255:
        from ..core.errors import MeshError

        raise MeshError(f"a face has {face_width} vertices; PLY lists here hold at most 255")
    float_props = _float_props(label)  # the standard errors only when the tiles computed them

    if clim is None:
        cmap, lim = colour_limits(n, open_rows().block, quantity, cmap, None)
    else:
        cmap, lim = colour_choice(np.empty(0), np.empty(0, bool), quantity, cmap=cmap, clim=clim)
    reader = open_rows()
    comment = describe_colours(label, quantity, cmap, lim) + "; property 'shown' holds it"
    fields = [(c, "f8") for c in "xyz"] + [(c, "u1") for c in ("red", "green", "blue", "alpha")]
    fields += [(c, "f4") for c in float_props + _DIR_PROPS] + [("valid", "u1"), ("reason", "u1"), ("shown", "f4")]
    if points:
        fields += [(f"n{c}", "f4") for c in "xyz"]
    face_kind = PlyElement.describe(np.empty(0, dtype=[("vertex_indices", "i4", (3,))]), "face",
                                    len_types={"vertex_indices": "u1"}, val_types={"vertex_indices": "i4"})
    face_kind.data = np.empty(n_faces, dtype=[("vertex_indices", "i4", (3,))])
    vertex_kind = PlyElement.describe(np.empty(0, dtype=fields), "vertex")
    vertex_kind.data = np.empty(n, dtype=fields)
    ply = PlyData([vertex_kind] if points else [vertex_kind, face_kind], text=False, byte_order="<",
                  comments=[" ".join(comment.split()), reason_legend()])
    header = ply.header.encode("ascii", errors="replace") + b"\n"
    record = np.dtype([(name, np.dtype(kind).newbyteorder("<")) for name, kind in fields])
    path = Path(path)
    total = n + n_faces
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(header)
            block = np.empty(min(n, _BLOCK), dtype=record)
            for lo in range(0, n, _BLOCK):
                hi = min(n, lo + _BLOCK)
                rows = block[:hi - lo]
                xyz = coordinates(lo, hi)
                cols = reader.block(lo, hi)
                for i, c in enumerate("xyz"):
                    rows[c] = xyz[:, i]
                values = compute(quantity, cols["k1"], cols["k2"])
                colors = map_colors(values, cmap=cmap, clim=lim, valid=cols["valid"])
                for i, c in enumerate(("red", "green", "blue", "alpha")):
                    rows[c] = colors[:, i]
                for name in float_props:
                    rows[name] = compute(name, cols["k1"], cols["k2"]) if name in ("mean", "gaussian") else cols[name]
                for i, c in enumerate("xyz"):
                    rows[f"d1{c}"] = cols["d1"][:, i]
                    rows[f"d2{c}"] = cols["d2"][:, i]
                    if points:
                        rows[f"n{c}"] = cols["normals"][:, i]
                rows["valid"] = cols["valid"]
                rows["reason"] = cols["reason"]
                rows["shown"] = values
                fh.write(memoryview(rows).cast("B"))
                yield hi / max(total, 1)
            if face_blocks is not None:
                tri = np.empty(_BLOCK, dtype=[("count", "u1"), ("corners", "<i4", (3,))])
                tri["count"] = 3
                done = n
                for chunk in face_blocks():
                    for lo in range(0, chunk.shape[0], _BLOCK):
                        part = chunk[lo:lo + _BLOCK]
                        if part.shape[1] != 3:
                            fh.write(memoryview(face_records(part)))
                            continue
                        rows = tri[:part.shape[0]]
                        rows["corners"] = part
                        fh.write(memoryview(rows).cast("B"))
                    done += chunk.shape[0]
                    yield done / max(total, 1)
    return path
