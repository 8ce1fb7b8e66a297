"""Consistency guarantees of every estimator, as hypothesis property tests (issue 5).

Scale (k scales as 1/s), rigid motion (k unchanged, directions rotate), orientation (reversing all
faces negates and swaps k1/k2), vertex order (results permute), and k1 >= k2 with unit, tangent,
orthogonal directions wherever valid. The meshes are small jittered ellipsoids, so each example is
a few milliseconds.
"""

from __future__ import annotations

import numpy as np
import pytest
import trimesh
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import curv
from curv.estimators.registry import all_variants

VARIANTS = all_variants()
SETTINGS = settings(max_examples=4, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])
_SPHERE = trimesh.creation.icosphere(subdivisions=2)

# Reported to the owner of `an` (closing note of issue 5): its fit mixes height equations (a length)
# with slope equations (dimensionless) unweighted, so its result depends on the unit of length.

PARAM = pytest.mark.parametrize("variant", VARIANTS, ids=[f"{m}{k}" for m, k in VARIANTS])


MIN_VALID = {("jet", 4): 0.8}
"""Valid share below the default 0.9 that is honest: at R4 on these 162-vertex meshes the support
is a cap of about 70 degrees, and on a flat ellipsoid's rim it wraps round the edge; the jet,
which fits a height over the support's own PCA plane, calls those supports degenerate (qs and nc
fit in the vertex normal's frame and do not see it)."""


@st.composite
def ellipsoids(draw):
    """A jittered ellipsoid (irregular triangles, no symmetry left) as a Mesh."""
    axes = np.array([draw(st.floats(0.6, 1.8)) for _ in range(3)])
    seed = draw(st.integers(0, 2**31 - 1))
    jitter = draw(st.floats(0.0, 0.04))
    rng = np.random.default_rng(seed)
    v = np.asarray(_SPHERE.vertices) * axes
    v = v + jitter * rng.normal(size=v.shape)
    return curv.Mesh(v, np.asarray(_SPHERE.faces))


@st.composite
def rotations(draw):
    q = np.array([draw(st.floats(-1, 1)) for _ in range(4)])
    if np.linalg.norm(q) < 1e-3:
        q = np.array([1.0, 0, 0, 0])
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def _close(a, b, scale=1.0):
    """Equal up to float noise relative to the magnitude of the values."""
    tol = 1e-6 * max(1.0, np.nanmax(np.abs(b), initial=0.0))
    np.testing.assert_allclose(a * scale, b, rtol=1e-6, atol=tol)


def _check_frame(res: curv.Curvature):
    v = res.valid
    assert np.all(res.k1[v] >= res.k2[v])
    for d in (res.d1[v], res.d2[v]):
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1, atol=1e-6)
        assert np.all(np.abs(np.einsum("ij,ij->i", d, res.normals[v])) < 1e-6)
    assert np.all(np.abs(np.einsum("ij,ij->i", res.d1[v], res.d2[v])) < 1e-6)
    assert np.all(np.isnan(res.k1[~v])) and np.all(np.isnan(res.d2[~v]))


@PARAM
@SETTINGS
@given(mesh=ellipsoids())
def test_k1_ge_k2_and_orthonormal_tangent_directions(mesh, variant):
    res = curv.estimate(mesh, *variant)
    assert res.valid.mean() > MIN_VALID.get(tuple(variant), 0.9)
    _check_frame(res)


@PARAM
@SETTINGS
@given(mesh=ellipsoids(), exponent=st.floats(-6, 6))
def test_scaling_by_s_scales_curvature_by_one_over_s(mesh, variant, exponent):
    s = 10.0**exponent
    ref = curv.estimate(mesh, *variant)
    res = curv.estimate(mesh.with_vertices(mesh.vertices * s), *variant)
    np.testing.assert_array_equal(res.valid, ref.valid)
    _close(res.k1, ref.k1, s)
    _close(res.k2, ref.k2, s)


@PARAM
@SETTINGS
@given(mesh=ellipsoids(), rot=rotations(),
       shift=st.tuples(*[st.floats(-100, 100)] * 3))
def test_rigid_motion_keeps_curvature_and_rotates_directions(mesh, variant, rot, shift):
    ref = curv.estimate(mesh, *variant)
    moved = mesh.with_vertices(mesh.vertices @ rot.T + np.asarray(shift))
    res = curv.estimate(moved, *variant)
    np.testing.assert_array_equal(res.valid, ref.valid)
    _close(res.k1, ref.k1)
    _close(res.k2, ref.k2)
    # directions are defined up to sign, and only where k1 and k2 differ clearly
    v = ref.valid & (ref.k1 - ref.k2 > 1e-3 * np.abs(ref.k1).max())
    dots = np.abs(np.einsum("ij,ij->i", res.d1[v], ref.d1[v] @ rot.T))
    np.testing.assert_allclose(dots, 1, atol=1e-4)


@PARAM
@SETTINGS
@given(mesh=ellipsoids())
def test_reversing_all_faces_negates_and_swaps(mesh, variant):
    ref = curv.estimate(mesh, *variant)
    res = curv.estimate(mesh.flipped(), *variant)
    np.testing.assert_array_equal(res.valid, ref.valid)
    _close(res.k1, -ref.k2)
    _close(res.k2, -ref.k1)
    np.testing.assert_allclose(res.normals, -ref.normals, atol=1e-9)


@PARAM
@SETTINGS
@given(mesh=ellipsoids(), seed=st.integers(0, 2**31 - 1))
def test_permuting_vertices_permutes_results(mesh, variant, seed):
    rng = np.random.default_rng(seed)
    perm = rng.permutation(mesh.n_vertices)          # new vertex i is old vertex perm[i]
    inverse = np.argsort(perm)
    faces = inverse[mesh.faces][rng.permutation(mesh.n_faces)]
    shuffled = curv.Mesh(mesh.vertices[perm], faces)
    ref = curv.estimate(mesh, *variant)
    res = curv.estimate(shuffled, *variant)
    np.testing.assert_array_equal(res.valid, ref.valid[perm])
    _close(res.k1, ref.k1[perm])
    _close(res.k2, ref.k2[perm])
