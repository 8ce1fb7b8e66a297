"""Code outside the owners asks them: the range rule (curv.core.ranges) and estimator facts (the registry).

Each test swaps or probes the owner and checks that the asking code follows it, so a copy of the
rule re-coded elsewhere fails here.
"""

from __future__ import annotations

import dataclasses

import pytest

import curv
from curv import memory
from curv.core import ranges
from curv.cli import build_parser
from curv.estimators import ESTIMATORS, get_spec, registry
from curv.fitted_normals import fitted_normals
from tests.meshes import icosphere


def _message(call) -> str:
    with pytest.raises(curv.EstimatorError) as info:
        call()
    return str(info.value)


@pytest.mark.parametrize("kwargs", [dict(range=0.5), dict(range="R0.5"), dict(radius=True), dict(radius=-1.0),
                                    dict(radius="wide"), dict(range=2, radius=0.3)])
def test_fitted_normals_refuse_what_the_range_rule_refuses_with_its_words(kwargs):
    # the fit is the jet's: whatever curv.core.ranges refuses for the jet, fitted_normals refuses the same way
    mesh = icosphere(1)
    expected = _message(lambda: ranges.resolve(get_spec("jet"), kwargs.get("range"), kwargs.get("radius")))
    assert _message(lambda: fitted_normals(mesh, **kwargs)) == expected


def test_fitted_normals_take_every_form_the_range_rule_takes():
    mesh = icosphere(2)
    labelled = fitted_normals(mesh, range="R2.5")
    number = fitted_normals(mesh, range=2.5)
    assert (labelled == number).all()


def test_cli_default_methods_are_the_registrys(monkeypatch):
    other = next(name for name in ESTIMATORS if name != registry.DEFAULT_ESTIMATORS["mesh"])
    monkeypatch.setitem(registry.DEFAULT_ESTIMATORS, "mesh", other)
    parser = build_parser()
    assert parser.parse_args(["estimate", "part.ply"]).method is None  # the input's kind decides
    sub = next(a for a in parser._subparsers._group_actions if a.choices)  # the subcommands
    help_text = " ".join(sub.choices["estimate"].format_help().split())
    assert f"default {other} on a mesh, {registry.DEFAULT_ESTIMATORS['points']} on a point cloud" in help_text


@pytest.mark.parametrize("method", list(ESTIMATORS))
def test_memory_model_takes_each_estimators_extra_from_its_spec(method, monkeypatch):
    n_vertices, n_faces = 100_000, 200_000
    units = n_vertices + n_faces / 2
    spec = get_spec(method)
    before = memory.estimate_peak_bytes(n_vertices, n_faces, method)
    monkeypatch.setitem(ESTIMATORS, method,
                        dataclasses.replace(spec, extra_bytes_per_unit=spec.extra_bytes_per_unit + 1000.0))
    after = memory.estimate_peak_bytes(n_vertices, n_faces, method)
    assert after - before == pytest.approx(1000.0 * units, abs=1.0)
