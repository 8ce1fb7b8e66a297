"""Writing a result as VTK XML (``.vtu`` unstructured grid, ``.vtp`` poly data) through meshio
(below :mod:`curv.io`): the curvature as point data, the reason codes as field data."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from ..core.errors import MeshError
from ..core.mesh import Mesh
from ..core.pointcloud import PointCloud
from ..core.result import Curvature
from ..core.support import support_of
from ..core.validity import Reason
from .atomic import atomic_write
from .plywrite import float_props

__all__ = ["save_vtu", "save_vtp", "point_arrays", "point_values", "reason_field_data", "VTK_CELL_TYPES"]

VTK_CELL_TYPES = {"vertex": 1, "triangle": 5, "polygon": 7, "quad": 9}
"""VTK's cell type codes of the cells a result is written with (a point cloud's points are vertex cells)."""


def point_arrays(curvature: Curvature, *, points: bool, extra=(), colors: bool = True) -> list[tuple[str, str, int]]:
    """The point arrays of a VTK file of ``curvature``, in the order :func:`save_vtu` writes them.

    The one list both writers follow (this module's through meshio, and a tiled run's
    :mod:`curv.tiles.vtkout`, which writes the file a block at a time).

    Parameters
    ----------
    curvature : Curvature
        Says whether the standard errors were computed (:func:`curv.formats.plywrite.float_props`).
    points : bool
        A point cloud: its ``normals`` (the ones the estimate used) are written too.
    extra : sequence of str
        Names of more float arrays (e.g. ``shown``), after ``reason``.
    colors : bool
        The ``rgba`` colours are written.

    Returns
    -------
    list of (name, numpy dtype string, components)
        ``k1``, ``k2``, ``mean``, ``gaussian``, ``k1_se``, ``k2_se`` (when computed) float64;
        ``d1``, ``d2`` float64 (3 components); ``valid``, ``reason`` uint8; ``extra`` float64;
        ``rgba`` uint8 (4); ``normals`` float64 (3) for a point cloud.
    """
    fields = [(name, "<f8", 1) for name in float_props(curvature)]
    fields += [("d1", "<f8", 3), ("d2", "<f8", 3), ("valid", "u1", 1), ("reason", "u1", 1)]
    fields += [(name, "<f8", 1) for name in extra]
    if colors:
        fields.append(("rgba", "u1", 4))
    if points:
        fields.append(("normals", "<f8", 3))
    return fields


def point_values(fields: list[tuple[str, str, int]], columns: dict) -> dict[str, np.ndarray]:
    """The arrays of ``fields`` (:func:`point_arrays`) from ``columns`` (name -> (m,) or (m, c)
    values, ``valid`` bool or uint8), each contiguous in its VTK dtype."""
    return {name: np.ascontiguousarray(columns[name], dtype=np.dtype(kind)) for name, kind, _ in fields}


def reason_field_data() -> str:
    """The ``<FieldData>`` block naming the reason codes (``reason_BORDER`` = 1, ...), as XML text."""
    arrays = "".join(f'<DataArray type="Int32" Name="reason_{r.name}" NumberOfTuples="1" format="ascii">'
                     f"{int(r)}</DataArray>" for r in Reason)
    return f"<FieldData>{arrays}</FieldData>"


def save_vtu(path, mesh: Mesh | PointCloud, curvature: Curvature, *, colors: np.ndarray | None = None,
             extra: dict[str, np.ndarray] | None = None) -> Path:
    """Write a VTK XML unstructured grid (``.vtu``, through meshio) with the curvature as point data.

    Parameters
    ----------
    path : str or Path
    mesh : Mesh or PointCloud
        Triangles, quads and other polygons become VTK triangle, quad and polygon cells; a point
        cloud's points become vertex cells.
    curvature : Curvature
    colors : (n, 4) uint8, optional
        Stored as the ``rgba`` point array (the colours on screen).
    extra : dict of str -> (n,) float, optional
        More point arrays (e.g. ``error_rel``).

    Returns
    -------
    Path
        Point data: ``k1``, ``k2``, ``mean``, ``gaussian``, ``k1_se``, ``k2_se`` (when computed) (n,), ``d1``, ``d2`` (n, 3),
        ``valid`` and ``reason`` (n,) uint8, ``extra``, ``rgba``; a point cloud also ``normals`` (n, 3),
        the ones the estimate used; field data ``reason_OK``, ``reason_BORDER``, ... hold each
        :class:`curv.Reason` code; written atomically like :func:`save_ply`.
    """
    payload = _vtk_document(path, mesh, curvature, colors=colors, extra=extra)
    return atomic_write(Path(path), lambda fh: fh.write(payload))


def save_vtp(path, mesh: Mesh | PointCloud, curvature: Curvature, *, colors: np.ndarray | None = None,
             extra: dict[str, np.ndarray] | None = None) -> Path:
    """Write a VTK XML poly data file (``.vtp``): the points as ``Verts`` (point cloud) or faces as ``Polys``.

    The same point and field data as :func:`save_vtu`, encoded by meshio (which writes no
    ``.vtp`` itself: its unstructured-grid document is retagged as poly data).
    """
    payload = _as_poly_data(_vtk_document(path, mesh, curvature, colors=colors, extra=extra),
                            "Polys" if support_of(mesh).has_faces else "Verts")
    return atomic_write(Path(path), lambda fh: fh.write(payload))


def _vtk_document(path, mesh: Mesh | PointCloud, curvature: Curvature, *, colors, extra) -> bytes:
    """The VTU document (bytes) meshio writes for ``mesh`` and ``curvature``, with the reason field data."""
    import meshio

    path = Path(path)
    n = mesh.n_vertices
    if curvature.k1.shape[0] != n:
        raise MeshError(f"curvature has {curvature.k1.shape[0]} values but the mesh has {n} vertices")
    points = not support_of(mesh).has_faces
    columns = {name: getattr(curvature, name) for name in float_props(curvature)}
    columns.update(d1=curvature.d1, d2=curvature.d2, valid=curvature.valid, reason=curvature.reason,
                   normals=curvature.normals, rgba=colors)
    columns.update(extra or {})
    data = point_values(point_arrays(curvature, points=points, extra=tuple(extra or ()), colors=colors is not None),
                        columns)
    if points:  # vertex cells (the normals the estimate used are in point_arrays)
        cells = [("vertex", np.arange(n, dtype=np.int64)[:, None])]
    else:
        cells = []
        sizes = mesh.face_sizes
        kinds = {3: "triangle", 4: "quad"}
        for size in np.unique(sizes):
            rows = np.flatnonzero(sizes == size)
            corners = mesh.face_offsets[rows][:, None] + np.arange(size)
            cells.append((kinds.get(int(size), "polygon"), mesh.face_indices[corners]))
    grid = meshio.Mesh(np.asarray(mesh.vertices, np.float64), cells, point_data=data)
    with tempfile.TemporaryDirectory(dir=path.parent if str(path.parent) else ".") as tmp_dir:
        staged = Path(tmp_dir) / "out.vtu"
        meshio.write(staged, grid, file_format="vtu")
        return _with_reason_field_data(staged.read_bytes())


def _as_poly_data(vtu: bytes, cells: str) -> bytes:
    """meshio's VTU document as a VTP one: the grid's cells become ``Verts`` or ``Polys``.

    Poly data keeps the cells' connectivity and offsets arrays and has no cell types; every other
    array (points, point data, field data) is the same XML. Tags are found as text: base64 and
    ASCII data never hold ``<``.
    """
    import re

    def swap(text: bytes, old: bytes, new: bytes, *, last: bool = False) -> bytes:
        at = text.rfind(old) if last else text.find(old)
        if at < 0:
            raise RuntimeError(f"unexpected VTU layout from meshio: no {old.decode()}")
        return text[:at] + new + text[at + len(old):]

    piece = re.search(rb'<Piece NumberOfPoints="(\d+)" NumberOfCells="(\d+)">', vtu)
    start, stop = vtu.find(b"<Cells>"), vtu.find(b"</Cells>")
    if piece is None or start < 0 or stop < start:
        raise RuntimeError("unexpected VTU layout from meshio: no Piece or Cells")
    counts = " ".join(f'NumberOf{k}="{piece[2].decode() if k == cells else 0}"'
                      for k in ("Verts", "Lines", "Strips", "Polys"))
    block, dropped = re.subn(rb'<DataArray[^>]*Name="types".*?</DataArray>\s*', b"", vtu[start + 7:stop], flags=re.S)
    if dropped != 1:
        raise RuntimeError("unexpected VTU layout from meshio: no cell types array")
    vtu = (vtu[:piece.start()] + f'<Piece NumberOfPoints="{piece[1].decode()}" {counts}>'.encode()
           + vtu[piece.end():start] + f"<{cells}>".encode() + block + f"</{cells}>".encode()
           + vtu[stop + 8:])
    vtu = swap(vtu, b'type="UnstructuredGrid"', b'type="PolyData"')
    vtu = swap(vtu, b"<UnstructuredGrid>", b"<PolyData>")
    return swap(vtu, b"</UnstructuredGrid>", b"</PolyData>", last=True)


def _with_reason_field_data(vtu: bytes) -> bytes:
    """The VTU document with a ``<FieldData>`` block naming the reason codes (``reason_BORDER`` = 1, ...).

    meshio writes no field data to VTU, so the block goes in by hand, right after the grid's opening tag.
    """
    tag = b"<UnstructuredGrid>"
    at = vtu.index(tag) + len(tag)
    return vtu[:at] + f"\n{reason_field_data()}".encode("ascii") + vtu[at:]
