"""The advisor: its features on meshes of known noise and irregularity, its ranking, its CLI."""

from __future__ import annotations

import json

import numpy as np
import pytest

import curv
from curv.advisor import (
    Advice, advise, angle_deviation_deg, kernel_predict, load_table, measure_features, predict,
)
from curv.cli import main
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
    names = {m for m, _, _ in adv.ranking}
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
    adv = curv.advise(noisy.mesh)
    assert isinstance(adv, Advice)
    assert len(adv.ranking) == len(table["variants"])  # a triangle mesh admits every registered variant
    errs = [e for _, _, e in adv.ranking]
    assert errs == sorted(errs) and all(np.isfinite(errs)) and errs[0] > 0
    assert (adv.method, adv.range, adv.expected_erel) == adv.ranking[0]
    assert {f"{m}:R{k}" for m, k, _ in adv.ranking} == set(table["variants"])
    pred = predict(table, adv.features)
    assert pred[f"{adv.method}:R{adv.range}"] == pytest.approx(adv.expected_erel)


def test_why_line_names_the_noise_the_irregularity_and_the_choice(noisy):
    adv = advise(noisy.mesh)
    assert "\n" not in adv.why
    assert f"noise about {adv.features.noise_level:.2g} of the paper's level" in adv.why
    assert f"({adv.features.irregularity_deg:.0f} degrees)" in adv.why
    assert adv.why.endswith(f"{adv.method} R{adv.range}, expected median e_rel {adv.expected_erel:.2g}")


def test_noise_raises_the_expected_error():
    clean, noisy = advise(_study_mesh(0.0, 12.5).mesh), advise(_study_mesh(1.0, 12.5).mesh)
    assert noisy.expected_erel > 2 * clean.expected_erel


def test_lazy_export_is_the_function_even_after_the_module_loads():
    import curv.advisor

    assert curv.advise is curv.advisor.advise and curv.Advice is curv.advisor.Advice


# ------------------------------------------------------------------ CLI
def test_cli_text(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["advise", path, "--top", "5"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith(f"{path}: 3169 vertices; ")
    adv = advise(noisy.mesh)
    assert f"advice: {adv.why}" in out
    rows = [line.split() for line in out if line[:4].strip().isdigit()]
    assert [r[0] for r in rows] == ["1", "2", "3", "4", "5"]
    assert rows[0][1:3] == [adv.method, f"R{adv.range}"]
    assert out[-1].strip().startswith(f"... {len(adv.ranking) - 5} more")


def test_cli_json(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["advise", path, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["input"] == path
    ranking = data["ranking"]
    assert (data["method"], data["range"]) == (ranking[0]["method"], ranking[0]["range"])
    errs = [r["expected_erel"] for r in ranking]
    assert errs == sorted(errs)
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
    assert out[0] == f"auto: {adv.method} R{adv.range} ({adv.why})"
    assert any(line.startswith(f"{adv.method} R{adv.range}: ") for line in out)


def test_estimate_method_auto_refuses_a_range(tmp_path, capsys, noisy):
    path = _write_off(tmp_path / "m.off", noisy.mesh)
    assert main(["estimate", path, "--method", "auto", "--range", "3"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["curv: error: --method auto chooses the range too; drop --range/--radius"]


# ------------------------------------------------------------------ the table builder
def test_calibration_fit_recovers_known_coefficients():
    from curv.advisor_table import fit_calibration

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


def test_a_tiny_table_builds_and_advises(tmp_path, noisy):
    from curv.advisor_table import build_table, table_settings

    settings = table_settings(samples=1, densities=(817,), noise=(0.0, 1.0), irregularity=(0.0,))
    table = build_table(settings, tmp_path / "study", workers=0, command="test", closed=("sphere",),
                        closed_vertices=(642,))
    n_meshes = 3 * 2 + 2  # three functions x two noise levels, one sphere at two noise levels
    assert len(table["points"]) == len(table["median_erel"]) == len(table["truth"]) == n_meshes
    assert all(len(row) == len(table["variants"]) for row in table["median_erel"])
    assert table["metadata"]["command"] == "test" and table["metadata"]["settings"]["samples"] == 1
    assert table["kernel"]["bandwidth"] in (0.15, 0.25, 0.35, 0.5, 0.7, 1.0, 1.5)
    table = json.loads(json.dumps(table))  # what load_table reads back
    adv = advise(noisy.mesh, table=table)
    assert len(adv.ranking) == len(table["variants"])
