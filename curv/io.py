"""Reading meshes and point clouds, writing results: the file formats' public face.

:func:`load` reads a mesh (:mod:`curv.formats.meshread`: PLY, OBJ and OFF with their polygons,
anything else trimesh reads) or a point cloud (:mod:`curv.formats.pointio`); :func:`save_result`
writes a result by its suffix (:data:`OUTPUT_FORMATS`): a coloured binary PLY
(:mod:`curv.formats.plywrite`) or VTK XML (:mod:`curv.formats.vtkwrite`), each atomically. Every
failure to read becomes a :class:`LoadError` or :class:`MeshError` whose one-line message starts
with the file name.
"""

from __future__ import annotations

from pathlib import Path

from .colors import colour_choice, map_colors
from .core.errors import MeshError
from .core.mesh import Mesh
from .core.pointcloud import PointCloud
from .core.result import Curvature
from .formats.meshread import is_point_file, peek_counts, read_arrays
from .formats.plywrite import describe_colours, save_ply  # noqa: F401 (describe_colours: a name curv.io has always offered)
from .formats.vtkwrite import save_vtp, save_vtu
from .geometry.repair import repair

__all__ = ["load", "is_point_file", "save_ply", "save_vtu", "save_vtp", "save_result", "check_output_suffix", "OUTPUT_FORMATS",
           "read_arrays", "peek_counts"]


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
