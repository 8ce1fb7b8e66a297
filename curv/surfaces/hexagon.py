"""The paper's planar test meshes (§5.1): a subdivided unit hexagon, regular or made irregular.

The hexagon is six equilateral triangles of edge 1 around the origin (circumradius 1, corners at
angles 0°, 60°, ..., 300°). With ``s`` subdivisions per side it has ``3 s (s + 1) + 1`` vertices
(s = 8, 16, 32, 64 give the paper's 217, 817, 3169, 12481) and ``6 s^2`` triangles.

Irregularity: interior vertices move by ``amplitude * h`` times a vector drawn uniformly in the unit
disc (``h = 1/s``, the edge length), the border stays fixed, and a Delaunay triangulation is
rebuilt. The amplitude is calibrated so that the RMS deviation of all triangle angles from 60°
matches the requested value.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy.spatial import Delaunay

from ..core.errors import MeshError
from ..core.mesh import Mesh

__all__ = [
    "PAPER_VERTEX_COUNTS",
    "PlanarMesh",
    "hexagon_subdivisions",
    "hexagon_grid",
    "hexagon_mesh",
    "triangle_angles",
    "angle_irregularity",
]

PAPER_VERTEX_COUNTS = (217, 817, 3169, 12481)
"""Vertex counts of the paper's four densities (s = 8, 16, 32, 64)."""

_APOTHEM = np.sqrt(3.0) / 2.0
# Outward unit normals of the six sides; side k is n_k . x <= _APOTHEM.
_SIDE_NORMALS = np.stack(
    [np.cos(np.pi / 6 + np.arange(6) * np.pi / 3), np.sin(np.pi / 6 + np.arange(6) * np.pi / 3)], axis=1
)
# Interior vertices keep this many edge lengths away from the border. Displacements that would go
# further are shortened; it keeps every border edge a Delaunay edge (see _delaunay).
_BORDER_MARGIN = 0.2
_TOLERANCE_DEG = 0.05  # calibration stops this close to the target
_MAX_ITERATIONS = 60


@dataclass(frozen=True, eq=False)
class PlanarMesh:
    """A triangulated hexagon in the plane z = 0.

    Attributes
    ----------
    xy : (n, 2) float64
        Vertex positions.
    triangles : (m, 3) int64
        Counter-clockwise (seen from +z) triangles.
    border : (n,) bool
        Vertices on the hexagon's border (they never move).
    subdivisions : int
        ``s``, the number of edges along each side.
    irregularity_deg : float
        Measured RMS deviation of all angles from 60° (:func:`angle_irregularity`).
    target_deg : float
        The irregularity asked for.
    amplitude : float
        Displacement amplitude in edge lengths that produced it (0 for the regular grid).
    info : dict
        ``iterations`` and ``seconds`` of the calibration.
    """

    xy: np.ndarray
    triangles: np.ndarray
    border: np.ndarray
    subdivisions: int
    irregularity_deg: float = 0.0
    target_deg: float = 0.0
    amplitude: float = 0.0
    info: dict = field(default_factory=dict, compare=False)

    @property
    def n_vertices(self) -> int:
        return self.xy.shape[0]

    @property
    def edge_length(self) -> float:
        """Edge length ``1/s`` of the regular grid."""
        return 1.0 / self.subdivisions

    @cached_property
    def mesh(self) -> Mesh:
        """The flat :class:`curv.Mesh` (z = 0, normals +z)."""
        v = np.column_stack([self.xy, np.zeros(self.n_vertices)])
        return Mesh(v, self.triangles)


def hexagon_subdivisions(n_vertices: int) -> int:
    """The number of subdivisions ``s`` with ``3 s (s + 1) + 1 == n_vertices``.

    Raises
    ------
    ValueError
        If ``n_vertices`` has no such ``s >= 1``; the message lists the paper's counts and the
        nearest valid ones.
    """
    n = int(n_vertices)
    s = int(round((-3 + np.sqrt(9 + 12 * max(n - 1, 0))) / 6))
    if s >= 1 and 3 * s * (s + 1) + 1 == n:
        return s
    near = sorted({3 * t * (t + 1) + 1 for t in (max(s, 1), max(s, 1) + 1, max(s - 1, 1))})
    raise ValueError(
        f"a hexagon grid has 3s(s+1)+1 vertices for s >= 1 subdivisions per side; {n_vertices} is not "
        f"one (nearest: {', '.join(map(str, near))}; the paper uses {', '.join(map(str, PAPER_VERTEX_COUNTS))})"
    )


def _lattice(s: int):
    """Axial lattice coordinates of the grid: positions (n, 2), triangles (m, 3), border (n,)."""
    a, b = np.meshgrid(np.arange(-s, s + 1), np.arange(-s, s + 1), indexing="ij")
    ring = np.maximum(np.maximum(np.abs(a), np.abs(b)), np.abs(a + b))
    inside = ring <= s
    index = np.full(a.shape, -1, dtype=np.int64)
    index[inside] = np.arange(int(inside.sum()))
    aa, bb = a[inside], b[inside]
    xy = np.column_stack([aa + 0.5 * bb, _APOTHEM * bb]) / s
    # corner (i, j) of the (2s+1)^2 table; each lattice rhombus gives two CCW triangles
    i, j = np.meshgrid(np.arange(2 * s), np.arange(2 * s), indexing="ij")
    i, j = i.ravel(), j.ravel()
    up = np.stack([index[i, j], index[i + 1, j], index[i, j + 1]], axis=1)
    down = np.stack([index[i + 1, j], index[i + 1, j + 1], index[i, j + 1]], axis=1)
    tris = np.concatenate([up, down])
    tris = tris[(tris >= 0).all(axis=1)]
    return xy, tris, ring[inside] == s


def hexagon_grid(n_vertices: int) -> PlanarMesh:
    """The regular hexagon grid: all angles 60°, interior valence 6.

    Parameters
    ----------
    n_vertices : int
        ``3 s (s + 1) + 1`` for some ``s >= 1``: 217, 817, 3169, 12481 in the paper.

    Returns
    -------
    PlanarMesh
    """
    s = hexagon_subdivisions(n_vertices)
    xy, tris, border = _lattice(s)
    return PlanarMesh(xy=xy, triangles=tris, border=border, subdivisions=s)


def triangle_angles(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Interior angles of planar triangles.

    Parameters
    ----------
    xy : (n, 2) float64
    triangles : (m, 3) int

    Returns
    -------
    (m, 3) float64
        Angle at each corner, in degrees.
    """
    p = xy[triangles]
    # at corner i: between the edges to corners i+1 and i+2
    a = np.roll(p, -1, axis=1) - p
    b = np.roll(p, -2, axis=1) - p
    cross = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    dot = np.einsum("mij,mij->mi", a, b)
    return np.degrees(np.arctan2(np.abs(cross), dot))


def angle_irregularity(xy: np.ndarray, triangles: np.ndarray) -> float:
    """RMS deviation of all triangle angles from 60°, in degrees (paper §5.1)."""
    return float(np.sqrt(np.mean((triangle_angles(xy, triangles) - 60.0) ** 2)))


def _displace(xy: np.ndarray, step: np.ndarray, border: np.ndarray, margin: float) -> np.ndarray:
    """Move ``xy`` by ``step``, shortening steps that would end within ``margin`` of the border."""
    reach = xy @ _SIDE_NORMALS.T  # (n, 6) distance along each side normal
    towards = step @ _SIDE_NORMALS.T
    room = _APOTHEM - margin - reach
    with np.errstate(divide="ignore", invalid="ignore"):
        limit = np.where(towards > 0, room / towards, np.inf)
    t = np.clip(limit.min(axis=1), 0.0, 1.0)
    t[border] = 0.0
    return xy + t[:, None] * step


# Far points around the hexagon: with them on the convex hull the collinear border points are
# interior to the point set, so Qhull never builds flat triangles along the straight sides.
_GHOSTS = 4.0 * np.stack([np.cos(np.arange(6) * np.pi / 3), np.sin(np.arange(6) * np.pi / 3)], axis=1)


def _delaunay(xy: np.ndarray) -> np.ndarray:
    """Delaunay triangles of ``xy`` inside the hexagon, counter-clockwise.

    Border edges of length h are Delaunay edges as long as no other point lies within ~h^2/16 of
    the border lines (the ghosts are >= 3 away), which the displacement margin guarantees.
    """
    n = xy.shape[0]
    tri = Delaunay(np.concatenate([xy, _GHOSTS])).simplices.astype(np.int64)
    tri = tri[(tri < n).all(axis=1)]
    p = xy[tri]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    cw = e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] < 0
    tri[cw] = tri[cw][:, [0, 2, 1]]
    return tri


def _check(xy: np.ndarray, tris: np.ndarray, border: np.ndarray) -> None:
    """Raise if the triangulation is not a full, non-degenerate triangulation of the hexagon."""
    n_border = int(border.sum())
    expected = 2 * xy.shape[0] - n_border - 2  # Euler for a triangulated disc
    p = xy[tris]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    area = 0.5 * (e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    if tris.shape[0] != expected or np.unique(tris).size != xy.shape[0] or not np.all(area > 0):
        raise MeshError(
            f"irregular hexagon triangulation failed: {tris.shape[0]} triangles (expected {expected}), "
            f"{int((area <= 0).sum())} flat"
        )
    if not np.isclose(area.sum(), 1.5 * np.sqrt(3.0), rtol=1e-9):
        raise MeshError(f"irregular hexagon triangulation covers area {area.sum()}, not the hexagon's")


def hexagon_mesh(n_vertices: int, *, irregularity_deg: float = 0.0, rng=None) -> PlanarMesh:
    """A hexagon grid made irregular to a measured RMS angle deviation.

    Parameters
    ----------
    n_vertices : int
        ``3 s (s + 1) + 1`` (217, 817, 3169, 12481 in the paper).
    irregularity_deg : float
        Target RMS deviation of all triangle angles from 60°, in degrees. 0 gives the regular grid.
        Reachable up to about 30°, where the point set is close to random.
    rng : numpy.random.Generator, int or None
        Random source; the same seed gives the same mesh.

    Returns
    -------
    PlanarMesh
        With the measured ``irregularity_deg`` within 0.05° of the target (1° at worst on small
        meshes where single edge flips jump further), and the ``amplitude`` that produced it.

    Notes
    -----
    One set of unit displacements is drawn and only its scale is searched (bracketing, then the
    Illinois variant of regula falsi), so the result is deterministic and the measured value moves
    almost continuously with the amplitude; each step costs one Delaunay triangulation.
    """
    target = float(irregularity_deg)
    if not np.isfinite(target) or target < 0:
        raise ValueError(f"irregularity_deg must be a finite value >= 0, got {irregularity_deg}")
    grid = hexagon_grid(n_vertices)
    if target == 0:
        return grid
    start = time.perf_counter()
    rng = np.random.default_rng(rng)
    n, h = grid.n_vertices, grid.edge_length
    radius = np.sqrt(rng.random(n))
    angle = rng.random(n) * 2 * np.pi
    unit = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])

    def measure(amplitude):
        xy = _displace(grid.xy, amplitude * h * unit, grid.border, _BORDER_MARGIN * h)
        tris = _delaunay(xy)
        return angle_irregularity(xy, tris), xy, tris

    lo, f_lo = 0.0, -target
    hi = 0.6 * target / 25.0  # the measure is near-linear: ~25° at amplitude 0.6
    best = (np.inf,)
    iterations = 0
    for _ in range(8):
        value, xy, tris = measure(hi)
        iterations += 1
        if abs(value - target) < best[0]:
            best = (abs(value - target), hi, value, xy, tris)
        if value >= target:
            break
        lo, f_lo = hi, value - target
        hi *= 1.6
    else:
        raise ValueError(f"irregularity {target}° is out of reach; at most about {value:.1f}° at {n} vertices")
    f_hi = value - target
    side = 0
    while best[0] > _TOLERANCE_DEG and iterations < _MAX_ITERATIONS:
        mid = hi - f_hi * (hi - lo) / (f_hi - f_lo)
        if not lo < mid < hi:
            mid = 0.5 * (lo + hi)
        value, xy, tris = measure(mid)
        iterations += 1
        if abs(value - target) < best[0]:
            best = (abs(value - target), mid, value, xy, tris)
        if value < target:
            lo, f_lo = mid, value - target
            f_hi = 0.5 * f_hi if side == -1 else f_hi  # Illinois: halve the stale end
            side = -1
        else:
            hi, f_hi = mid, value - target
            f_lo = 0.5 * f_lo if side == 1 else f_lo
            side = 1
        if hi - lo < 1e-9:
            break
    error, amplitude, value, xy, tris = best
    if error > 1.0:
        raise ValueError(f"could not calibrate irregularity {target}° at {n} vertices: best {value:.2f}°")
    _check(xy, tris, grid.border)
    return PlanarMesh(
        xy=xy, triangles=tris, border=grid.border, subdivisions=grid.subdivisions,
        irregularity_deg=value, target_deg=target, amplitude=float(amplitude),
        info={"iterations": iterations, "seconds": time.perf_counter() - start},
    )
