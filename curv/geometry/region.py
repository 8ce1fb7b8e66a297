"""Regions of a mesh to estimate at (``estimate(..., vertices=idx)``): from a file or a ball."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..core.errors import EstimatorError
from ..core.mesh import Mesh

__all__ = ["read_vertex_file", "vertices_in_ball"]


def read_vertex_file(path, n_vertices: int) -> np.ndarray:
    """(c,) int64 vertex indices from a text file, one index a line (blank lines and ``#`` comments skipped).

    Raises
    ------
    EstimatorError
        A file that cannot be read, a line that is not an integer, or an index out of range; the
        message names the file and the line.
    """
    try:
        text = Path(path).read_text()
    except OSError as exc:
        raise EstimatorError(f"{path}: cannot read the vertex list: {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise EstimatorError(f"{path}: not a text file of vertex indices (one a line)") from None
    out = []
    for number, line in enumerate(text.splitlines(), 1):
        entry = line.split("#", 1)[0].strip()
        if not entry:
            continue
        try:
            index = int(entry)
        except ValueError:
            raise EstimatorError(f"{path}, line {number}: {entry!r} is not a vertex index") from None
        if not 0 <= index < n_vertices:
            raise EstimatorError(f"{path}, line {number}: vertex index {index} is out of range for a mesh "
                                 f"of {n_vertices} vertices")
        out.append(index)
    return np.asarray(out, dtype=np.int64)


def vertices_in_ball(mesh: Mesh, centre, radius: float) -> np.ndarray:
    """(c,) int64 vertices within ``radius`` (mesh units) of the point ``centre`` (3,)."""
    point = np.asarray(centre, dtype=np.float64)
    if point.shape != (3,) or not np.isfinite(point).all():
        raise EstimatorError(f"a region centre must be three finite coordinates; got {centre!r}")
    if not (np.isfinite(radius) and radius > 0):
        raise EstimatorError(f"a region radius must be a positive length in mesh units; got {radius!r}")
    d2 = np.einsum("ij,ij->i", mesh.vertices - point, mesh.vertices - point)
    return np.flatnonzero(d2 <= radius * radius).astype(np.int64)
