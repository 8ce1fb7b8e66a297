"""The analytic surfaces sampled as point clouds, with their exact curvature at every point.

Samplings (:data:`SAMPLINGS`):

- ``"uniform"``: independent points, uniform by area (Poisson: clumps and holes).
- ``"blue"``: blue noise: a uniform sample 8x too dense thinned greedily so that no two points
  are closer than ``d`` (random sequential adsorption; ``d`` chosen so that about ``n_points``
  remain), an even sample without the regular mesh's lattice.
- ``"rows"``: scan-like, anisotropic: points along rows (planes ``y = const`` on Monge patches,
  ``z = const`` on the cylinder) ``ratio`` times farther apart than the points along a row
  (uniform random along each row). Surfaces whose projection does not keep the row plane
  (sphere, ellipsoid, torus) refuse it.

Points are drawn by area on a fine mesh of the surface (:meth:`Surface.mesh`) and moved onto the
exact surface by the surface's own ``project``; the truth is the surface's ``exact_at`` there. With
``noise``, each point moves by 3-D Gaussian noise of that many mean spacings (the range unit of
:mod:`curv.core.ranges`), and its truth stays that of the clean point, as for meshes
(:func:`curv.surfaces.add_noise`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..core.jit import jit
from ..core.knn import nearest_neighbours
from ..core.pointcloud import PointCloud
from ..core.ranges import point_spacing
from ..core.result import Curvature
from .base import Surface
from .monge import MongePatch

__all__ = ["SampledPoints", "sample_points", "SAMPLINGS"]

SAMPLINGS = ("uniform", "blue", "rows")

_BLUE_OVERSAMPLING = 8
_BLUE_NEIGHBOURS = 32
# random sequential adsorption of discs of diameter d saturates at a density of 0.697 / d^2; from 8x
# oversampling it stops short of that: 0.56 / d^2 measured (2390 of 3000 points asked at 0.697)
_RSA_DENSITY = 0.56


@dataclass(frozen=True, eq=False)
class SampledPoints:
    """A point sample of an analytic surface with its exact curvature at every point.

    Attributes
    ----------
    cloud : PointCloud
        The points (with the exact normals attached when asked for, as if read from a file).
    truth : Curvature
        Exact ``k1, k2, d1, d2, normals`` (outward on closed surfaces, up on Monge patches); with
        noise, those of the clean point.
    surface : Surface
    sampling : str
        One of :data:`SAMPLINGS`.
    noise : float
        Standard deviation of the 3-D noise in mean spacings.
    info : dict
        ``area``, ``spacing`` (mean clean spacing), ``ratio`` (rows), ``seed``.
    """

    cloud: PointCloud
    truth: Curvature
    surface: Surface
    sampling: str
    noise: float = 0.0
    info: dict = field(default_factory=dict)

    def describe(self) -> str:
        """One line: the surface, the point count, the sampling and the noise."""
        parts = [self.surface.describe(), f"{self.cloud.n_points} points", f"{self.sampling} sampling"]
        if self.noise:
            parts.append(f"noise {self.noise:g} × mean spacing")
        return ", ".join(parts)


def _area_sample(surface: Surface, count: int, rng: np.random.Generator, fine_vertices: int):
    """``count`` points uniform by area on a fine mesh of ``surface``, projected onto it; and the area."""
    if isinstance(surface, MongePatch):
        # the hexagon grids have 3 s (s + 1) + 1 vertices
        s = max(1, int(round(np.sqrt(fine_vertices / 3.0))))
        fine_vertices = 3 * s * (s + 1) + 1
    mesh = surface.mesh(fine_vertices).mesh
    tri = mesh.triangles
    area = mesh.face_areas
    face = rng.choice(tri.shape[0], size=count, p=area / area.sum())
    a, b = rng.random(count), rng.random(count)
    flip = a + b > 1.0
    a[flip], b[flip] = 1.0 - a[flip], 1.0 - b[flip]
    v = mesh.vertices
    p = v[tri[face, 0]] + a[:, None] * (v[tri[face, 1]] - v[tri[face, 0]]) + b[:, None] * (v[tri[face, 2]] - v[tri[face, 0]])
    return surface.project(p), float(area.sum())


@jit
def _thin(indices, distances, d):
    """Greedy: keep point i unless a kept point before it lies closer than d (points in random order)."""
    n, k = indices.shape
    keep = np.zeros(n, np.bool_)
    for i in range(n):
        ok = True
        for j in range(k):
            if distances[i, j] >= d:
                break
            q = indices[i, j]
            if q < i and keep[q]:
                ok = False
                break
        keep[i] = ok
    return keep


def sample_points(surface: Surface | str, n_points: int, *, sampling: str = "uniform", noise: float = 0.0,
                  ratio: float = 4.0, with_normals: bool = False, rng=None,
                  fine_vertices: int = 20000) -> SampledPoints:
    """Sample ``surface`` as about ``n_points`` points (module notes) with the exact curvature.

    Parameters
    ----------
    surface : Surface or str
        A smooth analytic surface with ``project`` (Monge patches, sphere, ellipsoid, torus,
        cylinder), or its name in :data:`curv.surfaces.SURFACES` (built with its default
        parameters, as :func:`curv.surfaces.make_surface` names it).
    n_points : int
        Wanted count (exact for ``"uniform"``, within a few percent otherwise).
    sampling : {"uniform", "blue", "rows"}
    noise : float
        3-D Gaussian noise, standard deviation in mean spacings of the clean sample.
    ratio : float
        ``"rows"``: distance between rows over the spacing along a row.
    with_normals : bool
        Attach the exact normals to the cloud (as a file with ``nx ny nz`` would).
    rng : numpy.random.Generator, int or None
    fine_vertices : int
        Vertices of the fine mesh the points are drawn on.

    Returns
    -------
    SampledPoints
    """
    if sampling not in SAMPLINGS:
        raise ValueError(f"sampling must be one of {', '.join(SAMPLINGS)}; got {sampling!r}")
    if isinstance(surface, str):
        from . import SURFACES

        if surface not in SURFACES:
            raise ValueError(f"unknown surface {surface!r}; choose one of {', '.join(SURFACES)}")
        surface = SURFACES[surface]()
    if not hasattr(surface, "project"):
        name = getattr(surface, "title", type(surface).__name__)
        raise ValueError(f"{name} cannot be sampled as points (no smooth projection)")
    if noise < 0:
        raise ValueError(f"noise must be >= 0, got {noise}")
    gen = np.random.default_rng(rng)
    n_points = int(n_points)
    info = {"seed": rng if isinstance(rng, int) else None}
    if sampling == "uniform":
        points, area = _area_sample(surface, n_points, gen, fine_vertices)
    elif sampling == "blue":
        dense, area = _area_sample(surface, _BLUE_OVERSAMPLING * n_points, gen, fine_vertices)
        d = np.sqrt(_RSA_DENSITY * area / n_points)
        indices, distances = nearest_neighbours(dense, _BLUE_NEIGHBOURS)
        points = dense[_thin(indices, distances, d)]
        info["min_distance"] = float(d)
    else:
        if not ratio >= 1:
            raise ValueError(f"ratio must be >= 1, got {ratio}")
        dense, area = _area_sample(surface, int(np.ceil(ratio * n_points)), gen, fine_vertices)
        along = np.sqrt(area / (ratio * n_points))
        gap = ratio * along
        axis = 1 if isinstance(surface, MongePatch) else 2
        row = np.round(dense[:, axis] / gap)
        band = np.abs(dense[:, axis] - row * gap) <= 0.5 * along
        snapped = dense[band].copy()
        snapped[:, axis] = row[band] * gap
        points = surface.project(snapped)
        if not np.allclose(points[:, axis], snapped[:, axis], rtol=0.0, atol=1e-9 * (1.0 + np.abs(points).max())):
            raise ValueError(f"{surface.title} cannot be sampled in rows: its projection moves points off "
                             f"the row planes (rows work on the Monge patches and the cylinder)")
        info.update(ratio=float(ratio), row_gap=float(gap))
    truth = surface.exact_at(points)
    info["area"] = area
    spacing = float(point_spacing(PointCloud(points)).mean())
    info["spacing"] = spacing
    if noise:
        points = points + gen.normal(scale=noise * spacing, size=points.shape)
        info["noise_sigma"] = noise * spacing
    cloud = PointCloud(points, normals=truth.normals if with_normals else None)
    return SampledPoints(cloud=cloud, truth=truth, surface=surface, sampling=sampling, noise=float(noise), info=info)
