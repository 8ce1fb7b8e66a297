"""What the hand-over tests (test_jet_handover.py, test_qs_handover.py) compare: an estimator's
rows from the normals' pass's fits against its own fit per point, to the rounding of the support's order."""

from __future__ import annotations

import numpy as np


def same_to_rounding(a, b, *, rtol: float) -> None:
    """Equal reasons, and k1, k2 and the directions equal to ``rtol`` of the largest |k|."""
    np.testing.assert_array_equal(a.reason, b.reason)
    ok = a.reason == 0
    scale = np.abs(b.k1[ok]).max() + np.abs(b.k2[ok]).max()
    for name in ("k1", "k2"):
        np.testing.assert_allclose(getattr(a, name)[ok], getattr(b, name)[ok], rtol=0, atol=rtol * scale, err_msg=name)
    for name in ("d1", "d2"):
        # a direction's sign is free where k1 = k2 (the sphere): compare the lines
        dot = np.abs(np.einsum("ij,ij->i", getattr(a, name)[ok], getattr(b, name)[ok]))
        umbilic = np.abs(b.k1[ok] - b.k2[ok]) < 1e-6 * scale
        assert (dot[~umbilic] > 1 - 1e-9).all(), name


def handed_and_refitted(cloud, method: str, fits, iterate, normals_of=lambda n: n):
    """``method`` at R2 with the pass's ``fits`` (:class:`curv.estimators._handover.NormalFits`)
    kept, the centres the hand-over leaves to a fit, and ``method`` with the fits dropped (a fit
    per point); ``iterate`` is its function, ``normals_of`` turns the pass's normals first."""
    from curv.core.jit import run_to_end
    from curv.core.ranges import ball_radii, resolve
    from curv.estimators import _handover, get_spec
    from curv.estimators._principal import new_rows
    from curv.point_normals import point_normals

    rng = resolve(get_spec(method), 2)
    normals = normals_of(point_normals(cloud, range=2, keep_fits_at=(rng,), keep_fits=fits).normals)
    radii = ball_radii(cloud, rng, uses_normals=False)
    kept = _handover.kept_fits(cloud, fits.options)
    assert kept is not None
    handed = run_to_end(iterate(cloud, normals, radii))
    n = cloud.n_points
    left = run_to_end(_handover.iter_handed(kept, normals, radii, np.arange(n), new_rows(n)))
    _handover.forget_fits(cloud)
    refitted = run_to_end(iterate(cloud, normals, radii))
    return handed, refitted, left
