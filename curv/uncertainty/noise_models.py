"""How the standard errors of ``an`` and ``mru`` take the errors of the neighbours' normals they read.

:data:`NOISE_MODELS` names the choices (``curv.estimate(..., noise_model=...)``); the ``"normals"``
model itself is :mod:`curv.uncertainty.normals_model`, and ``"sampled"`` measures its effect at a
sample of the vertices (:func:`sampled_scales`).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ..core.errors import EstimatorError
from ..core.validity import OK
from .parts import Errors

__all__ = ["NOISE_MODELS", "DEFAULT_NOISE_MODEL", "checked_noise_model", "SAMPLE_SIZE", "SAMPLE_RUN", "sampled_scales"]

NOISE_MODELS = ("sampled", "independent", "normals")
"""How the standard errors of ``an`` and ``mru`` (the fits that read the neighbours' normals) take
the errors of those normals (the curvatures do not depend on it):

- ``"sampled"`` (the default): the ``"normals"`` model's effect measured at a sample of the mesh's
  vertices (:data:`SAMPLE_SIZE`, evenly spaced) and applied to every vertex: each vertex's
  independent-equation propagation is scaled by the median, over the sample, of the ratio of the
  two models' ``var(k_i) / E[RSS]`` (:func:`sampled_scales`), and the noise level is pooled over the
  vertex and its edge neighbours. Within a few percent of ``"normals"`` on the noisy study meshes
  (regular and irregular) at about the independent model's cost. One factor for the whole mesh (or
  region): where the mesh's regularity changes from place to place, the vertices unlike the sample's
  majority get the majority's factor. A point cloud keeps the independent model.
- ``"independent"``: every equation's error independent, the noise level read from the vertex's own
  residuals (with the tilt of its own normal as two more unknowns). Where the normals are made from
  noisy vertex positions, as a mesh's are, neighbouring normals share faces and their errors are
  correlated, so ``± 2 se`` holds less than the nominal 95 % (docs/UNCERTAINTY.md gives the figures).
- ``"normals"``: the errors as the normals take them from independent height noise (each vertex
  normal tilts by the least-squares height gradient of its ring), followed exactly through the fit
  and pooled over the vertex's edge neighbours, at every vertex (:mod:`curv.uncertainty.normals_model`);
  calibrated on noisy meshes with their default normals, and 3-5 times the whole call's time (it
  visits every neighbour's ring: docs/UNCERTAINTY.md, Cost, says where the time goes). A point
  cloud, or a ring without a gradient, keeps the independent model."""

DEFAULT_NOISE_MODEL = NOISE_MODELS[0]


def checked_noise_model(noise_model: str) -> str:
    """``noise_model`` if it is one of :data:`NOISE_MODELS`; else an
    :class:`~curv.core.errors.EstimatorError` naming the choices."""
    if noise_model not in NOISE_MODELS:
        raise EstimatorError(f"noise_model must be one of {', '.join(NOISE_MODELS)}; got {noise_model!r}")
    return noise_model


SAMPLE_SIZE = 2000
"""Vertices at which ``noise_model="sampled"`` runs the normals' model (:func:`sampled_scales`)."""
SAMPLE_RUN = 125
"""... in runs of this many consecutive vertices (16 runs)."""


def sampled_scales(run_normals: Callable[[np.ndarray], None], fitted: np.ndarray, reason: np.ndarray,
                   errors: Errors) -> np.ndarray | None:
    """The factors by which the normals' model scales the independent model's standard errors,
    measured at a sample of the fitted vertices (``noise_model="sampled"``).

    Both models read the noise level from the same residuals, so at a vertex the ratio of their
    ``var(k_i) / E[RSS]`` (propagation per unit noise variance over the spare equations it expects)
    is the factor between their squared standard errors, free of the noise's units. The fit runs
    again with the normals' model at up to :data:`SAMPLE_SIZE` vertices (all of ``fitted`` or runs
    of :data:`SAMPLE_RUN` consecutive ones, evenly spaced); the factors are the medians over the
    sample where both models hold.

    Parameters
    ----------
    run_normals : callable
        ``run_normals(sample)`` fits the vertices ``sample`` with the normals' model, writing their
        rows of ``errors`` (and the same curvatures).
    fitted : (c,) int64
        The vertices the independent model's run fitted.
    reason : (n,) uint8
        Their reasons.
    errors : Errors
        After the independent model's run: ``k1_se``, ``k2_se`` hold ``var(k_i) / sigma²``, every
        fitted vertex is ``alone`` (its noise level in units of the normals).

    Returns
    -------
    (3,) float64 or None
        The factors of ``var(k1)``, ``var(k2)`` and the deviator's variance; None when no sampled
        vertex holds both models. The rows of the sample are left as the independent run wrote them.
    """
    if fitted.size <= SAMPLE_SIZE:
        sample = fitted
    else:
        # runs of consecutive vertices, evenly spaced: a run's supports share the pages of the
        # fresh scratch (single vertices spread over the mesh cost a page fault each)
        starts = np.linspace(0, fitted.size - SAMPLE_RUN, SAMPLE_SIZE // SAMPLE_RUN).astype(np.int64)
        sample = fitted[(starts[:, None] + np.arange(SAMPLE_RUN)).ravel()]
    parts = errors.parts
    sample = sample[(reason[sample] == OK) & errors.alone[sample] & (parts[sample, 1] > 0.0)]
    if sample.size == 0:
        return None
    kept = errors.k1_se[sample], errors.k2_se[sample], parts[sample], errors.alone[sample]
    run_normals(sample)
    exact = ~errors.alone[sample] & (parts[sample, 1] > 0.0)  # the normals' model held
    with np.errstate(divide="ignore", invalid="ignore"):
        per_spare_exact = np.stack([errors.k1_se[sample], errors.k2_se[sample], parts[sample, 2]]) / parts[sample, 1]
        per_spare_indep = np.stack([kept[0], kept[1], kept[2][:, 2]]) / kept[2][:, 1]
        ratio = per_spare_exact[:, exact] / per_spare_indep[:, exact]
    errors.k1_se[sample], errors.k2_se[sample], parts[sample], errors.alone[sample] = kept
    ratio = ratio[:, np.all(np.isfinite(ratio) & (ratio > 0.0), axis=0)]
    if ratio.shape[1] == 0:
        return None
    return np.median(ratio, axis=1)
