"""Helpers shared by the study tests: what 'identical results' means."""

from __future__ import annotations

import numpy as np

METRIC_COLUMNS_COMPARED = (
    "variant", "n_vertices", "irregularity_achieved", "mean_edge", "noise_sigma", "n_evaluated", "n_invalid",
    "n_kept", "excluded_share", "rms_erel", "median_erel", "mean_eabs", "rms_eabs", "rms_h", "nrms_h",
    "rms_k", "nrms_k", "error",
)
"""Every column but the timings."""


def canonical(table) -> dict:
    t = table.sorted(["function", "density", "irregularity", "noise", "sample", "variant"])
    return {c: t[c] for c in METRIC_COLUMNS_COMPARED}


def assert_same_results(a, b) -> None:
    """Bit-identical results, whatever order the rows were written in."""
    ca, cb = canonical(a), canonical(b)
    for c in METRIC_COLUMNS_COMPARED:
        if ca[c].dtype == object:
            assert ca[c].tolist() == cb[c].tolist(), c
        else:
            assert np.array_equal(ca[c], cb[c], equal_nan=True), c
