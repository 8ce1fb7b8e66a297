"""Error measures of the study (paper §5.1, eq. 5.2) and their per-mesh summary.

For vertex i with exact principal curvatures ``k1 >= k2`` and estimates ``k̂1 >= k̂2``:

- ``e_abs = |k1 - k̂1| + |k2 - k̂2|``
- ``e_rel = e_abs / (|k1| + |k2|)`` (eq. 5.2)

The paper reports the RMS of ``e_rel`` over the vertices with ``e_rel < 1`` ("outliers would
significantly change the result without much practical meaning"). That RMS is blind to how many
vertices were dropped, and on noisy meshes it saturates near 1 while more and more vertices fall
out, so every summary also carries the excluded share and the median of ``e_rel`` over *all*
evaluated vertices, which needs no exclusion. Errors of the mean curvature H and the Gaussian
curvature K are summarised as RMS of the absolute error, and normalised by the curvature scale
``c = (|k1| + |k2|) / 2`` of eq. 5.2's denominator: ``nrms_h = RMS(Ĥ - H) / RMS(c)`` and
``nrms_k = RMS(K̂ - K) / RMS(c²)``. Normalising by RMS(H) or RMS(K) instead would explode on
near-developable patches (a cylinder-like ellipsoid patch has K ≈ 0 but is far from flat).
"""

from __future__ import annotations

import numpy as np

from ..metrics import absolute_error, relative_error
from ..core.quantities import compute

__all__ = ["absolute_error", "relative_error", "summarize", "METRIC_COLUMNS"]

METRIC_COLUMNS: tuple[str, ...] = (
    "n_evaluated", "n_invalid", "n_kept", "excluded_share", "rms_erel", "median_erel", "mean_eabs",
    "rms_eabs", "rms_h", "nrms_h", "rms_k", "nrms_k",
)
"""Keys of :func:`summarize`'s result, in table order."""


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(x)))) if x.size else float("nan")


def summarize(truth, estimate, evaluated: np.ndarray) -> dict[str, float]:
    """Summarise the error of one estimate on one mesh.

    Parameters
    ----------
    truth, estimate : Curvature
        Exact and estimated curvature (only ``k1``, ``k2``, ``valid`` are used; ``truth`` must
        be valid at the evaluated vertices).
    evaluated : (n,) bool
        The vertices the study evaluates (no border vertex within R4).

    Returns
    -------
    dict
        ``n_evaluated``: evaluated vertices; ``n_invalid``: of those, vertices the estimator marked
        invalid (left out of every measure below); ``n_kept``: valid vertices with ``e_rel < 1``;
        ``excluded_share``: share of valid vertices with ``e_rel >= 1``; ``rms_erel``: RMS of
        ``e_rel`` over the kept vertices (the paper's measure); ``median_erel``: median of ``e_rel``
        over all valid vertices; ``mean_eabs``, ``rms_eabs``: of ``e_abs`` over all valid vertices;
        ``rms_h``, ``rms_k``: RMS error of H and K over valid vertices; ``nrms_h``, ``nrms_k``: the
        same divided by RMS(c) and RMS(c²), ``c = (|k1| + |k2|) / 2``. Measures over no vertex are NaN.
    """
    evaluated = np.asarray(evaluated, bool)
    use = evaluated & np.asarray(estimate.valid, bool)
    k1, k2 = truth.k1[use], truth.k2[use]
    e1, e2 = estimate.k1[use], estimate.k2[use]
    e_rel = relative_error(k1, k2, e1, e2)
    e_abs = absolute_error(k1, k2, e1, e2)
    kept = e_rel < 1.0
    h, h_hat = compute("mean", k1, k2), compute("mean", e1, e2)
    g, g_hat = compute("gaussian", k1, k2), compute("gaussian", e1, e2)
    n_valid = int(use.sum())
    rms_h, rms_k = _rms(h_hat - h), _rms(g_hat - g)
    scale = 0.5 * (np.abs(k1) + np.abs(k2))
    ref_h, ref_k = _rms(scale), _rms(scale**2)
    return {
        "n_evaluated": int(evaluated.sum()),
        "n_invalid": int((evaluated & ~use).sum()),
        "n_kept": int(kept.sum()),
        "excluded_share": float(1.0 - kept.mean()) if n_valid else float("nan"),
        "rms_erel": _rms(e_rel[kept]),
        "median_erel": float(np.median(e_rel)) if n_valid else float("nan"),
        "mean_eabs": float(e_abs.mean()) if n_valid else float("nan"),
        "rms_eabs": _rms(e_abs),
        "rms_h": rms_h,
        "nrms_h": rms_h / ref_h if ref_h > 0 else float("nan"),
        "rms_k": rms_k,
        "nrms_k": rms_k / ref_k if ref_k > 0 else float("nan"),
    }
