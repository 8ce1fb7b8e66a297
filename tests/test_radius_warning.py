"""A radius= that leaves the input without estimates says so (issue 36, item 5): a curv.RadiusWarning
once per call naming the radius and the median spacing, the same words in ``info["warnings"]`` and in
the command line's summary."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

import curv
from curv.cli import main
from curv.core.jit import run_to_end
from curv.core.ranges import point_spacing
from curv.surfaces import Sphere, sample_points
from tests.meshes import icosphere


def _sample_mesh(name: str) -> Path | None:
    """One of pymeshlab's sample meshes (real scans nobody here made), or None without pymeshlab."""
    try:
        import pymeshlab
    except ImportError:
        return None
    path = Path(pymeshlab.__file__).parent / "tests" / "sample_meshes" / name
    return path if path.is_file() else None


def _caught(call):
    """``call()``'s result and the curv warnings it gave, every one recorded."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        result = call()
    return result, [w for w in caught if issubclass(w.category, curv.CurvWarning)]


@pytest.fixture(scope="module")
def cloud():
    return sample_points(Sphere(2.0), 3000, sampling="blue", rng=2).cloud


@pytest.mark.skipif(_sample_mesh("bunny.obj") is None, reason="pymeshlab's sample meshes are not installed")
def test_the_bunny_at_a_radius_below_its_spacing_warns_once_naming_both():
    bunny = curv.load(_sample_mesh("bunny.obj"))
    spacing = float(np.median(bunny.longest_edge))
    assert 0.005 < spacing  # the call: every vertex NaN
    res, caught = _caught(lambda: curv.estimate(bunny, "jet", radius=0.005))
    assert res.valid.sum() == 0
    assert len(caught) == 1 and caught[0].category is curv.RadiusWarning
    text = str(caught[0].message)
    assert "radius=0.005 is below the median spacing" in text and f"{spacing:.4g}" in text
    assert "100 % of the vertices have too few neighbours" in text
    assert caught[0].filename == __file__  # the caller's line, not curv's
    assert res.info["warnings"] == (text,)


def test_a_cloud_at_a_radius_below_its_spacing_warns_once(cloud):
    spacing = float(np.median(point_spacing(cloud)))
    res, caught = _caught(lambda: curv.estimate(cloud, "qs", radius=0.5 * spacing))
    assert len(caught) == 1
    text = str(caught[0].message)
    assert f"radius={0.5 * spacing:g} is below the median spacing {spacing:.4g}" in text
    assert "(the distance to the 6th nearest point)" in text and "of the points have too few neighbours" in text
    assert f"try radius={2 * spacing:.3g} (2 spacings) or range=2" in text
    assert res.info["warnings"] == (text,)
    # the generator form warns once too, at its caller's line
    _, caught = _caught(lambda: run_to_end(curv.iter_estimate(cloud, "qs", radius=0.5 * spacing)))
    assert len(caught) == 1 and caught[0].filename == __file__


def test_most_points_without_an_estimate_warn_above_the_spacing_too(cloud):
    """A degree-4 jet needs 15 neighbours: a ball of 1.3 spacings holds fewer at most points."""
    spacing = float(np.median(point_spacing(cloud)))
    res, caught = _caught(lambda: curv.estimate(cloud, "jet", radius=1.3 * spacing, degree=4))
    short = np.isin(res.reason, (curv.Reason.TOO_FEW_NEIGHBOURS, curv.Reason.SINGULAR)).mean()
    assert short > 0.5
    assert len(caught) == 1
    assert f"is only 1.3 times the median spacing {spacing:.4g}" in str(caught[0].message)


def test_a_sensible_radius_or_a_range_gives_no_warning(cloud):
    spacing = float(np.median(point_spacing(cloud)))
    for call in (lambda: curv.estimate(cloud, "qs", radius=2.5 * spacing), lambda: curv.estimate(cloud, "qs", 2),
                 lambda: curv.estimate(icosphere(2), "qs", radius=0.5)):
        res, caught = _caught(call)
        assert caught == [] and "warnings" not in res.info


def test_a_region_is_judged_on_its_own_rows():
    mesh = icosphere(3)
    spacing = float(np.median(mesh.longest_edge))
    _, caught = _caught(lambda: curv.estimate(mesh, "qs", radius=0.5 * spacing, vertices=np.arange(20)))
    assert len(caught) == 1 and "100 % of the vertices" in str(caught[0].message)


def test_the_command_line_says_it_in_the_summary(tmp_path, capsys):
    mesh = icosphere(2)
    path = tmp_path / "sphere.ply"
    curv.save_ply(path, mesh, curv.estimate(mesh, "qs"))
    spacing = float(np.median(mesh.longest_edge))
    assert main(["estimate", str(path), "-m", "qs", "--radius", f"{0.4 * spacing:.4g}", "-q"]) == 0
    out = capsys.readouterr()
    lines = [line for line in out.out.splitlines() if line.startswith("warning: ")]
    assert len(lines) == 1 and "is below the median spacing" in lines[0]
    assert "Warning" not in out.err  # said once, in the summary, not again as a Python warning
