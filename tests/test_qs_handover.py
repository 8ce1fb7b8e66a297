"""qs at its normals' range reads the fit the normals' pass made in the frame of the fitted normal
(curv.estimators.qs, curv.estimators._handover): to the bit the fit in the turned frame over the same
support, and the same answer as fitting again to the rounding of the support's order."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

import curv
from curv.core.validity import OK
from curv.estimators import _handover
from curv.estimators._frames import Geometry
from curv.estimators._jet_fit import jet_scratch
from curv.estimators._principal import new_rows
from curv.estimators._three_unknowns import fit_at
from curv.estimators.jet import JET_FITS
from curv.estimators.qs import NO_FIT, QS, QS_FITS, _handed_fit, _keep_fit, iter_qs, new_qs_fits
from curv.point_normals import grid_ordered, point_normals
from curv.surfaces import QuadraticPatch, Sphere, sample_points
from tests.handover_checks import handed_and_refitted, same_to_rounding


def _clouds():
    yield "sphere", sample_points(Sphere(1.0), 3000, rng=1).cloud
    yield "blue patch", sample_points(QuadraticPatch(), 2000, sampling="blue", rng=4).cloud
    yield "rows", sample_points(QuadraticPatch(), 3000, sampling="rows", ratio=4, rng=12).cloud


CLOUDS = dict(_clouds())


def _rows_equal(a, b, at=slice(None)):
    for name in ("k1", "k2", "d1", "d2", "reason"):
        np.testing.assert_array_equal(getattr(a, name)[at], getattr(b, name)[at], err_msg=name)


def test_the_kept_fit_turned_over_is_the_fit_in_the_turned_frame():
    """Every normal turned over: the kept fit, turned, finishes to the bit as qs's own fit
    (``fit_at``) with the turned normal over the same support in the same order; so does the
    normal itself. Supports of a sphere, a saddle, a line (singular), two points (too few)."""
    rng = np.random.default_rng(3)
    sphere = rng.normal(size=(400, 3))
    sphere /= np.linalg.norm(sphere, axis=1, keepdims=True)
    uv = rng.uniform(-1, 1, size=(300, 2))
    saddle = np.column_stack([uv, 0.3 * uv[:, 0] * uv[:, 1] - 0.2 * uv[:, 0] ** 2])
    line = np.column_stack([np.linspace(0, 1, 30), 2 * np.linspace(0, 1, 30), np.zeros(30)])
    points = np.vstack([sphere, saddle + 5.0, line + 20.0, [[40.0, 0, 0], [40.01, 0, 0]]])
    n = points.shape[0]
    x, y, z = (np.ascontiguousarray(points[:, c]) for c in range(3))
    # fitted normals: the true ones tilted a little, either sign
    normals = rng.normal(size=(n, 3)) * 0.05 + np.where(np.arange(n)[:, None] < 400, points, [0.0, 0.0, 1.0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    normals *= rng.choice([-1.0, 1.0], size=(n, 1))
    radii = np.full(n, 0.35)
    tree = cKDTree(points)
    fits = new_qs_fits(radii)
    turned = -normals
    handed, fitted = new_rows(n), new_rows(n)
    geometry = Geometry(x, y, z, *(np.ascontiguousarray(turned[:, c]) for c in range(3)))
    scratch = jet_scratch()
    offsets = np.empty((64, 2))
    for p in range(n):
        ball = np.array([q for q in tree.query_ball_point(points[p], radii[p]) if q != p], np.int64)
        queue = np.concatenate(([p], rng.permutation(ball))).astype(np.int64)
        _keep_fit(fits, p, p, (OK, 1.0, True, scratch), (queue, queue.size), (x, y, z), normals)
        assert _handed_fit(fits, p, turned, 0, handed)
        fit_at(QS, p, queue, queue.size, radii[p], geometry, fitted, None, None, offsets)
    _rows_equal(handed, fitted)
    reasons = set(fitted.reason.tolist())
    assert {int(curv.Reason.OK), int(curv.Reason.SINGULAR), int(curv.Reason.TOO_FEW_NEIGHBOURS)} <= reasons
    # the kept normal itself, and one that is neither it nor its opposite: a fit must tell
    again = new_rows(n)
    for p in range(n):
        assert _handed_fit(fits, p, normals, 0, again)
        assert not _handed_fit(fits, p, normals + 1e-12, 0, again)
    assert (again.k1[handed.reason == OK] == -handed.k2[handed.reason == OK]).all()


def _handed_and_refitted(cloud, normals_of=lambda n: n):
    """qs at R2 with the pass's fits kept, and with them dropped (a fit per point)."""
    return handed_and_refitted(cloud, "qs", QS_FITS, iter_qs, normals_of)


@pytest.mark.parametrize("name", list(CLOUDS))
def test_the_handed_fits_are_the_fits(name):
    handed, refitted, left = _handed_and_refitted(CLOUDS[name])
    assert left.size == 0  # NaN normals are DEGENERATE as a fit makes them: nothing left to fit
    assert (handed.reason == OK).sum() > 0.5 * handed.reason.size
    same_to_rounding(handed, refitted, rtol=1e-7 if name == "rows" else 1e-11)


def test_the_handed_fits_follow_the_normal_turned_over():
    """Every normal turned over: the fits of the other side, and a normal the pass did not fit
    with (rotated) is fitted again."""
    cloud = CLOUDS["sphere"]
    handed, refitted, left = _handed_and_refitted(cloud, lambda n: -n)
    assert left.size == 0
    same_to_rounding(handed, refitted, rtol=1e-11)
    assert (handed.k1[handed.reason == OK] < 0).all()  # outward sphere seen from inside

    def rotated(n):
        out = n.copy()
        out[::3] = n[::3, [1, 2, 0]]
        return out

    handed, refitted, left = _handed_and_refitted(cloud, rotated)
    every_third = np.zeros(cloud.n_points, bool)
    every_third[::3] = True
    finite = np.isfinite(rotated(point_normals(cloud, range=2).normals)).all(axis=1)
    np.testing.assert_array_equal(np.sort(left), np.flatnonzero(every_third & finite))
    _rows_equal(handed, refitted, left)  # fitted again: the fit itself
    same_to_rounding(handed, refitted, rtol=1e-11)


def test_an_estimate_reads_the_fits_only_where_they_match():
    """The whole call: qs at R2 (handed over) against the same with standard errors (a fit per
    point); other estimates keep no qs fits, and a region reads them too."""
    cloud = CLOUDS["blue patch"]
    plain = curv.estimate(cloud, "qs", 2)
    fitted = curv.estimate(cloud, "qs", 2, standard_errors=True)
    same_to_rounding(plain, fitted, rtol=1e-11)
    np.testing.assert_array_equal(plain.valid, fitted.valid)
    region = curv.estimate(cloud, "qs", 2, vertices=np.arange(0, cloud.n_points, 7))
    _rows_equal(region, plain, slice(0, None, 7))
    other = curv.PointCloud(np.asarray(cloud.vertices) + 0.0)
    twin = grid_ordered(other)[0]  # the estimate's cloud, kept with the cloud
    curv.estimate(other, "qs", 2, standard_errors=True)
    curv.estimate(other, "mru", 2)
    assert _handover.kept_fits(twin, QS_FITS.options) is None
    curv.estimate(other, "qs", 2)
    assert _handover.kept_fits(twin, QS_FITS.options) is not None
    assert _handover.kept_fits(twin, JET_FITS.options) is None
    fits = _handover.kept_fits(twin, QS_FITS.options)
    assert (fits.state != NO_FIT).mean() > 0.9


def test_the_memory_model_counts_the_kept_fits():
    from curv.memory import estimate_peak_bytes

    n = 1_000_000
    extra = estimate_peak_bytes(n, 0, "qs", points=True, threads=1) - estimate_peak_bytes(n, 0, "mru", points=True,
                                                                                           threads=1)
    assert extra == n * QS_FITS.bytes_per_point == n * (6 * 8 + 1 + 8)
