"""Analytic surfaces with exact principal curvatures and directions, and their meshing.

>>> from curv.surfaces import make_surface, QuadraticPatch
>>> s = make_surface("torus", n_vertices=2000)
>>> s.mesh, s.truth.k1            # doctest: +SKIP
>>> patch = QuadraticPatch.random(0)
>>> s = patch.mesh(817, irregularity_deg=14, rng=0)
>>> round(s.irregularity_deg)
14

Monge patches (``quadratic``, ``ellipsoid_patch``, ``trigonometric``, ``saddle``) are sampled on the
paper's hexagon (§5.1, :func:`hexagon_mesh`), normals up. ``sphere``, ``ellipsoid`` and ``torus`` are
closed meshes with outward normals; ``cylinder`` is an open tube. ``capped_cylinder``, ``box``,
``hemisphere`` (on a disc) and ``cone`` are closed solids with sharp creases: exact curvature on their
smooth parts, NaN with ``Reason.FEATURE`` on creases, corners and the apex (:mod:`.creased`).
The smooth ones are also sampled as point clouds (uniform, blue noise, scan rows; :func:`sample_points`).
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np

from .base import Param, SampledSurface, Surface, add_noise
from .closed import Cylinder, Ellipsoid, ImplicitSurface, Sphere, Torus
from .creased import Box, CappedCylinder, Cone, CreasedSurface, HemisphereOnDisc, crease_distance_rings
from .hexagon import (
    PAPER_VERTEX_COUNTS, PlanarMesh, angle_irregularity, hexagon_grid, hexagon_mesh, hexagon_subdivisions,
    triangle_angles,
)
from .monge import EllipsoidPatch, MongePatch, QuadraticPatch, Saddle, TrigonometricPatch
from .points import SAMPLINGS, SampledPoints, sample_points

__all__ = [
    "Surface", "Param", "SampledSurface", "ImplicitSurface", "MongePatch",
    "Sphere", "Cylinder", "Torus", "Ellipsoid", "Saddle", "QuadraticPatch", "EllipsoidPatch", "TrigonometricPatch",
    "CreasedSurface", "CappedCylinder", "Box", "HemisphereOnDisc", "Cone", "crease_distance_rings",
    "SURFACES", "PAPER_SURFACES", "make_surface", "add_noise",
    "PlanarMesh", "PAPER_VERTEX_COUNTS", "hexagon_grid", "hexagon_mesh", "hexagon_subdivisions",
    "angle_irregularity", "triangle_angles", "SampledPoints", "sample_points", "SAMPLINGS",
]

SURFACES = MappingProxyType({
    cls.name: cls
    for cls in (
        Sphere, Cylinder, Torus, Ellipsoid, Saddle, QuadraticPatch, EllipsoidPatch, TrigonometricPatch,
        CappedCylinder, Box, HemisphereOnDisc, Cone,
    )
})
"""Registry name -> surface class. Each class has ``params`` (:class:`Param` with defaults and ranges),
``title``, ``closed`` and ``default_vertices``; calling it with no arguments gives the defaults."""

PAPER_SURFACES = ("quadratic", "ellipsoid_patch", "trigonometric")
"""The three functions of the paper's eq. 5.1."""


def make_surface(
    name: str,
    *,
    n_vertices: int | None = None,
    irregularity: float = 0.0,
    noise: float = 0.0,
    seed=None,
    random_params: bool = False,
    **params,
) -> SampledSurface:
    """Build and mesh a registered surface.

    Parameters
    ----------
    name : str
        A key of :data:`SURFACES`.
    n_vertices : int, optional
        Hexagon patches: ``3 s (s + 1) + 1`` (217, 817, 3169, 12481; default 817). Closed surfaces:
        approximate count (default 2562).
    irregularity : float
        Target RMS angle deviation from 60° in degrees; hexagon patches only.
    noise : float
        3D Gaussian vertex noise, standard deviation in mean edge lengths (truth unchanged).
    seed : int, numpy.random.Generator or None
        One random source, used in this order: random parameters, irregularity, noise.
    random_params : bool
        Draw the parameters with the class's ``random`` (paper §5.1 ranges; Monge patches only).
        Parameters given in ``params`` then override the drawn ones.
    **params
        Constructor parameters of the surface (see ``SURFACES[name].params``).

    Returns
    -------
    SampledSurface
        ``info["seed"]`` records ``seed`` when it is an int.

    Raises
    ------
    ValueError
        Unknown name or parameter, or a surface that does not support the option.
    """
    try:
        cls = SURFACES[name]
    except KeyError:
        raise ValueError(f"unknown surface {name!r}; choose one of {', '.join(SURFACES)}") from None
    allowed = [p.name for p in cls.params]
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise ValueError(f"{name} has no parameter {', '.join(unknown)}; its parameters are {', '.join(allowed)}")
    rng = np.random.default_rng(seed)
    if random_params:
        if not issubclass(cls, MongePatch):
            raise ValueError(f"random parameters are defined for the hexagon patches, not for {name}")
        params = {**cls.random(rng).parameters, **params}
    surface = cls(**params)
    sampled = surface.mesh(n_vertices, irregularity_deg=irregularity, rng=rng)
    sampled = add_noise(sampled, noise, rng)
    if isinstance(seed, (int, np.integer)):
        sampled.info["seed"] = int(seed)
    return sampled
