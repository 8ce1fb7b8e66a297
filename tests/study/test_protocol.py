"""The grid, the variants taken from the registry, and the per-task random streams."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.study.protocol import (
    DENSITIES, Smoothing, StudySettings, Task, Variant, parse_variants, preset_settings, study_variants,
)


def test_variants_come_from_the_registry():
    plain = study_variants(smoothing=False)
    expected = [(name, k) for name, spec in curv.ESTIMATORS.items() for k in spec.ranges]
    assert [(v.method, v.range) for v in plain] == expected
    smoothed = [v for v in study_variants() if v.smooth is not Smoothing.NONE]
    with_r2 = [name for name, spec in curv.ESTIMATORS.items() if 2 in spec.ranges]
    assert sorted((v.method, v.smooth.value) for v in smoothed) == sorted(
        (m, s) for m in with_r2 for s in ("mesh", "values"))


def test_the_paper_has_twenty_plain_variants():
    # meyer R1; csm, nc, qs R1-R4; an, mru R2-R4; ru R2 (paper §5)
    paper = [v for v in study_variants(smoothing=False) if curv.ESTIMATORS[v.method].in_paper]
    assert len(paper) == 20
    assert {name for name, spec in curv.ESTIMATORS.items() if not spec.in_paper} >= {"jet", "icc"}


def test_variant_ids_round_trip():
    for v in study_variants():
        assert Variant.from_id(v.id) == v
    assert Variant("mru", 2, Smoothing.MESH).label == "MRU (R2SM)"
    assert Variant("meyer", 1).label == "My (R1)"


def test_parse_variants_selectors_and_errors():
    got = parse_variants(["mru:R2,3", "nc:1", "csm:R2SV"])
    assert [v.id for v in got] == ["csm:R2SV", "nc:R1", "mru:R2", "mru:R3"]
    assert all(v.method == "qs" for v in parse_variants(["qs"]))
    assert len(parse_variants(["qs"], smoothing=False)) == len(curv.ESTIMATORS["qs"].ranges)
    with pytest.raises(ValueError, match="unknown estimator 'foo'"):
        parse_variants(["foo"])
    with pytest.raises(ValueError, match="allowed: R2"):
        parse_variants(["ru:R4"])


def test_settings_validate_and_count_tasks():
    s = StudySettings(samples=3, densities=(217, 817), noise=(0.0, 1.0), irregularity=(0.0,))
    assert s.n_tasks == 3 * 2 * 2 * 1 * 3 == len(list(s.tasks()))
    with pytest.raises(ValueError, match="hexagon subdivision"):
        StudySettings(densities=(300,))
    with pytest.raises(ValueError, match="unknown function"):
        StudySettings(functions=("sphere",))
    assert preset_settings("paper").n_tasks == 1000 * 4 * 4 * 3 * 3
    assert set(preset_settings("paper").densities) == set(DENSITIES)


def test_smoothing_variants_only_at_the_fig10_density():
    s = StudySettings(densities=(817, 3169), estimators=("mru",))
    assert s.fig10_density == 3169
    at = [v for t in s.tasks() if t.density == 3169 for v in s.variants_for(t)]
    off = [v for t in s.tasks() if t.density == 817 for v in s.variants_for(t)]
    assert any(v.smooth is Smoothing.MESH for v in at)
    assert not any(v.smooth is not Smoothing.NONE for v in off)
    assert StudySettings(densities=(217, 817)).fig10_density == 817


def test_random_streams_depend_on_their_key_only():
    a = Task(5, "quadratic", 817, 14.0, 0.33, 1)
    # the surface is shared across density, irregularity and noise of one sample (paired design)
    same_surface = Task(5, "quadratic", 3169, 25.0, 1.0, 1)
    assert np.array_equal(a.surface_rng().random(4), same_surface.surface_rng().random(4))
    # the noise field is shared across noise levels, not across samples
    assert np.array_equal(a.noise_rng().random(4), Task(5, "quadratic", 817, 14.0, 1.0, 1).noise_rng().random(4))
    assert not np.array_equal(a.noise_rng().random(4), Task(5, "quadratic", 817, 14.0, 0.33, 2).noise_rng().random(4))
    assert not np.array_equal(a.surface_rng().random(4), Task(6, "quadratic", 817, 14.0, 0.33, 1).surface_rng().random(4))
    assert not np.array_equal(a.mesh_rng().random(4), Task(5, "quadratic", 817, 0.0, 0.33, 1).mesh_rng().random(4))


def test_any_hexagon_subdivision_is_a_density():
    from curv.study.testmesh import build_test_mesh

    s = StudySettings(densities=(1801, 7057, 817), noise=(0.0,), irregularity=(0.0,), functions=("quadratic",))
    assert s.densities == (1801, 7057, 817) and StudySettings().densities == DENSITIES
    assert [t.density for t in s.tasks()] == [7057, 1801, 817]  # densest first, as for the paper's
    assert s.fig10_density == 7057  # 3169 not in the grid: the largest
    assert build_test_mesh(Task(0, "quadratic", 271, 0.0, 0.0, 0)).mesh.n_vertices == 271  # s = 9
    with pytest.raises(ValueError, match=r"density 818 is not a hexagon subdivision.*nearest: [0-9, ]*817"):
        StudySettings(densities=(817, 818))
    with pytest.raises(ValueError, match="hexagon subdivision"):
        StudySettings(densities=(0,))
