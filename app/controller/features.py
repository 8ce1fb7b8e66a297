"""What an estimate worker runs: ``curv.iter_estimate`` with the feature angle turned into the
document's remembered feature-edge mask (computed in the worker the first time)."""

from __future__ import annotations

__all__ = ["estimate_with_masks"]


def estimate_with_masks(iterate, masks, mesh, method: str, *, features=None, **kwargs):
    """``yield from iterate(mesh, method, features=mask, **kwargs)``; returns its Curvature.

    Parameters
    ----------
    iterate : callable
        ``curv.iter_estimate`` (the controller passes the one it holds).
    masks : app.model.features.FeatureMasks
        Where the mask of ``features`` degrees is remembered (the same mask
        :func:`curv.features.feature_edges` gives, so the result equals ``features=angle``'s).
    features : float or None
        The feature angle in degrees; ``info["features"]`` of the result names it.
    """
    if features is None:
        return (yield from iterate(mesh, method, **kwargs))
    result = yield from iterate(mesh, method, features=masks.mask(mesh, features), **kwargs)
    result.info["features"] = float(features)
    return result
