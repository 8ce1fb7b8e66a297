"""``curv.estimate_table``: several estimators at several ranges in one call; csm and icc in one pass
give what one ``estimate_ranges`` each gives."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.api import estimate_ranges, estimate_table
from curv.core.errors import EstimatorError
from creased_meshes import box
from meshes import icosphere, noisy_torus, paraboloid_patch

RANGES = (3, 1, 4, 2.5, 2)

MESHES = {"sphere": lambda: icosphere(3), "noisy torus": lambda: noisy_torus(36, 16, seed=4),
          "open patch": lambda: paraboloid_patch(12)}

FIELDS = ("k1", "k2", "d1", "d2", "reason", "valid")


def _same(a, b):
    for name in FIELDS:
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=True), name
    assert a.method == b.method and a.range == b.range


@pytest.mark.parametrize("mesh_name", sorted(MESHES))
@pytest.mark.parametrize("region", [False, True], ids=["whole", "region"])
def test_the_shared_pass_gives_each_estimators_own_bits(mesh_name, region):
    mesh = MESHES[mesh_name]()
    idx = np.arange(3, mesh.n_vertices, 5) if region else None
    table = estimate_table(mesh, ["icc", "csm"], RANGES, vertices=idx)
    assert list(table) == ["icc", "csm"]
    for method in ("csm", "icc"):
        alone = estimate_ranges(mesh, method, RANGES, vertices=idx)
        assert len(table[method]) == len(RANGES)
        for a, b in zip(alone, table[method]):
            _same(a, b)
    if mesh_name == "open patch":
        # the border is reached by the wide balls only: the levels are not all alike
        assert np.count_nonzero(table["icc"][2].reason == curv.Reason.BORDER) > np.count_nonzero(
            table["icc"][1].reason == curv.Reason.BORDER)


def test_the_shared_pass_at_creases_and_in_chunks():
    """Both estimators' supports walk face by face at the creases, each with stamps of its own."""
    mesh = box(4)
    table = estimate_table(mesh, ["csm", "icc"], (1, 2, 3), features=30, block_size=7)
    for method in ("csm", "icc"):
        for a, b in zip(estimate_ranges(mesh, method, (1, 2, 3), features=30), table[method]):
            _same(a, b)
            assert np.count_nonzero(b.reason == curv.Reason.FEATURE) > 0


def test_ranges_of_their_own_and_other_estimators():
    mesh = noisy_torus(30, 14, seed=2)
    ranges = {"csm": (1, 2, 3, 4), "icc": (4, 2), "qs": (2, 1), "meyer": (1,)}
    table = estimate_table(mesh, list(ranges), ranges, standard_errors=False)
    assert list(table) == list(ranges)
    for method, rs in ranges.items():
        alone = estimate_ranges(mesh, method, rs, standard_errors=False)
        assert [r.range for r in table[method]] == list(rs)
        for a, b in zip(alone, table[method]):
            if method == "icc":
                # the pass runs R1 and R3 too (csm asks for them): icc's sums of a range are the narrower
                # range's plus the vertices it adds, in another order
                for name in ("reason", "valid"):
                    assert np.array_equal(getattr(a, name), getattr(b, name)), name
                assert np.allclose(a.k1, b.k1, rtol=1e-11, atol=1e-12, equal_nan=True)
                assert np.allclose(a.k2, b.k2, rtol=1e-11, atol=1e-12, equal_nan=True)
            else:
                _same(a, b)


def test_options_go_to_the_estimators_that_take_them():
    mesh = icosphere(2)
    table = estimate_table(mesh, ["csm", "icc"], (2,), from_measures=False)
    _same(table["icc"][0], curv.estimate(mesh, "icc", 2, from_measures=False))
    _same(table["csm"][0], curv.estimate(mesh, "csm", 2))
    assert table["icc"][0].info["from_measures"] is False and "from_measures" not in table["csm"][0].info
    with pytest.raises(EstimatorError, match="degree"):
        estimate_table(mesh, ["csm", "icc"], (2,), degree=3)
    with pytest.raises(EstimatorError, match="once"):
        estimate_table(mesh, ["csm", "csm"], (2,))
    with pytest.raises(EstimatorError, match="radius"):
        estimate_table(mesh, ["csm", "icc"], (2,), radius=0.3)


def test_estimate_table_is_part_of_the_package():
    assert curv.estimate_table is estimate_table and "estimate_table" in curv.__all__
