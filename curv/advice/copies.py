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

__all__ = ["noisy_copy", "within_reach", "read_rows", "widest_reach", "part_normals"]


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


def read_rows(part, calls: list, centres: np.ndarray, patch: np.ndarray) -> np.ndarray:
    """(k,) int64 the vertices of a mesh ``part`` whose normals ``calls`` read at its ``centres``: within
    the farthest any of them reads around its own patch's centre (:func:`widest_reach`; the twin's
    patches are apart).

    Parameters
    ----------
    part : Mesh
        A part of a noisy copy (:func:`within_reach`).
    calls : list of dict
        Keyword arguments of :func:`curv.estimate` (``method``, ``range`` or ``radius``).
    centres : (c,) int64
        The twin's centres in ``part``'s numbering.
    patch : (k,) int64
        The centre (0..c-1) each of ``part``'s vertices belongs to.
    """
    reach = widest_reach(part, calls, centres)
    x = part.vertices
    return np.flatnonzero(np.linalg.norm(x - x[centres][patch], axis=1) <= reach[patch])


def widest_reach(mesh, calls: list, centres: np.ndarray) -> np.ndarray:
    """(c,) float64 how far ``calls`` read normals around each of ``centres`` of a mesh: their supports
    and the rings of the supports' vertices, as :func:`curv.tiles.reach.support_reach` (the farthest
    ``|q - p|`` + q's longest edge over the vertices q of the ball), the calls' balls taken together
    (the widest at each centre): one search for all of them, at least each one's reach.

    Parameters
    ----------
    mesh : Mesh
    calls : list of dict
        Keyword arguments of :func:`curv.estimate` (``method``, ``range`` or ``radius``).
    centres : (c,) int64
    """
    from ..core.ranges import ball_radii, resolve
    from ..estimators import get_spec
    from ..tiles.reach import ball_max

    longest = np.asarray(mesh.longest_edge, dtype=np.float64)
    radii = np.full(mesh.n_vertices, -np.inf)
    for kw in calls:
        spec = get_spec(kw["method"])
        own = (ball_radii(mesh, resolve(spec, kw.get("range"), kw.get("radius"), None), uses_normals=spec.uses_normals,
                          at=centres) if spec.has_support else longest)
        radii[centres] = np.maximum(radii[centres], own[centres])
    return ball_max(mesh.vertices, radii, longest, centres)


def part_normals(part, calls: list, centres: np.ndarray, patch: np.ndarray) -> np.ndarray:
    """(k, 3) the fitted normals (``normals="fit"`` at the calls' ``fit_range``) that ``calls`` read on a
    mesh ``part``, fitted only where they read them (:func:`read_rows`: about a third of a part's
    vertices, the rest reach only the fits); NaN elsewhere. Parameters as in :func:`read_rows`."""
    from ..fitted_normals import fitted_normals

    return fitted_normals(part, range=calls[0].get("fit_range", 2), vertices=read_rows(part, calls, centres, patch))
