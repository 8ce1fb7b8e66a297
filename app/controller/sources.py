"""Turning a document source into a mesh (and its exact curvature for analytic surfaces)."""

from __future__ import annotations

import curv

from app.model.sources import FileSource, SurfaceSource

__all__ = ["load_source"]


def load_source(source):
    """Load or mesh ``source``; runs in a worker thread.

    Parameters
    ----------
    source : FileSource or SurfaceSource

    Returns
    -------
    (source, mesh, truth)
        ``truth`` is the exact :class:`curv.Curvature` of an analytic surface, else None.

    Raises
    ------
    curv.CurvError or ValueError
        With a one-line message (unreadable file, bad parameters, ...).
    """
    if isinstance(source, FileSource):
        # STL stores every triangle with its own corners: merge them, or nothing is connected
        merge = source.path.lower().endswith(".stl")
        return source, curv.load(source.path, merge_vertices=merge), None
    if isinstance(source, SurfaceSource):
        sampled = curv.surfaces.make_surface(
            source.name, n_vertices=source.n_vertices, irregularity=source.irregularity,
            noise=source.noise, seed=source.seed, random_params=source.random_params, **source.params)
        return source, sampled.mesh, sampled.truth
    raise TypeError(f"unknown source {source!r}")
