"""The fits' ranges in one walk (nc, qs, an, mru with ``standard_errors=False``; the jet): each range
equals its own call to rounding."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.api import estimate_ranges
from meshes import hex_plane, icosphere, noisy_torus, paraboloid_patch

FITS = ("nc", "qs", "an", "mru", "jet")
RANGES = {"nc": (3, 1, 4, 2.5, 2), "qs": (3, 1, 4, 2.5, 2), "an": (3, 4, 2.5, 2), "mru": (3, 4, 2.5, 2),
          "jet": (3, 1, 4, 2.5, 2)}


def _noisy_torus():
    return noisy_torus(30, 14, seed=7)


def _open_patch():
    return paraboloid_patch(10)


MESHES = {"sphere": lambda: icosphere(3), "noisy torus": _noisy_torus, "open patch": _open_patch}


def _compare(one, res):
    assert np.array_equal(one.reason, res.reason) and np.array_equal(one.valid, res.valid)
    for name in ("k1", "k2"):
        assert np.allclose(getattr(one, name), getattr(res, name), rtol=1e-9, atol=1e-9, equal_nan=True), name
    # directions: only where k1 and k2 stand apart are they defined
    apart = one.valid & (one.k1 - one.k2 > 1e-6 * np.maximum(np.abs(one.k1), 1.0))
    for name in ("d1", "d2"):
        cos = np.abs(np.einsum("ij,ij->i", getattr(one, name)[apart], getattr(res, name)[apart]))
        assert np.allclose(cos, 1.0, atol=1e-6), name
    assert one.range == res.range
    assert np.isnan(res.k1_se).all() and np.isnan(res.k2_se).all()


@pytest.mark.parametrize("mesh_name", sorted(MESHES))
@pytest.mark.parametrize("method", FITS)
@pytest.mark.parametrize("region", [False, True], ids=["whole", "region"])
def test_fit_ranges_equal_one_call_each(mesh_name, method, region):
    mesh = MESHES[mesh_name]()
    idx = np.arange(2, mesh.n_vertices, 3) if region else None
    many = estimate_ranges(mesh, method, RANGES[method], vertices=idx, standard_errors=False, block_size=50)
    for r, res in zip(RANGES[method], many):
        _compare(curv.estimate(mesh, method, r, vertices=idx, standard_errors=False), res)


@pytest.mark.parametrize("method", ["nc", "qs", "mru", "jet"])
def test_fit_ranges_first_level_is_bit_for_bit(method):
    """The narrowest range's sums are added in its own search's order (an's are in the widest
    range's coordinates: to rounding, above)."""
    mesh = _noisy_torus()
    low = min(RANGES[method])
    many = estimate_ranges(mesh, method, (4, low), standard_errors=False)
    one = curv.estimate(mesh, method, low, standard_errors=False)
    assert np.array_equal(one.k1, many[1].k1, equal_nan=True) and np.array_equal(one.d1, many[1].d1, equal_nan=True)


def _band_mesh():
    """A plane with one vertex q moved nearly above its neighbour p: q's tangent offset from p is
    2e-9 of p's longest edge, so it counts at p's narrowest range and not at the widest
    (``MIN_TANGENT_LENGTH`` of the radius); and one vertex without a normal."""
    flat = hex_plane(8)
    v = flat.vertices.copy()
    v[:, 2] = 0.3 * v[:, 0] ** 2 + 0.1 * v[:, 1] ** 2
    p = int(np.argmin(np.linalg.norm(v[:, :2], axis=1)))
    ptr, ring = flat.neighbour_lists
    q = int(ring[ptr[p]])
    mesh = curv.Mesh(v, flat.faces)
    length = mesh.longest_edge[p]
    v[q] = v[p] + [2e-9 * length, 0.0, 0.4 * length]
    mesh = curv.Mesh(v, flat.faces)
    assert mesh.longest_edge[p] == pytest.approx(length)
    normals = np.tile([0.0, 0.0, 1.0], (mesh.n_vertices, 1))
    normals[p + 5] = np.nan
    return mesh, normals, p


@pytest.mark.parametrize("method", FITS)
def test_fit_ranges_where_a_row_counts_at_some_ranges_only(method):
    mesh, normals, p = _band_mesh()
    ranges = RANGES[method]
    many = estimate_ranges(mesh, method, ranges, normals=normals, standard_errors=False)
    for r, res in zip(ranges, many):
        one = curv.estimate(mesh, method, r, normals=normals, standard_errors=False)
        _compare(one, res)
        assert res.reason[p + 5] == curv.Reason.DEGENERATE


@pytest.mark.parametrize("method", FITS)
def test_fit_ranges_too_few_and_degenerate(method):
    """A strip two triangles wide: vertices with fewer than three usable neighbours at the small
    ranges (TOO_FEW_NEIGHBOURS), more at the large ones."""
    xs = np.arange(6.0)
    v = np.array([(x, y, 0.05 * x * x) for y in (0.0, 1.0) for x in xs])
    n = xs.size
    faces = [(i, i + 1, n + i) for i in range(n - 1)] + [(i + 1, n + i + 1, n + i) for i in range(n - 1)]
    mesh = curv.Mesh(v, np.array(faces))
    ranges = (4, 2) if method in ("an", "mru") else (4, 3, 2, 1)
    many = estimate_ranges(mesh, method, ranges, standard_errors=False)
    codes = set()
    for r, res in zip(ranges, many):
        one = curv.estimate(mesh, method, r, standard_errors=False)
        _compare(one, res)
        codes |= set(res.reason.tolist())
    assert codes - {curv.Reason.OK, curv.Reason.BORDER}  # not every row is OK or BORDER


def test_fit_ranges_sphere_value():
    mesh = icosphere(4, radius=2.0)
    for method in FITS:
        for res in estimate_ranges(mesh, method, (2, 3, 4), standard_errors=False):
            assert np.allclose(res.k1[res.valid], 0.5, rtol=0.03) and np.allclose(res.k2[res.valid], 0.5, rtol=0.03)


@pytest.mark.parametrize("weights", ["uniform", "smooth"])
def test_jet_ranges_standard_errors(weights):
    """The jet's standard errors come from each level's own fit: to rounding, as its values."""
    mesh = _noisy_torus()
    many = estimate_ranges(mesh, "jet", (2, 4, 1), weights=weights, standard_errors=True)
    for r, res in zip((2, 4, 1), many):
        one = curv.estimate(mesh, "jet", r, weights=weights, standard_errors=True)
        assert np.array_equal(one.reason, res.reason)
        assert np.allclose(one.k1_se, res.k1_se, rtol=1e-9, equal_nan=True)
        assert np.allclose(one.k2_se, res.k2_se, rtol=1e-9, equal_nan=True)
        assert np.isfinite(res.k1_se[res.valid]).all()


@pytest.mark.parametrize("method", ["qs", "an"])
def test_fit_ranges_at_creases_and_in_chunks(method):
    """Supports that stop at creases, a few vertices per kernel call."""
    from creased_meshes import box

    mesh = box(4)
    ranges = RANGES[method][:3]
    many = estimate_ranges(mesh, method, ranges, features=30, block_size=7, standard_errors=False)
    for r, res in zip(ranges, many):
        _compare(curv.estimate(mesh, method, r, features=30, standard_errors=False), res)
    assert (many[0].reason == curv.Reason.FEATURE).any()
