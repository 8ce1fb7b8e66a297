"""Confidence intervals by resampling the random surfaces (the paper reports none).

The unit of resampling is one random surface draw ``(seed, sample)``: with the study's common
random numbers, one draw fixes the surface at every density, irregularity and noise level, so
the settings of one draw are correlated and must stay together. A bootstrap resample draws N
draws with replacement and recomputes any statistic of an :class:`~curv.study.analysis.Analysis`
with those counts as weights (:meth:`Analysis.resampled`); nothing is recomputed on meshes.

>>> lo, hi = interval(an, lambda a: a.err("mru:R2", noise=0.0))        # doctest: +SKIP
>>> stability(an, lambda a: a.err("csm:R2") < a.err("mru:R2"))           # doctest: +SKIP
0.97
"""

from __future__ import annotations

import warnings
from typing import Callable, Iterator

import numpy as np

from .analysis import Analysis

__all__ = ["N_BOOT", "LEVEL", "resamples", "replicates", "interval", "stability"]

N_BOOT = 200
"""Bootstrap resamples of the report: percentile intervals at 95 % are stable to about a
percent of their width at this count, and the whole report's resampling takes seconds."""

LEVEL = 0.95
"""Confidence level of every interval in the report."""


def resamples(an: Analysis, n_boot: int = N_BOOT, seed: int = 0) -> Iterator[Analysis]:
    """``n_boot`` bootstrap resamples of ``an``'s random surface draws (those of non-zero weight).

    Parameters
    ----------
    an : Analysis
    n_boot : int
    seed : int
        Seed of the resampling stream (fixed, so that a report is reproducible).

    Yields
    ------
    Analysis
        ``an`` with the draw counts of one resample as weights.
    """
    base = np.ones(an.cube.n_units) if an.weights is None else np.asarray(an.weights, float)
    active = np.flatnonzero(base > 0)
    rng = np.random.default_rng([seed, 7011])
    for _ in range(n_boot):
        counts = np.bincount(rng.integers(0, active.size, active.size), minlength=active.size)
        w = np.zeros_like(base)
        w[active] = counts
        yield an.resampled(w)


def replicates(an: Analysis, statistic: Callable[[Analysis], object], n_boot: int = N_BOOT,
               seed: int = 0) -> np.ndarray:
    """(n_boot, ...) float64: ``statistic`` (a number or an array) on each resample."""
    return np.array([np.asarray(statistic(a), float) for a in resamples(an, n_boot, seed)])


def interval(an: Analysis, statistic: Callable[[Analysis], object], *, n_boot: int = N_BOOT,
             level: float = LEVEL, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """Percentile bootstrap interval of ``statistic``.

    Returns
    -------
    lo, hi : float64 arrays of the statistic's shape
        NaN where fewer than half of the resamples give a finite value.
    """
    reps = replicates(an, statistic, n_boot, seed)
    alpha = (1.0 - level) / 2.0
    finite = np.isfinite(reps)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns are handled below
        lo = np.nanquantile(reps, alpha, axis=0)
        hi = np.nanquantile(reps, 1.0 - alpha, axis=0)
    enough = finite.sum(axis=0) >= n_boot / 2
    return np.where(enough, lo, np.nan), np.where(enough, hi, np.nan)


def stability(an: Analysis, outcome: Callable[[Analysis], object], *, n_boot: int = N_BOOT,
              seed: int = 0) -> float:
    """Share of resamples on which ``outcome`` equals its value on the full data (e.g. a verdict)."""
    ref = outcome(an)
    same = sum(outcome(a) == ref for a in resamples(an, n_boot, seed))
    return same / n_boot
