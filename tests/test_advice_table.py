"""The advisor's table builder (``tools/advice_table``, run from a checkout) and the packaged table it wrote."""

from __future__ import annotations

import json

import numpy as np
import pytest

import tools.advice_table as table_package
from curv.advice.advisor import advise
from curv.advice.prediction import kernel_predict, load_table, predict
from curv.study.protocol import NOISE_FRACTION
from tools.advice_table import base as table_base
from tools.advice_table import extend as table_extend
from tools.advice_table import kernel as table_kernel


@pytest.fixture(scope="module")
def noisy():
    """A noisy irregular study patch (3169 vertices, the paper's noise level, 12.5 degrees)."""
    from curv.study.protocol import Task
    from curv.study.testmesh import build_test_mesh

    return build_test_mesh(Task(7, "quadratic", 3169, 12.5, 1.0, 0))

def test_calibration_fit_recovers_known_coefficients():
    from tools.advice_table.base import fit_calibration

    rng = np.random.default_rng(0)
    rows = []
    for i in range(40):
        density, clean = rng.uniform(0.02, 0.6), rng.uniform(0, 30)
        for level in (0.0, 0.3, 1.0):
            sigma = level * NOISE_FRACTION
            rows.append({"key": [0, "f", i, 0.0, level, 0], "noise_true": sigma, "density": density,
                         "noise_raw": np.sqrt(0.002**2 + 0.01 * density**4 + (1.3 * sigma) ** 2),
                         "irregularity_raw": np.sqrt(clean**2 + (9.0 * level) ** 2)})
    cal = fit_calibration(rows)
    assert cal["noise_floor"] == pytest.approx(0.002, rel=1e-6)
    assert cal["noise_gain"] == pytest.approx(1.3, rel=1e-9)
    assert cal["noise_density4"] == pytest.approx(0.01, rel=1e-6)
    assert cal["irregularity_noise_deg"] == pytest.approx(9.0, rel=1e-9)


def test_a_tiny_table_builds_advises_and_rebuilds_from_its_measured_rows(tmp_path, noisy, monkeypatch):

    settings = table_base.table_settings(samples=1, densities=(817,), noise=(0.0, 1.0), irregularity=(0.0,))
    build = lambda: table_base.build_table(settings, tmp_path / "study", workers=0, command="test",  # noqa: E731
                                   closed=("sphere",), closed_vertices=(642,))
    table = build()
    n_meshes = 3 * 2 + 2  # three functions x two noise levels, one sphere at two noise levels
    assert len(table["points"]) == len(table["median_erel"]) == len(table["truth"]["key"]) == n_meshes
    assert all(len(row) == len(table["variants"]) for row in table["median_erel"])
    assert table["metadata"]["command"] == "test" and table["metadata"]["settings"]["samples"] == 1
    assert table["kernel"]["bandwidth"] in table_kernel.BANDWIDTHS
    table = json.loads(json.dumps(table))  # what load_table reads back
    adv = advise(noisy.mesh, table=table, check=False)
    assert len(adv.ranking) == len(table["variants"])

    # the study resumes and the measured rows are cached in the study directory: nothing is measured again
    def boom(*args):
        raise AssertionError("measured again")

    monkeypatch.setattr(table_base, "mesh_features", boom)
    monkeypatch.setattr(table_base, "closed_mesh_point", boom)
    again = json.loads(json.dumps(build()))
    assert again["points"] == table["points"] and again["median_erel"] == table["median_erel"]
    assert (tmp_path / "study" / table_base.ROWS_NAME).exists()
    monkeypatch.setattr(table_base, "MEASURES", "other measures")  # rows of other measures are not reused
    with pytest.raises(AssertionError, match="measured again"):
        build()


def test_closed_shapes_are_random_per_sample_and_shared_across_sizes_and_noise():
    from tools.advice_table.base import closed_mesh_point, random_closed_params

    draw = lambda name: random_closed_params(name, np.random.default_rng(3))  # noqa: E731
    assert draw("torus") == draw("torus") and draw("cylinder") == {}
    assert all(0.5 <= x <= 1.5 for x in draw("ellipsoid").values()) and set(draw("ellipsoid")) == {"a", "b", "c"}
    assert 0.2 <= draw("torus")["minor"] <= 0.6 and draw("torus")["major"] == 1.0
    assert 0.5 <= draw("sphere")["radius"] <= 3.0
    point = lambda n, level, sample: closed_mesh_point((0, "ellipsoid", n, level, sample, ("qs:R1",)))  # noqa: E731
    (a, ea), (b, _), (c, _) = point(642, 0.0, 0), point(162, 1.0, 0), point(642, 0.0, 1)
    assert a["params"] == b["params"] != c["params"]
    assert a["key"] == [0, "ellipsoid", 642, 0.0, 0.0, 0] and set(ea) == {"qs:R1"} and 0 < ea["qs:R1"] < 0.05
    assert b["noise_raw"] > a["noise_raw"]


def test_rounding_in_the_table_changes_predictions_by_less_than_a_percent():
    from curv.advice.features import MeshFeatures
    from tools.advice_table.base import EREL_DIGITS, make_table, table_points, table_settings

    rng = np.random.default_rng(5)
    settings = table_settings(samples=1, densities=(817,), noise=(0.0,), irregularity=(0.0,))
    n, v = 60, len(settings.variants())
    levels, densities, irregularities = rng.uniform(0, 1, n), rng.uniform(0.02, 0.3, n), rng.uniform(0, 30, n)
    rows = [{"key": [0, "quadratic", 817, 0.0, lv, i], "noise_true": lv * NOISE_FRACTION, "density": d,
             "noise_raw": np.hypot(0.002, 1.2 * lv * NOISE_FRACTION), "irregularity_raw": irr,
             "irregularity_planar": irr, "density_true": d}
            for i, (lv, d, irr) in enumerate(zip(levels, densities, irregularities))]
    erel = np.exp(rng.normal(-3, 1, (n, v)))
    table = json.loads(json.dumps(make_table(settings, rows, erel)))
    stored = np.array(table["median_erel"], float)
    assert np.all(np.abs(stored / erel - 1) <= 0.5 * 10.0 ** (1 - EREL_DIGITS))
    exact = {**table, "median_erel": erel.tolist(), "points": table_points(rows, table["calibration"]).tolist()}
    for lv, d, irr in ((0.0, 0.05, 3.0), (0.4, 0.1, 20.0), (1.0, 0.25, 12.0)):
        f = MeshFeatures(irregularity_deg=irr, noise=lv * NOISE_FRACTION, density=d, border_share=0.0)
        a, b = np.array(list(predict(table, f).values())), np.array(list(predict(exact, f).values()))
        assert np.all(np.abs(a / b - 1) < 0.01)


def test_the_table_commands_name_files_not_the_directories_they_ran_in():

    assert table_base.table_command(["--table", "/scratch/a/t.json", "--out", "out/u.json", "--work", "w", "--workers", "1"],
                            "fill") == "python -m tools.advice_table fill --table t.json --out u.json --work w --workers 1"
    meta = load_table()["metadata"]
    commands = [v for k, v in meta.items() if k.endswith("command")] + meta["fill_commands"]
    assert len(commands) >= 10 and not any("/" in c for c in commands)


def test_the_packaged_table_is_what_the_documented_commands_write():

    table = load_table()
    meta = table["metadata"]
    doc = " ".join(table_package.__doc__.replace("\\\n", " ").split())
    assert " ".join(meta["command"].split()) in doc
    args = meta["command"].split()[3:]
    assert set(args[::2]) <= {"--work", "--workers"}  # every grid setting is a default
    assert meta["settings"] == table_base.table_settings().as_dict()
    assert meta["closed"] == {"surfaces": list(table_base.DEFAULT_CLOSED), "vertices": list(table_base.DEFAULT_CLOSED_VERTICES)}
    ext = meta["extension_command"].split()
    assert ext[:4] == ["python", "-m", "tools.advice_table", "extend"] and set(ext[4::2]) <= {"--base", "--work",
                                                                                             "--workers", "--out"}
    assert "python -m tools.advice_table extend --base base.json" in doc
    n_base = table_base.table_settings().n_tasks + len(table_base.DEFAULT_CLOSED) * len(table_base.DEFAULT_CLOSED_VERTICES) * len(
        table_base.DEFAULT_NOISE) * table_base.DEFAULT_SAMPLES
    fills = [c.split() for c in meta["fill_commands"]]
    assert all(f[:4] == ["python", "-m", "tools.advice_table", "fill"] for f in fills)
    fill = [f for f in fills if "--coarse-samples" in f][-1]
    samples = int(fill[fill.index("--coarse-samples") + 1])
    sizes = meta["coarse"]["closed_vertices"]
    assert set(table_extend.COARSE_CLOSED_VERTICES) <= set(sizes)
    n_coarse = len(table_extend.coarse_jobs({**table, "truth": {"key": []}}, samples, sizes))  # every coarse mesh of those samples
    assert n_coarse == samples * (3 * len(table_extend.COARSE_DENSITIES) * 4 * 7 + 3 * len(sizes) * 7)
    # the noise twins (fill --noise-levels) of the noise-free meshes of --sizes, every one a row
    twin = [f for f in fills if "--noise-levels" in f]
    assert len(twin) == 1 and meta["twin_noise_levels"] == [float(twin[0][twin[0].index("--noise-levels") + 1])]
    after = twin[0][twin[0].index("--sizes") + 1:]
    twin_sizes = {int(x) for x in after[:next((i for i, a in enumerate(after) if a.startswith("--")), len(after))]}
    levels = np.array([k[4] for k in table["truth"]["key"]])
    n_free = sum(1 for k in table["truth"]["key"] if k[4] == 0 and k[2] in twin_sizes)
    assert n_free >= 90 and np.sum(levels == meta["twin_noise_levels"][0]) == n_free
    assert meta["n_meshes"] == len(table["points"]) == n_base + n_coarse + n_free
    lv = twin[0][twin[0].index("--noise-levels") + 1]
    assert f"--noise-levels {lv} --sizes {' '.join(map(str, sorted(twin_sizes)))}" in doc
    assert f"--coarse-samples {samples}" in doc
    assert table["variants"] == [v.id for v in table_base.table_settings().variants()] + table_extend.option_variants()


def test_the_packaged_table_has_the_option_calls_wherever_it_has_the_named_ones():
    """An option call is predicted from the same neighbours as a named call: every size of closed
    surface and of patch (but the 12481-vertex patches of samples 1 and 2) ran the option calls on
    every mesh, so each option column has values across the group (empty only where the call gives
    none, e.g. a fit that needs more neighbours than a coarse mesh has), and the closed sizes between
    the grid's are rows."""

    table = load_table()
    erel = np.array(table["median_erel"], float)
    keys = table["truth"]["key"]
    options = np.isin(table["variants"], table_extend.option_variants())
    assert options.sum() == 40
    closed = np.array([k[1] in table_base.DEFAULT_CLOSED for k in keys])
    size = np.array([k[2] for k in keys])
    sample = np.array([k[5] for k in keys])
    assert {1000, 1600, 5000} <= set(size[closed].tolist())
    for is_closed in (True, False):
        for n in np.unique(size[closed == is_closed]):
            group = (closed == is_closed) & (size == n) & ~(~closed & (size == 12481) & (sample > 0))
            have = np.isfinite(erel[group][:, options])
            assert have.any(axis=0).all(), (is_closed, n)  # every option call has values in every group
            assert have.mean() >= 0.8, (is_closed, n, have.mean())
    dense = ~closed & (size == 12481) & (sample > 0)  # not run there (yet): empty, the prediction leaves them out
    assert dense.sum() == 168 and not np.isfinite(erel[dense][:, options]).any()


def test_the_packaged_table_reaches_the_densest_hexagon_and_stays_small():
    from importlib import resources

    from curv.advice.prediction import TABLE_RESOURCE

    table = load_table()
    hexagon = {k[2] for k in table["truth"]["key"] if k[1] in ("quadratic", "ellipsoid_patch", "trigonometric")}
    assert {217, 331, 469, 817, 3169, 12481} <= hexagon and len(hexagon) >= 8
    assert min(k[2] for k in table["truth"]["key"]) == 162
    assert len(resources.files("curv").joinpath(TABLE_RESOURCE).read_bytes()) < 1_700_000
    values = np.array(table["median_erel"], float)
    n_options = len(table_extend.option_variants())
    assert np.isfinite(values[:, :-n_options]).mean() > 0.99 and np.nanmin(values) > 0
    assert np.all(np.isfinite(values[:, -n_options:]).sum(axis=0) > 0.3 * len(values))   # every option column




def test_leave_one_out_regret_is_the_kernel_prediction_of_the_others():
    from tools.advice_table.kernel import _regret, loo_regret

    rng = np.random.default_rng(3)
    coords = rng.normal(size=(40, 3))
    logv = rng.normal(size=(40, 5))
    logv[rng.random((40, 5)) < 0.2] = np.nan
    logv[:, 0] = np.where(np.isfinite(logv[:, 0]), logv[:, 0], 0.0)
    for h in (0.05, 0.5):  # 0.05: most weights underflow, the exact per-variant shift decides
        chosen = []
        for i in range(40):
            rest = np.arange(40) != i
            pred = kernel_predict(coords[rest], logv[rest], coords[i], h)
            chosen.append(int(np.argmin(np.where(np.isfinite(pred) & np.isfinite(logv[i]), pred, np.inf))))
        assert loo_regret(coords, logv, h) == pytest.approx(_regret(logv, np.array(chosen)))
    # a group is left out together: two exact twins then cannot advise each other
    twins = np.concatenate([coords[:1], coords[:1]])
    values = np.log(np.array([[0.1, 1.0], [0.1, 1.0]]))
    far = np.concatenate([twins, coords[1:2] + 10])
    vals = np.concatenate([values, np.log([[1.0, 0.1]])])
    assert loo_regret(far, vals, 0.5)[:2] == pytest.approx([1.0, 1.0])
    assert loo_regret(far, vals, 0.5, groups=[0, 0, 1])[:2] == pytest.approx([10.0, 10.0])


def test_the_selection_takes_an_axis_that_decides_and_leaves_a_random_one_out():
    from tools.advice_table.kernel import select_axes

    rng = np.random.default_rng(0)
    p = 240
    kind = rng.random(p) < 0.5  # closed or open: which variant wins depends on it only
    points = np.c_[np.exp(rng.uniform(-4, -1, p)), rng.uniform(0, 1, p), rng.uniform(0, 30, p),
                   np.where(kind, 0.0, rng.uniform(0.02, 0.2, p)), rng.random(p)]
    erel = np.where(kind[:, None], [0.01, 0.05], [0.05, 0.01]) * np.exp(rng.normal(0, 0.1, (p, 2)))
    kernel = select_axes(points, ["density", "noise_level", "irregularity_deg", "border_share", "edge_cv"], erel,
                         np.arange(p))
    names = [a[0] for a in kernel["axes"]]
    assert "border_share" in names and "edge_cv" not in names
    assert kernel["loo_mean_regret"][str(kernel["bandwidth"])] < kernel["selection"][0]["loo_mean_regret"]


def test_the_packaged_table_has_the_selected_axes_and_the_floor():
    from curv.advice.prediction import BASE_COLUMNS, kernel_axes

    table = load_table()
    assert table["columns"] == [*BASE_COLUMNS, *table_kernel.EXTRA_COLUMNS]
    assert all(len(p) == len(table["columns"]) for p in table["points"])
    axes = kernel_axes(table)
    assert [a[0] for a in axes[:3]] == list(BASE_COLUMNS) and {a[0] for a in axes} <= set(table["columns"])
    assert table["kernel"]["erel_floor"] == table_kernel.EREL_FLOOR
    doc = " ".join(table_package.__doc__.replace("\\\n", " ").split())
    for step in ("fill", "refeature", "reselect"):
        cmd = table["metadata"][f"{step}_command"].split()
        assert cmd[:4] == ["python", "-m", "tools.advice_table", step]
        assert f"python -m tools.advice_table {step}" in doc


def test_reselection_separates_a_nearly_umbilic_surface_from_an_umbilic_one_by_the_anisotropys_log():
    """Noise-free spheres (anisotropy about 0.001) and ellipsoids (0.02-0.04) have different winners
    (the sphere's exact call is far from the best on an ellipsoid); the patches' anisotropies (0.3-1)
    set the axis's spread, so on a linear axis the two stand within one bandwidth. The reselection
    (stored points, nothing measured) takes the axis logarithmic and advises the ellipsoids apart."""
    from tools.advice_table.kernel import loo_regret
    from tools.advice_table.refeature import reselect_table
    from curv.advice.prediction import table_coordinates

    rng = np.random.default_rng(3)
    p = 300
    kind = rng.choice(3, p, p=[0.25, 0.25, 0.5])  # sphere, ellipsoid, patch
    aniso = np.choose(kind, [rng.uniform(5e-4, 2e-3, p), rng.uniform(0.02, 0.04, p), rng.uniform(0.3, 1.0, p)])
    points = np.c_[np.exp(rng.uniform(-4, -1, p)), np.zeros(p), rng.uniform(0, 30, p), aniso]
    best = np.array([[1e-6, 1e-3, 1e-2], [1e-3, 1e-4, 1e-2], [1e-2, 1e-2, 1e-3]])[kind]  # (p, 3): each kind's winner
    erel = best * np.exp(rng.normal(0, 0.1, (p, 3)))
    table = {"columns": ["density", "noise_level", "irregularity_deg", "anisotropy"],
             "points": points.tolist(), "median_erel": erel.tolist(), "metadata": {},
             "truth": {"key": [[0, "surface", 817, 0.0, 0.0, i] for i in range(p)]}}
    out = reselect_table(table, command="python -m tools.advice_table reselect")
    axes = out["kernel"]["axes"]
    assert axes[-1][:2] == ["anisotropy", "log"]
    assert out["points"] == table["points"] and out["metadata"]["reselect_command"].endswith("reselect")
    coords = table_coordinates(out, *points.T)
    regret = loo_regret(coords, np.log(erel), out["kernel"]["bandwidth"])
    assert np.percentile(regret[kind == 1], 90) < 1.5


def test_surface_groups_hold_one_random_surface_at_every_setting():
    from tools.advice_table.kernel import noise_groups, surface_groups

    keys = [[0, "quadratic", 817, 0.0, 0.0, 0], [0, "quadratic", 3169, 16.0, 0.6, 0],
            [0, "quadratic", 817, 0.0, 0.0, 1], [0, "trigonometric", 817, 0.0, 0.0, 0],
            [0, "torus", 642, 0.0, 0.2, 2], [0, "torus", 162, 0.0, 1.0, 2]]
    g = surface_groups(keys)
    assert g[0] == g[1] and g[4] == g[5] and len(set(g[[0, 2, 3, 4]])) == 4
    n = noise_groups(keys)
    assert n[0] != n[1]  # by noise level only, the same surface at another density is another group


def test_the_selection_leaves_out_an_axis_that_only_names_the_surface():
    """An axis that tells the surfaces apart wins a leave-one-out that keeps the same surface's other
    settings as neighbours, but cannot help a new surface: left out by surface, it is not taken."""
    from tools.advice_table.kernel import select_axes

    rng = np.random.default_rng(1)
    surfaces, per = 24, 12
    surf = np.repeat(np.arange(surfaces), per)
    p = surf.size
    name = rng.random(surfaces)[surf]  # a per-surface constant, no relation to which variant wins
    wins = rng.random(surfaces)[surf] < 0.5  # which variant wins: a property of the surface only
    points = np.c_[np.exp(rng.uniform(-4, -1, p)), rng.uniform(0, 1, p), rng.uniform(0, 30, p), name]
    erel = np.where(wins[:, None], [0.01, 0.05], [0.05, 0.01]) * np.exp(rng.normal(0, 0.1, (p, 2)))
    cols = ["density", "noise_level", "irregularity_deg", "valence_sd"]  # a column on a linear axis
    by_mesh = select_axes(points, cols, erel, np.arange(p))
    by_surface = select_axes(points, cols, erel, surf)
    assert "valence_sd" in [a[0] for a in by_mesh["axes"]]
    assert "valence_sd" not in [a[0] for a in by_surface["axes"]]
    both = select_axes(points, cols, erel, [surf, np.arange(p)])  # the score is the mean of the two
    step = both["selection"][0]["loo_mean_regret"]
    one = [select_axes(points, cols[:3], erel, g)["selection"][0]["loo_mean_regret"] for g in (surf, np.arange(p))]
    assert step == pytest.approx(np.mean(one), abs=1e-3)


def test_fill_adds_coarse_surfaces_as_rows_measured_with_the_calibration(monkeypatch):
    from curv.advice.features import calibrate_irregularity, calibrate_noise

    table = {"variants": ["nc:R1", "qs:R1"], "calibration": {"noise_floor": 0.0, "noise_gain": 1.2,
                                                              "noise_density4": 0.01, "irregularity_noise_deg": 10.0},
             "metadata": {"settings": {"functions": ["quadratic"], "irregularity": [0.0], "noise": [0.0, 0.5]},
                          "fill_command": "python -m tools.advice_table fill"},
             "truth": {"key": [[0, "quadratic", 217, 0.0, 0.0, 0]], "noise_true": [0.0],
                       "irregularity_planar": [0.0], "density_true": [0.2], "n_evaluated": [40]},
             "points": [[0.2, 0.0, 20.0, 0.1]], "columns": ["density", "noise_level", "irregularity_deg", "edge_cv"],
             "median_erel": [[0.01, None]]}
    monkeypatch.setattr(table_extend, "COARSE_DENSITIES", (217,))
    monkeypatch.setattr(table_extend, "COARSE_CLOSED_VERTICES", ())
    jobs = table_extend.coarse_jobs(table, 2)
    assert [j[0] for j in jobs] == [[0, "quadratic", 217, 0.0, 0.5, 0], [0, "quadratic", 217, 0.0, 0.0, 1],
                                    [0, "quadratic", 217, 0.0, 0.5, 1]]  # the ones the table lacks
    row = {"key": jobs[2][0], "noise_true": 0.05, "irregularity_planar": 0.0, "density_true": 0.3,
           "noise_raw": 0.07, "irregularity_raw": 22.0, "density": 0.25, "n_evaluated": 35}
    done = {table_kernel.key_text(jobs[2][0]): [row, {"nc:R1": 0.02, "qs:R1": 0.03}],
            table_kernel.key_text(table["truth"]["key"][0]): [{}, {"qs:R1": 0.04}]}
    out = table_extend.fill_table(table, done, command="python -m tools.advice_table fill --coarse-samples 2",
                        new_keys=[j[0] for j in jobs])
    assert out["median_erel"] == [[0.01, 0.04], [0.02, 0.03]]  # an empty cell filled, a new row
    assert out["truth"]["key"][1] == jobs[2][0] and out["metadata"]["n_meshes"] == 2  # not run: not added
    noise = calibrate_noise(0.07, table["calibration"], 0.25)
    irr = calibrate_irregularity(22.0, noise, table["calibration"])
    assert out["points"][1] == pytest.approx([0.25, noise / 0.1, irr], rel=1e-3)
    assert out["columns"] == ["density", "noise_level", "irregularity_deg"] and len(out["points"][0]) == 3
    assert out["metadata"]["fill_commands"][0] == "python -m tools.advice_table fill"


def test_fill_runs_the_empty_cells_of_the_chosen_kinds_and_sizes_and_keeps_the_extra_columns():

    keys = [[0, "quadratic", 817, 0.0, 0.0, 1], [0, "quadratic", 12481, 0.0, 0.0, 1],
            [0, "sphere", 642, 0.0, 0.0, 1], [0, "trigonometric", 817, 8.0, 0.2, 0]]
    table = {"variants": ["nc:R1", "jet:R2;degree=4"], "columns": ["density", "noise_level", "irregularity_deg",
                                                                     "valence_sd"],
             "points": [[0.1, 0.0, 20.0, 0.3], [0.02, 0.0, 20.0, 0.3], [0.2, 0.0, 0.0, 0.07], [0.1, 0.2, 9.0, 0.3]],
             "median_erel": [[0.01, None], [0.02, None], [0.03, None], [0.04, 0.05]],
             "truth": {"key": keys}, "metadata": {"fill_command": "python -m tools.advice_table fill"},
             "calibration": {}}
    jobs = table_extend.fill_jobs(table, kinds=("quadratic", "trigonometric"), sizes=(817, 1801))
    assert jobs == [(keys[0], ("jet:R2;degree=4",))]  # not the 12481 patch, nor the sphere, nor a full row
    assert len(table_extend.fill_jobs(table, kinds=("quadratic", "trigonometric"))) == 2
    done = {table_kernel.key_text(keys[0]): [{}, {"jet:R2;degree=4": 0.006}]}
    out = table_extend.fill_table(table, done, command="python -m tools.advice_table fill --sizes 817")
    assert out["median_erel"][0] == [0.01, 0.006] and out["median_erel"][1] == [0.02, None]
    # no new rows: the measured extra columns and the kernel's columns stay as they were
    assert out["columns"] == table["columns"] and out["points"] == table["points"]


def test_fill_adds_closed_surfaces_of_a_new_coarse_size_only():

    settings = {"functions": ["quadratic"], "irregularity": [0.0], "noise": [0.0]}
    have = [[0, "quadratic", d, 0.0, 0.0, 0] for d in table_extend.COARSE_DENSITIES]
    have += [[0, nm, n, 0.0, 0.0, 0] for nm in table_base.DEFAULT_CLOSED for n in table_extend.COARSE_CLOSED_VERTICES]
    table = {"variants": ["nc:R1"], "metadata": {"settings": settings}, "truth": {"key": have}}
    assert table_extend.coarse_jobs(table, 1) == []
    jobs = table_extend.coarse_jobs(table, 1, (*table_extend.COARSE_CLOSED_VERTICES, 482))
    assert [j[0] for j in jobs] == [[0, nm, 482, 0.0, 0.0, 0] for nm in table_base.DEFAULT_CLOSED]
    row = {"key": jobs[0][0], "noise_true": 0.0, "irregularity_planar": float("nan"), "density_true": 0.3,
           "noise_raw": 0.001, "irregularity_raw": 4.0, "density": 0.3, "n_evaluated": 492}
    table.update(calibration={"noise_floor": 0.0, "noise_gain": 1.2, "noise_density4": 0.01,
                              "irregularity_noise_deg": 10.0},
                 points=[[0.1, 0.0, 20.0]] * len(have), median_erel=[[0.01]] * len(have),
                 truth={"key": have, "noise_true": [0.0] * len(have), "irregularity_planar": [0.0] * len(have),
                        "density_true": [0.1] * len(have), "n_evaluated": [40] * len(have)})
    table["metadata"]["coarse"] = {"densities": list(table_extend.COARSE_DENSITIES), "closed_vertices": [162, 252, 362]}
    out = table_extend.fill_table(table, {table_kernel.key_text(jobs[0][0]): [row, {"nc:R1": 0.002}]}, new_keys=[j[0] for j in jobs],
                        closed_vertices=[162, 252, 362, 482])
    assert out["truth"]["key"][-1] == jobs[0][0] and len(out["points"]) == len(have) + 1
    assert out["metadata"]["coarse"]["closed_vertices"] == [162, 252, 362, 482]
    assert out["metadata"]["coarse"]["densities"] == list(table_extend.COARSE_DENSITIES)


def test_fill_adds_the_noise_twins_of_the_noise_free_meshes_at_a_level_between_the_grid():

    keys = [[0, "quadratic", 817, 8.0, 0.0, 1], [0, "quadratic", 817, 8.0, 0.05, 1],
            [0, "torus", 2562, 0.0, 0.0, 2], [0, "quadratic", 12481, 0.0, 0.0, 0], [0, "torus", 2562, 0.0, 0.015, 0]]
    table = {"variants": ["nc:R1", "jet:R2;degree=4"], "truth": {"key": keys}}
    jobs = table_extend.noise_jobs(table, [0.015, 0.005], sizes=(817, 2562))
    assert [j[0] for j in jobs] == [[0, "torus", 2562, 0.0, 0.015, 2], [0, "torus", 2562, 0.0, 0.005, 2],
                                    [0, "quadratic", 817, 8.0, 0.015, 1], [0, "quadratic", 817, 8.0, 0.005, 1]]
    assert all(j[1] == ("nc:R1", "jet:R2;degree=4") for j in jobs)  # every candidate on a new row
    assert len(table_extend.noise_jobs(table, [0.015])) == 3  # every size; the torus of sample 0 has no noise-free twin
    assert table_extend.noise_jobs({**table, "truth": {"key": keys + [j[0] for j in jobs]}}, [0.015, 0.005], (817, 2562)) == []
    # the twin is the same surface and tessellation, only its noise level differs
    mesh0, truth0, _ = table_extend.table_mesh([0, "torus", 162, 0.0, 0.0, 2])
    mesh1, truth1, _ = table_extend.table_mesh([0, "torus", 162, 0.0, 0.015, 2])
    assert np.array_equal(mesh0.faces, mesh1.faces) and np.array_equal(truth0.k1, truth1.k1)
    step = np.linalg.norm(mesh1.vertices - mesh0.vertices, axis=1)
    assert 0 < np.median(step) < 0.01 * np.mean(np.linalg.norm(mesh0.vertices[mesh0.edges[:, 0]]
                                                                - mesh0.vertices[mesh0.edges[:, 1]], axis=1))
