"""The closed-form symmetric 3x3 eigen-solve against LAPACK and the Jacobi solve it replaces in the point passes."""

from __future__ import annotations

import numpy as np
import pytest

from curv.core.small_linalg import sym3_eigen, sym3_eigen_closed


def _rotation(rng):
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return q


def _matrices(rng):
    """Covariances as the point passes see them (planes, lines, discs) and harder cases, rotated."""
    for k in range(600):
        kind = k % 6
        if kind == 0:
            m = rng.normal(size=(3, 3))
            a = m @ m.T
        elif kind == 1:  # a thin plane
            a = np.cov((rng.normal(size=(30, 3)) * [1.0, 1.0, 10.0 ** rng.uniform(-6, -1)] @ _rotation(rng)).T)
        elif kind == 2:  # a line
            a = np.cov((rng.normal(size=(30, 3)) * [1.0, 1e-4, 1e-4] @ _rotation(rng)).T)
        elif kind == 3:  # a disc: a double eigenvalue
            r = _rotation(rng)
            a = r @ np.diag([1e-6, 1.0, 1.0]) @ r.T
        elif kind == 4:  # points exactly on a plane
            pts = rng.normal(size=(30, 3))
            pts[:, 2] = 0.0
            a = np.cov((pts @ _rotation(rng)).T)
        else:  # scales far from 1
            a = np.cov((rng.normal(size=(30, 3)) @ _rotation(rng)).T) * 10.0 ** rng.integers(-8, 8)
        yield 0.5 * (a + a.T)


def _solve(solver, a):
    vecs = np.empty((4, 3))
    solver(a.copy(), vecs)
    return vecs


def test_closed_form_matches_lapack_to_rounding():
    rng = np.random.default_rng(3)
    for a in _matrices(rng):
        got = _solve(sym3_eigen_closed, a)
        values, vectors = np.linalg.eigh(a)
        scale = np.abs(values).max()
        assert np.all(np.diff(got[3]) >= 0.0)
        assert np.abs(got[3] - values).max() <= 1e-13 * scale
        assert np.abs(got[:3].T @ got[:3] - np.eye(3)).max() <= 1e-14  # orthonormal, repeated eigenvalues too
        for j in range(3):
            gap = min(abs(values[j] - values[i]) for i in range(3) if i != j) / scale
            if gap > 1e-6:
                sine = np.linalg.norm(np.cross(got[:3, j], vectors[:, j]))
                assert sine * gap <= 1e-14, (a, j)
        # the Jacobi solve it replaces: the same pairs up to sign, where they are determined
        old = _solve(sym3_eigen, a)
        assert np.abs(old[3] - got[3]).max() <= 1e-12 * scale


@pytest.mark.parametrize("diagonal", [(0.0, 0.0, 0.0), (2.0, 2.0, 2.0), (1.0, 1.0, 0.0), (3.0, 1.0, 1.0)])
def test_closed_form_degenerate_cases(diagonal):
    a = np.diag(diagonal)
    got = _solve(sym3_eigen_closed, a)
    assert np.array_equal(got[3], np.sort(diagonal))
    assert np.allclose(np.abs(got[:3].T @ got[:3]), np.eye(3), atol=1e-15)
    assert np.allclose(a @ got[:3], got[:3] * got[3], atol=1e-15)
    if len(set(diagonal)) == 1:  # a multiple of the identity: its columns, as the Jacobi solve gives
        assert np.array_equal(got, _solve(sym3_eigen, a))


def test_closed_form_nan_input_gives_nan():
    a = np.eye(3)
    a[0, 1] = a[1, 0] = np.nan
    assert np.isnan(_solve(sym3_eigen_closed, a)).all()


def _factored(a):
    """``a`` in the layout of :func:`curv.core.small_linalg.cholesky_scaled`, factored; its norm bound."""
    from curv.core.small_linalg import cholesky_scaled, scaled_norm_bound

    size = a.shape[0]
    m = np.zeros((size + 1, size))
    m[:size] = np.triu(a)
    lam_max = scaled_norm_bound(m, size, size)
    assert cholesky_scaled(m, size, size)
    return m, lam_max


@pytest.mark.parametrize("size", [6, 10, 15])
def test_the_condition_estimate_does_not_follow_a_turned_axis(size):
    """A jet fit in a frame turned over (e2 and e3 to their opposites) has the normal matrix S A S,
    S the signs of its unknowns (V_SIGNS): its condition estimate, and so SINGULAR, is A's to the bit."""
    from curv.core.small_linalg import reciprocal_condition
    from curv.estimators._jet_fit import V_SIGNS

    rng = np.random.default_rng(3)
    signs = V_SIGNS[:size]
    for k in range(200):
        # ill-conditioned too: the smallest eigenvector on either side of the signs
        q, _ = np.linalg.qr(rng.normal(size=(size, size)))
        a = q @ np.diag(10.0 ** rng.uniform(-10 if k % 2 else -3, 0, size)) @ q.T
        turned = a * np.outer(signs, signs)
        m, lam = _factored(a)
        mt, lam_t = _factored(turned)
        assert lam == lam_t
        vec = np.empty((3, size))
        r = reciprocal_condition(m, size, lam, vec, 2, signs)
        rt = reciprocal_condition(mt, size, lam_t, vec, 2, signs)
        assert r == rt
        # an estimate: at least the true reciprocal condition of D A D, within a modest factor
        d = 1.0 / np.sqrt(np.diag(a))
        eig = np.linalg.eigvalsh(a * np.outer(d, d))
        assert r >= 0.999 * eig[0] / lam
