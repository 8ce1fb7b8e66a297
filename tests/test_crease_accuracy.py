"""Why ``features=`` exists: near a crease every estimator is as good as in the interior with it, and
far worse without it.

Error measure: ``e = (|k1 - k1^| + |k2 - k2^|) / kappa`` (e_abs scaled by a characteristic curvature
of the solid) rather than the paper's e_rel, which is undefined on the flat parts (k1 = k2 = 0).
``kappa`` is ``1 / radius`` for the capped cylinder and the hemisphere (the curvature of their round
part) and ``2 / shortest side`` for the box (that of the largest ball inside it).

Statistic: the mean of ``e`` over the vertices 1 ring, and 2 rings, from the nearest crease vertex of
each smooth part, against the mean over that part's interior (4 or more rings away, beyond every
default support). With features the ring means must stay within ``2 x interior + FLOOR``; without,
the mean over rings 1 and 2 must be at least ``10 x (interior + FLOOR)``.

``FLOOR = 0.01`` (1 % of kappa): flat parts are fitted exactly (interior error ~1e-15) and several
estimators are exact on these cylinders and spheres too, so a bare 2x would demand bit-exact values
next to a crease. 1 % of the curvature scale lies within the spread of the interior errors on the
round parts at these densities (1e-15 to 0.05 of kappa), so it excuses no real loss of accuracy; and
it does not decide the features-off side, where the ring errors are 1 to 15 kappa (100-1000 x it).

Where an estimator truly misses a requirement it stays here as ``xfail(strict=True)`` with the
measured numbers.
"""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.features import feature_set
from curv.metrics import absolute_error
from curv.surfaces import Box, CappedCylinder, Cone, HemisphereOnDisc, Torus, crease_distance_rings

FLOOR = 0.01
WITHIN = 2.0
BEYOND = 10.0
INTERIOR_RINGS = 4
FEATURE_DEGREES = 30
DENSITIES = (1500, 4000)

SOLIDS = {
    "capped_cylinder": (CappedCylinder(radius=1.0, height=2.0), 1.0),
    "box": (Box(2.0, 1.5, 1.0), 2.0),
    "hemisphere": (HemisphereOnDisc(radius=1.0), 1.0),
}
"""name -> (solid, kappa)."""

MISSES_WITH_FEATURES: dict[tuple[str, str], str] = {}
"""(solid, method) -> the measured numbers of a requirement an estimator misses (none today). csm on
the dome used to: ring 1 e = 0.13 (1500) / 0.11 (4000) against the limit 0.114, while it took the
faces touching the rim and left out the rim edges' whole dihedral term (the dome's curvature across
the rim lost, the faces' area kept); it now leaves out the faces touching a crease vertex and keeps
the half of each edge's term that belongs to a kept face: ring 1 0.069 / 0.088, interior 0.052."""
NEEDS_NO_FEATURES = ("meyer",)
"""Estimators whose values next to a crease do not depend on ``features=``: meyer's 1-ring at a
vertex next to a crease is the vertex's own faces, all on its side (the crease vertices are their
corners), and it uses positions and its own normal only, never a neighbour's normal. So it is as
good there without features as with them, and the crease cannot spoil it (the 10x check does not
apply: :func:`test_meyer_next_to_a_crease_needs_no_features` checks what holds instead)."""


def cases(misses, methods=tuple(curv.ESTIMATORS)):
    out = []
    for solid in SOLIDS:
        for method in methods:
            why = misses.get((solid, method))
            marks = [pytest.mark.xfail(strict=True, reason=why)] if why else []
            out.append(pytest.param(solid, method, marks=marks, id=f"{solid}-{method}"))
    return out


def ring_errors(solid_name, n, method, features):
    """Per smooth part with an interior: mean e at ring 1, ring 2, rings 1-2, and the interior."""
    solid, kappa = SOLIDS[solid_name]
    s = solid.mesh(n)
    res = curv.estimate(s.mesh, method, features=features)
    e = absolute_error(s.truth.k1, s.truth.k2, res.k1, res.k2) / kappa
    rings = crease_distance_rings(s.mesh, ~s.truth.valid)
    out = {}
    for index, name in enumerate(s.info["parts"]):
        on = s.info["part"] == index
        if not (on & (rings >= INTERIOR_RINGS)).any():
            continue
        near = [on & (rings == 1), on & (rings == 2), on & np.isin(rings, (1, 2)), on & (rings >= INTERIOR_RINGS)]
        assert all(np.isfinite(e[m]).all() and m.any() for m in near), f"{name}: an invalid or empty ring"
        out[name] = [float(e[m].mean()) for m in near]
    assert out
    return out


@pytest.mark.parametrize("n", DENSITIES)
@pytest.mark.parametrize("solid, method", cases(MISSES_WITH_FEATURES))
def test_with_features_the_crease_neighbours_are_as_good_as_the_interior(solid, method, n):
    for part, (ring1, ring2, _, interior) in ring_errors(solid, n, method, FEATURE_DEGREES).items():
        limit = WITHIN * interior + FLOOR
        assert ring1 <= limit and ring2 <= limit, (
            f"{part}: ring 1 {ring1:.3g}, ring 2 {ring2:.3g}, interior {interior:.3g} (limit {limit:.3g})")


@pytest.mark.parametrize("n", DENSITIES)
@pytest.mark.parametrize("solid, method", cases({}, [m for m in curv.ESTIMATORS if m not in NEEDS_NO_FEATURES]))
def test_without_features_the_crease_spoils_its_neighbours(solid, method, n):
    for part, (_, _, near, interior) in ring_errors(solid, n, method, None).items():
        assert near >= BEYOND * (interior + FLOOR), f"{part}: rings 1-2 {near:.3g}, interior {interior:.3g}"


@pytest.mark.parametrize("solid", list(SOLIDS))
def test_meyer_next_to_a_crease_needs_no_features(solid):
    s = SOLIDS[solid][0].mesh(DENSITIES[0])
    plain, with_features = curv.estimate(s.mesh, "meyer"), curv.estimate(s.mesh, "meyer", features=FEATURE_DEGREES)
    smooth = s.truth.valid
    for name in ("k1", "k2", "d1", "d2", "reason"):
        np.testing.assert_array_equal(getattr(plain, name)[smooth], getattr(with_features, name)[smooth], err_msg=name)
    for part, (ring1, ring2, _, interior) in ring_errors(solid, DENSITIES[0], "meyer", None).items():
        limit = WITHIN * interior + FLOOR
        assert ring1 <= limit and ring2 <= limit, f"{part}: ring 1 {ring1:.3g}, ring 2 {ring2:.3g}, interior {interior:.3g}"


@pytest.mark.parametrize("method", list(curv.ESTIMATORS))
def test_crease_corner_and_apex_vertices_are_feature(method):
    for solid in (CappedCylinder(), Box(), HemisphereOnDisc()):
        s = solid.mesh(1500)
        res = curv.estimate(s.mesh, method, features=FEATURE_DEGREES)
        feature = res.reason == curv.Reason.FEATURE
        np.testing.assert_array_equal(feature, ~s.truth.valid)     # the creases, and nothing else
        assert np.isnan(res.k1[feature]).all() and not res.valid[feature].any()
    box = Box().mesh(1500)
    corners = np.flatnonzero(feature_set(box.mesh, FEATURE_DEGREES).corners)
    np.testing.assert_allclose(np.abs(box.mesh.vertices[corners]), np.tile(box.surface.sizes / 2, (8, 1)))
    # the apex, and every vertex of the rim; near the apex the mesh itself is sharp (k1 = cos(alpha) / rho
    # at rho ~ one edge), so a few more vertices there are FEATURE as well
    cone = Cone().mesh(1500)
    res = curv.estimate(cone.mesh, method, features=FEATURE_DEGREES)
    feature = res.reason == curv.Reason.FEATURE
    assert feature[~cone.truth.valid].all()
    apex = np.argmax(cone.mesh.vertices[:, 2])
    assert feature_set(cone.mesh, FEATURE_DEGREES).corners[apex]
    assert np.all(np.linalg.norm(cone.mesh.vertices[feature & cone.truth.valid] - cone.mesh.vertices[apex], axis=1)
                  < 3 * cone.mesh.mean_edge_length)


@pytest.mark.parametrize("method", list(curv.ESTIMATORS))
def test_smooth_surface_unchanged_by_features(method):
    mesh = Torus(major=1.0, minor=0.4).mesh(1200).mesh
    assert not feature_set(mesh, FEATURE_DEGREES).edges.any()      # no dihedral angle there is that large
    plain, with_features = curv.estimate(mesh, method), curv.estimate(mesh, method, features=FEATURE_DEGREES)
    for name in ("k1", "k2", "d1", "d2", "normals", "valid", "reason"):
        np.testing.assert_array_equal(getattr(with_features, name), getattr(plain, name), err_msg=name)
