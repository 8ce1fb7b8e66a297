"""An estimator reads the fits of a point cloud's normals' pass instead of searching and fitting again.

A cloud's jet normals (:mod:`curv.point_normals`, the one pass) hold each point's ball at the
normals' range. An estimator whose fit at that range is the pass's own fit (the ``jet``,
:mod:`curv.estimators._jet_handover`) or a fit the pass can make on the support it holds (``qs``,
in the frame of the fitted normal: :mod:`curv.estimators.qs`) has the pass keep, per point, what
it needs to finish, and finishes from it: no second search, no second fit. This module owns the
flow; each such estimator owns its fits' layout and registers it (:func:`register_handover`):

- :class:`NormalFits`: what an estimator reads (the registry's ``reads_normal_fits`` returns it):
  ``options``, the fit's identity (an estimate reads kept fits only of its own options), and
  ``new(radii)``, the empty bundle a pass fills;
- the bundle: a namedtuple of arrays whose first field ``radii`` (n,) is the pass's radius per
  point (a point of another radius is fitted as before);
- :class:`Handover` of the bundle's class: ``keep(fits, p, i, fit, support, coords, fitted)``, run
  by the pass per point after its jet fit (``p`` the point, ``i`` its position in the pass's grid
  order, ``fit = (code, h, referenced, scratch)`` the jet fit's outcome and
  :func:`~curv.estimators._jet_fit.jet_scratch`, ``support = (sub, count)`` the fit's support in
  grid positions, centre first, ``coords = (x, y, z)`` in grid order, ``fitted`` (n, 3) the jet
  normals so far); ``handed(fits, p, normals, scratch, out)``, which writes row p of ``out``
  (:class:`~curv.estimators._principal.Rows`) as the estimator's own fit with the reference
  ``normals[p]`` would, or returns False (nothing written: a fit must tell); ``scratch(fits)``, a
  thread's scratch of ``handed``.

The pass's fits go with the cloud (:func:`keep_for`, the latest pass's); :func:`kept_fits` answers
an estimator with fits of its options. :func:`iter_handed` runs the hand-over over an estimate's
centres and returns those a fit must tell.
"""

from __future__ import annotations

import weakref
from collections import namedtuple

import numpy as np
from numba.extending import overload

from ..core.jit import JIT_OPTIONS, iter_chunks, jit_parallel, launch, prange, slice_bounds, threads

__all__ = ["NormalFits", "Handover", "Kept", "register_handover", "keep_fit", "handed_fit", "keep_for", "kept_fits",
           "forget_fits", "iter_handed"]

NormalFits = namedtuple("NormalFits", ["options", "new", "bytes_per_point"])
"""What an estimator reads of the normals' pass (module notes): its fits' identity (hashable),
``new(radii)`` the bundle for a pass to fill, and the bundle's bytes per point (the estimator's
``extra_bytes_per_point`` in :mod:`curv.memory`'s model)."""

Handover = namedtuple("Handover", ["keep", "handed", "scratch"])
"""A bundle class's ``@jit`` functions (module notes)."""

Kept = namedtuple("Kept", ["fits", "options"])
"""The fits a pass kept: the filled bundle and the :attr:`NormalFits.options` it was made for."""

_HANDOVERS: dict = {}
_KEPT: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def register_handover(bundle: type, handover: Handover) -> None:
    """Run ``handover`` for the fits bundles of class ``bundle`` (a namedtuple class, ``radii`` first)."""
    _HANDOVERS[bundle] = handover


def keep_fit(fits, p, i, fit, support, coords, fitted):
    """The bundle's ``keep`` (:class:`Handover`), chosen by the type of ``fits`` inside numba code."""
    raise NotImplementedError("called from numba code only")


def handed_fit(fits, p, normals, scratch, out):
    """The bundle's ``handed`` (:class:`Handover`), inside numba code."""
    raise NotImplementedError("called from numba code only")


def handed_scratch(fits):
    """The bundle's ``scratch`` (:class:`Handover`), inside numba code."""
    raise NotImplementedError("called from numba code only")


@overload(keep_fit, jit_options=JIT_OPTIONS)
def _keep_fit(fits, p, i, fit, support, coords, fitted):
    keep = _HANDOVERS[fits.instance_class].keep
    return lambda fits, p, i, fit, support, coords, fitted: keep(fits, p, i, fit, support, coords, fitted)


@overload(handed_fit, jit_options=JIT_OPTIONS)
def _handed_fit(fits, p, normals, scratch, out):
    handed = _HANDOVERS[fits.instance_class].handed
    return lambda fits, p, normals, scratch, out: handed(fits, p, normals, scratch, out)


@overload(handed_scratch, jit_options=JIT_OPTIONS)
def _handed_scratch(fits):
    make = _HANDOVERS[fits.instance_class].scratch
    return lambda fits: make(fits)


@jit_parallel
def _handed_kernel(fits, chunk, radii, normals, out, refit, parts):
    """Rows ``centres[lo:hi]`` of ``out`` (``chunk = (centres, lo, hi)``) from the kept ``fits`` where
    the radius is the pass's and the hand-over answers; ``refit[p]`` True where a fit must tell."""
    centres, lo, hi = chunk
    for t in prange(parts):
        scratch = handed_scratch(fits)
        start, stop = slice_bounds(lo, hi, t, parts)
        for c in range(start, stop):
            p = centres[c]
            refit[p] = not (radii[p] == fits.radii[p] and handed_fit(fits, p, normals, scratch, out))


def keep_for(cloud, kept: Kept) -> None:
    """Keep a pass's fits with ``cloud`` (the latest pass's; they go with the cloud)."""
    _KEPT[cloud] = kept


def kept_fits(cloud, options):
    """The fits bundle a pass kept with ``cloud`` when it was made for ``options``
    (:attr:`NormalFits.options`), else None."""
    try:
        kept = _KEPT.get(cloud)
    except TypeError:  # an input that cannot be referenced weakly keeps nothing
        return None
    if kept is None or kept.options != options:
        return None
    return kept.fits


def forget_fits(cloud) -> None:
    """Drop the fits kept with ``cloud`` (its estimates fit every point again)."""
    _KEPT.pop(cloud, None)


def iter_handed(fits, normals: np.ndarray, radii: np.ndarray, centres: np.ndarray, out, *,
                chunk: int | None = None):
    """Rows ``centres`` of ``out`` from the kept fits, a generator (yields the fraction done).

    Parameters
    ----------
    fits : namedtuple
        A kept bundle (:func:`kept_fits`).
    normals : (n, 3) float64
        The estimator's reference normals (any layout).
    radii : (n,) float64
        The estimator's radii.
    centres : (c,) int64
    out : Rows

    Returns
    -------
    (r,) int64
        The centres still to fit (their rows unset), in the order of ``centres``.
    """
    refit = np.zeros(fits.radii.shape[0], np.bool_)
    parts = max(1, min(threads(), centres.size))
    radius = np.asarray(radii, np.float64)
    normals = np.asarray(normals, np.float64)

    def run(lo: int, hi: int) -> None:
        launch(_handed_kernel, fits, (centres, lo, hi), radius, normals, out, refit, parts)

    yield from iter_chunks(centres.size, run, chunk=chunk)
    return centres[refit[centres]]
