import numpy as np
import pytest

import curv
from curv.core.validity import Reason
from curv.locality import locality_ordered
from tests.meshes import icosphere, torus_grid, tube


@pytest.fixture(scope="module")
def sphere():
    return icosphere(3, 2.0)


def test_unknown_method_lists_the_known_ones(sphere):
    with pytest.raises(curv.EstimatorError, match="unknown estimator 'foo'; choose one of .*mru") as err:
        curv.estimate(sphere, "foo", 2)
    assert isinstance(err.value, ValueError)


@pytest.mark.parametrize("method, bad, allowed", [
    ("meyer", 2, "R1 (a fixed 1-ring formula)"), ("ru", 3, "R2 (a fixed 1-ring formula)"),
    ("mru", 1, "any k >= 2 (R2, R3, R4 are the paper's), or radius=r in mesh units"),
    ("an", 1.5, "any k >= 2 (R2, R3, R4 are the paper's), or radius=r in mesh units"),
    ("nc", 0.5, "any k >= 1 (R1, R2, R3, R4 are the paper's), or radius=r in mesh units")])
def test_unsupported_range_names_the_allowed_ones(sphere, method, bad, allowed):
    with pytest.raises(ValueError, match=f"no range {bad!r}; allowed: {allowed}$".replace("(", r"\(").replace(")", r"\)")):
        curv.estimate(sphere, method, bad)


def test_range_spellings(sphere):
    a = curv.estimate(sphere, "qs", 3)
    b = curv.estimate(sphere, "qs", "R3")
    np.testing.assert_array_equal(a.k1, b.k1)
    assert a.range == b.range == 3 and a.method == "qs"


def test_result_contract(sphere):
    res = curv.estimate(sphere, "mru", 2)
    n = sphere.n_vertices
    assert res.k1.shape == res.k2.shape == res.valid.shape == res.reason.shape == (n,)
    assert res.d1.shape == res.d2.shape == res.normals.shape == (n, 3)
    np.testing.assert_allclose(res.mean, 0.5 * (res.k1 + res.k2))
    np.testing.assert_allclose(res.gaussian, res.k1 * res.k2)
    np.testing.assert_allclose(res.shape_index, 1.0)  # umbilic cap: shape index +1
    assert res.valid.dtype == bool and res.reason.dtype == np.uint8
    # right-handed frames (d1, d2, N)
    assert np.all(np.einsum("ij,ij->i", np.cross(res.d1, res.d2), res.normals) > 0.99)


def test_given_normals_are_used(sphere):
    exact = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    res = curv.estimate(sphere, "an", 2, normals=3 * exact)  # normalised on the way in
    np.testing.assert_allclose(res.normals, exact, atol=1e-15)
    with pytest.raises(curv.MeshError, match=r"normals must have shape \(642, 3\)"):
        curv.estimate(sphere, "an", 2, normals=exact[:10])


def test_iter_estimate_reports_progress_and_returns_the_result(sphere):
    gen = curv.iter_estimate(sphere, "nc", 4, block_size=100)
    fractions = []
    try:
        while True:
            fractions.append(next(gen))
    except StopIteration as stop:
        res = stop.value
    assert fractions[0] == 0.0 and fractions[-1] == 1.0
    assert np.all(np.diff(fractions) >= 0) and len(fractions) >= 8
    np.testing.assert_allclose(res.k1, curv.estimate(sphere, "nc", 4).k1)


def test_stopping_the_generator_midway_is_clean(sphere):
    gen = curv.iter_estimate(sphere, "qs", 2, block_size=50)
    next(gen), next(gen)
    gen.close()  # cancel: no exception, nothing left running


def test_invalid_values_are_nan_never_made_up():
    m = tube(40, 20)
    res = curv.estimate(m, "meyer", 1)
    bad = ~res.valid
    assert bad.any() and (res.reason[bad] == Reason.BORDER).all()
    for arr in (res.k1, res.k2, res.mean, res.gaussian):
        assert np.isnan(arr[bad]).all() and np.isfinite(arr[~bad]).all()
    assert np.isnan(res.d1[bad]).all()


def test_mesh_smoothing_reduces_noise_error():
    rng = np.random.default_rng(1)
    clean = icosphere(4)
    noisy = clean.with_vertices(clean.vertices + 0.1 * clean.mean_edge_length * rng.standard_normal(clean.vertices.shape))
    plain = curv.estimate(noisy, "nc", 2)
    sm = curv.estimate(noisy, "nc", 2, smooth="mesh", smooth_iterations=2)
    assert sm.info["smooth"] == "mesh"
    err = lambda r: np.sqrt(np.nanmean((r.k1 - 1) ** 2 + (r.k2 - 1) ** 2))
    assert err(sm) < 0.8 * err(plain)


def test_value_smoothing_averages_neighbours_only_over_valid_vertices():
    rng = np.random.default_rng(2)
    clean = icosphere(4)
    noisy = clean.with_vertices(clean.vertices + 0.1 * clean.mean_edge_length * rng.standard_normal(clean.vertices.shape))
    plain = curv.estimate(noisy, "mru", 2)
    sv = curv.estimate(noisy, "mru", 2, smooth="values")
    assert np.nanstd(sv.mean) < 0.8 * np.nanstd(plain.mean)
    assert np.all(sv.k1[sv.valid] >= sv.k2[sv.valid])
    m = tube(40, 20)
    res = curv.estimate(m, "ru", 2, smooth="values")
    assert np.isnan(res.k1[~res.valid]).all() and np.isfinite(res.k1[res.valid]).all()


def test_not_a_mesh_is_rejected():
    with pytest.raises(curv.MeshError, match="expected a curv.Mesh or curv.PointCloud"):
        curv.estimate(object(), "nc", 1)
    with pytest.raises(curv.MeshError, match=r"must have shape \(n, 3\)"):
        curv.estimate(np.zeros((3, 2)), "nc", 1)  # an (n, 3) array is a point cloud (curv.convert.as_input)


def test_fitted_normals_option(sphere):
    fit = curv.estimate(sphere, "mru", 2, normals="fit")
    assert fit.info["normals"] == "fit R2"
    assert curv.estimate(sphere, "mru", 2).info["normals"] == "max"
    # the jet normals of a sphere are radial
    radial = sphere.vertices / np.linalg.norm(sphere.vertices, axis=1, keepdims=True)
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", fit.normals, radial)), 1.0, atol=1e-6)
    np.testing.assert_allclose(fit.k1[fit.valid], 0.5, rtol=0.02)
    with pytest.raises(curv.EstimatorError, match="'fit'"):
        curv.estimate(sphere, "mru", 2, normals="jet")


def test_unknown_estimator_option_names_the_allowed_ones(sphere):
    with pytest.raises(curv.EstimatorError, match="'qs' has no option 'degree'; its options: none"):
        curv.estimate(sphere, "qs", 2, degree=3)


def _shuffled(mesh: curv.Mesh, seed: int = 3) -> tuple[curv.Mesh, np.ndarray]:
    """The mesh with its vertices in a random numbering, and that permutation (new vertex i is old perm[i])."""
    perm = np.random.default_rng(seed).permutation(mesh.n_vertices)
    rank = np.empty_like(perm)
    rank[perm] = np.arange(perm.size)
    return curv.Mesh(mesh.vertices[perm], rank[mesh.faces]), perm


@pytest.mark.parametrize("method,k", [("qs", 2), ("meyer", 1), ("ru", 2), ("mru", 2)])
def test_a_scattered_numbering_runs_in_grid_order_with_the_same_result(monkeypatch, method, k):
    # a shuffled numbering is estimated on a renumbered twin; the rows come back in the caller's order
    mesh = torus_grid(40, 16)[0]  # no umbilic: the directions are defined
    shuffled, perm = _shuffled(mesh)
    assert not shuffled.scattered_order()  # below the size where the order matters
    ref = curv.estimate(mesh, method, k)
    monkeypatch.setattr(curv.core.mesh, "SCATTERED_SPAN", 40)
    assert shuffled.scattered_order()
    res = curv.estimate(shuffled, method, k)
    assert locality_ordered(shuffled, None, None) is not None
    assert np.array_equal(res.valid, ref.valid[perm]) and np.array_equal(res.reason, ref.reason[perm])
    for field in ("k1", "k2", "normals", "k1_se", "k2_se"):
        got, want = getattr(res, field), getattr(ref, field)[perm]
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12, err_msg=field)
    for field in ("d1", "d2"):  # a direction up to its sign
        cos = np.abs(np.sum(getattr(res, field) * getattr(ref, field)[perm], axis=1))
        np.testing.assert_allclose(cos[res.valid], 1.0, atol=1e-9, err_msg=field)
    # a region is estimated on the mesh as it is: no whole-mesh renumbering for a few rows
    region = curv.estimate(shuffled, method, k, vertices=np.arange(10))
    np.testing.assert_allclose(region.k1[:10], ref.k1[perm[:10]], rtol=1e-9, atol=1e-12)
