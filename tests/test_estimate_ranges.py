"""``curv.estimate_ranges``: several ranges of one estimator in one call equal one call per range."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.api import estimate_ranges
from curv.core.errors import EstimatorError
from creased_meshes import box
from meshes import icosphere, noisy_torus, paraboloid_patch

RANGES = (3, 1, 4, 2.5, 2)


def _noisy_torus():
    return noisy_torus(36, 16, seed=4)


def _open_patch():
    return paraboloid_patch(12)


MESHES = {"sphere": lambda: icosphere(3), "noisy torus": _noisy_torus, "open patch": _open_patch}


def _compare(one, many_res, shared: bool):
    for name in ("reason", "valid"):
        assert np.array_equal(getattr(one, name), getattr(many_res, name)), name
    for name in ("k1", "k2", "d1", "d2", "k1_se", "k2_se"):
        a, b = getattr(one, name), getattr(many_res, name)
        if not shared:
            assert np.array_equal(a, b, equal_nan=True), name
        elif name in ("d1", "d2"):
            # the sums over a support are added in another order: rounding only. The directions
            # are those of the rounded tensor: only where k1 and k2 stand apart are they defined
            apart = one.valid & (one.k1 - one.k2 > 1e-7 * np.abs(one.k1))
            cos = np.abs(np.einsum("ij,ij->i", a[apart], b[apart]))
            assert np.allclose(cos, 1.0, atol=1e-6), name
        else:
            assert np.allclose(a, b, rtol=1e-11, atol=1e-12, equal_nan=True), name
    assert one.range == many_res.range and one.info["range_label"] == many_res.info["range_label"]


@pytest.mark.parametrize("mesh_name", sorted(MESHES))
@pytest.mark.parametrize("method", ["csm", "icc", "qs"])
@pytest.mark.parametrize("region", [False, True], ids=["whole", "region"])
def test_ranges_equal_one_call_each(mesh_name, method, region):
    mesh = MESHES[mesh_name]()
    idx = np.arange(3, mesh.n_vertices, 5) if region else None
    many = estimate_ranges(mesh, method, RANGES, vertices=idx, standard_errors=True)
    assert len(many) == len(RANGES)
    for r, res in zip(RANGES, many):
        _compare(curv.estimate(mesh, method, r, vertices=idx, standard_errors=True), res,
                 shared=method in ("csm", "icc"))
    if mesh_name == "open patch" and method != "qs":
        # the wide balls reach the border where the narrow ones do not (BORDER for the clipping
        # estimators): the levels differ
        reasons = [np.count_nonzero(res.reason == curv.Reason.BORDER) for res in many]
        assert reasons[RANGES.index(4)] > reasons[RANGES.index(1)]


@pytest.mark.parametrize("method", ["csm", "icc"])
def test_ranges_at_creases_and_in_chunks(method):
    """Supports that stop at creases walk face by face, with a stamp of their own per range."""
    mesh = box(4)
    many = estimate_ranges(mesh, method, (1, 2, 3), features=30, block_size=7, standard_errors=True)
    for r, res in zip((1, 2, 3), many):
        _compare(curv.estimate(mesh, method, r, features=30, standard_errors=True), res, shared=True)


def test_one_range_is_estimate():
    mesh = icosphere(2)
    (res,) = estimate_ranges(mesh, "csm", [2])
    ref = curv.estimate(mesh, "csm", 2)
    assert np.array_equal(res.k1, ref.k1) and np.array_equal(res.d2, ref.d2)
    (single,) = estimate_ranges(mesh, "csm", "R2")
    assert np.array_equal(single.k1, ref.k1)
    pair = estimate_ranges(mesh, "qs", np.array([2, 1]))
    assert [r.range for r in pair] == [2, 1] and np.array_equal(pair[1].k1, curv.estimate(mesh, "qs", 1).k1)


def test_flat_rows_are_the_levels_one_after_another():
    """The clipping pass writes row ``level * n + p`` of its flat outputs (no row view per centre):
    they must be views of the (levels, n) outputs in that order, for icc's extra outputs too."""
    from curv.estimators._output_rows import LevelOutputs
    from curv.estimators.icc import IccOutputs

    for out in (LevelOutputs(3, 5), IccOutputs(3, 5)):
        for full, flat in zip(out.rows, out.flat_rows):
            assert flat.shape == (15, *full.shape[2:]) and np.shares_memory(flat, full)
            flat[2 * 5 + 4] = 7  # level 2, vertex 4
            assert np.all(full[2, 4] == 7)


def test_sphere_sign_and_value():
    mesh = icosphere(4, radius=2.0)
    for res in estimate_ranges(mesh, "icc", (1, 2, 4)):
        assert np.allclose(res.k1[res.valid], 0.5, rtol=0.02) and np.allclose(res.k2[res.valid], 0.5, rtol=0.02)


def test_refusals():
    mesh = icosphere(1)
    with pytest.raises(EstimatorError, match="radius"):
        estimate_ranges(mesh, "csm", (1, 2), radius=0.3)
    with pytest.raises(EstimatorError, match="at least one"):
        estimate_ranges(mesh, "csm", ())
    with pytest.raises(EstimatorError):
        estimate_ranges(mesh, "csm", (1, 0.2))


def test_estimate_ranges_is_part_of_the_package():
    assert curv.estimate_ranges is estimate_ranges and "estimate_ranges" in curv.__all__
