"""A corpus of bad and awkward mesh files, generated in code (issue 5).

:func:`write_corpus` writes every case into a folder and returns :class:`Case` descriptors that say
what ``curv.load`` + ``curv.estimate`` must do with it: give a result (``"ok"``) whose masks are
honest, or raise :class:`curv.LoadError` / :class:`curv.MeshError` with a one-line message naming
the file and the problem.

The meshes are small (a few hundred vertices) so that every case runs through every estimator and
range in seconds. Most defects are planted in an icosphere of radius 1, whose exact curvature
(k1 = k2 = 1) lets the tests catch made-up values at vertices marked valid.
"""

from __future__ import annotations

import atexit
import functools
import os
import shutil
import tempfile
import stat
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import trimesh

OK, LOAD_ERROR, MESH_ERROR = "ok", "load_error", "mesh_error"


@dataclass
class Case:
    """One corpus file and what must happen to it.

    Attributes
    ----------
    name : str
        Short identifier (test id).
    path : Path
        The file (or folder) to load.
    outcome : {"ok", "load_error", "mesh_error"}
        What ``curv.load`` must do (with ``load_kwargs``).
    message : str
        For errors: a lower-case fragment the message must contain (besides the file name).
    load_kwargs : dict
        Repairs to request.
    triangles : bool
        Every face is a triangle (triangle-only estimators must work; else they raise MeshError).
    radius : (n,) float or None
        Where the mesh samples spheres: the radius of the sphere at each vertex (NaN where it
        does not). Valid k1, k2 there must be close to 1 / radius.
    invalid : (n,) bool or None
        Vertices that every estimator must mark invalid (isolated, all-border meshes, ...).
    report : dict
        Expected :class:`curv.MeshReport` fields.
    repairs : tuple of str
        Lines expected in ``mesh.info["repairs"]``.
    same_as : str or None
        Name of a case whose result this one must reproduce (after repair), up to ``scale``.
    scale : float
        Length scale relative to ``same_as``: curvatures must be ``1 / scale`` times its values.
    as_root : bool
        False when the case cannot be set up for the root user (file permissions).
    """

    name: str
    path: Path
    outcome: str
    message: str = ""
    load_kwargs: dict = field(default_factory=dict)
    triangles: bool = True
    radius: np.ndarray | None = None
    invalid: np.ndarray | None = None
    report: dict = field(default_factory=dict)
    repairs: tuple = ()
    same_as: str | None = None
    scale: float = 1.0
    as_root: bool = True
    description: str = ""

    def __str__(self) -> str:
        return self.name


# ---------------------------------------------------------------------------- geometry
def _sphere(subdivisions: int = 2, radius: float = 1.0):
    tm = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return np.asarray(tm.vertices, float), np.asarray(tm.faces, np.int64)


def _torus_polygons(n_major: int = 16, n_minor: int = 10, R: float = 2.0, r: float = 0.75):
    """Closed torus of quads, with every few cell pairs turned into a pentagon + a triangle."""
    i, j = np.meshgrid(np.arange(n_major), np.arange(n_minor), indexing="ij")
    theta, phi = 2 * np.pi * i.ravel() / n_major, 2 * np.pi * j.ravel() / n_minor
    ring = R + r * np.cos(phi)
    v = np.stack([ring * np.cos(theta), ring * np.sin(theta), r * np.sin(phi)], axis=1)

    def vid(a, b):
        return (a % n_major) * n_minor + b % n_minor

    faces, used = [], np.zeros((n_major, n_minor), bool)
    for a in range(0, n_major, 4):          # small fixed loops over the pattern, not over vertices
        for b in range(0, n_minor - 1, 3):
            q0, q1, q2, q3 = vid(a, b), vid(a + 1, b), vid(a + 1, b + 1), vid(a, b + 1)
            c2, c3 = vid(a + 1, b + 2), vid(a, b + 2)
            faces += [[q0, q1, q2, c2, q3], [q3, c2, c3]]
            used[a, b] = used[a, b + 1] = True
    ii, jj = np.nonzero(~used)
    quads = np.stack([vid(ii, jj), vid(ii + 1, jj), vid(ii + 1, jj + 1), vid(ii, jj + 1)], axis=1)
    return v, [list(q) for q in quads] + faces


def _saddle_quads(n: int = 9):
    """Open grid of non-planar quads on z = x^2 - y^2 over [-0.5, 0.5]^2."""
    x, y = np.meshgrid(np.linspace(-0.5, 0.5, n), np.linspace(-0.5, 0.5, n), indexing="ij")
    v = np.stack([x.ravel(), y.ravel(), (x**2 - y**2).ravel()], axis=1)
    i, j = np.meshgrid(np.arange(n - 1), np.arange(n - 1), indexing="ij")
    a = (i * n + j).ravel()
    return v, np.stack([a, a + n, a + n + 1, a + 1], axis=1)


def _edge_with_faces(faces: np.ndarray, pick: int = 0):
    """An interior edge (a, b) of a closed triangle mesh and its two faces (a->b in f_ab)."""
    f = faces[pick]
    a, b = int(f[0]), int(f[1])
    rows = np.flatnonzero((faces == b).any(1) & (faces == a).any(1))
    other = int(rows[rows != pick][0])
    return a, b, pick, other


# ---------------------------------------------------------------------------- writers
def _write_ply(path: Path, vertices, faces, *, text: bool = False, byte_order: str = "<") -> Path:
    from plyfile import PlyData, PlyElement

    vertices = np.asarray(vertices, float)
    vert = np.empty(len(vertices), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    for k, c in enumerate("xyz"):
        vert[c] = vertices[:, k]
    face = np.empty(len(faces), dtype=[("vertex_indices", object)])
    face["vertex_indices"] = [np.asarray(f, dtype=np.int32) for f in faces]
    PlyData([PlyElement.describe(vert, "vertex"),
             PlyElement.describe(face, "face", len_types={"vertex_indices": "u1"},
                                 val_types={"vertex_indices": "i4"})],
            text=text, byte_order=byte_order).write(str(path))
    return path


def _ascii_ply(path: Path, vertices, faces, *, n_vertices=None, n_faces=None) -> Path:
    """Hand-written ASCII PLY (so counts in the header can lie and values can be nan/inf)."""
    lines = ["ply", "format ascii 1.0",
             f"element vertex {len(vertices) if n_vertices is None else n_vertices}",
             "property float x", "property float y", "property float z",
             f"element face {len(faces) if n_faces is None else n_faces}",
             "property list uchar int vertex_indices", "end_header"]
    lines += [" ".join(repr(float(c)) for c in p) for p in vertices]
    lines += [" ".join(str(int(i)) for i in [len(f), *f]) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def _write_obj(path: Path, vertices, faces) -> Path:
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, float).tolist()]
    lines += ["f " + " ".join(str(int(i) + 1) for i in f) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


def _write_off(path: Path, vertices, faces) -> Path:
    lines = ["OFF", f"{len(vertices)} {len(faces)} 0"]
    lines += [f"{x!r} {y!r} {z!r}" for x, y, z in np.asarray(vertices, float).tolist()]
    lines += [" ".join(str(int(i)) for i in [len(f), *f]) for f in faces]
    path.write_text("\n".join(lines) + "\n")
    return path


# ---------------------------------------------------------------------------- the corpus
def write_corpus(folder) -> list[Case]:
    """Write every case into ``folder`` (created if needed); return the descriptors.

    Parameters
    ----------
    folder : str or Path

    Returns
    -------
    list of Case
        At least 30 cases, each with a distinct file.
    """
    d = Path(folder)
    d.mkdir(parents=True, exist_ok=True)
    cases: list[Case] = []
    sv, sf = _sphere()
    n = len(sv)
    ones = np.ones(n)

    def add(case: Case) -> None:
        cases.append(case)

    # --- clean references -----------------------------------------------------------------
    add(Case("sphere", _write_ply(d / "sphere.ply", sv, sf), OK, radius=ones,
             report=dict(vertices=n, faces=len(sf), components=1, border_edges=0),
             description="clean closed icosphere, radius 1"))
    add(Case("sphere_ascii", _write_ply(d / "sphere_ascii.ply", sv, sf, text=True), OK, radius=ones,
             same_as="sphere", description="the same sphere as ASCII PLY"))
    add(Case("sphere_big_endian", _write_ply(d / "sphere_be.ply", sv, sf, byte_order=">"), OK, radius=ones,
             same_as="sphere", description="binary big-endian PLY"))
    add(Case("sphere_obj", _write_obj(d / "sphere.obj", sv, sf), OK, radius=ones, same_as="sphere",
             description="OBJ"))
    add(Case("sphere_off", _write_off(d / "sphere.off", sv, sf), OK, radius=ones, same_as="sphere",
             description="OFF"))

    # --- files that are not meshes ---------------------------------------------------------
    (d / "empty.ply").write_bytes(b"")
    add(Case("empty_file", d / "empty.ply", LOAD_ERROR, "empty", description="zero bytes"))
    # A PLY without faces (no face element, or an empty one) is a point cloud, not a bad mesh:
    # tests/test_points_io.py reads both kinds.
    full = _write_ply(d / "full.bin", sv, sf).read_bytes()
    (d / "truncated.ply").write_bytes(full[: int(len(full) * 0.6)])
    add(Case("truncated_binary", d / "truncated.ply", LOAD_ERROR, "not a readable ply",
             description="binary PLY cut at 60 %"))
    (d / "truncated_header.ply").write_bytes(full[:40])
    add(Case("truncated_header", d / "truncated_header.ply", LOAD_ERROR, "not a readable ply",
             description="binary PLY cut inside its header"))
    add(Case("ascii_count_too_high", _ascii_ply(d / "count_high.ply", sv, sf, n_vertices=n + 40),
             LOAD_ERROR, "not a readable ply", description="header claims 40 more vertices than written"))
    add(Case("ascii_count_too_low", _ascii_ply(d / "count_low.ply", sv, sf, n_faces=len(sf) - 7),
             LOAD_ERROR, "more data than its header declares", description="header claims 7 fewer faces than written"))
    (d / "picture.ply").write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(range(256)) * 8)
    add(Case("not_a_mesh", d / "picture.ply", LOAD_ERROR, "not a readable ply",
             description="PNG bytes with a .ply suffix"))
    (d / "notes.obj").write_text("this is a shopping list\nmilk\neggs\n")
    add(Case("text_as_obj", d / "notes.obj", LOAD_ERROR, "", description="plain text with an .obj suffix"))
    (d / "folder.ply").mkdir(exist_ok=True)
    add(Case("directory", d / "folder.ply", LOAD_ERROR, "directory", description="a folder named .ply"))
    add(Case("missing", d / "missing.ply", LOAD_ERROR, "no such file", description="path that does not exist"))
    locked = _write_ply(d / "locked.ply", sv, sf)
    os.chmod(locked, 0)
    add(Case("unreadable", locked, LOAD_ERROR, "permission denied", as_root=False,
             description="file with mode 000"))

    # --- malformed data --------------------------------------------------------------------
    bad = sv.copy()
    bad[17, 1] = np.nan
    add(Case("nan_coordinate", _ascii_ply(d / "nan.ply", bad, sf), MESH_ERROR, "vertex 17 has a nan",
             description="one NaN coordinate"))
    bad = sv.copy()
    bad[5, 2] = np.inf
    bad[9, 0] = -np.inf
    add(Case("inf_coordinate", _ascii_ply(d / "inf.ply", bad, sf), MESH_ERROR, "vertex 5 has an infinite",
             description="two infinite coordinates"))
    f = sf.copy()
    f[12, 1] = n + 3
    add(Case("index_out_of_range", _ascii_ply(d / "index_high.ply", sv, f), MESH_ERROR,
             f"face 12 refers to vertex {n + 3}", description="a face refers past the last vertex"))
    f = sf.copy()
    f[30, 2] = -4
    add(Case("negative_index", _ascii_ply(d / "index_negative.ply", sv, f), MESH_ERROR,
             "face 30 has a negative vertex index -4", description="a negative face index"))
    add(Case("two_vertex_face", _ascii_ply(d / "edge_face.ply", sv, [*sf.tolist(), [0, 1]]), MESH_ERROR,
             f"face {len(sf)} has 2 vertices", description="a 'face' with 2 indices"))
    add(Case("obj_index_out_of_range", _write_obj(d / "index_high.obj", sv, [*sf.tolist(), [0, 1, n + 9]]),
             MESH_ERROR, "refers to vertex", description="OBJ face past the last vertex"))

    # --- degenerate faces in an otherwise fine sphere --------------------------------------
    a, b, fa, fb = _edge_with_faces(sf)
    add(Case("repeated_index", _write_ply(d / "repeated.ply", sv, [*sf.tolist(), [a, a, b]]), OK,
             radius=ones, report=dict(degenerate_faces=1),
             description="an extra face (a, a, b) with a repeated index"))
    add(Case("repeated_index_removed", d / "repeated.ply", OK, load_kwargs=dict(remove_degenerate=True),
             radius=ones, repairs=("removed 1 degenerate faces",), same_as="sphere",
             description="the same, with remove_degenerate"))
    # zero-area sliver: split face fa = (a, b, c) at the midpoint m of (a, b) and close the T-junction
    # with the collinear triangle (a, b, m): manifold, consistently oriented, area exactly 0.
    c = int(sf[fa][2])
    m = len(sv)
    v2 = np.vstack([sv, 0.5 * (sv[a] + sv[b])])
    f2 = np.vstack([np.delete(sf, fa, axis=0), [[a, m, c], [m, b, c], [a, b, m]]])
    r2 = np.append(ones, np.nan)
    add(Case("zero_area", _write_ply(d / "zero_area.ply", v2, f2), OK, radius=r2,
             report=dict(degenerate_faces=1, border_edges=0, nonmanifold_edges=0),
             description="a collinear sliver closing a T-junction"))
    # needles: a full edge split at a point very close to a
    f3 = np.vstack([np.delete(sf, [fa, fb], axis=0)])
    d_ = [int(x) for x in sf[fb] if x not in (a, b)][0]
    for eps, tag in ((1e-7, "needle"), (1e-3, "thin")):
        p3 = sv[a] + eps * (sv[b] - sv[a])
        v3 = np.vstack([sv, p3 / np.linalg.norm(p3)])   # on the sphere: the surface stays exact
        faces3 = np.vstack([f3, [[a, m, c], [m, b, c], [b, m, d_], [m, a, d_]]])
        add(Case(f"{tag}_triangles", _write_ply(d / f"{tag}.ply", v3, faces3), OK, radius=np.append(ones, 1.0),
                 description=f"edge split at {eps:g} of its length: two needle/cap triangles"))
    # a mesh that is all degenerate: every vertex on one line
    line = np.stack([np.linspace(0, 1, 6), np.zeros(6), np.zeros(6)], axis=1)
    add(Case("all_collinear", _ascii_ply(d / "collinear.ply", line, [[0, 1, 2], [2, 3, 4], [1, 3, 5]]), OK,
             invalid=np.ones(6, bool), report=dict(degenerate_faces=3),
             description="every face has zero area"))

    # --- duplicates and unused vertices ----------------------------------------------------
    soup_v = sv[sf.reshape(-1)]
    soup_f = np.arange(soup_v.shape[0]).reshape(-1, 3)
    add(Case("triangle_soup", _write_ply(d / "soup.ply", soup_v, soup_f), OK,
             invalid=np.ones(len(soup_v), bool), report=dict(components=len(sf)),
             description="every face has its own three vertices (STL-like)"))
    add(Case("triangle_soup_merged", d / "soup.ply", OK, load_kwargs=dict(merge_vertices=True),
             radius=ones, repairs=(f"merged {len(soup_v) - n} duplicate vertices",),
             report=dict(vertices=n, components=1, border_edges=0),
             description="the same, with merge_vertices"))
    stl = d / "sphere.stl"
    trimesh.Trimesh(sv, sf, process=False).export(stl)
    add(Case("stl_soup", stl, OK, invalid=np.ones(3 * len(sf), bool),
             description="binary STL: no shared vertices unless merged"))
    add(Case("stl_merged", stl, OK, load_kwargs=dict(merge_vertices=True), radius=ones,
             repairs=(f"merged {len(soup_v) - n} duplicate vertices",),
             description="binary STL with merge_vertices"))
    # duplicates along a seam: faces with x > 0 use copies of the vertices they share with x <= 0
    right = sv[sf].mean(axis=1)[:, 0] > 0
    seam = np.unique(sf[right]).tolist()
    seam = np.intersect1d(seam, np.unique(sf[~right]))
    copy_of = np.full(n, -1)
    copy_of[seam] = n + np.arange(seam.size)
    f4 = sf.copy()
    sub = f4[right]
    f4[right] = np.where(copy_of[sub] >= 0, copy_of[sub], sub)
    v4 = np.vstack([sv, sv[seam]])
    add(Case("duplicate_seam", _write_ply(d / "seam.ply", v4, f4), OK, radius=np.ones(len(v4)),
             report=dict(border_loops=2),
             description=f"{seam.size} vertices duplicated along a seam (cut into two open halves)"))
    add(Case("duplicate_seam_merged", d / "seam.ply", OK, load_kwargs=dict(merge_vertices=True),
             radius=ones, repairs=(f"merged {seam.size} duplicate vertices",), report=dict(border_edges=0),
             description="the same, merged"))
    rng = np.random.default_rng(5)
    extra = rng.normal(size=(7, 3)) * 3
    iso = np.zeros(n + 7, bool)
    iso[n:] = True
    add(Case("isolated_vertices", _write_ply(d / "isolated.ply", np.vstack([sv, extra]), sf), OK,
             radius=np.append(ones, np.full(7, np.nan)), invalid=iso, report=dict(isolated_vertices=7),
             description="7 stray points no face uses"))
    # unreferenced vertices first: every index shifts by 40 (a common export bug)
    v5 = np.vstack([rng.normal(size=(40, 3)), sv])
    unref = np.zeros(n + 40, bool)
    unref[:40] = True
    add(Case("unreferenced_vertices", _write_ply(d / "unreferenced.ply", v5, sf + 40), OK,
             radius=np.append(np.full(40, np.nan), ones), invalid=unref,
             description="40 unused vertices before the used ones"))
    add(Case("unreferenced_removed", d / "unreferenced.ply", OK, load_kwargs=dict(remove_unreferenced=True),
             radius=ones, repairs=("removed 40 unreferenced vertices",), same_as="sphere",
             description="the same, with remove_unreferenced"))
    collapsed = np.vstack([sv, [[3.0, 0, 0]]])
    add(Case("collapsed_face", _write_ply(d / "collapsed.ply", collapsed, [*sf.tolist(), [n, n, n]]), OK,
             radius=np.append(ones, np.nan), invalid=np.append(np.zeros(n, bool), True),
             report=dict(degenerate_faces=1),
             description="a vertex used only by the face (v, v, v)"))

    # --- topology ---------------------------------------------------------------------------
    fin = np.vstack([sv, 1.5 * (sv[a] + sv[b]) / 2])
    add(Case("nonmanifold_edge", _write_ply(d / "fin.ply", fin, [*sf.tolist(), [a, b, n]]), OK,
             radius=np.append(ones, np.nan), report=dict(nonmanifold_edges=1),
             description="a fin triangle on a sphere edge: 3 faces on one edge"))
    top = int(np.argmax(sv[:, 2]))
    shift = sv[top] - (-sv[top])      # second sphere's bottom pole lands on the first sphere's top pole
    v6 = np.vstack([sv, sv + shift])
    f6 = np.vstack([sf, sf + n])
    bottom2 = int(np.argmin(sv[:, 2])) + n
    f6[f6 == bottom2] = top
    v6[bottom2] = 1e3                  # unused afterwards; far away
    r6 = np.append(ones, ones)
    r6[bottom2] = np.nan
    add(Case("bowtie_vertex", _write_ply(d / "bowtie.ply", v6, f6), OK, radius=r6,
             report=dict(nonmanifold_vertices=1, nonmanifold_edges=0, isolated_vertices=1),
             description="two spheres sharing one vertex"))
    flip = rng.random(len(sf)) < 0.15
    f7 = np.where(flip[:, None], sf[:, ::-1], sf)
    add(Case("inconsistent_orientation", _write_ply(d / "flipped.ply", sv, f7), OK,
             description="15 % of the faces reversed"))
    add(Case("inconsistent_orientation_oriented", d / "flipped.ply", OK, load_kwargs=dict(orient=True),
             radius=ones, repairs=(f"flipped {int(flip.sum())} faces to a consistent orientation",),
             same_as="sphere", description="the same, with orient"))
    add(Case("inside_out", _write_ply(d / "inside_out.ply", sv, sf[:, ::-1]), OK, radius=-ones,
             description="a sphere with every face reversed (normals point in: curvature -1)"))
    add(Case("inside_out_oriented", d / "inside_out.ply", OK, load_kwargs=dict(orient=True), radius=ones,
             same_as="sphere", repairs=(f"flipped {len(sf)} faces to a consistent orientation",),
             description="the same, with orient (closed: turned outward)"))
    sv2, sf2 = _sphere(2, radius=2.0)
    v8 = np.vstack([sv, sv2 + [5.0, 0, 0]])
    add(Case("two_components", _write_ply(d / "two.ply", v8, np.vstack([sf, sf2 + n])), OK,
             radius=np.append(ones, np.full(len(sv2), 2.0)), report=dict(components=2),
             description="spheres of radius 1 and 2"))
    add(Case("single_triangle", _ascii_ply(d / "triangle.ply", np.eye(3), [[0, 1, 2]]), OK,
             invalid=np.ones(3, bool), report=dict(faces=1, border_edges=3),
             description="one triangle: no estimator can fit a surface"))
    tet = np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], float)
    add(Case("tetrahedron", _ascii_ply(d / "tetra.ply", tet, [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]]),
             OK, report=dict(border_edges=0, components=1), description="closed tetrahedron"))
    holes = rng.choice(len(sf), 6, replace=False)
    add(Case("holes", _write_ply(d / "holes.ply", sv, np.delete(sf, holes, axis=0)), OK, radius=ones,
             description="sphere with 6 faces removed"))
    v9, f9 = _torus_polygons()
    add(Case("mixed_polygons", _write_ply(d / "mixed.ply", v9, f9), OK, triangles=False,
             report=dict(border_edges=0), description="torus of quads, pentagons and triangles"))
    add(Case("mixed_polygons_obj", _write_obj(d / "mixed.obj", v9, f9), OK, triangles=False,
             same_as="mixed_polygons", description="the same as OBJ"))
    add(Case("mixed_polygons_off", _write_off(d / "mixed.off", v9, f9), OK, triangles=False,
             same_as="mixed_polygons", description="the same as OFF"))
    v10, f10 = _saddle_quads()
    add(Case("nonplanar_quads", _write_ply(d / "saddle.ply", v10, f10), OK, triangles=False,
             description="quads on z = x^2 - y^2 (none planar)"))

    # --- scale -------------------------------------------------------------------------------
    for s, tag in ((1e-6, "tiny"), (1e6, "huge")):
        add(Case(f"{tag}_scale", _write_ply(d / f"{tag}.ply", sv * s, sf), OK, radius=ones * s,
                 same_as="sphere", scale=s, description=f"the sphere scaled by {s:g}"))
    add(Case("far_from_origin", _write_ply(d / "far.ply", sv + 1e4, sf), OK, radius=ones,
             description="the sphere translated by 1e4 (cancellation in differences)"))
    return cases


def restore_permissions(cases: list[Case]) -> None:
    """Make every corpus file removable again (tmp-dir cleanup)."""
    for case in cases:
        if case.path.is_file():
            os.chmod(case.path, stat.S_IRUSR | stat.S_IWUSR)


def as_root() -> bool:
    """True when running as root (file permissions do not apply)."""
    return hasattr(os, "geteuid") and os.geteuid() == 0


@functools.lru_cache(maxsize=1)
def session_corpus() -> tuple[Case, ...]:
    """The corpus written once per process into a temporary folder (removed at exit)."""
    folder = Path(tempfile.mkdtemp(prefix="curv-corpus-"))
    cases = tuple(write_corpus(folder))

    def cleanup():
        restore_permissions(list(cases))
        shutil.rmtree(folder, ignore_errors=True)

    atexit.register(cleanup)
    return cases
