"""Writing a result as a binary PLY with vertex colours and curvature properties (below :mod:`curv.io`).

The vertex records and (on an input with faces) the face lists go a block at a time, so a large
file never holds all of them at once; the file is written atomically
(:func:`curv.formats.atomic.atomic_write`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..colors import colour_choice, map_colors
from ..core.errors import MeshError
from ..core.mesh import Mesh
from ..core.pointcloud import PointCloud
from ..core.quantities import EXPORTED, STANDARD_ERRORS
from ..core.result import Curvature
from ..core.support import support_of
from ..core.validity import reason_legend
from .atomic import atomic_write

__all__ = ["save_ply", "describe_colours", "result_label", "float_props", "DIR_PROPS"]

DIR_PROPS = tuple(f"d{i}{c}" for i in (1, 2) for c in "xyz")


def float_props(curvature: Curvature) -> tuple[str, ...]:
    """The float fields an export writes: the standard errors only when they were computed."""
    return EXPORTED + (STANDARD_ERRORS if curvature.has_standard_errors else ())


_WRITE_BLOCK = 1 << 18
"""Vertex or face records per block written."""


def _write_face_lists(fh, mesh: Mesh) -> None:
    """Write the faces as binary little-endian PLY list records: a uchar count, then that many int32 indices.

    Faces of one size (triangles, an all-quad mesh) go as packed (count, k indices) records a block
    at a time. Mixed polygons are built in one go with numpy: face f's count byte sits at
    ``f + 4 * offset[f]`` and corner c's four index bytes right after the counts and corners before
    it, at ``corner_face[c] + 1 + 4 c``.
    """
    sizes = mesh.face_sizes
    if sizes.size and sizes.max() > 255:
        raise MeshError(f"a face has {int(sizes.max())} vertices; PLY lists here hold at most 255")
    k = int(sizes[0]) if sizes.size else 3
    if (sizes == k).all():
        # one packed record per face (numpy's structured dtypes have no padding unless asked)
        faces = mesh.face_indices.reshape(-1, k)
        block = np.empty(min(mesh.n_faces, _WRITE_BLOCK), dtype=[("count", "u1"), ("corners", "<i4", (k,))])
        block["count"] = k
        for lo in range(0, mesh.n_faces, _WRITE_BLOCK):
            rows = block[:min(mesh.n_faces - lo, _WRITE_BLOCK)]
            rows["corners"] = faces[lo:lo + rows.size]
            fh.write(memoryview(rows).cast("B"))
        return
    offsets = mesh.face_offsets[:-1]
    h = mesh.face_indices.size
    out = np.empty(mesh.n_faces + 4 * h, np.uint8)
    out[np.arange(mesh.n_faces) + 4 * offsets] = sizes
    index_bytes = mesh.face_indices.astype("<i4").view(np.uint8).reshape(h, 4)
    first = mesh.corner_face + 1 + 4 * np.arange(h)
    out[first[:, None] + np.arange(4)] = index_bytes
    fh.write(memoryview(out))


def save_ply(path, mesh: Mesh | PointCloud, curvature: Curvature, *, quantity: str = "mean", cmap: str | None = None,
             clim: tuple[float, float] | None = None, colors: np.ndarray | None = None,
             extra: dict[str, np.ndarray] | None = None, comment: str | None = None) -> Path:
    """Write a binary PLY with vertex colours and curvature properties, atomically.

    Parameters
    ----------
    path : str or Path
        Output file; written to a temporary file in the same folder, then renamed, so a failure
        never leaves a partial file.
    mesh : Mesh or PointCloud
        A point cloud is written as a vertex-only PLY (no face element) that also holds ``nx``,
        ``ny``, ``nz``: the normals the estimate used, so that the file reads back with them.
    curvature : Curvature
        Values at the mesh vertices (the points).
    quantity : str
        What the colours show (``mean``, ``gaussian``, ``k1``, ``k2``, ``shape_index``, ``curvedness``).
    cmap : str, optional
        matplotlib colour map; default diverging for signed quantities, sequential otherwise.
    clim : (lo, hi), optional
        Colour limits; default symmetric 2-98 % percentiles for signed quantities.
    colors : (n, 4) uint8, optional
        Colours to write as they are (the viewer passes what it shows); overrides quantity/cmap/clim.
    extra : dict of str -> (n,) float, optional
        More float vertex properties (e.g. ``error_rel``).
    comment : str, optional
        The header comment saying what the colours show; default names the quantity, the
        estimator, the range, the colour map and the limits (pass your own when ``colors`` show
        something else, as the viewer does).

    Returns
    -------
    Path
        The written file, with the permissions a plain ``open(path, "w")`` would give. Properties: x, y, z, red, green, blue, alpha (uchar), k1, k2, mean,
        gaussian, k1_se, k2_se (when computed), d1x..d1z, d2x..d2z (float), valid and reason (uchar; a second header comment
        names the :class:`curv.Reason` codes), ``shown`` (the coloured values, when the colours
        come from ``quantity``), plus ``extra``; faces as ``vertex_indices`` lists.
    """
    from plyfile import PlyData, PlyElement

    path = Path(path)
    n = mesh.n_vertices
    if curvature.k1.shape[0] != n:
        raise MeshError(f"curvature has {curvature.k1.shape[0]} values but the mesh has {n} vertices")
    if colors is None:
        values = curvature.quantity(quantity)
        cmap, lim = colour_choice(values, curvature.valid, quantity, cmap=cmap, clim=clim)
        colors = map_colors(values, cmap=cmap, clim=lim, valid=curvature.valid)
        extra = {"shown": values, **(extra or {})}
        if comment is None:
            comment = describe_colours(curvature, quantity, cmap, lim) + "; property 'shown' holds it"
    elif comment is None:
        comment = f"curvlab: {result_label(curvature)}, colours given by the caller"
    colors = np.asarray(colors)
    if colors.shape != (n, 4):
        raise ValueError(f"colors must have shape ({n}, 4), got {colors.shape}")
    extra = dict(extra or {})
    fields = [(c, "f8") for c in "xyz"] + [(c, "u1") for c in ("red", "green", "blue", "alpha")]
    fields += [(c, "f4") for c in float_props(curvature) + DIR_PROPS] + [("valid", "u1"), ("reason", "u1")]
    fields += [(name, "f4") for name in extra]
    columns = {c: mesh.vertices[:, i] for i, c in enumerate("xyz")}
    columns.update({c: colors[:, i] for i, c in enumerate(("red", "green", "blue", "alpha"))})
    columns.update({name: getattr(curvature, name) for name in float_props(curvature)})
    for i, c in enumerate("xyz"):
        columns[f"d1{c}"] = curvature.d1[:, i]
        columns[f"d2{c}"] = curvature.d2[:, i]
    columns["valid"] = curvature.valid
    columns["reason"] = np.asarray(curvature.reason)
    columns.update({name: np.asarray(values) for name, values in extra.items()})
    points_only = not support_of(mesh).has_faces
    if points_only:  # the normals the estimate used, so that the file reads back with them
        fields += [(f"n{c}", "f4") for c in "xyz"]
        columns.update({f"n{c}": curvature.normals[:, i] for i, c in enumerate("xyz")})
    # plyfile describes both elements (the header); empty elements of the right kinds stand in,
    # because plyfile writes list properties one face at a time (20 s at 1M faces)
    face_kind = PlyElement.describe(np.empty(0, dtype=[("vertex_indices", "i4", (3,))]), "face",
                                    len_types={"vertex_indices": "u1"}, val_types={"vertex_indices": "i4"})
    face_kind.data = np.empty(0 if points_only else mesh.n_faces, dtype=[("vertex_indices", "i4", (3,))])
    vertex_kind = PlyElement.describe(np.empty(0, dtype=fields), "vertex")
    vertex_kind.data = np.empty(n, dtype=fields)  # only its length and dtype are read: no memory is touched
    ply = PlyData([vertex_kind] if points_only else [vertex_kind, face_kind], text=False, byte_order="<",
                  comments=[" ".join(comment.split()), reason_legend()])
    header = ply.header.encode("ascii", errors="replace") + b"\n"
    record = np.dtype([(name, np.dtype(kind).newbyteorder("<")) for name, kind in fields])

    def write(fh):
        fh.write(header)
        # the vertex records a block at a time: a 10M-vertex file never holds all of them at once
        block = np.empty(min(n, _WRITE_BLOCK), dtype=record)
        for lo in range(0, n, _WRITE_BLOCK):
            rows = block[:min(n - lo, _WRITE_BLOCK)]
            for name, values in columns.items():
                rows[name] = values[lo:lo + rows.size]
            fh.write(memoryview(rows).cast("B"))
        if not points_only:
            _write_face_lists(fh, mesh)

    return atomic_write(path, write)


def result_label(curvature: Curvature) -> str:
    from ..core.ranges import range_label

    rng = curvature.range
    if curvature.info.get("range_label"):
        return f"{curvature.method} {curvature.info['range_label']}"
    label = range_label(rng) if isinstance(rng, (int, float, np.integer, np.floating)) else str(rng or "")
    return f"{curvature.method} {label}".strip()


def describe_colours(curvature: Curvature, field: str, cmap: str, clim: tuple[float, float]) -> str:
    """``curvlab: mru R2, colours show mean (coolwarm, limits -1.234 .. 1.234)``: the export comment."""
    return (f"curvlab: {result_label(curvature)}, colours show {field} ({cmap}, "
            f"limits {clim[0]:.4g} .. {clim[1]:.4g})")
