"""The paper's conclusions (§5.3 and §6) as checks against measured data.

Each claim is a function of an :class:`~curv.study.analysis.Analysis` returning a :class:`Verdict`:
``agrees``, ``partly``, ``disagrees`` or ``not tested`` (the grid lacks what the claim needs), with
the measured numbers that decided it. The thresholds are stated in each claim's ``test`` text so a
reader can judge them.
"""

from __future__ import annotations

from . import conclusion_claims as conclusions, factor_claims as factors
from .analysis import Analysis
from .verdicts import Claim, Status, Verdict

__all__ = ["Status", "Verdict", "Claim", "CLAIMS", "check", "check_all"]

CLAIMS: tuple[Claim, ...] = (
    Claim("irregularity", "§5.3, Tab. 1", "The error of most estimators increases with irregularity.",
          "every R1–R3 variant, no noise: error at 0° < 14° < 25°; agrees if ≥ 2/3 of the variants", factors.irregularity_rises),
    Claim("csm-robust", "§5.3, Tab. 1", "CSM is significantly more robust against irregular triangulations than the other estimators.",
          "in each range group R1–R3, CSM has the smallest error increase at the highest irregularity", factors.csm_most_robust),
    Claim("range-robust", "§5.3, Tab. 1", "With a larger range the degradation with irregularity is reduced.",
          "median (over estimators) increase at the highest irregularity falls from R1 to R2 to R3 (to R4)", factors.range_reduces_degradation),
    Claim("csm-r1-dip", "§5.3, Tab. 1", "CSM (R1) is more accurate on slightly irregular (14°) than on regular meshes.",
          "CSM (R1) error at 14° below its 0° error", factors.csm_r1_dips),
    Claim("functions", "§5.3", "Averaged over all estimators, the elliptic function gives the best results, followed by the trigonometric one.",
          "mean error over all plain variants and settings: ellipsoid_patch < trigonometric < quadratic", factors.function_order),
    Claim("noise-up", "§5.3", "The error increases with noise.",
          "each plain variant's error rises at each noise step; agrees if ≥ 90% of variants", factors.noise_increases),
    Claim("noise-linear", "§5.3", "Between 33% and 100% noise the error grows linearly.",
          "the 66% error lies within 15% (of the 33→100% rise) of the straight line, for ≥ 2/3 of variants", factors.noise_linear),
    Claim("coarse-small-range", "§5.3, Fig. 8", "On the coarsest mesh (217 vertices), ranges R1 and R2 are the most accurate.",
          "for every estimator with three or more ranges, its best range at 217 vertices (no noise) is R1 or R2", factors.coarse_small_ranges),
    Claim("dense-r4", "§5.3, Fig. 8", "On the densest mesh (12481 vertices), R4 greatly reduces the error.",
          "for every estimator with R4, R4 is its best range at 12481 vertices (no noise)", factors.dense_r4),
    Claim("range-density", "§5.3, Fig. 8", "817 vertices are best processed with R2; denser meshes get better results with larger ranges.",
          "best range at 817 vertices is R2, and the best range does not decrease with density (no noise)", factors.range_follows_density),
    Claim("an-vs-r1", "§5.3, Fig. 8", "AN (R2) outperforms QS (R1) and NC (R1) at every density.",
          "no noise, per density: AN (R2) < QS (R1) and AN (R2) < NC (R1)", factors.an_beats_r1),
    Claim("nc-equal-range", "§5.3, Fig. 8", "At equal ranges, NC often performs better (than QS and AN).",
          "no noise, per range R2–R4 and density: NC below both QS and AN in at least half the cases", factors.nc_equal_range),
    Claim("ru-dense-irregular", "§5.3, Fig. 8", "RU's advantage is reproduced on dense irregular meshes; on regular coarse meshes an R1 estimator is better.",
          "densest mesh at the highest irregularity: RU < best R1; coarsest mesh at 0°: best R1 < RU (no noise)", factors.ru_dense_irregular),
    Claim("noise-csm-mru", "§5.3, Fig. 9", "With noise, CSM (R2–R4) handles noise best, MRU (R3, R4) second.",
          "at the highest noise, CSM has the lowest error in each of R2–R4 and MRU the second lowest at R3 and R4", factors.noise_csm_then_mru),
    Claim("r3-vs-smoothing", "§5.3, Fig. 10", "R3 estimators are useful mainly without noise; with noise, smoothing looks better.",
          "at the Fig. 10 density: R3 < min(R2SM, R2SV) without noise and min(R2SM, R2SV) < R3 with noise, for ≥ 2/3 of the estimators", factors.r3_vs_smoothing),
    Claim("smooth-mesh-first", "§6", "Smoothing the noisy mesh gives better results than smoothing the curvature values afterwards.",
          "at the Fig. 10 density and highest noise: R2SM < R2SV for ≥ 2/3 of the estimators", conclusions.mesh_beats_values),
    Claim("range-not-smoothing", "§6", "Increasing the estimation range produces different results than smoothing.",
          "the R3 error and the R2SM/R2SV errors differ by more than 10% in ≥ 2/3 of the cases", conclusions.range_differs_from_smoothing),
    Claim("range-noise", "§6", "A larger range improves robustness against noise.",
          "at the highest noise, every estimator's error falls with each range step", conclusions.larger_range_noise),
    Claim("ru-mru-irregular", "§6", "Without noise, RU and MRU perform best also on irregular meshes; on regular meshes the Goldfeather–Interrante estimators do very well too.",
          "no noise, highest irregularity: the best variant of each range R2–R4 is RU or MRU (the 0° ratio of the best G&I variant is shown)", conclusions.ru_mru_best_irregular),
    Claim("mru-vs-csm", "§6", "MRU gives better results than CSM, but only for meshes without noise.",
          "per range R2–R4: MRU < CSM without noise and CSM < MRU at the highest noise", conclusions.mru_vs_csm),
    Claim("mru-range", "§6", "MRU has a higher accuracy on larger estimation ranges (than the original RU).",
          "no noise: MRU (R3) and MRU (R4) below RU (R2)", conclusions.mru_larger_range),
    Claim("mru-fast", "§6", "MRU is faster than all other estimators with a comparable range.",
          "at the densest mesh, MRU has the lowest mean time in each range group it belongs to (our implementations, not the paper's)", conclusions.runtime),
)
"""The checked statements, in the order of the paper; their checks are §5.3's
(:mod:`curv.study.factor_claims`) and §6's (:mod:`curv.study.conclusion_claims`)."""


def check(claim: Claim, an: Analysis) -> Verdict:
    """One claim on the paper's estimators of ``an``; a check that fails on odd data is reported,
    not raised."""
    try:
        return claim.check(an.paper())
    except (ValueError, KeyError, ZeroDivisionError) as exc:
        return Verdict(Status.NOT_TESTED, f"could not be evaluated: {exc}")


def check_all(an: Analysis) -> list[tuple[Claim, Verdict]]:
    """Check every claim. The claims are the paper's statements about its own estimators, so
    estimators beyond the paper (``in_paper=False``) are left out of every comparison."""
    return [(claim, check(claim, an)) for claim in CLAIMS]
