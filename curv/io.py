"""Reading meshes (keeping polygons where the format has them) and writing coloured PLY files.

Readers: PLY through plyfile (polygons kept), OBJ through meshio and OFF (polygons kept), anything
else trimesh reads (STL, glTF/GLB, 3MF, ...) through trimesh (triangles). Every failure becomes a
:class:`LoadError` or :class:`MeshError` whose one-line message starts with the file name. Before a
library sees a file, :func:`curv.formats.guards.check_header` checks what its header promises
against its size, so that no header makes a reader allocate or loop beyond the file.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from .colors import colour_choice, map_colors
from .core.errors import LoadError, MeshError
from .core.mesh import Mesh
from .core.paths import check_readable as _check_path
from .core.paths import read_with
from .core.pointcloud import PointCloud
from .core.quantities import EXPORTED, STANDARD_ERRORS
from .formats.atomic import plain_mode
from .formats.guards import check_header, check_off_header, check_ply_header, read_ply_header
from .geometry.repair import repair
from .core.result import Curvature
from .core.validity import Reason, reason_legend

__all__ = ["load", "is_point_file", "save_ply", "save_vtu", "save_vtp", "save_result", "check_output_suffix", "OUTPUT_FORMATS",
           "read_arrays", "peek_counts"]

_MESHIO_SUFFIXES = {".obj"}


def _ply_header(fh) -> tuple[str, dict[str, int], dict[str, list[str]]]:
    """Format, element counts and list property names per element of the PLY header after the ``ply`` line."""
    header = read_ply_header(fh)
    return header.format, header.counts, {e.name: e.lists for e in header.elements}


def _ply_trailing_data(fh, fmt: str, header_end: int, counts: dict[str, int], position: int) -> bool:
    """True when the file holds more data than the header's element counts declare."""
    if fmt == "ascii":
        fh.seek(header_end)
        lines = [ln for ln in fh.read().split(b"\n") if ln.strip()]
        return len(lines) > sum(counts.values())
    fh.seek(position)
    return bool(fh.read(64).strip())


def _read_off(path: Path):
    """OFF / COFF / NOFF: vertices (extra per-vertex values ignored), polygons of any size."""
    text = path.read_bytes().decode("ascii", errors="strict")
    lines = [ln.split("#", 1)[0].split() for ln in text.splitlines()]
    lines = [ln for ln in lines if ln]
    if not lines or not lines[0][0].upper().endswith("OFF"):
        raise ValueError("no OFF keyword on the first line")
    head = lines[0][1:] or lines[1]
    body = lines[1:] if lines[0][1:] else lines[2:]
    if len(head) < 2:
        raise ValueError("missing vertex and face counts")
    nv, nf = int(head[0]), int(head[1])
    if len(body) < nv + nf:
        raise ValueError(f"header declares {nv} vertices and {nf} faces but the file ends after {len(body)} lines")
    if len(body) > nv + nf:
        raise ValueError(f"header declares {nv} vertices and {nf} faces but the file has {len(body)} data lines")
    vertices = np.array([ln[:3] for ln in body[:nv]], dtype=np.float64).reshape(-1, 3)
    faces = [np.array(ln[1:1 + int(ln[0])], dtype=np.int64) for ln in body[nv:]]
    bad = [i for i, (ln, f) in enumerate(zip(body[nv:], faces)) if f.size != int(ln[0])]
    if bad:
        raise ValueError(f"face {bad[0]} lists fewer indices than its count")
    if not faces:
        raise LoadError(f"{path}: has {nv} vertices but no faces; curv needs a mesh")
    return vertices, faces


def _read_ply(path: Path):
    from plyfile import PlyData, PlyElementParseError

    with open(path, "rb") as fh:
        fmt, counts, lists = _ply_header(fh)
        header_end = fh.tell()
        fh.seek(0)
        key = next((k for k in ("vertex_indices", "vertex_index") if k in lists.get("face", [])), None)
        data = None
        if fmt.startswith("binary") and key is not None and lists["face"] == [key]:
            # fast path: triangles memory-mapped as an (m, 3) array, no per-face Python objects
            try:
                data = PlyData.read(fh, known_list_len={"face": {key: 3}})
            except PlyElementParseError as exc:
                if "unexpected list length" not in str(exc):
                    raise
                fh.seek(0)
        if data is None:
            data = PlyData.read(fh)
        position = fh.tell() if not fh.closed else 0
    with open(path, "rb") as fh:
        if _ply_trailing_data(fh, fmt, header_end, counts, position):
            raise LoadError(f"{path}: holds more data than its header declares "
                            f"({', '.join(f'{n} {e}' for e, n in counts.items())}); the element counts are wrong")
        names = [e.name for e in data.elements]
        if "vertex" not in names:
            raise LoadError(f"{path}: PLY file has no vertex element")
        vert = data["vertex"].data
        missing = [c for c in "xyz" if c not in vert.dtype.names]
        if missing:
            raise LoadError(f"{path}: PLY vertices lack coordinate(s) {', '.join(missing)}")
        vertices = np.stack([np.asarray(vert[c], dtype=np.float64) for c in "xyz"], axis=1)
        if "face" not in names or len(data["face"].data) == 0:
            raise LoadError(f"{path}: has {len(vertices)} vertices but no faces (a point cloud?); curv needs a mesh")
        face = data["face"].data
        key = next((k for k in ("vertex_indices", "vertex_index") if k in face.dtype.names), None)
        if key is None:
            raise LoadError(f"{path}: PLY faces have no vertex_indices list")
        column = face[key]
        if column.dtype != object:
            return vertices, np.asarray(column)  # Mesh converts to int64 once, copying
        sizes = np.fromiter((len(p) for p in column), dtype=np.int64, count=len(column))
        if np.all(sizes == sizes[0]) and sizes[0] > 0:
            return vertices, np.stack(column).astype(np.int64)
        return vertices, list(column)


def _read_meshio(path: Path):
    import meshio

    m = meshio.read(path)
    polys = []
    for block in m.cells:
        data = block.data
        if block.type in ("vertex", "line"):
            continue
        if isinstance(data, np.ndarray) and data.ndim == 2:
            polys.extend(data)
        else:
            polys.extend(np.asarray(p) for p in data)
    if not polys:
        raise LoadError(f"{path}: has {len(m.points)} points but no faces; curv needs a mesh")
    pts = np.asarray(m.points, dtype=np.float64)
    if pts.ndim == 2 and pts.shape[1] == 2:
        pts = np.column_stack([pts, np.zeros(len(pts))])
    return pts, polys


def _read_trimesh(path: Path):
    import trimesh

    loaded = trimesh.load(path, force="mesh", process=False)
    faces = np.asarray(getattr(loaded, "faces", np.zeros((0, 3))))
    if faces.size == 0:
        raise LoadError(f"{path}: contains no faces")
    return np.asarray(loaded.vertices, dtype=np.float64), faces


def peek_counts(path) -> tuple[int, int] | None:
    """``(n_vertices, n_faces)`` from a PLY or OFF header without reading the data; None otherwise.

    Never raises: a file it cannot peek into gives None (:func:`load` then reports the problem).
    """
    path = Path(path)
    try:
        if path.suffix.lower() == ".ply":
            counts = check_ply_header(path).counts  # counts the file can hold, or a LoadError
            if "vertex" in counts:
                return counts["vertex"], counts.get("face", 0)
        elif path.suffix.lower() == ".off":
            check_off_header(path)
            with open(path, "rb") as fh:
                words = fh.read(4096).split()
            if words and words[0].upper().endswith(b"OFF") and len(words) >= 3:
                return int(words[1]), int(words[2])
    except (OSError, ValueError):  # LoadError is an OSError
        return None
    return None


def is_point_file(path) -> bool:
    """True when ``path`` holds a point cloud: a point-cloud suffix, or a PLY that declares no faces."""
    from .formats.pointio import POINT_SUFFIXES

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".ply" and path.is_file():
        counts = peek_counts(path)
        return counts is not None and counts[1] == 0
    return suffix in POINT_SUFFIXES


def read_arrays(path) -> tuple[np.ndarray, list | np.ndarray]:
    """Read raw ``(vertices (n, 3), faces)`` from a file without building a :class:`Mesh`.

    Raises
    ------
    LoadError
        Missing, unreadable, empty, malformed or face-less file, or a header that promises more
        than the file holds.
    """
    path = Path(path)
    _check_path(path)
    suffix = path.suffix.lower()
    reader = {".ply": _read_ply, ".off": _read_off}.get(suffix) or (
        _read_meshio if suffix in _MESHIO_SUFFIXES else _read_trimesh)

    def guarded(path: Path):
        check_header(path)
        return reader(path)

    return read_with(guarded, path, suffix.lstrip(".").upper() or "mesh")


def load(path, *, merge_vertices: bool = False, remove_degenerate: bool = False, orient: bool = False,
         remove_unreferenced: bool = False) -> Mesh | PointCloud:
    """Load a mesh or a point-cloud file.

    Parameters
    ----------
    path : str or Path
        PLY, OBJ, OFF (polygons kept) or anything trimesh reads (STL, glTF/GLB, ...); point clouds:
        a PLY without faces, ``.xyz`` / ``.txt`` / ``.csv``, PCD, LAS/LAZ (:func:`curv.formats.pointio.read_points`).
    merge_vertices : bool
        Merge vertices at identical positions.
    remove_degenerate : bool
        Drop faces with repeated vertices or zero area.
    orient : bool
        Make face orientation consistent within each component (closed components outward).
    remove_unreferenced : bool
        Drop vertices no face uses (renumbers the vertices).

    Returns
    -------
    Mesh or PointCloud
        ``mesh.info`` holds ``{"path": ..., "repairs": [human-readable lines]}``; a point cloud
        when the file has no faces.

    Raises
    ------
    LoadError
        The file cannot be read as a mesh or point cloud.
    MeshError
        The file was read but its data are malformed (message names the file and the problem), or
        a repair was asked of a point cloud.
    """
    from .formats.pointio import read_points

    path = Path(path)
    if is_point_file(path):
        asked = [name for name, on in (("merge_vertices", merge_vertices), ("remove_degenerate", remove_degenerate),
                                       ("orient", orient), ("remove_unreferenced", remove_unreferenced)) if on]
        if asked:
            raise MeshError(f"{path}: is a point cloud; {', '.join(asked)} repair(s) meshes only")
        return read_points(path)
    vertices, faces = read_arrays(path)
    try:
        mesh = Mesh(vertices, faces)
        mesh, repairs = repair(mesh, merge_vertices=merge_vertices, remove_degenerate=remove_degenerate,
                               orient=orient, remove_unreferenced=remove_unreferenced)
    except MeshError as exc:
        raise MeshError(f"{path}: {exc}") from None
    mesh.info.update(path=str(path), repairs=repairs)
    return mesh


_DIR_PROPS = tuple(f"d{i}{c}" for i in (1, 2) for c in "xyz")


def _float_props(curvature: Curvature) -> tuple[str, ...]:
    """The float fields an export writes: the standard errors only when they were computed."""
    return EXPORTED + (STANDARD_ERRORS if curvature.has_standard_errors else ())


_WRITE_BLOCK = 1 << 18
"""Vertex or face records per block written."""


def _write_face_lists(fh, mesh: Mesh) -> None:
    """Write the faces as binary little-endian PLY list records: a uchar count, then that many int32 indices.

    Triangles go as packed (count, 3 indices) records a block at a time. Other polygons are built in
    one go with numpy: face f's count byte sits at ``f + 4 * offset[f]`` and corner c's four index
    bytes right after the counts and corners before it, at ``corner_face[c] + 1 + 4 c``.
    """
    sizes = mesh.face_sizes
    if sizes.size and sizes.max() > 255:
        raise MeshError(f"a face has {int(sizes.max())} vertices; PLY lists here hold at most 255")
    if mesh.is_triangular:
        # one packed record per face (numpy's structured dtypes have no padding unless asked)
        triangles = mesh.face_indices.reshape(-1, 3)
        block = np.empty(min(mesh.n_faces, _WRITE_BLOCK), dtype=[("count", "u1"), ("corners", "<i4", (3,))])
        block["count"] = 3
        for lo in range(0, mesh.n_faces, _WRITE_BLOCK):
            rows = block[:min(mesh.n_faces - lo, _WRITE_BLOCK)]
            rows["corners"] = triangles[lo:lo + rows.size]
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
        comment = f"curvlab: {_result_label(curvature)}, colours given by the caller"
    colors = np.asarray(colors)
    if colors.shape != (n, 4):
        raise ValueError(f"colors must have shape ({n}, 4), got {colors.shape}")
    extra = dict(extra or {})
    fields = [(c, "f8") for c in "xyz"] + [(c, "u1") for c in ("red", "green", "blue", "alpha")]
    fields += [(c, "f4") for c in _float_props(curvature) + _DIR_PROPS] + [("valid", "u1"), ("reason", "u1")]
    fields += [(name, "f4") for name in extra]
    columns = {c: mesh.vertices[:, i] for i, c in enumerate("xyz")}
    columns.update({c: colors[:, i] for i, c in enumerate(("red", "green", "blue", "alpha"))})
    columns.update({name: getattr(curvature, name) for name in _float_props(curvature)})
    for i, c in enumerate("xyz"):
        columns[f"d1{c}"] = curvature.d1[:, i]
        columns[f"d2{c}"] = curvature.d2[:, i]
    columns["valid"] = curvature.valid
    columns["reason"] = np.asarray(curvature.reason)
    columns.update({name: np.asarray(values) for name, values in extra.items()})
    points_only = isinstance(mesh, PointCloud)
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

    return _atomic_write(path, write)


def _result_label(curvature: Curvature) -> str:
    from .core.ranges import range_label

    rng = curvature.range
    if curvature.info.get("range_label"):
        return f"{curvature.method} {curvature.info['range_label']}"
    label = range_label(rng) if isinstance(rng, (int, float, np.integer, np.floating)) else str(rng or "")
    return f"{curvature.method} {label}".strip()


def describe_colours(curvature: Curvature, field: str, cmap: str, clim: tuple[float, float]) -> str:
    """``curvlab: mru R2, colours show mean (coolwarm, limits -1.234 .. 1.234)``: the export comment."""
    return (f"curvlab: {_result_label(curvature)}, colours show {field} ({cmap}, "
            f"limits {clim[0]:.4g} .. {clim[1]:.4g})")


def _atomic_write(path: Path, write) -> Path:
    """Write through ``write(fh)`` into a temporary file beside ``path``, then rename it over ``path``.

    A failure never leaves a partial file; the result has the permissions of a plain write
    (``mkstemp`` creates 0600 files).
    """
    folder = path.parent if str(path.parent) else Path(".")
    mode = plain_mode(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=folder)
    try:
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fchmod(fh.fileno(), mode)
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


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
    return _atomic_write(Path(path), lambda fh: fh.write(payload))


def save_vtp(path, mesh: Mesh | PointCloud, curvature: Curvature, *, colors: np.ndarray | None = None,
             extra: dict[str, np.ndarray] | None = None) -> Path:
    """Write a VTK XML poly data file (``.vtp``): the points as ``Verts`` (point cloud) or faces as ``Polys``.

    The same point and field data as :func:`save_vtu`, encoded by meshio (which writes no
    ``.vtp`` itself: its unstructured-grid document is retagged as poly data).
    """
    payload = _as_poly_data(_vtk_document(path, mesh, curvature, colors=colors, extra=extra),
                            "Verts" if isinstance(mesh, PointCloud) else "Polys")
    return _atomic_write(Path(path), lambda fh: fh.write(payload))


def _vtk_document(path, mesh: Mesh | PointCloud, curvature: Curvature, *, colors, extra) -> bytes:
    """The VTU document (bytes) meshio writes for ``mesh`` and ``curvature``, with the reason field data."""
    import meshio

    path = Path(path)
    n = mesh.n_vertices
    if curvature.k1.shape[0] != n:
        raise MeshError(f"curvature has {curvature.k1.shape[0]} values but the mesh has {n} vertices")
    data = {name: np.asarray(getattr(curvature, name), np.float64) for name in _float_props(curvature)}
    data.update(d1=np.asarray(curvature.d1, np.float64), d2=np.asarray(curvature.d2, np.float64),
                valid=curvature.valid.astype(np.uint8), reason=np.asarray(curvature.reason, np.uint8))
    data.update({k: np.asarray(v, np.float64) for k, v in (extra or {}).items()})
    if colors is not None:
        data["rgba"] = np.ascontiguousarray(colors, dtype=np.uint8)
    if isinstance(mesh, PointCloud):
        data["normals"] = np.asarray(curvature.normals, np.float64)
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
    arrays = "".join(f'<DataArray type="Int32" Name="reason_{r.name}" NumberOfTuples="1" format="ascii">'
                     f"{int(r)}</DataArray>" for r in Reason)
    tag = b"<UnstructuredGrid>"
    at = vtu.index(tag) + len(tag)
    return vtu[:at] + f"\n<FieldData>{arrays}</FieldData>".encode("ascii") + vtu[at:]


OUTPUT_FORMATS = {".ply": "binary PLY with colours and curvature properties (vertex-only for points)",
                  ".vtu": "VTK XML unstructured grid with curvature point data (ParaView, pyvista)",
                  ".vtp": "VTK XML poly data, the same point data (points as vertices, faces as polygons)"}
"""Output suffixes ``save_result`` writes, each in its own format."""


def check_output_suffix(path) -> str:
    """The lower-case suffix of ``path`` if curvlab writes it; ``ValueError`` naming the ones it does."""
    suffix = Path(path).suffix.lower()
    if suffix not in OUTPUT_FORMATS:
        raise ValueError(f"{path}: cannot write {suffix or 'files without a suffix'}; "
                         f"use one of {', '.join(OUTPUT_FORMATS)}")
    return suffix


def save_result(path, mesh: Mesh | PointCloud, curvature: Curvature, **kw) -> Path:
    """Write ``curvature`` in the format of ``path``'s suffix (:data:`OUTPUT_FORMATS`).

    Keywords go to :func:`save_ply` (all of them) or :func:`save_vtu` / :func:`save_vtp`
    (``colors``, ``extra``).
    """
    suffix = check_output_suffix(path)
    if suffix in (".vtu", ".vtp"):
        kept = {k: v for k, v in kw.items() if k in ("colors", "extra")}
        if kept.get("colors") is None:
            q = kw.get("quantity", "mean")
            values = curvature.quantity(q)
            cmap, lim = colour_choice(values, curvature.valid, q, cmap=kw.get("cmap"), clim=kw.get("clim"))
            kept["colors"] = map_colors(values, cmap=cmap, clim=lim, valid=curvature.valid)
            kept["extra"] = {"shown": values, **(kept.get("extra") or {})}
        return (save_vtp if suffix == ".vtp" else save_vtu)(path, mesh, curvature, **kept)
    return save_ply(path, mesh, curvature, **kw)
