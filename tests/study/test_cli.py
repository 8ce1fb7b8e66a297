"""``curv study``: the whole pipeline on a tiny grid, outputs, report-only, interruption message."""

from __future__ import annotations

import argparse

import pytest

from curv.study.cli import add_study_parser, run_study, settings_from_args
from curv.study.runner import RESULTS_NAME
from curv.study.store import ResultsFile

PNG = b"\x89PNG\r\n\x1a\n"


def _parse(argv):
    parser = argparse.ArgumentParser(prog="curv")
    add_study_parser(parser.add_subparsers(dest="command", required=True))
    return parser.parse_args(["study", *argv])


TINY = ["--densities", "817", "--functions", "quadratic", "--noise", "0", "100", "--irregularity", "0", "25",
        "--estimators", "csm:R1,R2,R3", "nc:R1,R2,R3", "mru", "--samples", "1", "--workers", "0", "--seed", "3"]


def test_options_override_the_preset():
    s = settings_from_args(_parse(["--out", "x", "--preset", "medium", "--noise", "0", "50",
                                   "--functions", "ellipsoid", "--samples", "5"]))
    assert s.noise == (0.0, 0.5) and s.functions == ("ellipsoid_patch",) and s.samples == 5
    with pytest.raises(SystemExit):
        _parse(["--out", "x", "--densities", "300"])


def test_densities_take_any_hexagon_subdivision_and_name_the_nearest(capsys):
    s = settings_from_args(_parse(["--out", "x", "--densities", "817", "1801", "7057"]))
    assert s.densities == (817, 1801, 7057)
    for bad in ("1800", "abc"):
        with pytest.raises(SystemExit):
            _parse(["--out", "x", "--densities", bad])
    err = capsys.readouterr().err
    assert "1800 is not one (nearest: 1657, 1801" in err and "not a whole number: 'abc'" in err


def test_study_writes_table_figures_and_report(tmp_path, capsys):
    args = _parse(["--out", str(tmp_path), *TINY])
    assert run_study(args) == 0
    err = capsys.readouterr().err
    assert "4/4 meshes" in err and "ETA" in err
    rows = ResultsFile(tmp_path / RESULTS_NAME).load()
    # explicit ranges select no smoothing variant; a bare "mru" brings R2SM/R2SV (817 = the fig10 density here)
    assert len(rows) == 4 * (3 + 3 + 3 + 2)
    for name in ("fig8.png", "fig9.png", "fig10.png"):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(PNG) and len(data) > 10_000
    table1 = (tmp_path / "table1.md").read_text()
    assert "**R1**" in table1 and "| 25° |" in table1 and "(111%)" in table1  # the paper's CSM (R1) 25° value beside ours
    report = (tmp_path / "report.md").read_text()
    assert "samples per setting: **1**" in report
    assert "CSM is significantly more robust" in report
    assert any(mark in report for mark in ("✅ agrees", "❌ disagrees", "🟡 partly"))
    assert "not tested" in report  # e.g. 12481 vertices are not in this grid

    # report-only rebuilds from the results without running anything
    (tmp_path / "report.md").unlink()
    assert run_study(_parse(["--out", str(tmp_path), *TINY, "--report-only", "--measure", "median_erel"])) == 0
    assert "median of e_rel" in (tmp_path / "report.md").read_text()


def test_report_only_without_results_fails_cleanly(tmp_path, capsys):
    assert run_study(_parse(["--out", str(tmp_path), *TINY, "--report-only"])) == 2
    assert "no results" in capsys.readouterr().err


@pytest.mark.slow
def test_quick_preset_runs_under_a_minute(tmp_path):
    import time

    t0 = time.perf_counter()
    assert run_study(_parse(["--out", str(tmp_path), "--preset", "quick", "--quiet"])) == 0
    assert time.perf_counter() - t0 < 60
    assert (tmp_path / "fig10.png").exists()
