"""Full-length arrays of one value that cost only the rows written (curv.core.filled), and the region's ball radii."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.core.filled import MIN_MAPPED_BYTES, filled
from curv.core.ranges import Range, ball_radii
from curv.surfaces import Torus
from curv.core.validity import Reason

LARGE = MIN_MAPPED_BYTES // 8 + 12345  # float64 rows above the mapping threshold


@pytest.mark.parametrize("shape, value, dtype", [
    (LARGE, np.nan, np.float64), ((LARGE, 3), np.nan, np.float64), (3 * LARGE, Reason.NOT_COMPUTED, np.uint8),
    (10, np.nan, np.float64), ((7, 3), 2.5, np.float64),
])
def test_filled_is_np_full(shape, value, dtype):
    out = filled(shape, value, dtype)
    np.testing.assert_array_equal(out, np.full(shape, value, dtype))
    assert out.dtype == np.dtype(dtype) and out.flags.writeable and out.flags.c_contiguous


def test_most_written_arrays_are_ordinary_and_the_rest_mapped():
    import mmap

    mapped, plain = filled(LARGE, np.nan), filled(LARGE, np.nan, most_written=True)
    np.testing.assert_array_equal(plain, mapped)
    base = mapped
    while isinstance(base, np.ndarray):
        base = base.base
    assert isinstance(base, memoryview) and isinstance(base.obj, mmap.mmap)
    assert plain.base is None  # np.full's own buffer: a whole-mesh write pays no copy-on-write


def test_filled_arrays_are_independent_and_grow():
    a = filled(LARGE, np.nan)
    a[[0, 5, LARGE - 1]] = 1.0
    b = filled(LARGE, np.nan)
    assert np.isnan(b).all()                      # a's writes stay a's own
    b[:] = 2.0
    assert np.count_nonzero(a == 1.0) == 3 and np.isnan(a).sum() == LARGE - 3
    bigger = filled(4 * LARGE, np.nan)            # a larger request than any before
    assert np.isnan(bigger).all() and np.count_nonzero(a == 1.0) == 3


@pytest.mark.parametrize("rng", [Range(k=2.0), Range(k=3.5), Range(radius=0.3)])
@pytest.mark.parametrize("uses_normals", [False, True])
def test_ball_radii_at_a_region_are_the_full_ones_there(rng, uses_normals):
    mesh = Torus().mesh(3000).mesh
    at = np.array([0, 17, 999, 2000])
    full = ball_radii(mesh, rng, uses_normals=uses_normals)
    part = ball_radii(mesh, rng, uses_normals=uses_normals, at=at)
    np.testing.assert_array_equal(part[at], full[at])
    rest = np.setdiff1d(np.arange(mesh.n_vertices), at)
    assert part.shape == full.shape and np.isnan(part[rest]).all()


def test_a_large_region_result_is_full_length_nan_outside():
    mesh = Torus().mesh(LARGE // 2).mesh                # d1, d2 large enough to be mapped
    idx = np.arange(100, 600)
    res = curv.estimate(mesh, "mru", vertices=idx)
    rest = np.ones(mesh.n_vertices, bool)
    rest[idx] = False
    assert np.isnan(res.k1[rest]).all() and np.isnan(res.d1[rest]).all()
    assert (res.reason[rest] == Reason.NOT_COMPUTED).all() and not res.valid[rest].any()
    full = curv.estimate(mesh, "mru")
    np.testing.assert_array_equal(res.k1[idx], full.k1[idx])
    np.testing.assert_array_equal(res.d2[idx], full.d2[idx])
    res.d1[np.flatnonzero(rest)[:10]] = 0.0             # the arrays are the caller's to write
    assert (res.d1[np.flatnonzero(rest)[:10]] == 0.0).all()


def test_the_latest_choice_is_kept_with_the_mesh():
    from curv.geometry.neighbourhood import latest_with_mesh

    mesh = Torus().mesh(300).mesh
    built = []

    def build():
        built.append(object())
        return built[-1]

    first = latest_with_mesh(mesh, "test", (30.0,), build)
    assert latest_with_mesh(mesh, "test", (30.0,), build) is first and len(built) == 1
    assert latest_with_mesh(mesh, "test", (40.0,), build) is built[1]
    assert latest_with_mesh(mesh, "test", (30.0,), build) is built[2]     # only the latest is kept
    flags = np.zeros(3, bool)
    kept = latest_with_mesh(mesh, "test", (flags,), build)
    assert latest_with_mesh(mesh, "test", (flags,), build) is kept           # arrays by identity
    assert latest_with_mesh(mesh, "test", (flags.copy(),), build) is not kept
    assert latest_with_mesh(Torus().mesh(300).mesh, "test", (flags,), build) is not kept  # per mesh
