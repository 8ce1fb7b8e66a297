"""The report's reductions: dense-cube means equal row means, sample weights, bootstrap intervals,
claims restricted to the paper's estimators, and the report's uncertainty columns."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from curv.study import StudySettings
from curv.study.analysis import Analysis, table1
from curv.study.claims import CLAIMS, Status, check, check_all
from curv.study.report import report_markdown
from curv.study.table import Table
from curv.study.uncertainty import interval, resamples, stability

FUNCTIONS = ("quadratic", "ellipsoid_patch")
DENSITIES = (817, 3169)
IRREG = (0.0, 25.0)
NOISE = (0.0, 1.0)


def synthetic(variants: dict[str, float], samples: int, *, spread: float = 0.1, seed: int = 0,
              noise_gain: dict[str, float] | None = None, drop: float = 0.0) -> Table:
    """A results table whose rms_erel is ``base * (1 + noise) * (1 + irregularity/25)`` times a
    per-sample factor ``1 + spread * z_sample``; ``drop`` sets that share of values to NaN."""
    rng = np.random.default_rng(seed)
    factor = 1 + spread * rng.standard_normal(samples)
    noise_gain = noise_gain or {}
    rows = []
    for vid, (f, d, i, n, s) in itertools.product(variants, itertools.product(FUNCTIONS, DENSITIES, IRREG, NOISE,
                                                                                range(samples))):
        value = variants[vid] * (1 + n * noise_gain.get(vid, 1.0)) * (1 + i / 25) * factor[s]
        if rng.random() < drop:
            value = np.nan
        method, _, rng_label = vid.partition(":")
        rows.append({"seed": 0, "function": f, "density": d, "irregularity": i, "noise": n, "sample": s,
                     "variant": vid, "method": method, "range": int(rng_label[1:]), "smooth": "none",
                     "rms_erel": value, "median_erel": value / 2, "seconds": 0.01, "n_invalid": 0,
                     "n_evaluated": 10, "irregularity_achieved": i})
    return Table.from_rows(rows)


def settings(samples: int, estimators: tuple[str, ...]) -> StudySettings:
    return StudySettings(samples=samples, densities=DENSITIES, noise=NOISE, irregularity=IRREG,
                         functions=FUNCTIONS, estimators=estimators)


VARIANTS = {"csm:R2": 0.05, "mru:R2": 0.04, "jet:R2": 0.01, "csm:R3": 0.06, "mru:R3": 0.03}


def test_cube_means_equal_the_row_means_with_missing_values():
    t = synthetic(VARIANTS, 4, drop=0.2, seed=3)
    an = Analysis(t, settings(4, tuple(VARIANTS)))
    for vid, where in itertools.product(VARIANTS, ({}, {"noise": 1.0}, {"density": 817, "irregularity": 25.0},
                                                   {"function": "quadratic", "noise": (0.0, 1.0)})):
        vals = np.asarray(t.where(variant=vid, **where)["rms_erel"], float)
        vals = vals[np.isfinite(vals)]
        assert an.err(vid, **where) == pytest.approx(vals.mean(), rel=1e-12)
    assert np.isnan(an.err("csm:R2", density=12481))  # not in the grid
    with pytest.raises(KeyError):
        an.err("csm:R2", sample=0)


def test_first_samples_is_the_mean_over_those_samples_only():
    t = synthetic(VARIANTS, 5, spread=0.3)
    an = Analysis(t, settings(5, tuple(VARIANTS)))
    early = an.first_samples(2)
    ref = np.asarray(t.where(variant="mru:R2", sample=(0, 1))["rms_erel"], float).mean()
    assert early.n_samples == 2 and an.n_samples == 5
    assert early.err("mru:R2") == pytest.approx(ref, rel=1e-12)
    assert early.err("mru:R2") != pytest.approx(an.err("mru:R2"), rel=1e-6)


def test_resamples_draw_whole_surfaces_with_replacement():
    an = Analysis(synthetic(VARIANTS, 6), settings(6, tuple(VARIANTS)))
    weights = [a.weights for a in resamples(an, 50)]
    assert all(w.sum() == 6 and np.all(w == np.round(w)) for w in weights)
    assert any(np.any(w > 1) for w in weights)  # with replacement
    early = an.first_samples(3)
    assert all(np.all(a.weights[3:] == 0) and a.weights.sum() == 3 for a in resamples(early, 20))


def test_interval_covers_the_estimate_and_narrows_with_more_surfaces():
    def width(n):
        an = Analysis(synthetic(VARIANTS, n, spread=0.2, seed=1), settings(n, tuple(VARIANTS)))
        lo, hi = interval(an, lambda a: a.err("csm:R2"))
        assert lo <= an.err("csm:R2") <= hi
        return float(hi - lo)

    assert width(80) < 0.5 * width(5)


def test_table1_is_the_ratio_of_means_to_the_regular_error():
    an = Analysis(synthetic(VARIANTS, 3, spread=0.0), settings(3, tuple(VARIANTS)))
    t1 = table1(an)
    assert t1[2]["csm"][25.0] == pytest.approx(200.0)  # (1 + 25/25) x the 0° error


def _claim(claim_id: str):
    return next(c for c in CLAIMS if c.id == claim_id)


def test_claims_ignore_estimators_beyond_the_paper():
    # jet (not in the paper) is best everywhere; among the paper's estimators MRU beats CSM without
    # noise and CSM beats MRU with noise, which is the paper's claim 20
    gains = {"csm:R2": 0.2, "csm:R3": 0.2, "mru:R2": 3.0, "mru:R3": 4.0, "jet:R2": 0.0}
    an = Analysis(synthetic(VARIANTS, 3, noise_gain=gains), settings(3, tuple(VARIANTS)))
    assert "jet" in an.methods() and "jet" not in an.paper().methods()
    verdict = check(_claim("mru-vs-csm"), an)
    assert verdict.status is Status.AGREES, verdict.measured
    assert "JET" not in check(_claim("noise-csm-mru"), an).measured


def test_claim_verdict_follows_the_data():
    # MRU worse than CSM without noise: claim 20 can no longer agree
    flipped = {**VARIANTS, "mru:R2": 0.09, "mru:R3": 0.09}
    an = Analysis(synthetic(flipped, 3, noise_gain={"mru:R2": 0.0, "mru:R3": 0.0}), settings(3, tuple(flipped)))
    assert check(_claim("mru-vs-csm"), an).status is not Status.AGREES


def test_stability_is_one_for_a_clear_difference_and_lower_for_a_coin_flip():
    rng = np.random.default_rng(5)
    t = synthetic({"csm:R2": 0.05, "mru:R2": 0.05}, 30, spread=0.0)
    # make the two estimators differ by pure per-sample noise around the same mean
    vals = np.asarray(t["rms_erel"], float) * (1 + 0.5 * rng.standard_normal(len(t)))
    t.columns["rms_erel"] = vals
    an = Analysis(t, settings(30, ("csm:R2", "mru:R2")))
    assert stability(an, lambda a: a.err("csm:R2") > 0) == 1.0
    coin = stability(an, lambda a: a.err("csm:R2") < a.err("mru:R2"))
    assert 0.2 < coin < 0.98


def test_report_has_intervals_stability_and_the_early_verdicts():
    an_vars = tuple(VARIANTS)
    text = report_markdown(synthetic(VARIANTS, 4), settings(4, an_vars))
    assert "95% percentile bootstrap over the 4 random surface draws" in text
    assert "| # | claim | verdict | stability | N=2 |" in text
    assert "Best estimator per setting" in text and "JET (R2)" in text
    assert "Estimators marked * are beyond the paper" in text
    assert "% [" in text  # Table 1 cells carry intervals


def test_a_study_without_results_reports_no_noise_level():
    """An empty results table (a study stopped before its first task) has no noise levels: the
    highest level reads 0, nothing noisy is claimed, and the report is still written."""
    an = Analysis(Table.from_rows([]), settings(2, tuple(VARIANTS)))
    assert an.noise_levels == [] and an.noise_max == 0.0
    noisy = [v for c, v in check_all(an) if c.id in {"noise-csm-mru", "mru-vs-csm"}]
    assert len(noisy) == 2 and all(v.status is Status.NOT_TESTED and v.measured == "needs noisy meshes" for v in noisy)
    text = report_markdown(Table.from_rows([]), settings(2, tuple(VARIANTS)))
    assert text.startswith("# curvlab study report") and "@ noise 100%" not in text
