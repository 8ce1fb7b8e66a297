"""The estimator registry: every estimator family registers its spec here.

The CLI, the viewer, the study and the warm-up list estimators from :data:`ESTIMATORS`; adding an
estimator is one module ending in one ``register(EstimatorSpec(...))`` call (a fit's: ``register(fit_spec(...))``),
imported by :mod:`curv.estimators` (docs/ARCHITECTURE.md, "A new estimator is one module plus one
registry entry").
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable, Generator

from ..core.errors import EstimatorError
from ..core.support import support_of
from ..core.result import Principal

__all__ = ["EstimatorSpec", "ESTIMATORS", "DEFAULT_ESTIMATOR", "DEFAULT_ESTIMATORS", "default_estimator", "input_kind",
           "register", "get_spec", "EstimatorFunction",
           "SHARED_PASSES", "SharedPass", "register_pass", "PASS_KERNELS",
           "polygon_estimators", "point_estimators", "refusal"]

DEFAULT_ESTIMATORS = {"mesh": "mru", "points": "jet"}
"""The estimator used when none is named, per input kind (:func:`input_kind`); the API and the command
line ask :func:`default_estimator`. On a mesh the paper's own method. On a point cloud one of the
two the README tells scan users to prefer (``qs``, ``jet``): ``mru``, which errs least on many
smooth clouds (cylinders, tori, noisy patches), keeps about a tenth of the points of scan rows 4:1
apart and gives wrong values marked valid there at R3-R4. Of the two, at the default R2 without normals
(``benchmarks/bench_points_default.py``) ``jet`` errs about 0.55x as much as ``qs`` on noisy
clouds (0.05 spacings) and about 1.3x on clean Monge patches, where both are below 1 %."""

DEFAULT_ESTIMATOR = DEFAULT_ESTIMATORS["mesh"]
"""The default estimator on a mesh (:data:`DEFAULT_ESTIMATORS`)."""

EstimatorFunction = Callable[..., Generator[float, None, "Principal | list[Principal]"]]
"""``fn(mesh, normals, radii, *, chunk, centres, features, **options) -> Generator[fraction done, None, Principal]``.

``mesh`` a :class:`curv.Mesh` (or a :class:`curv.PointCloud` for a spec with ``takes_points``);
``normals`` (n, 3) is None only for a spec with ``computes_normals``; ``radii`` (n,) float64 is the
ball radius every vertex collects its support in (:func:`curv.core.ranges.ball_radii`), None for an
estimator without a support (``has_support=False``), or (levels, n) ascending per vertex for a spec
with ``takes_levels``, which then returns a list of one :class:`Principal` per level; ``chunk``
fixes the vertices per kernel call (default adaptive, :func:`curv.core.jit.iter_chunks`);
``centres`` (c,) int64 the vertices to estimate (None: all; a whole point cloud passes every point
in its grid's order), whose rows alone it must write; ``features`` a
:class:`curv.core.features.FeatureSet` on a mesh with creases, else None; ``options`` the spec's
own ``options`` and, for a spec with ``skips_errors``, ``standard_errors``."""


@dataclass(frozen=True)
class EstimatorSpec:
    """Description of one estimator family.

    Attributes
    ----------
    name : str
        Registry key, e.g. ``"mru"``.
    title : str
        Human-readable name.
    ranges : tuple of int
        The ranges k of Rk it supports.
    function : EstimatorFunction
        The generator computing it.
    triangles_only : bool
        Needs a triangle mesh.
    uses_normals : bool
        Uses the neighbours' vertex normals, so its support at Rk is collected within
        ``(k - 1)`` times the longest 1-ring edge.
    closed_ring : bool
        Assumes a closed 1-ring: border-affected vertices are invalid.
    reference : str
        Where the method comes from.
    summary : str
        One line on what it does.
    has_support : bool
        Collects a range support (any real range >= its smallest named one, or a radius). False for
        the fixed 1-ring formulas (``meyer``, ``ru``), which take only their one named range.
    options : dict
        Estimator-specific keyword options ``{name: allowed values}`` (e.g. the jet's
        ``{"degree": (2, 3, 4)}``), passed through by :func:`curv.estimate`.
    in_paper : bool
        One of the paper's seven estimators (its 20 variants are the study's core; the others run
        as extra rows beside them).
    kernels : tuple
        The numba dispatchers the estimator calls, so that a caller can announce a first-run
        compilation (:func:`curv.core.jit.compile_pending`).
    computes_normals : bool
        Can compute the default (Max-weighted) vertex normals in its own pass over the mesh: called
        with ``normals=None`` it returns them in :attr:`Principal.normals`, already NaN at
        :func:`curv.geometry.normals.unusable_normal_vertices`, saving a separate pass.
    min_neighbours : int or callable
        Fewest support vertices (the centre excluded) a vertex needs, else ``TOO_FEW_NEIGHBOURS``:
        the fit's unknowns, or a function of the estimator options giving it (the jet's degree);
        0 for the estimators without a fit. Read through :meth:`fewest_neighbours` (the advisor
        counts the vertices a candidate can estimate with it).
    extra_bytes_per_unit : float
        Peak memory beyond the common per-vertex arrays, in bytes per size unit (vertices + faces / 2):
        whole-mesh per-edge and per-face arrays and stamps (``csm``, ``icc``); :mod:`curv.memory`
        adds it to its model.
    reads_normal_fits : callable or None
        ``(options, standard_errors) -> NormalFits or None``: the fits its estimate with these options
        at the point normals' range reads from the normals' pass (:mod:`curv.estimators._handover`:
        the ``jet``'s own fits, ``qs`` fitted in the pass), so that pass makes and keeps them; None
        (the field or its answer): it reads none.
    extra_bytes_per_point : float
        Peak memory of a point-cloud estimate beyond :data:`curv.memory.PER_POINT_BYTES`, bytes per
        point (the kept fits of ``reads_normal_fits``: its ``bytes_per_point``).
    takes_points : bool
        Runs on a :class:`curv.PointCloud`: it needs only positions, normals and a support (no
        faces, no edges). The face-based estimators refuse point clouds (:func:`refusal`).
    takes_levels : bool
        ``function`` also takes ``radii`` of shape ``(levels, n)``, the radii of several ranges in
        ascending order, and returns one result per level (:func:`curv.estimate_ranges`): ``csm``,
        ``icc`` (one walk serves every range), the fits ``nc``, ``qs``, ``an``, ``mru`` (one walk
        and one set of sums without standard errors on a mesh, else a fit per level:
        :func:`curv.estimators._fit_driver.run_fit_levels`) and ``jet`` (one walk on a mesh with the
        fixed width, a fit per level).
    skips_errors : bool
        ``function`` takes ``standard_errors`` (default False) and computes the standard errors of
        k1 and k2 only when it is True, paying nothing for them otherwise (the least-squares fits:
        ``nc``, ``qs``, ``an``, ``mru``, ``jet``).
    pools_errors : bool
        Its standard errors pool the noise level over each vertex's edge neighbours
        (:mod:`curv.uncertainty.pooling`): a region's fits also run at its neighbours, and a tile's
        halo reaches one ring further (``nc``, ``qs``, ``an``, ``mru``; not the ``jet``).
    shared_pass : str
        A pass (:data:`SHARED_PASSES`) that runs this estimator together with the others naming it
        and shares their work (``csm`` and ``icc``: one search and one clip of the crossing faces per
        vertex and range, :func:`curv.estimate_table`); empty: it runs alone. The estimators of one
        pass take the same normals, ranges and supports (``uses_normals``, ``has_support``).
    """

    name: str
    title: str
    ranges: tuple[int, ...]
    function: EstimatorFunction = field(repr=False, compare=False)
    triangles_only: bool
    uses_normals: bool
    closed_ring: bool
    reference: str
    summary: str = ""
    computes_normals: bool = False
    has_support: bool = True
    in_paper: bool = True
    options: dict = field(default_factory=dict, compare=False)
    kernels: tuple = field(default=(), repr=False, compare=False)
    extra_bytes_per_unit: float = 0.0
    reads_normal_fits: object = field(default=None, repr=False, compare=False)
    extra_bytes_per_point: float = 0.0
    takes_points: bool = False
    takes_levels: bool = False
    skips_errors: bool = False
    pools_errors: bool = False
    min_neighbours: object = field(default=0, compare=False)
    shared_pass: str = field(default="", compare=False)

    def fewest_neighbours(self, options: dict | None = None) -> int:
        """:attr:`min_neighbours` for these estimator options."""
        m = self.min_neighbours
        return int(m(dict(options or {})) if callable(m) else m)

    def check_options(self, options: dict) -> dict:
        """Validate estimator options; :class:`EstimatorError` names the allowed ones."""
        for name, value in options.items():
            if name not in self.options:
                allowed = ", ".join(self.options) or "none"
                raise EstimatorError(f"estimator {self.name!r} has no option {name!r}; its options: {allowed}")
            if value not in self.options[name]:
                raise EstimatorError(f"estimator {self.name!r}: {name} must be one of "
                                     f"{', '.join(map(str, self.options[name]))}; got {value!r}")
        return options

    def variants(self) -> list[tuple[str, int]]:
        """``[(name, k), ...]`` for every supported range."""
        return [(self.name, k) for k in self.ranges]


ESTIMATORS: dict[str, EstimatorSpec] = {}
"""Registry: name -> :class:`EstimatorSpec`, in registration (paper) order."""


def register(spec: EstimatorSpec) -> EstimatorSpec:
    """Add ``spec`` to :data:`ESTIMATORS` (the name must be new); the kernels of its shared pass, if
    registered already, join its :attr:`~EstimatorSpec.kernels`."""
    if spec.name in ESTIMATORS:
        raise ValueError(f"estimator {spec.name!r} is registered twice")
    spec = replace(spec, kernels=spec.kernels + PASS_KERNELS.get(spec.shared_pass, ()))
    ESTIMATORS[spec.name] = spec
    return spec


SharedPass = Callable[..., Generator[float, None, dict]]
"""``fn(mesh, normals, radii, methods, *, chunk, centres, features, options) -> {name: [Principal]}``:
the estimators ``methods`` (names whose spec names this pass) at every level of ``radii``
(levels, n), ascending per vertex, one Principal per level each; ``options`` maps each name to its
estimator options. Otherwise as :data:`EstimatorFunction`."""

SHARED_PASSES: dict[str, SharedPass] = {}
"""Registry: pass name -> the function running its estimators together (:attr:`EstimatorSpec.shared_pass`)."""

PASS_KERNELS: dict[str, tuple] = {}
"""Registry: pass name -> the numba dispatchers the pass calls (part of each of its estimators' kernels)."""


def register_pass(name: str, function: SharedPass, kernels: tuple = ()) -> SharedPass:
    """Add a shared pass to :data:`SHARED_PASSES` (the name must be new); ``kernels`` join the
    :attr:`~EstimatorSpec.kernels` of every estimator naming the pass."""
    if name in SHARED_PASSES:
        raise ValueError(f"shared pass {name!r} is registered twice")
    SHARED_PASSES[name] = function
    PASS_KERNELS[name] = tuple(kernels)
    for key, spec in ESTIMATORS.items():
        if spec.shared_pass == name:
            ESTIMATORS[key] = replace(spec, kernels=spec.kernels + PASS_KERNELS[name])
    return function


def get_spec(name: str) -> EstimatorSpec:
    """Look up an estimator; :class:`EstimatorError` lists the known names."""
    try:
        return ESTIMATORS[name]
    except (KeyError, TypeError):
        raise EstimatorError(f"unknown estimator {name!r}; choose one of {', '.join(ESTIMATORS)}") from None


def input_kind(mesh) -> str:
    """``"points"`` for a :class:`curv.PointCloud`, else ``"mesh"``: the keys of :data:`DEFAULT_ESTIMATORS`."""
    return support_of(mesh).kind


def default_estimator(mesh) -> str:
    """The estimator used on ``mesh`` (a Mesh or a PointCloud) when none is named (:data:`DEFAULT_ESTIMATORS`)."""
    return DEFAULT_ESTIMATORS[input_kind(mesh)]


def polygon_estimators() -> list[str]:
    """Names of the estimators that run on polygon (non-triangle) meshes, in registry order."""
    return [name for name, spec in ESTIMATORS.items() if not spec.triangles_only]


def point_estimators() -> list[str]:
    """Names of the estimators that run on point clouds, in registry order."""
    return [name for name, spec in ESTIMATORS.items() if spec.takes_points]


def refusal(spec: EstimatorSpec, mesh) -> str | None:
    """Why ``spec`` cannot run on ``mesh`` (a Mesh or a PointCloud), in one sentence, or None if it can.

    The one place that decides which estimators an input rules out: the API raises it, the viewer
    greys the estimator out with it as the tooltip.
    """
    support = support_of(mesh)
    if support.runs(spec):
        return None
    others = [name for name, other in ESTIMATORS.items() if support.runs(other)]
    return f"estimator {spec.name!r} {support.why_not(spec)}; use one of: {', '.join(others)}"


def all_variants() -> list[tuple[str, int]]:
    """Every (name, range) pair of the registry, in registry order."""
    return [v for spec in ESTIMATORS.values() for v in spec.variants()]
