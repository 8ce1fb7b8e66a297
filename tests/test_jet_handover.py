"""The jet at its normals' range reads the normals' pass's fits (curv.estimators._jet_handover): the
same answer as fitting again, to the rounding of the support's order. qs's hand-over: test_qs_handover.py."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.estimators import _handover, _jet_handover
from curv.estimators.jet import JET_FITS, iter_jet
from curv.point_normals import grid_ordered
from curv.surfaces import QuadraticPatch, Sphere, sample_points
from tests.handover_checks import handed_and_refitted, same_to_rounding


def _clouds():
    yield "sphere", sample_points(Sphere(1.0), 3000, rng=1).cloud
    yield "blue patch", sample_points(QuadraticPatch(), 2000, sampling="blue", rng=4).cloud
    yield "rows", sample_points(QuadraticPatch(), 3000, sampling="rows", ratio=4, rng=12).cloud


CLOUDS = dict(_clouds())


def _handed_and_refitted(cloud, normals_of=lambda n: n):
    """jet at R2 with the pass's fits kept, and with them dropped (a fit per point)."""
    return handed_and_refitted(cloud, "jet", JET_FITS, iter_jet, normals_of)


@pytest.mark.parametrize("name", list(CLOUDS))
def test_the_handed_fits_are_the_fits(name):
    handed, refitted, left = _handed_and_refitted(CLOUDS[name])
    assert left.size < 0.1 * handed.reason.size
    assert (handed.reason == 0).sum() > 0.5 * handed.reason.size
    # scan rows 4:1 apart fit nearly singular systems, whose rounding the support's order moves more
    same_to_rounding(handed, refitted, rtol=1e-5 if name == "rows" else 1e-11)


def test_the_handed_fits_follow_any_reference():
    """Normals turned over (every frame on the other side of the pass's) and normals tilted past the
    DEGENERATE test: the same as the fit with those references."""
    cloud = CLOUDS["sphere"]
    handed, refitted, _ = _handed_and_refitted(cloud, lambda n: -n)
    same_to_rounding(handed, refitted, rtol=1e-11)
    assert (handed.k1[handed.reason == 0] < 0).all()  # outward sphere seen from inside

    def tilted(n):
        out = n.copy()
        out[::3] = np.cross(n[::3], [0.0, 0.0, 1.0])  # at right angles: DEGENERATE
        return out / np.linalg.norm(out, axis=1, keepdims=True)

    handed, refitted, _ = _handed_and_refitted(cloud, tilted)
    same_to_rounding(handed, refitted, rtol=1e-11)
    assert (handed.reason[::3] == curv.Reason.DEGENERATE).mean() > 0.9


def test_an_estimate_reads_the_fits_only_where_they_match():
    """The whole call: the jet at R2 (handed over) against the same with standard errors (a fit per
    point: their kernel reads the fit's normal matrix), and no other estimate keeps the jet's fits."""
    cloud = CLOUDS["blue patch"]
    plain = curv.estimate(cloud, "jet", 2)
    fitted = curv.estimate(cloud, "jet", 2, standard_errors=True)
    same_to_rounding(plain, fitted, rtol=1e-11)
    np.testing.assert_array_equal(plain.valid, fitted.valid)
    other = curv.PointCloud(np.asarray(cloud.vertices) + 0.0)
    twin = grid_ordered(other)[0]  # the estimate's cloud, kept with the cloud
    curv.estimate(other, "qs", 2)
    curv.estimate(other, "jet", 3)
    curv.estimate(other, "jet", 2, degree=3)
    assert _handover.kept_fits(twin, JET_FITS.options) is None
    curv.estimate(other, "jet", 2)
    assert _handover.kept_fits(twin, JET_FITS.options) is not None


def test_the_memory_model_counts_the_kept_fits():
    from curv.memory import estimate_peak_bytes

    n = 1_000_000
    extra = estimate_peak_bytes(n, 0, "jet", points=True, threads=1) - estimate_peak_bytes(n, 0, "mru", points=True,
                                                                                            threads=1)
    assert extra == n * _jet_handover.BYTES_PER_POINT
