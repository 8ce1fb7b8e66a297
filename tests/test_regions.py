"""Regions: ``estimate(..., vertices=idx)`` equals the full run at idx, NOT_COMPUTED elsewhere."""

from __future__ import annotations

import numpy as np
import pytest

import curv
from curv.estimators import ESTIMATORS
from creased_meshes import box
from meshes import torus_grid

METHODS = sorted(ESTIMATORS)


@pytest.fixture(scope="module")
def torus():
    return torus_grid(30, 14)[0]


def _region(mesh):
    rng = np.random.default_rng(3)
    return np.sort(rng.choice(mesh.n_vertices, size=37, replace=False))


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("features", [None, 30])
def test_region_equals_full_run(torus, method, features):
    _assert_region_equals_full_run(torus if features is None else box(4), method, features)


@pytest.mark.parametrize("method", ["csm", "icc"])
@pytest.mark.parametrize("features", [None, 30])
@pytest.mark.parametrize("share", [0.0, 1.0], ids=["terms-everywhere", "walk-first"])
def test_clipping_region_either_way(torus, method, features, share, monkeypatch):
    """Both ways of a clipping region: the per-triangle terms of the whole mesh, or a walk first."""
    from curv.estimators import _ball_sums

    monkeypatch.setattr(_ball_sums, "REGION_WALK_SHARE", share)
    _assert_region_equals_full_run(torus if features is None else box(4), method, features)


def _assert_region_equals_full_run(mesh, method, features):
    idx = _region(mesh)
    full = curv.estimate(mesh, method, features=features)
    part = curv.estimate(mesh, method, vertices=idx, features=features)
    for name in ("k1", "k2", "d1", "d2", "reason", "valid"):
        assert np.array_equal(getattr(full, name)[idx], getattr(part, name)[idx], equal_nan=True), name
    rest = np.setdiff1d(np.arange(mesh.n_vertices), idx)
    assert np.all(part.reason[rest] == curv.Reason.NOT_COMPUTED)
    assert np.isnan(part.k1[rest]).all() and np.isnan(part.d1[rest]).all() and not part.valid[rest].any()
    assert part.k1.shape == (mesh.n_vertices,) and part.d1.shape == (mesh.n_vertices, 3)
    assert part.info["region"] == idx.size and full.info["region"] == mesh.n_vertices


@pytest.mark.parametrize("method", ["qs", "mru", "jet"])
def test_region_with_radius_fit_normals_and_chunks(torus, method):
    idx = _region(torus)[::-1]  # any order
    full = curv.estimate(torus, method, radius=0.6, normals="fit")
    part = curv.estimate(torus, method, radius=0.6, normals="fit", vertices=idx, block_size=5)
    assert np.array_equal(full.k1[idx], part.k1[idx], equal_nan=True)


def test_empty_region(torus):
    res = curv.estimate(torus, "qs", vertices=np.zeros(0, np.int64))
    assert np.all(res.reason == curv.Reason.NOT_COMPUTED)


@pytest.mark.parametrize("bad, message", [
    (np.array([0, 10**9]), "out of range"),
    (np.array([-1]), "out of range"),
    (np.array([0.5]), "indices"),
    (np.ones((2, 2), np.int64), "1-D"),
])
def test_bad_regions(torus, bad, message):
    with pytest.raises(curv.EstimatorError, match=message):
        curv.estimate(torus, "qs", vertices=bad)


def test_region_refuses_smoothed_values(torus):
    with pytest.raises(curv.EstimatorError, match="smooth"):
        curv.estimate(torus, "qs", vertices=[0, 1], smooth="values")


# ---------------------------------------------------------------------------- command line
def _write_off(path, mesh):
    lines = ["OFF", f"{mesh.n_vertices} {mesh.n_faces} 0"]
    lines += [f"{x:.17g} {y:.17g} {z:.17g}" for x, y, z in mesh.vertices]
    lines += [f"3 {a} {b} {c}" for a, b, c in mesh.triangles]
    path.write_text("\n".join(lines) + "\n")
    return str(path)


@pytest.fixture()
def box_file(tmp_path):
    return _write_off(tmp_path / "box.off", box(4))


def test_cli_features_region_and_vertices(box_file, tmp_path, capsys):
    from curv.cli import main

    assert main(["estimate", box_file, "-m", "qs", "-q"]) == 0
    out = capsys.readouterr().out
    assert "sharp edges" in out and "--features 45" in out
    assert main(["estimate", box_file, "-m", "qs", "-q", "--features", "30"]) == 0
    out = capsys.readouterr().out
    n_feature = int(curv.feature_vertices(box(4), curv.feature_edges(box(4), 30)).sum())
    assert f"feature {n_feature}" in out and "try --features" not in out
    listing = tmp_path / "v.txt"
    listing.write_text("0\n# a comment\n\n5\n17\n")
    assert main(["estimate", box_file, "-m", "qs", "-q", "--vertices", str(listing)]) == 0
    assert "region: 3 vertices estimated" in capsys.readouterr().out
    mesh = box(4)
    inside = int((np.linalg.norm(mesh.vertices - [0.5, 0.5, 0.0], axis=1) <= 0.3).sum())
    assert main(["estimate", box_file, "-m", "qs", "-q", "--region", "0.5", "0.5", "0", "0.3"]) == 0
    assert f"region: {inside} vertices estimated" in capsys.readouterr().out


@pytest.mark.parametrize("args, message", [
    (["--features", "-3"], "between 0 and 180"),
    (["--features", "sharp"], "angle in degrees"),
    (["--vertices", "{bad}"], "line 2: 'x' is not a vertex index"),
    (["--vertices", "{out}"], "vertex index 9999 is out of range"),
    (["--vertices", "{missing}"], "cannot read"),
    (["--region", "0", "0", "0", "-1"], "positive length"),
])
def test_cli_bad_region_or_features(box_file, tmp_path, capsys, args, message):
    from curv.cli import main

    (tmp_path / "bad.txt").write_text("0\nx\n")
    (tmp_path / "out.txt").write_text("1\n9999\n")
    paths = {"bad": tmp_path / "bad.txt", "out": tmp_path / "out.txt", "missing": tmp_path / "none.txt"}
    args = [a.format(**paths) for a in args]
    assert main(["estimate", box_file, "-m", "qs", "-q", *args]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1
