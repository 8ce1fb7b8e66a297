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

__all__ = ["noisy_copy", "within_reach"]


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


def within_reach(copy: Mesh | PointCloud, twin, reach: np.ndarray) -> tuple[Mesh | PointCloud, np.ndarray, np.ndarray]:
    """The part of a noisy ``copy`` of ``twin`` that a call reading up to ``reach`` around each centre
    can see: every patch cut to the twin's vertices within its centre's reach (a mesh keeps the faces
    whose corners all stay), so a call of a short reach does its set-up (normals, grids, border
    tests) on its own part of the copy, not on the widest call's patches.

    Parameters
    ----------
    copy : Mesh or PointCloud
        A noisy copy of ``twin`` (:func:`noisy_copy`).
    twin : Twin
    reach : (c,) float64
        How far the call reads around each of the twin's centres, in input units, margin included
        (:func:`curv.advice.check.call_reach`).

    Returns
    -------
    part : Mesh or PointCloud
        The vertices (points) kept, in the copy's order (the copy itself where all are kept).
    rows : (k,) int64
        The copy's rows ``part`` holds.
    centres : (c,) int64
        The twin's centres in ``part``'s numbering.
    """
    x = twin.shape.vertices
    distance = np.linalg.norm(x - x[twin.centres][twin.patch], axis=1)
    keep = distance <= reach[twin.patch]
    keep[twin.centres] = True
    rows = np.flatnonzero(keep)
    if rows.size == keep.size:
        return copy, rows, twin.centres
    new = np.full(x.shape[0], -1, np.int64)
    new[rows] = np.arange(rows.size)
    if support_of(copy).has_faces:
        faces = copy.faces
        local = np.where(faces >= 0, new[np.maximum(faces, 0)], -1)
        whole = np.all((local >= 0) | (faces < 0), axis=1)
        part = Mesh(copy.vertices[rows], local[whole])
    else:
        part = PointCloud(copy.vertices[rows], normals=None if copy.normals is None else copy.normals[rows])
    return part, rows, new[twin.centres]
