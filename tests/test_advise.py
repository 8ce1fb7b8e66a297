"""The advisor: its features on meshes of known noise and irregularity, its ranking, its CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

import curv
import curv.advice.table
from curv.advice.advisor import (
    Advice, advise, angle_deviation_deg, kernel_predict, load_table, measure_features, predict,
)
from curv.cli import _stats_line, main
from curv.study.protocol import NOISE_FRACTION, Task
from curv.study.testmesh import build_test_mesh
from curv.surfaces import angle_irregularity, hexagon_mesh, make_surface


def _study_mesh(noise: float, irregularity: float = 0.0, function: str = "quadratic", seed: int = 7):
    return build_test_mesh(Task(seed, function, 3169, irregularity, noise, 0))


def _write_off(path, mesh) -> str:
    lines = ["OFF", f"{mesh.n_vertices} {mesh.n_faces} 0"]
    lines += [" ".join(f"{c:.17g}" for c in v) for v in mesh.vertices]
    lines += [f"3 {a} {b} {c}" for a, b, c in mesh.triangles]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


@pytest.fixture(scope="module")
def noisy():
    return _study_mesh(1.0, 12.5)


# ------------------------------------------------------------------ features
@pytest.mark.parametrize("level", [0.33, 0.66, 1.0])
def test_noise_estimate_within_a_quarter_of_the_truth(level):
    feats = measure_features(_study_mesh(level, 12.5, "trigonometric", seed=11).mesh)
    truth = level * NOISE_FRACTION
    assert abs(feats.noise / truth - 1) < 0.25, (feats.noise, truth)
    assert feats.noise_level == pytest.approx(feats.noise / NOISE_FRACTION)


def test_noise_estimate_is_near_zero_without_noise():
    feats = measure_features(_study_mesh(0.0).mesh)
    assert feats.noise < 0.1 * NOISE_FRACTION


def test_irregularity_on_a_plane_is_the_papers_planar_measure():
    planar = hexagon_mesh(817, irregularity_deg=14.0, rng=3)
    mesh = curv.Mesh(np.c_[planar.xy, np.zeros(len(planar.xy))], planar.triangles)
    feats = measure_features(mesh)
    assert feats.irregularity_deg == pytest.approx(angle_irregularity(planar.xy, planar.triangles), rel=1e-9)
    assert feats.irregularity_deg == pytest.approx(14.0, abs=0.5)
    assert feats.noise < 1e-6 and feats.density < 1e-6


def test_irregularity_grows_with_the_meshes_irregularity_and_is_corrected_for_noise():
    regular, irregular = _study_mesh(0.0, 0.0), _study_mesh(0.0, 25.0)
    f0, f25 = measure_features(regular.mesh), measure_features(irregular.mesh)
    assert f25.irregularity_deg > f0.irregularity_deg + 5
    # without noise there is nothing to correct
    assert f0.irregularity_deg == pytest.approx(angle_deviation_deg(regular.mesh.vertices, regular.mesh.triangles))
    # noise adds angle jitter; the calibrated correction takes most of it out again
    clean = measure_features(_study_mesh(0.0, 0.0, "trigonometric").mesh)
    fn = measure_features(_study_mesh(1.0, 0.0, "trigonometric").mesh)
    assert fn.irregularity_raw_deg > clean.irregularity_deg + 2
    assert abs(fn.irregularity_deg - clean.irregularity_deg) < 0.3 * (fn.irregularity_raw_deg - clean.irregularity_deg)


def test_density_of_a_sphere_is_twice_edge_over_radius():
    s = make_surface("sphere", n_vertices=2562, radius=2.0)
    feats = measure_features(s.mesh)
    assert feats.density == pytest.approx(2 * s.mesh.mean_edge_length / 2.0, rel=0.05)
    assert feats.border_share == 0 and feats.polygon_kinds == {3: s.mesh.n_faces}


def test_polygon_mesh_gets_no_triangle_only_estimator():
    n = 30
    x, y = np.meshgrid(np.linspace(-1, 1, n), np.linspace(-1, 1, n))
    v = np.c_[x.ravel(), y.ravel(), 0.5 * (x.ravel() ** 2 + 0.5 * y.ravel() ** 2)]
    i = np.arange(n * n).reshape(n, n)
    quads = np.stack([i[:-1, :-1], i[:-1, 1:], i[1:, 1:], i[1:, :-1]], axis=-1).reshape(-1, 4)
    adv = advise(curv.Mesh(v, quads))
    assert adv.features.polygon_kinds == {4: len(quads)}
    assert 0 < adv.features.border_share < 0.2
    assert "polygons" in adv.why
    names = {c.method for c in adv.ranking}
    assert names and not names & {n for n, s in curv.ESTIMATORS.items() if s.triangles_only}


# ------------------------------------------------------------------ prediction and ranking
def test_kernel_prediction_tends_to_the_nearest_point_and_to_the_mean():
    points = np.array([[0.0, 0, 0], [1, 0, 0], [0, 3, 0]])
    logv = np.log(np.array([[0.1, 0.4], [0.2, np.nan], [0.8, 0.4]]))
    near = kernel_predict(points, logv, np.array([0.9, 0, 0]), 0.01)
    assert near[0] == pytest.approx(0.2) and near[1] == pytest.approx(0.4)  # NaN left out, not zero
    wide = kernel_predict(points, logv, np.array([0.5, 1.0, 0]), 1e6)
    assert wide[0] == pytest.approx(np.exp(np.mean(np.log([0.1, 0.2, 0.8]))))


def test_ranking_covers_every_candidate_best_first(noisy):
    table = load_table()
    adv = curv.advise(noisy.mesh, check=False)
    assert isinstance(adv, Advice) and not adv.checked and adv.note
    assert len(adv.ranking) == len(table["variants"])  # a triangle mesh admits every registered variant
    errs = [c.expected_erel for c in adv.ranking]
    assert all(np.isfinite(errs)) and min(errs) > 0
    top = max(c.valid_share for c in adv.ranking)
    full = [c.valid_share >= top - curv.advice.advisor.VALID_SHARE_SLACK for c in adv.ranking]
    n_full = sum(full)
    assert full == [True] * n_full + [False] * (len(full) - n_full)     # the calls that cover the mesh first
    assert errs[:n_full] == sorted(errs[:n_full]) and errs[n_full:] == sorted(errs[n_full:])
    assert 0 < n_full < len(errs)          # a 3169-vertex patch: R3-R4 balls of csm, icc reach the border
    best = adv.ranking[0]
    assert (adv.method, adv.range, adv.expected_erel, adv.options) == (best.method, best.range, best.expected_erel,
                                                                       best.options)
    assert {c.variant.id for c in adv.ranking} == set(table["variants"])
    assert best.valid_share == pytest.approx(1 - adv.features.border_share, abs=0.01)   # only the border lost
    pred = predict(table, adv.features)
    assert pred[best.variant.id] == pytest.approx(adv.expected_erel)


def test_why_line_names_the_noise_the_irregularity_and_the_choice(noisy):
    adv = advise(noisy.mesh, check=False)
    assert "\n" not in adv.why
    assert f"noise about {adv.features.noise_level:.2g} of the paper's level" in adv.why
    assert f"({adv.features.irregularity_deg:.0f} degrees)" in adv.why
    assert f"{adv.label}, expected median e_rel {adv.expected_erel:.2g}" in adv.why


def test_noise_raises_the_expected_error():
    clean, noisy = (advise(_study_mesh(level, 12.5).mesh, check=False) for level in (0.0, 1.0))
    assert noisy.expected_erel > 2 * clean.expected_erel


def test_lazy_export_is_the_function_even_after_the_module_loads():
    import curv.advice.advisor

    assert curv.advise is curv.advice.advisor.advise and curv.Advice is curv.advice.advisor.Advice


# ------------------------------------------------------------------ CLI
def test_cli_text(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["advise", path, "--top", "5", "--no-check"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"{path}: 3169 vertices; ")
    adv = advise(noisy.mesh, check=False)
    assert "  not checked: the table's ranking alone (check=False)" in out
    assert f"advice: {adv.why}" in out
    assert f"  call: {adv.call}" in out
    f = adv.features  # the table's other axes are said too
    assert f"  spreads      valence {f.valence_sd:.2f} (sd), curvature {f.curvature_spread:.2f} (IQR of log |k1|+|k2|)" in out
    assert any(line.startswith(f"  shape        anisotropy {f.anisotropy:.2f}, model residual {f.residual_ratio:.2g} ")
               for line in out)
    rows = [line for line in out if line[:4].strip().isdigit()]
    assert [r.split()[0] for r in rows] == ["1", "2", "3", "4", "5"]
    for row, c in zip(rows, adv.ranking):
        assert row.split(maxsplit=1)[1].startswith(c.label + " ")
        assert row.split()[-2:] == [f"{100 * c.valid_share:.0f}%", f"{c.expected_erel:.3g}"]
    assert out[-1].strip().startswith(f"... {len(adv.ranking) - 5} more")


def test_cli_json(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["advise", path, "--json", "--no-check"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["checked"] is False and data["check"] is None
    assert data["input"] == path
    ranking = data["ranking"]
    assert (data["method"], data["range"], data["options"]) == tuple(ranking[0][k] for k in ("method", "range", "options"))
    assert data["kwargs"] == {"method": data["method"], "range": data["range"], **data["options"]}
    assert data["call"] == "curv.estimate(mesh, " + ", ".join(f"{k}={v!r}" for k, v in data["kwargs"].items()) + ")"
    top = max(r["valid_share"] for r in ranking)
    errs = [r["expected_erel"] for r in ranking if r["valid_share"] >= top - 0.02]
    assert errs == sorted(errs) and [r["expected_erel"] for r in ranking[: len(errs)]] == errs
    assert any(r["options"] for r in ranking) and all(r["kwargs"]["method"] == r["method"] for r in ranking)
    res = curv.estimate(noisy.mesh, **data["kwargs"])        # the JSON's call runs as it stands
    assert res.valid_fraction == pytest.approx(data["valid_share"], abs=0.02)   # a 2000-vertex sample
    assert data["features"]["noise"] == pytest.approx(data["features"]["noise_level"] * NOISE_FRACTION)
    assert data["features"]["polygon_kinds"] == {"3": noisy.mesh.n_faces}


def test_cli_bad_input_is_one_line(tmp_path, capsys):
    missing = tmp_path / "nope.ply"
    assert main(["advise", str(missing)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("curv: error: ") and str(missing) in err[0]
    garbage = tmp_path / "bad.off"
    garbage.write_text("not a mesh\n")
    assert main(["advise", str(garbage), "--json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("curv: error: ")


def test_estimate_method_auto_uses_and_announces_the_advice(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    adv = advise(noisy.mesh)
    assert main(["estimate", path, "--method", "auto", "-q"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"auto: {adv.label} ({adv.why}); the same as --method {adv.method} --range {adv.range}")
    assert any(line.startswith(f"{adv.method} R{adv.range}: ") for line in out)


def test_estimate_method_auto_refuses_a_range(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["estimate", path, "--method", "auto", "--range", "3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["curv: error: --method auto chooses the range and the options too; drop --range"]
    assert main(["estimate", path, "--method", "auto", "--normals", "fit"]) == 2
    assert capsys.readouterr().err.strip().endswith("drop --normals")


def test_estimate_method_auto_applies_the_options(tmp_path, capsys, monkeypatch, noisy):
    import curv.advice.advising

    path = _write_off(tmp_path / "m.off", noisy.mesh)
    real = curv.advice.advising.iter_advise
    for options in ({"degree": 4}, {"normals": "fit", "fit_range": 4}):

        def fake(mesh, **kw):  # the advisor's answer with the first candidate carrying these options
            adv = yield from real(mesh, **{**kw, "check": False})
            best = curv.advice.advisor.Candidate("jet" if "degree" in options else "mru", 3, options, 0.01)
            return Advice(features=adv.features, ranking=[best], method=best.method, range=3, expected_erel=0.01,
                          why="test", options=options)

        monkeypatch.setattr(curv.advice.advising, "iter_advise", fake)
        assert main(["estimate", path, "--method", "auto", "-q"]) == 0
        out = capsys.readouterr().out.splitlines()
        method = "jet" if "degree" in options else "mru"
        flags = " ".join(f"--{k.replace('_', '-')} {v}" for k, v in options.items())
        assert out[0].endswith(f"the same as --method {method} --range 3 {flags}")
        expected = curv.estimate(noisy.mesh, method=method, range=3, **options)
        plain = curv.estimate(noisy.mesh, method=method, range=3)
        assert _stats_line("k1", expected.quantity("k1")) in out            # the options were applied
        assert _stats_line("k1", plain.quantity("k1")) not in out


# ------------------------------------------------------------------ the table builder
def test_calibration_fit_recovers_known_coefficients():
    from curv.advice.table import fit_calibration

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
    import curv.advice.table as at

    settings = at.table_settings(samples=1, densities=(817,), noise=(0.0, 1.0), irregularity=(0.0,))
    build = lambda: at.build_table(settings, tmp_path / "study", workers=0, command="test",  # noqa: E731
                                   closed=("sphere",), closed_vertices=(642,))
    table = build()
    n_meshes = 3 * 2 + 2  # three functions x two noise levels, one sphere at two noise levels
    assert len(table["points"]) == len(table["median_erel"]) == len(table["truth"]["key"]) == n_meshes
    assert all(len(row) == len(table["variants"]) for row in table["median_erel"])
    assert table["metadata"]["command"] == "test" and table["metadata"]["settings"]["samples"] == 1
    assert table["kernel"]["bandwidth"] in at.BANDWIDTHS
    table = json.loads(json.dumps(table))  # what load_table reads back
    adv = advise(noisy.mesh, table=table, check=False)
    assert len(adv.ranking) == len(table["variants"])

    # the study resumes and the measured rows are cached in the study directory: nothing is measured again
    def boom(*args):
        raise AssertionError("measured again")

    monkeypatch.setattr(at, "mesh_features", boom)
    monkeypatch.setattr(at, "closed_mesh_point", boom)
    again = json.loads(json.dumps(build()))
    assert again["points"] == table["points"] and again["median_erel"] == table["median_erel"]
    assert (tmp_path / "study" / at.ROWS_NAME).exists()
    monkeypatch.setattr(at, "MEASURES", "other measures")  # rows of other measures are not reused
    with pytest.raises(AssertionError, match="measured again"):
        build()


def test_closed_shapes_are_random_per_sample_and_shared_across_sizes_and_noise():
    from curv.advice.table import closed_mesh_point, random_closed_params

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
    from curv.advice.advisor import MeshFeatures
    from curv.advice.table import EREL_DIGITS, make_table, table_points, table_settings

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


# ------------------------------------------------------------------ the packaged table
def test_the_table_commands_name_files_not_the_directories_they_ran_in():
    import curv.advice.table as at

    assert at.table_command(["--table", "/scratch/a/t.json", "--out", "out/u.json", "--work", "w", "--workers", "1"],
                            "fill") == "python -m curv.advice.table fill --table t.json --out u.json --work w --workers 1"
    meta = load_table()["metadata"]
    commands = [v for k, v in meta.items() if k.endswith("command")] + meta["fill_commands"]
    assert len(commands) >= 10 and not any("/" in c for c in commands)


def test_the_packaged_table_is_what_the_documented_commands_write():
    import curv.advice.table as at

    table = load_table()
    meta = table["metadata"]
    doc = " ".join(at.__doc__.replace("\\\n", " ").split())
    assert " ".join(meta["command"].split()) in doc
    args = meta["command"].split()[3:]
    assert set(args[::2]) <= {"--work", "--workers"}  # every grid setting is a default
    assert meta["settings"] == at.table_settings().as_dict()
    assert meta["closed"] == {"surfaces": list(at.DEFAULT_CLOSED), "vertices": list(at.DEFAULT_CLOSED_VERTICES)}
    ext = meta["extension_command"].split()
    assert ext[:4] == ["python", "-m", "curv.advice.table", "extend"] and set(ext[4::2]) <= {"--base", "--work",
                                                                                             "--workers", "--out"}
    assert "python -m curv.advice.table extend --base base.json" in doc
    n_base = at.table_settings().n_tasks + len(at.DEFAULT_CLOSED) * len(at.DEFAULT_CLOSED_VERTICES) * len(
        at.DEFAULT_NOISE) * at.DEFAULT_SAMPLES
    fills = [c.split() for c in meta["fill_commands"]]
    assert all(f[:4] == ["python", "-m", "curv.advice.table", "fill"] for f in fills)
    fill = [f for f in fills if "--coarse-samples" in f][-1]
    samples = int(fill[fill.index("--coarse-samples") + 1])
    sizes = meta["coarse"]["closed_vertices"]
    assert set(at.COARSE_CLOSED_VERTICES) <= set(sizes)
    n_coarse = len(at.coarse_jobs({**table, "truth": {"key": []}}, samples, sizes))  # every coarse mesh of those samples
    assert n_coarse == samples * (3 * len(at.COARSE_DENSITIES) * 4 * 7 + 3 * len(sizes) * 7)
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
    assert table["variants"] == [v.id for v in at.table_settings().variants()] + at.option_variants()


def test_the_packaged_table_has_the_option_calls_wherever_it_has_the_named_ones():
    """An option call is predicted from the same neighbours as a named call: every size of closed
    surface and of patch (but the 12481-vertex patches of samples 1 and 2) ran the option calls on
    every mesh, so each option column has values across the group (empty only where the call gives
    none, e.g. a fit that needs more neighbours than a coarse mesh has), and the closed sizes between
    the grid's are rows."""
    import curv.advice.table as at

    table = load_table()
    erel = np.array(table["median_erel"], float)
    keys = table["truth"]["key"]
    options = np.isin(table["variants"], at.option_variants())
    assert options.sum() == 40
    closed = np.array([k[1] in at.DEFAULT_CLOSED for k in keys])
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

    from curv.advice.advisor import TABLE_RESOURCE

    table = load_table()
    hexagon = {k[2] for k in table["truth"]["key"] if k[1] in ("quadratic", "ellipsoid_patch", "trigonometric")}
    assert {217, 331, 469, 817, 3169, 12481} <= hexagon and len(hexagon) >= 8
    assert min(k[2] for k in table["truth"]["key"]) == 162
    assert len(resources.files("curv").joinpath(TABLE_RESOURCE).read_bytes()) < 1_700_000
    values = np.array(table["median_erel"], float)
    n_options = len(curv.advice.table.option_variants())
    assert np.isfinite(values[:, :-n_options]).mean() > 0.99 and np.nanmin(values) > 0
    assert np.all(np.isfinite(values[:, -n_options:]).sum(axis=0) > 0.3 * len(values))   # every option column




# ------------------------------------------------------------------ valid share, options, the whole call
def _mixed_mesh(m=30, tri_cells=121, seed=0):
    """The issue's repro: a 30 x 30 grid (900 vertices) on a unit sphere cap, 720 quads and 121 cells
    split into two triangles each."""
    u, v = np.meshgrid(np.linspace(-0.6, 0.6, m), np.linspace(-0.6, 0.6, m), indexing="ij")
    verts = np.stack([u.ravel(), v.ravel(), np.sqrt(1 - u.ravel() ** 2 - v.ravel() ** 2)], 1)
    idx = np.arange(m * m).reshape(m, m)
    a, b, c, d = (x.ravel() for x in (idx[:-1, :-1], idx[1:, :-1], idx[1:, 1:], idx[:-1, 1:]))
    cells = np.random.default_rng(seed).permutation(a.size)
    tri, quad = cells[:tri_cells], cells[tri_cells:]
    faces = np.full((quad.size + 2 * tri.size, 4), -1)
    faces[: quad.size] = np.stack([a[quad], b[quad], c[quad], d[quad]], 1)
    faces[quad.size:, :3] = np.concatenate([np.stack([a[tri], b[tri], c[tri]], 1), np.stack([a[tri], c[tri], d[tri]], 1)])
    return curv.Mesh(verts, faces)


def _every_candidate():
    from curv.advice.table import option_variants

    return list(dict.fromkeys([*load_table()["variants"], *option_variants()]))


@pytest.mark.parametrize("which", ["mixed", "patch217"])
def test_valid_shares_are_what_the_estimators_leave_valid(which):
    from curv.advice.advisor import valid_shares
    from curv.variants import Variant

    mesh = _mixed_mesh() if which == "mixed" else build_test_mesh(Task(0, "quadratic", 217, 25.0, 0.33, 0)).mesh
    ids = _every_candidate()
    shares = valid_shares(mesh, ids)
    for vid in ids:
        try:
            real = curv.estimate(mesh, **Variant.from_id(vid).kwargs).valid_fraction
        except curv.MeshError:  # refused: a triangle-only estimator on polygons
            real = 0.0
        assert shares[vid] == pytest.approx(real, abs=1e-12), vid
    assert len({round(x, 6) for x in shares.values()}) >= 3       # the rule does separate candidates here


def test_valid_shares_on_a_sample_of_a_larger_mesh():
    from curv.advice.advisor import valid_shares

    mesh = _study_mesh(0.0).mesh
    full = valid_shares(mesh, ["csm:R4", "jet:R1;degree=2", "qs:R2"], sample=10**9)
    part = valid_shares(mesh, ["csm:R4", "jet:R1;degree=2", "qs:R2"], sample=1000)
    assert full["csm:R4"] < full["qs:R2"] - 0.1                      # R4 balls reach the border from far in
    for vid in full:
        assert part[vid] == pytest.approx(full[vid], abs=0.05)


def test_the_mixed_quad_mesh_is_not_advised_a_call_that_leaves_it_invalid():
    mesh = _mixed_mesh()
    assert mesh.n_vertices == 900 and curv.advice.advisor.polygon_kinds(mesh) == {3: 242, 4: 720}
    jet1 = curv.estimate(mesh, method="jet", range=1)
    assert np.sum(jet1.reason == curv.Reason.TOO_FEW_NEIGHBOURS) > 600           # the 676 of 900
    adv = advise(mesh, check=False)
    shares = {c.variant.id: c.valid_share for c in adv.ranking}
    assert shares["jet:R1"] == pytest.approx(jet1.valid_fraction)
    assert adv.valid_share >= max(shares.values()) - curv.advice.advisor.VALID_SHARE_SLACK
    full = [c for c in adv.ranking if c.valid_share >= max(shares.values()) - curv.advice.advisor.VALID_SHARE_SLACK]
    assert adv.ranking[: len(full)] == full                                    # every full call before jet R1
    assert [c.expected_erel for c in full] == sorted(c.expected_erel for c in full)
    res = curv.estimate(mesh, **adv.kwargs)
    assert res.valid_fraction == pytest.approx(adv.valid_share) and res.valid_fraction > 0.8
    assert not any(curv.ESTIMATORS[c.method].triangles_only for c in adv.ranking)


def test_rank_puts_calls_that_lose_vertices_after_the_rest():
    from curv.advice.advisor import rank

    pred = {"a": 0.1, "b": 0.2, "c": 0.05, "d": 0.01, "e": np.nan}
    assert rank(pred, {"a": 0.9, "b": 0.9, "c": 0.5, "d": 0.0, "e": 0.9}) == ["a", "b", "c"]
    assert rank(pred, {"a": 0.9, "b": 0.9, "c": 0.885, "d": 0.0}) == ["c", "a", "b"]   # within the slack
    assert rank(pred, {}) == ["d", "c", "a", "b"]


def test_support_sizes_match_the_stored_supports():
    from curv.geometry.neighbourhood import support_sizes, supports
    from curv.core.ranges import ball_radii, resolve

    mesh = build_test_mesh(Task(0, "trigonometric", 331, 16.0, 0.5, 0)).mesh
    radii = ball_radii(mesh, resolve(curv.ESTIMATORS["qs"], 1.5), uses_normals=False)
    centres = np.arange(0, mesh.n_vertices, 3)
    counts, flagged = support_sizes(mesh, radii, centres, mesh.border_vertices)
    indptr, indices = supports(mesh, radii, centres)
    np.testing.assert_array_equal(counts, np.diff(indptr))
    border = mesh.border_vertices
    expected = [border[c] or border[indices[indptr[i]:indptr[i + 1]]].any() for i, c in enumerate(centres)]
    np.testing.assert_array_equal(flagged, expected)
    assert flagged.any() and not flagged.all()


def test_variants_and_candidates_carry_the_whole_call():
    from curv.advice.advisor import Candidate
    from curv.variants import Variant

    v = Variant.from_id("mru:R3;normals=fit;fit_range=4")
    assert v.id == "mru:R3;fit_range=4;normals=fit" and Variant.from_id(v.id) == v
    assert v.kwargs == {"method": "mru", "range": 3, "normals": "fit", "fit_range": 4}
    assert v.label == "MRU (R3, normals fit R4)" and Variant.from_id("mru:R2SM").options == ()
    c = Candidate("jet", 4, {"degree": 4}, 0.01, 0.97)
    assert c.kwargs == {"method": "jet", "range": 4, "degree": 4} and c.label == "jet R4 degree 4"
    assert c.call == "curv.estimate(mesh, method='jet', range=4, degree=4)"
    mesh = make_surface("sphere", n_vertices=642).mesh
    np.testing.assert_allclose(np.nanmedian(curv.estimate(mesh, **c.kwargs).mean), 1.0, rtol=0.02)


def test_the_ranking_holds_the_option_candidates_and_the_advice_runs(noisy):
    adv = advise(noisy.mesh)
    options = {tuple(sorted(c.options.items())) for c in adv.ranking}
    assert (("degree", 4),) in options and (("fit_range", 4), ("normals", "fit")) in options
    res = curv.estimate(noisy.mesh, **adv.kwargs)
    assert res.valid_fraction == pytest.approx(adv.valid_share, abs=0.02)   # counted on 2000 of 3169 vertices
    assert adv.as_dict()["kwargs"] == adv.kwargs


def test_at_full_noise_the_advice_is_a_wide_call():
    """At the paper's full noise on a dense patch the small ranges are hopeless: every study says so."""
    adv = advise(_study_mesh(1.0, 0.0, "trigonometric").mesh)
    assert adv.range >= 3 or adv.options.get("fit_range", 0) >= 4


def test_coarse_meshes_measure_their_density():
    coarse = make_surface("sphere", n_vertices=162, radius=1.5)
    fine = make_surface("sphere", n_vertices=2562, radius=1.5)
    fc, ff = measure_features(coarse.mesh), measure_features(fine.mesh)
    # the quadric fit over-reads the curvature of a coarse mesh (162 vertices: by 18 %); the table's
    # meshes are measured the same way, so the bias moves the table's points along with the user's
    for s, f, rel in ((coarse, fc, 0.25), (fine, ff, 0.05)):
        assert f.density == pytest.approx(2 * s.mesh.mean_edge_length / 1.5, rel=rel)
    assert fc.density > 3 * ff.density
    patch = build_test_mesh(Task(0, "quadratic", 217, 0.0, 0.0, 0))
    truth = patch.truth
    exact = patch.mesh.mean_edge_length * np.median(np.abs(truth.k1) + np.abs(truth.k2))
    assert measure_features(patch.mesh).density == pytest.approx(exact, rel=0.25)


def test_estimate_takes_the_options_as_flags(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["estimate", path, "-m", "jet", "-r", "3", "--degree", "4", "-q"]) == 0
    assert _stats_line("k1", curv.estimate(noisy.mesh, method="jet", range=3, degree=4).quantity("k1")) in \
        capsys.readouterr().out.splitlines()
    assert main(["estimate", path, "-m", "mru", "-r", "3", "--normals", "fit", "--fit-range", "4", "-q"]) == 0
    fitted = curv.estimate(noisy.mesh, method="mru", range=3, normals="fit", fit_range=4)
    assert _stats_line("k1", fitted.quantity("k1")) in capsys.readouterr().out.splitlines()
    assert main(["estimate", path, "-m", "mru", "--fit-range", "4"]) == 2
    assert "--normals fit" in capsys.readouterr().err
    assert main(["estimate", path, "-m", "mru", "--degree", "4"]) == 2
    assert "degree" in capsys.readouterr().err


# ------------------------------------------------------------------ shape and tessellation axes
def test_shape_measures_tell_a_sphere_a_torus_and_a_patch_apart():
    from curv.advice.advisor import SHAPE_MEASURES

    sphere = measure_features(make_surface("sphere", n_vertices=2562, radius=1.3).mesh)
    torus = measure_features(make_surface("torus", n_vertices=2562, major=1.0, minor=0.4).mesh)
    patch = measure_features(build_test_mesh(Task(0, "quadratic", 817, 0.0, 0.0, 0)).mesh)
    irregular = measure_features(build_test_mesh(Task(0, "quadratic", 817, 16.0, 0.0, 0)).mesh)
    assert all(np.isfinite(getattr(f, k)) for f in (sphere, torus, patch) for k in SHAPE_MEASURES)
    # an umbilic surface of one curvature everywhere, no saddles
    assert sphere.anisotropy < 0.01 and sphere.curvature_spread < 0.01 and sphere.hyperbolic_share == 0
    # a torus bends one way only at its top and bottom circles and is a saddle on its inner half
    assert torus.anisotropy > 0.5 and 0.3 < torus.hyperbolic_share < 0.7
    # a geodesic sphere has 12 vertices of valence 5, a regular grid none; an irregular hexagon more
    assert 12 * (1 - 12 / 2562) ** 2 / 2562 == pytest.approx(sphere.valence_sd**2, rel=0.01)
    assert torus.valence_sd == 0 and patch.valence_sd == 0 and irregular.valence_sd > 0.2
    assert sphere.border_share == 0 and patch.border_share > 0
    # a regular hexagon lifted onto a steep patch: its edges spread more than the sphere's
    assert patch.edge_cv > sphere.edge_cv > 0


def test_table_coordinates_follow_the_kernels_axes():
    from curv.advice.advisor import table_coordinates

    old = {"kernel": {"noise_axis": "sqrt", "scales": [2.0, 0.5, 10.0]}}
    assert table_coordinates(old, np.e, 0.25, 5.0) == pytest.approx([0.5, 1.0, 0.5])
    new = {"columns": ["density", "noise_level", "irregularity_deg", "border_share", "anisotropy"],
           "kernel": {"axes": [["density", "log", 2.0], ["border_share", "sqrt", 0.1], ["anisotropy", "linear", 0.5]]}}
    c = table_coordinates(new, np.array([1.0, np.e]), 0.3, 7.0, np.array([0.04, 0.0]), 0.25)
    assert c.shape == (2, 3)
    assert c[0] == pytest.approx([0.0, 2.0, 0.5]) and c[1] == pytest.approx([0.5, 0.0, 0.5])


def test_errors_below_the_floor_do_not_outweigh_the_other_neighbours():
    """A call exact to rounding on one neighbour (nc R1 on a noise-free sphere: 1e-15) must not win
    over a call that is better on every other neighbour: the mean of logs is taken above the floor."""
    from curv.advice.advisor import MeshFeatures

    table = {"columns": ["density", "noise_level", "irregularity_deg"], "variants": ["a", "b"],
             "kernel": {"noise_axis": "linear", "scales": [1.0, 1.0, 1.0], "bandwidth": 100.0, "erel_floor": 1e-6},
             "points": [[0.1, 0.0, 5.0], [0.1, 0.0, 5.0], [0.1, 0.0, 5.0]],
             "median_erel": [[1e-15, 1e-4], [1e-2, 1e-4], [1e-2, 1e-4]]}
    f = MeshFeatures(irregularity_deg=5.0, noise=0.0, density=0.1, border_share=0.0)
    pred = predict(table, f)
    assert pred["b"] < pred["a"] == pytest.approx((1e-6 * 1e-2 * 1e-2) ** (1 / 3))
    table["kernel"]["erel_floor"] = 0.0
    assert predict(table, f)["a"] < 1e-6  # without the floor the rounding would win


def test_leave_one_out_regret_is_the_kernel_prediction_of_the_others():
    from curv.advice.table import _regret, loo_regret

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
    from curv.advice.table import select_axes

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
    import curv.advice.table as at
    from curv.advice.advisor import BASE_COLUMNS, kernel_axes

    table = load_table()
    assert table["columns"] == [*BASE_COLUMNS, *at.EXTRA_COLUMNS]
    assert all(len(p) == len(table["columns"]) for p in table["points"])
    axes = kernel_axes(table)
    assert [a[0] for a in axes[:3]] == list(BASE_COLUMNS) and {a[0] for a in axes} <= set(table["columns"])
    assert table["kernel"]["erel_floor"] == at.EREL_FLOOR
    doc = " ".join(at.__doc__.replace("\\\n", " ").split())
    for step in ("fill", "refeature", "reselect"):
        cmd = table["metadata"][f"{step}_command"].split()
        assert cmd[:4] == ["python", "-m", "curv.advice.table", step]
        assert f"python -m curv.advice.table {step}" in doc


def test_reselection_separates_a_nearly_umbilic_surface_from_an_umbilic_one_by_the_anisotropys_log():
    """Noise-free spheres (anisotropy about 0.001) and ellipsoids (0.02-0.04) have different winners
    (the sphere's exact call is far from the best on an ellipsoid); the patches' anisotropies (0.3-1)
    set the axis's spread, so on a linear axis the two stand within one bandwidth. The reselection
    (stored points, nothing measured) takes the axis logarithmic and advises the ellipsoids apart."""
    from curv.advice.table import loo_regret, reselect_table
    from curv.advice.advisor import table_coordinates

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
    out = reselect_table(table, command="python -m curv.advice.table reselect")
    axes = out["kernel"]["axes"]
    assert axes[-1][:2] == ["anisotropy", "log"]
    assert out["points"] == table["points"] and out["metadata"]["reselect_command"].endswith("reselect")
    coords = table_coordinates(out, *points.T)
    regret = loo_regret(coords, np.log(erel), out["kernel"]["bandwidth"])
    assert np.percentile(regret[kind == 1], 90) < 1.5


def test_a_noise_free_ellipsoid_is_not_advised_the_spheres_exact_call():
    """nc R1 is exact on a noise-free sphere and 8 times the best error on a noise-free ellipsoid of
    4400 vertices; the packaged table tells the two apart (its anisotropy axis is logarithmic)."""
    from curv.advice.table import variant_errors

    for name, params, exact in (("sphere", {}, True), ("ellipsoid", dict(a=1.06, b=1.01, c=0.93), False)):
        s = make_surface(name, n_vertices=4447, noise=0.0, seed=1, **params)
        adv = advise(s.mesh)
        assert (adv.label == "nc R1") == exact
        if not exact:
            e = variant_errors(s.mesh, s.truth, np.ones(s.mesh.n_vertices, bool), [adv.best.variant.id, "nc:R1"])
            assert e[adv.best.variant.id] < e["nc:R1"] / 2


def test_surface_groups_hold_one_random_surface_at_every_setting():
    from curv.advice.table import noise_groups, surface_groups

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
    from curv.advice.table import select_axes

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
    import curv.advice.table as at
    from curv.advice.advisor import calibrate_irregularity, calibrate_noise

    table = {"variants": ["nc:R1", "qs:R1"], "calibration": {"noise_floor": 0.0, "noise_gain": 1.2,
                                                              "noise_density4": 0.01, "irregularity_noise_deg": 10.0},
             "metadata": {"settings": {"functions": ["quadratic"], "irregularity": [0.0], "noise": [0.0, 0.5]},
                          "fill_command": "python -m curv.advice.table fill"},
             "truth": {"key": [[0, "quadratic", 217, 0.0, 0.0, 0]], "noise_true": [0.0],
                       "irregularity_planar": [0.0], "density_true": [0.2], "n_evaluated": [40]},
             "points": [[0.2, 0.0, 20.0, 0.1]], "columns": ["density", "noise_level", "irregularity_deg", "edge_cv"],
             "median_erel": [[0.01, None]]}
    monkeypatch.setattr(at, "COARSE_DENSITIES", (217,))
    monkeypatch.setattr(at, "COARSE_CLOSED_VERTICES", ())
    jobs = at.coarse_jobs(table, 2)
    assert [j[0] for j in jobs] == [[0, "quadratic", 217, 0.0, 0.5, 0], [0, "quadratic", 217, 0.0, 0.0, 1],
                                    [0, "quadratic", 217, 0.0, 0.5, 1]]  # the ones the table lacks
    row = {"key": jobs[2][0], "noise_true": 0.05, "irregularity_planar": 0.0, "density_true": 0.3,
           "noise_raw": 0.07, "irregularity_raw": 22.0, "density": 0.25, "n_evaluated": 35}
    done = {at._key_text(jobs[2][0]): [row, {"nc:R1": 0.02, "qs:R1": 0.03}],
            at._key_text(table["truth"]["key"][0]): [{}, {"qs:R1": 0.04}]}
    out = at.fill_table(table, done, command="python -m curv.advice.table fill --coarse-samples 2",
                        new_keys=[j[0] for j in jobs])
    assert out["median_erel"] == [[0.01, 0.04], [0.02, 0.03]]  # an empty cell filled, a new row
    assert out["truth"]["key"][1] == jobs[2][0] and out["metadata"]["n_meshes"] == 2  # not run: not added
    noise = calibrate_noise(0.07, table["calibration"], 0.25)
    irr = calibrate_irregularity(22.0, noise, table["calibration"])
    assert out["points"][1] == pytest.approx([0.25, noise / 0.1, irr], rel=1e-3)
    assert out["columns"] == ["density", "noise_level", "irregularity_deg"] and len(out["points"][0]) == 3
    assert out["metadata"]["fill_commands"][0] == "python -m curv.advice.table fill"


def test_fill_runs_the_empty_cells_of_the_chosen_kinds_and_sizes_and_keeps_the_extra_columns():
    import curv.advice.table as at

    keys = [[0, "quadratic", 817, 0.0, 0.0, 1], [0, "quadratic", 12481, 0.0, 0.0, 1],
            [0, "sphere", 642, 0.0, 0.0, 1], [0, "trigonometric", 817, 8.0, 0.2, 0]]
    table = {"variants": ["nc:R1", "jet:R2;degree=4"], "columns": ["density", "noise_level", "irregularity_deg",
                                                                     "valence_sd"],
             "points": [[0.1, 0.0, 20.0, 0.3], [0.02, 0.0, 20.0, 0.3], [0.2, 0.0, 0.0, 0.07], [0.1, 0.2, 9.0, 0.3]],
             "median_erel": [[0.01, None], [0.02, None], [0.03, None], [0.04, 0.05]],
             "truth": {"key": keys}, "metadata": {"fill_command": "python -m curv.advice.table fill"},
             "calibration": {}}
    jobs = at.fill_jobs(table, kinds=("quadratic", "trigonometric"), sizes=(817, 1801))
    assert jobs == [(keys[0], ("jet:R2;degree=4",))]  # not the 12481 patch, nor the sphere, nor a full row
    assert len(at.fill_jobs(table, kinds=("quadratic", "trigonometric"))) == 2
    done = {at._key_text(keys[0]): [{}, {"jet:R2;degree=4": 0.006}]}
    out = at.fill_table(table, done, command="python -m curv.advice.table fill --sizes 817")
    assert out["median_erel"][0] == [0.01, 0.006] and out["median_erel"][1] == [0.02, None]
    # no new rows: the measured extra columns and the kernel's columns stay as they were
    assert out["columns"] == table["columns"] and out["points"] == table["points"]


def test_fill_adds_closed_surfaces_of_a_new_coarse_size_only():
    import curv.advice.table as at

    settings = {"functions": ["quadratic"], "irregularity": [0.0], "noise": [0.0]}
    have = [[0, "quadratic", d, 0.0, 0.0, 0] for d in at.COARSE_DENSITIES]
    have += [[0, nm, n, 0.0, 0.0, 0] for nm in at.DEFAULT_CLOSED for n in at.COARSE_CLOSED_VERTICES]
    table = {"variants": ["nc:R1"], "metadata": {"settings": settings}, "truth": {"key": have}}
    assert at.coarse_jobs(table, 1) == []
    jobs = at.coarse_jobs(table, 1, (*at.COARSE_CLOSED_VERTICES, 482))
    assert [j[0] for j in jobs] == [[0, nm, 482, 0.0, 0.0, 0] for nm in at.DEFAULT_CLOSED]
    row = {"key": jobs[0][0], "noise_true": 0.0, "irregularity_planar": float("nan"), "density_true": 0.3,
           "noise_raw": 0.001, "irregularity_raw": 4.0, "density": 0.3, "n_evaluated": 492}
    table.update(calibration={"noise_floor": 0.0, "noise_gain": 1.2, "noise_density4": 0.01,
                              "irregularity_noise_deg": 10.0},
                 points=[[0.1, 0.0, 20.0]] * len(have), median_erel=[[0.01]] * len(have),
                 truth={"key": have, "noise_true": [0.0] * len(have), "irregularity_planar": [0.0] * len(have),
                        "density_true": [0.1] * len(have), "n_evaluated": [40] * len(have)})
    table["metadata"]["coarse"] = {"densities": list(at.COARSE_DENSITIES), "closed_vertices": [162, 252, 362]}
    out = at.fill_table(table, {at._key_text(jobs[0][0]): [row, {"nc:R1": 0.002}]}, new_keys=[j[0] for j in jobs],
                        closed_vertices=[162, 252, 362, 482])
    assert out["truth"]["key"][-1] == jobs[0][0] and len(out["points"]) == len(have) + 1
    assert out["metadata"]["coarse"]["closed_vertices"] == [162, 252, 362, 482]
    assert out["metadata"]["coarse"]["densities"] == list(at.COARSE_DENSITIES)


def test_fill_adds_the_noise_twins_of_the_noise_free_meshes_at_a_level_between_the_grid():
    import curv.advice.table as at

    keys = [[0, "quadratic", 817, 8.0, 0.0, 1], [0, "quadratic", 817, 8.0, 0.05, 1],
            [0, "torus", 2562, 0.0, 0.0, 2], [0, "quadratic", 12481, 0.0, 0.0, 0], [0, "torus", 2562, 0.0, 0.015, 0]]
    table = {"variants": ["nc:R1", "jet:R2;degree=4"], "truth": {"key": keys}}
    jobs = at.noise_jobs(table, [0.015, 0.005], sizes=(817, 2562))
    assert [j[0] for j in jobs] == [[0, "torus", 2562, 0.0, 0.015, 2], [0, "torus", 2562, 0.0, 0.005, 2],
                                    [0, "quadratic", 817, 8.0, 0.015, 1], [0, "quadratic", 817, 8.0, 0.005, 1]]
    assert all(j[1] == ("nc:R1", "jet:R2;degree=4") for j in jobs)  # every candidate on a new row
    assert len(at.noise_jobs(table, [0.015])) == 3  # every size; the torus of sample 0 has no noise-free twin
    assert at.noise_jobs({**table, "truth": {"key": keys + [j[0] for j in jobs]}}, [0.015, 0.005], (817, 2562)) == []
    # the twin is the same surface and tessellation, only its noise level differs
    mesh0, truth0, _ = at.table_mesh([0, "torus", 162, 0.0, 0.0, 2])
    mesh1, truth1, _ = at.table_mesh([0, "torus", 162, 0.0, 0.015, 2])
    assert np.array_equal(mesh0.faces, mesh1.faces) and np.array_equal(truth0.k1, truth1.k1)
    step = np.linalg.norm(mesh1.vertices - mesh0.vertices, axis=1)
    assert 0 < np.median(step) < 0.01 * np.mean(np.linalg.norm(mesh0.vertices[mesh0.edges[:, 0]]
                                                                - mesh0.vertices[mesh0.edges[:, 1]], axis=1))
