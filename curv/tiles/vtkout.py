"""Writing a tiled run's VTK XML file (``.vtu`` unstructured grid, ``.vtp`` poly data) a block at a
time: the arrays :func:`curv.save_vtu` and :func:`curv.save_vtp` write, for an input that never was
in memory whole.

meshio builds the whole document in memory (every array base64-encoded and compressed before the
first byte is written), so it cannot stream. This writes VTK's own binary layout instead: the XML
header, then ``<AppendedData encoding="raw">`` holding each array as a UInt64 byte count followed by
its little-endian bytes. Every array's size follows from the point count, the face count and (for
polygons) the faces of each size, so the header, which gives every array's offset, goes first. The
arrays lie in the reverse of the header's order, which VTK does not mind and meshio's raw reader
needs (``_layout``).

Each array is contiguous, and a block of result rows holds a slice of all of them: the writer reads
the rows once and puts each block's slice of each array at its place in the file (a seek per array
and block). Reading the rows again for every array instead (a pass per field, each written in
order) took 2.1-2.3 s against 0.6-0.8 s for the seeks on a 1M-point cloud of 6 tiles
(docs/BENCHMARKS.md, "A tiled run's VTU/VTP output").

The arrays are :func:`curv.formats.vtkwrite.point_arrays`' (names, dtypes and order, ``shown``
and ``rgba`` as :func:`curv.save_result` adds them), the field data its ``reason_*`` codes
(:func:`curv.formats.vtkwrite.reason_field_data`). Cells as :func:`curv.save_vtu` makes them: a point
cloud's points are vertex cells (VTU) or ``Verts`` (VTP); a mesh's faces go grouped by their corner
count, smallest first (triangles, quads, then the polygons of each size), each group in the input's
order, as ``triangle``, ``quad`` and ``polygon`` cells (VTU) or ``Polys`` (VTP). The colours' limits
are :func:`curv.tiles.plyout.colour_limits`' (sampled above
:data:`curv.tiles.plyout.LIMIT_SAMPLE` points). Written atomically
(:func:`curv.formats.atomic.atomic_path`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Generator

import numpy as np

from ..colors import colour_choice, map_colors
from ..core.quantities import compute
from ..core.result import Curvature
from ..formats.atomic import atomic_path
from ..formats.plywrite import describe_colours
from ..formats.vtkwrite import VTK_CELL_TYPES, point_arrays, point_values, reason_field_data
from .plyout import colour_limits

__all__ = ["iter_write_vtk"]

_BLOCK = 1 << 18
"""Points (or faces) per block written."""

_VTK_TYPES = {"<f8": "Float64", "<i8": "Int64", "u1": "UInt8"}

_COUNT = np.dtype("<u8")
"""The byte count before each appended array (``header_type="UInt64"``: arrays over 4 GiB)."""


@dataclass
class _Array:
    """One appended array: its XML attributes, its size and where its byte count starts."""

    name: str
    kind: str
    components: int
    rows: int
    offset: int = 0

    @property
    def nbytes(self) -> int:
        return self.rows * self.components * np.dtype(self.kind).itemsize

    def xml(self) -> str:
        parts = f'<DataArray type="{_VTK_TYPES[self.kind]}" Name="{self.name}"'
        if self.components > 1:
            parts += f' NumberOfComponents="{self.components}"'
        return parts + f' format="appended" offset="{self.offset}"/>'


def cell_groups(n: int, face_blocks, face_width: int, *, points: bool) -> list[tuple[int, int]]:
    """``(corners, cells)`` per group of cells, in the order they are written (module notes).

    A point cloud is one group of ``n`` one-corner cells; a triangle mesh one group of triangles;
    wider faces are counted in a pass over ``face_blocks()`` ((m, k) int blocks, -1 padding).
    """
    if points:
        return [(1, n)]
    counts = np.zeros(max(face_width, 3) + 1, np.int64)
    for chunk in face_blocks():
        counts += np.bincount((chunk >= 0).sum(axis=1), minlength=counts.size)
    return [(int(size), int(c)) for size, c in enumerate(counts) if c]


def _layout(n: int, groups, fields, *, poly: bool) -> list[_Array]:
    """The appended arrays in file order, each with the offset of its byte count."""
    cells = sum(c for _, c in groups)
    corners = sum(size * c for size, c in groups)
    arrays = [_Array("Points", "<f8", 3, n), _Array("connectivity", "<i8", 1, corners), _Array("offsets", "<i8", 1, cells)]
    if not poly:  # Int64 as meshio writes them (save_vtu's file)
        arrays.append(_Array("types", "<i8", 1, cells))
    arrays += [_Array(name, kind, width, n) for name, kind, width in fields]
    # the data in the reverse of the header's order: meshio's raw reader finds each array by its
    # offset while renaming the offsets it has done to base64 ones, and a renamed one earlier in the
    # header can match a later array's offset; done last-first, the array with the offset comes first
    at = 0
    for array in reversed(arrays):
        array.offset = at
        at += _COUNT.itemsize + array.nbytes
    return arrays


def _header(n: int, groups, arrays: list[_Array], *, poly: bool, points: bool, comment: str) -> bytes:
    """The XML before the appended data, ending with its opening ``_``."""
    cells = sum(c for _, c in groups)
    kind = "PolyData" if poly else "UnstructuredGrid"
    if poly:
        section = "Verts" if points else "Polys"
        counts = " ".join(f'NumberOf{k}="{cells if k == section else 0}"' for k in ("Verts", "Lines", "Strips", "Polys"))
    else:
        section, counts = "Cells", f'NumberOfCells="{cells}"'
    xml = {a.name: a.xml() for a in arrays}
    cell_names = ("connectivity", "offsets") + (() if poly else ("types",))
    text = "\n".join([
        '<?xml version="1.0"?>',
        f'<VTKFile type="{kind}" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
        f"<!--{comment.replace('--', '-')}-->",
        f"<{kind}>",
        reason_field_data(),
        f'<Piece NumberOfPoints="{n}" {counts}>',
        f"<Points>{xml['Points']}</Points>",
        f"<{section}>" + "".join(xml[c] for c in cell_names) + f"</{section}>",
        "<PointData>" + "".join(a.xml() for a in arrays[len(cell_names) + 1:]) + "</PointData>",
        "</Piece>",
        f"</{kind}>",
        '<AppendedData encoding="raw">',
        "_",
    ])
    return text.encode("ascii", errors="replace")


def _block_columns(cols: dict, quantity: str, cmap, lim) -> dict:
    """A block's columns under :func:`curv.formats.vtkwrite.point_arrays`' names: the rows' own,
    H and K from k1 and k2 (as in memory), the shown values and their colours."""
    values = compute(quantity, cols["k1"], cols["k2"])
    out = dict(cols)
    out.update(mean=compute("mean", cols["k1"], cols["k2"]), gaussian=compute("gaussian", cols["k1"], cols["k2"]),
               shown=values, rgba=map_colors(values, cmap=cmap, clim=lim, valid=cols["valid"]))
    return out


def iter_write_vtk(path, n: int, coordinates: Callable[[int, int], np.ndarray], open_rows, *, face_blocks=None,
                   points: bool, label: Curvature, quantity: str = "mean", cmap=None, clim=None, face_width: int = 3,
                   poly: bool | None = None) -> Generator[float, None, Path]:
    """Write the VTU or VTP (module notes) a block at a time: yields the fraction written, returns the path.

    Parameters
    ----------
    path : str or Path
        ``.vtu`` or ``.vtp`` (``poly`` says which when given).
    n : int
        Points (vertices).
    coordinates : callable
        ``coordinates(start, stop) -> (m, 3) float64``: the input's positions, in order.
    open_rows : callable
        ``open_rows()`` returns a new reader of the result rows (:class:`curv.tiles.merge.Rows`),
        read block by block in order: one for the colours' limits (when automatic), one to write.
    face_blocks : callable, optional
        ``face_blocks()`` yields a mesh's faces in order, (m, k) int blocks (-1 pads a polygon);
        called twice when ``face_width`` > 3 (the faces of each size are counted first).
    points : bool
        A point cloud (its normals are written, its points are the cells).
    label : Curvature
        A result whose ``method``, ``range``, ``info`` and standard errors name the estimate.
    quantity, cmap, clim
        What the ``rgba`` colours and the ``shown`` array show, as in :func:`curv.save_result`.
    face_width : int
        The longest face's corners (k).
    poly : bool, optional
        Write VTP poly data; default from the suffix.
    """
    path = Path(path)
    poly = path.suffix.lower() == ".vtp" if poly is None else poly
    if clim is None:
        cmap, lim = colour_limits(n, open_rows().block, quantity, cmap, None)
    else:
        cmap, lim = colour_choice(np.empty(0), np.empty(0, bool), quantity, cmap=cmap, clim=clim)
    fields = point_arrays(label, points=points, extra=("shown",))
    groups = cell_groups(n, face_blocks, face_width, points=points)
    arrays = _layout(n, groups, fields, poly=poly)
    at = {a.name: a for a in arrays}
    comment = describe_colours(label, quantity, cmap, lim) + "; point array 'shown' holds it"
    header = _header(n, groups, arrays, poly=poly, points=points, comment=comment)
    n_faces = 0 if points else sum(c for _, c in groups)
    total = max(n + n_faces, 1)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as fh:
            fh.write(header)
            base = len(header)

            def put(name: str, row: int, values: np.ndarray) -> None:
                """``values`` (rows ``row``.. of array ``name``) at their place in the file."""
                array = at[name]
                step = array.components * np.dtype(array.kind).itemsize
                fh.seek(base + array.offset + _COUNT.itemsize + row * step)
                fh.write(memoryview(np.ascontiguousarray(values, array.kind)).cast("B"))

            for array in arrays:
                fh.seek(base + array.offset)
                fh.write(np.array(array.nbytes, _COUNT).tobytes())
            reader = open_rows()
            for lo in range(0, n, _BLOCK):
                hi = min(n, lo + _BLOCK)
                put("Points", lo, coordinates(lo, hi))
                columns = _block_columns(reader.block(lo, hi), quantity, cmap, lim)
                for name, values in point_values(fields, columns).items():
                    put(name, lo, values)
                if points:  # each point a vertex cell, as save_vtu makes them
                    put("connectivity", lo, np.arange(lo, hi))
                    put("offsets", lo, np.arange(lo + 1, hi + 1))
                    if not poly:
                        put("types", lo, np.full(hi - lo, VTK_CELL_TYPES["vertex"]))
                yield hi / total
            if not points:
                yield from _write_faces(put, face_blocks, groups, n, total, poly=poly)
            fh.seek(base + arrays[0].offset + _COUNT.itemsize + arrays[0].nbytes)
            # meshio's raw reader drops what follows the data's last newline: the newline ends the data
            fh.write(b"\n</AppendedData>\n</VTKFile>\n")
    return path


def _write_faces(put, face_blocks, groups, n: int, total: int, *, poly: bool):
    """The faces, from ``face_blocks()`` in order, into each size group's cells (module notes):
    connectivity, offsets (where each cell's corners end) and the cell types (VTU)."""
    first_cell, first_corner, done = {}, {}, {}
    cell = corner = 0
    for size, count in groups:
        first_cell[size], first_corner[size], done[size] = cell, corner, 0
        cell += count
        corner += size * count
    kinds = {3: "triangle", 4: "quad"}
    written = n
    for chunk in face_blocks():
        sizes = (chunk >= 0).sum(axis=1)
        for size in np.unique(sizes):
            size = int(size)
            faces = chunk[sizes == size, :size]  # the padding trails each face's corners
            m, j = faces.shape[0], done[size]
            put("connectivity", first_corner[size] + size * j, faces)
            put("offsets", first_cell[size] + j, first_corner[size] + size * np.arange(j + 1, j + m + 1))
            if not poly:
                put("types", first_cell[size] + j, np.full(m, VTK_CELL_TYPES[kinds.get(size, "polygon")]))
            done[size] = j + m
        written += chunk.shape[0]
        yield written / total
