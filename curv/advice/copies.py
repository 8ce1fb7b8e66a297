"""Noisy copies of a smooth twin: the input's noise put back on the twin.

The noise is Gaussian along the twin's own normal at every vertex, of the standard deviation
measured about the twin's fits (:attr:`curv.advice.twin.Twin.sigma`). Only the normal component
is added: the twin keeps the input's tangent coordinates, which already carry the input's
tangential noise (the study's noise is isotropic in 3-D), so adding it again would double the
jitter of the sampling while the normal part, which the fits removed, is what is put back.
"""

from __future__ import annotations

import numpy as np

from ..core.mesh import Mesh
from ..core.pointcloud import PointCloud
from ..core.support import support_of

__all__ = ["noisy_copy"]


def noisy_copy(shape: Mesh | PointCloud, twin, noise: float, rng: np.random.Generator) -> Mesh | PointCloud:
    """One noisy copy of ``twin`` (a :class:`curv.advice.twin.Twin` of ``shape``).

    Parameters
    ----------
    shape : Mesh or PointCloud
        The input (a cloud's own normals, if it has them, travel with each point to its copy).
    twin : Twin
    noise : float
        Standard deviation along the normal, in input units (0: the twin itself).
    rng : numpy.random.Generator

    Returns
    -------
    Mesh or PointCloud
        The twin's connectivity (or sampling) at the moved positions.
    """
    positions = twin.shape.vertices
    if noise > 0:
        positions = positions + twin.surface_normals * rng.normal(scale=noise, size=(positions.shape[0], 1))
    if support_of(twin.shape).has_faces:
        return twin.shape.with_vertices(positions)
    normals = None if shape.normals is None else shape.normals[twin.origin]
    return PointCloud(positions, normals=normals)
