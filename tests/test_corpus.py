"""Every corpus case through ``curv.load`` + ``curv.estimate`` for every estimator and range.

Outcome per case: a one-line ``LoadError`` / ``MeshError`` naming the file and the problem, or a
result whose masks are honest: valid vertices finite, ``k1 >= k2``, unit orthogonal tangent
directions, and (where the mesh samples a sphere) values near the truth; invalid vertices NaN with
a reason code.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

import curv
from curv.estimators.registry import all_variants
from tests.corpus import LOAD_ERROR, MESH_ERROR, OK, as_root, session_corpus

CASES = {c.name: c for c in session_corpus()}
VARIANTS = all_variants()
OK_CASES = [name for name, c in CASES.items() if c.outcome == OK]
ERROR_CASES = [name for name, c in CASES.items() if c.outcome != OK]

TRUTH_TOLERANCE = 0.6
"""|k r - 1| allowed at valid vertices of a sampled sphere (coarse mesh, R4: about 0.46 when clean)."""

TRUTH_TOLERANCE_FOR = {("jet", 4): 0.7}
"""Wider bounds that are the method's, not a mask's: a degree-2 jet fitted over the R4 support of
these 162-vertex spheres (a cap of about 70 degrees, with its own tangent plane) is off by up to
0.67 (median 0.62); at R2 it is within 0.12."""

# Known accuracy limits that are not bugs of the masks (Meyer's cotan weights degrade next to needles):
# (test, case) -> (variants, reason).
_FITTED = {"nc", "qs", "an", "mru"}
KNOWN = {
    ("truth", "needle_triangles"): ({"meyer"}, "meyer: |k - 1| = 0.75 next to an edge split by a needle"),
    ("truth", "thin_triangles"): ({"meyer"}, "meyer: |k - 1| = 0.75 next to an edge split by a needle"),
}


def _known(test: str, name: str, method: str, request) -> None:
    methods, reason = KNOWN.get((test, name), ((), ""))
    if method in methods:
        request.node.add_marker(pytest.mark.xfail(reason=reason, strict=False))


def test_corpus_is_big_and_distinct():
    cases = list(CASES.values())
    assert len(cases) >= 30
    assert len({c.name for c in cases}) == len(cases)
    kinds = {c.outcome for c in cases}
    assert kinds == {OK, LOAD_ERROR, MESH_ERROR}


@functools.lru_cache(maxsize=None)
def _load(name: str) -> curv.Mesh:
    case = CASES[name]
    return curv.load(case.path, **case.load_kwargs)


@functools.lru_cache(maxsize=None)
def _estimate(name: str, method: str, k: int) -> curv.Curvature:
    return curv.estimate(_load(name), method, k)


@pytest.mark.parametrize("name", ERROR_CASES)
def test_bad_file_gives_one_line_error_naming_file(name, monkeypatch):
    case = CASES[name]
    if not case.as_root and as_root():
        # root reads any file: pretend the permission check fails the way it does for users
        monkeypatch.setattr("os.access", lambda *a, **k: False)
    expected = curv.LoadError if case.outcome == LOAD_ERROR else curv.MeshError
    with pytest.raises(expected) as err:
        _load.__wrapped__(name)
    message = str(err.value)
    assert message.startswith(f"{case.path}: "), message
    assert "\n" not in message and len(message) < 300
    assert case.message.lower() in message.lower()


@pytest.mark.parametrize("name", OK_CASES)
def test_load_reports_what_it_found_and_repaired(name):
    case = CASES[name]
    mesh = _load(name)
    report = mesh.report()
    for key, value in case.report.items():
        assert getattr(report, key) == value, (key, report)
    assert tuple(mesh.info["repairs"]) == case.repairs
    assert mesh.info["path"] == str(case.path)
    assert all(isinstance(line, str) and "\n" not in line for line in report.lines())


@pytest.mark.parametrize("method, k", VARIANTS, ids=[f"{m}{k}" for m, k in VARIANTS])
@pytest.mark.parametrize("name", OK_CASES)
def test_estimate_is_honest(name, method, k, request):
    case = CASES[name]
    mesh = _load(name)
    spec = curv.ESTIMATORS[method]
    if spec.triangles_only and not case.triangles:
        with pytest.raises(curv.MeshError, match="needs a triangle mesh"):
            curv.estimate(mesh, method, k)
        return
    res = _estimate(name, method, k)
    n = mesh.n_vertices
    v = res.valid
    assert res.k1.shape == res.k2.shape == v.shape == res.reason.shape == (n,)
    assert res.d1.shape == res.d2.shape == (n, 3)
    # invalid: NaN everywhere, with a reason; valid: finite, reason OK
    assert np.all((res.reason == curv.Reason.OK) == v)
    for arr in (res.k1, res.k2, res.d1, res.d2):
        assert np.all(np.isnan(arr[~v]))
        assert np.all(np.isfinite(arr[v]))
    assert np.all(res.k1[v] >= res.k2[v])
    d1, d2, nrm = res.d1[v], res.d2[v], res.normals[v]
    np.testing.assert_allclose(np.linalg.norm(d1, axis=1), 1, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(d2, axis=1), 1, atol=1e-6)
    assert np.all(np.abs(np.einsum("ij,ij->i", d1, d2)) < 1e-6)
    assert np.all(np.abs(np.einsum("ij,ij->i", d1, nrm)) < 1e-6)
    assert np.all(np.abs(np.einsum("ij,ij->i", d2, nrm)) < 1e-6)
    # always invalid: isolated vertices; for closed-ring estimators also borders and non-manifold
    assert not np.any(v & mesh.isolated_vertices)
    assert not np.any(v & mesh.nonmanifold_vertices)
    if spec.closed_ring:
        assert not np.any(v & mesh.border_vertices)
    if case.invalid is not None:
        _known("honest", name, method, request)
        assert not np.any(v & case.invalid), f"{np.sum(v & case.invalid)} vertices wrongly valid"


@pytest.mark.parametrize("method, k", VARIANTS, ids=[f"{m}{k}" for m, k in VARIANTS])
@pytest.mark.parametrize("name", [n for n in OK_CASES if CASES[n].radius is not None])
def test_valid_values_on_spheres_are_not_made_up(name, method, k, request):
    """Where the mesh samples a sphere of radius r, a valid k1, k2 must be near 1/r."""
    case = CASES[name]
    spec = curv.ESTIMATORS[method]
    if spec.triangles_only and not case.triangles:
        pytest.skip("triangle-only estimator on polygons (checked above)")
    res = _estimate(name, method, k)
    check = res.valid & np.isfinite(case.radius)
    _known("truth", name, method, request)
    tolerance = TRUTH_TOLERANCE_FOR.get((method, k), TRUTH_TOLERANCE)
    for kk in (res.k1, res.k2):
        err = np.abs(kk[check] * case.radius[check] - 1)
        assert err.max(initial=0) <= tolerance, f"worst |k r - 1| = {err.max():.3g}"


@pytest.mark.parametrize("method, k", VARIANTS, ids=[f"{m}{k}" for m, k in VARIANTS])
@pytest.mark.parametrize("name", [n for n in OK_CASES if CASES[n].same_as])
def test_same_surface_same_result(name, method, k, request):
    """Other formats, repaired files and scaled copies reproduce the reference (scaled by 1/s)."""
    case = CASES[name]
    spec = curv.ESTIMATORS[method]
    if spec.triangles_only and not case.triangles:
        pytest.skip("triangle-only estimator on polygons")
    _known("same", name, method, request)
    ref = _estimate(case.same_as, method, k)
    res = _estimate(name, method, k)
    np.testing.assert_array_equal(res.valid, ref.valid)
    for a, b in ((res.k1, ref.k1), (res.k2, ref.k2)):
        np.testing.assert_allclose(a * case.scale, b, rtol=1e-6, atol=1e-8)


def test_repairs_are_off_by_default_and_counted():
    mesh = _load("triangle_soup")
    assert mesh.report().duplicate_vertices == mesh.n_vertices - _load("sphere").n_vertices
    assert mesh.info["repairs"] == []
    merged = _load("triangle_soup_merged")
    assert merged.report().duplicate_vertices == 0


def test_flipped_faces_are_reported_and_their_vertices_invalid():
    mesh = _load("inconsistent_orientation")
    bad = mesh.inconsistent_edges
    assert mesh.report().inconsistent_edges == int(bad.sum()) > 0
    res = _estimate("inconsistent_orientation", "mru", 2)
    touched = np.zeros(mesh.n_vertices, bool)
    touched[mesh.edges[bad].reshape(-1)] = True
    assert not res.valid[touched].any()
    assert np.all(res.reason[touched] == curv.Reason.DEGENERATE)
    assert _load("inconsistent_orientation_oriented").report().inconsistent_edges == 0


def test_inside_out_sphere_has_negative_curvature_unless_oriented():
    for method, k in VARIANTS:
        res = _estimate("inside_out", method, k)
        assert np.all(res.k1[res.valid] < 0), method
        fixed = _estimate("inside_out_oriented", method, k)
        assert np.all(fixed.k2[fixed.valid] > 0), method
