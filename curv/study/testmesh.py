"""The test meshes of §5.1: a random Monge patch on an (irregular) hexagon mesh, with noise.

The planar hexagon of six unit triangles is subdivided to the task's vertex count, its interior
vertices shifted and re-triangulated (Delaunay) until the RMS angle deviation from 60° reaches the
target, lifted onto the random surface, and perturbed by 3D Gaussian noise. The vertices the study
evaluates are fixed on the noise-free mesh: those with no border vertex within range R4
(:data:`~curv.study.protocol.EXCLUSION_RANGE`), as the paper selects them before adding noise.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..core.mesh import Mesh
from ..geometry.neighbourhood import iter_neighbourhoods
from ..core.result import Curvature
from .protocol import EXCLUSION_RANGE, NOISE_FRACTION, Task

__all__ = ["TestMesh", "build_test_mesh", "evaluated_vertices", "random_surface"]


@dataclass(frozen=True)
class TestMesh:
    """One mesh of the study with its exact curvature and the vertices to evaluate.

    Attributes
    ----------
    sampled : curv.surfaces.SampledSurface
        The (noisy) mesh, the exact curvature of the clean surface at its vertices, the surface.
    evaluated : (n,) bool
        Vertices with no border vertex within R4 of the noise-free mesh.
    irregularity : float
        Measured RMS deviation of all triangle angles from 60°, in degrees (before noise).
    noise_sigma : float
        Standard deviation per coordinate of the added noise (0 without noise).
    """

    __test__ = False  # not a pytest test class despite its name

    sampled: object
    evaluated: np.ndarray
    irregularity: float
    noise_sigma: float

    @property
    def mesh(self) -> Mesh:
        return self.sampled.mesh

    @property
    def truth(self) -> Curvature:
        return self.sampled.truth


def evaluated_vertices(mesh: Mesh, *, range_factor: float = EXCLUSION_RANGE) -> np.ndarray:
    """Vertices that are not on a border and have no border vertex within range ``R{range_factor}``.

    Parameters
    ----------
    mesh : Mesh
    range_factor : float
        The range k: the support is every vertex reachable along edges inside the ball of radius
        ``k * mesh.longest_edge[p]`` (the convention of :mod:`curv.geometry.neighbourhood`).

    Returns
    -------
    (n,) bool
    """
    border = mesh.border_vertices
    out = ~border
    for block in iter_neighbourhoods(mesh, range_factor):
        out[block.vertices] &= ~block.any(border)
    return out


def random_surface(function: str, rng: np.random.Generator):
    """A random Monge patch of eq. 5.1 with the paper's parameter ranges (§5.1)."""
    from .. import surfaces

    return surfaces.SURFACES[function].random(rng)


def build_test_mesh(task: Task) -> TestMesh:
    """Make the mesh of a task; every random choice comes from the task's own streams.

    Parameters
    ----------
    task : Task

    Returns
    -------
    TestMesh
    """
    from ..surfaces import add_noise

    clean, evaluated = _clean_mesh(task.seed, task.function, task.density, task.irregularity, task.sample)
    noisy = add_noise(clean, task.noise * NOISE_FRACTION, task.noise_rng())
    sigma = task.noise * NOISE_FRACTION * clean.mesh.mean_edge_length
    return TestMesh(sampled=noisy, evaluated=evaluated, irregularity=float(clean.irregularity_deg),
                    noise_sigma=float(sigma))


# Consecutive tasks share their meshes: the planar hexagon (with its Delaunay calibration of the
# irregularity) depends on (seed, density, irregularity, sample) only, so the 3 functions x 4 noise
# levels of a random surface reuse one; the clean lifted mesh and its evaluated vertices only lack
# the noise. A few of each are kept per worker process; the results are the same as building anew.
_KEPT = 8


@lru_cache(maxsize=_KEPT)
def _planar_mesh(seed: int, density: int, irregularity: float, sample: int):
    from ..surfaces import hexagon_mesh

    task = Task(seed, "", density, irregularity, 0.0, sample)
    return hexagon_mesh(density, irregularity_deg=irregularity, rng=task.mesh_rng())


@lru_cache(maxsize=_KEPT)
def _clean_mesh(seed: int, function: str, density: int, irregularity: float, sample: int):
    """The noise-free sampled surface of a task and the vertices the study evaluates on it."""
    task = Task(seed, function, density, irregularity, 0.0, sample)
    clean = random_surface(function, task.surface_rng()).sample(_planar_mesh(seed, density, irregularity, sample))
    evaluated = evaluated_vertices(clean.mesh)
    evaluated.setflags(write=False)
    return clean, evaluated
