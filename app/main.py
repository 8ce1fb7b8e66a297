"""``curvlab``: start the viewer, optionally on a mesh or surface, or render a scripted snapshot.

Examples
--------
curvlab part.ply
curvlab scan.las --method jet --knn 20 --point-size 4
curvlab --surface torus --sample blue --vertices 20000 --method qs --compare jet:2 --screenshot out.png
curvlab --surface torus --method mru --range 3 --quantity gaussian
curvlab --surface ellipsoid_patch --method mru --range 2 --compare qs:2 --difference --screenshot out.png
curvlab --surface box --method mru --range 2 --compare mru:2:30 --screenshot features.png
curvlab scan.ply --advise
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

__all__ = ["main", "build_parser", "configure"]


def build_parser() -> argparse.ArgumentParser:
    """The command-line interface of ``curvlab``."""
    p = argparse.ArgumentParser(prog="curvlab", description="Estimate and inspect the curvature of surface meshes and point clouds.")
    p.add_argument("mesh", nargs="?", help="mesh or point-cloud file to open (PLY, OBJ, STL, OFF, glTF, ...; "
                                          "xyz, txt, csv, PCD, LAS, LAZ and vertex-only PLY are point clouds)")
    src = p.add_argument_group("synthetic surface (default when no mesh is given)")
    src.add_argument("--surface", help="analytic surface name, e.g. sphere, torus, ellipsoid_patch")
    src.add_argument("--param", action="append", default=[], metavar="NAME=VALUE", help="surface parameter")
    src.add_argument("--random", action="store_true", help="draw the surface parameters at random from --seed")
    src.add_argument("--vertices", type=int, help="vertex count (217, 817, 3169, 12481 for the hexagon), or point count "
                                                  "with --sample")
    src.add_argument("--sample", metavar="HOW", help="sample the surface as a point cloud instead of meshing it: "
                                                      + ", ".join(_sampling_names()))
    src.add_argument("--irregularity", type=float, default=0.0, help="RMS angle deviation in degrees (0-25)")
    src.add_argument("--noise", type=float, default=0.0, help="Gaussian noise in mean edge lengths (in mean spacings with --sample)")
    src.add_argument("--seed", type=int, default=0)
    est = p.add_argument_group("estimate and display")
    est.add_argument("--method", help="estimator of pane A (default: the last session's panes, else the "
                                      "registry's default estimator)")
    est.add_argument("--range", help="range k of Rk for pane A (2, R2, 2.5 or R2.5)")
    est.add_argument("--radius", type=float, help="fixed support radius of pane A in mesh units (instead of --range)")
    est.add_argument("--knn", type=int, metavar="K", help="point clouds: the support of pane A is the K nearest points "
                                                          "(instead of --range)")
    est.add_argument("--features", type=float, metavar="DEG",
                     help="feature angle of pane A in degrees: edges sharper than this are creases (default off)")
    est.add_argument("--compare", action="append", default=[], metavar="M:R[:DEG]",
                     help="add a pane (up to 3), optionally with a feature angle, e.g. mru:2:30")
    est.add_argument("--difference", action="store_true", help="show the A - B difference pane")
    est.add_argument("--quantity", help=", ".join(_quantity_names()) + " (default: the last session's, else mean)")
    est.add_argument("--show", help="estimate, uncertainty (2 standard errors), exact, error or e_rel (the last "
                                    "three: analytic sources; default: the last session's, else estimate)")
    est.add_argument("--directions", action="store_true", help="draw principal direction glyphs")
    est.add_argument("--borders", action="store_true", help="draw border edges and the panes' feature edges")
    est.add_argument("--point-size", type=float, metavar="PX", help="width of a point cloud's points in pixels")
    est.add_argument("--cmap", help="colour map for the shown field")
    est.add_argument("--limits", help="colour limits LO,HI (default: symmetric 2-98 %% percentiles)")
    est.add_argument("--advise", action="store_true",
                     help="run the advisor on the mesh and show its ranking in the Advice panel")
    snap = p.add_argument_group("scripted snapshot")
    snap.add_argument("--screenshot", metavar="PNG", help="render, save the window image and exit")
    snap.add_argument("--size", help="window size WxH for the snapshot (default 1400x860); never larger than the "
                                     "screen's available area")
    snap.add_argument("--timeout", type=float, default=300.0, help="seconds before the snapshot gives up")
    return p


def _sampling_names() -> list[str]:
    from app.model.inputs import samplings

    return list(samplings())


def _quantity_names() -> list[str]:
    from curv.core.quantities import QUANTITIES

    return list(QUANTITIES)


def requested_panes(args) -> tuple[list, bool]:
    """The panes the command line asks for, validated, and whether it names any estimate at all.

    Returns
    -------
    panes : list of app.model.Pane
        Pane A from ``--method``/``--range``/``--radius``/``--knn``/``--features`` (the registry's
        default estimator and range where not given), then one per ``--compare``.
    explicit : bool
        False when no estimate option was given: the viewer then keeps the last session's panes.

    Raises
    ------
    ValueError
        An unknown estimator, a bad range or more than 4 panes (the message names the allowed forms).
    """
    from curv.core.errors import EstimatorError
    from curv.estimators import DEFAULT_ESTIMATOR, ESTIMATORS

    from app.model import Pane

    explicit = (args.method is not None or args.range is not None or args.radius is not None or args.compare
                or args.features is not None or args.knn is not None)
    # a missing range is the estimator's default one (curv.core.ranges decides), a radius replaces it
    panes = [(args.method or DEFAULT_ESTIMATOR, args.range, args.features)] + [
        tuple((c.split(":", 2) + [None, None])[:3]) for c in args.compare]
    if len(panes) > 4:
        raise ValueError("at most 4 panes (--compare up to 3 times)")
    checked = []
    for i, (method, k, features) in enumerate(panes):
        if method not in ESTIMATORS:
            raise ValueError(f"unknown estimator {method!r}; choose one of {', '.join(ESTIMATORS)}")
        radius = args.radius if i == 0 else None
        knn = args.knn if i == 0 else None
        try:
            pane = Pane.default(method) if not k else Pane(method, k).validated()
            checked.append(Pane(method, pane.range, radius, features if features not in (None, "") else None,
                                knn=knn).validated())
        except EstimatorError as exc:
            raise ValueError(str(exc)) from None
    return checked, bool(explicit)


def configure(window, args) -> object:
    """Apply parsed ``args`` to a :class:`~app.views.main_window.MainWindow`; return the source to open.

    Raises
    ------
    ValueError
        An unknown estimator, range, quantity, surface or colour map (message names the allowed ones).
    """
    from curv.surfaces import SURFACES

    from app.model import FileSource, Layer, LimitMode, Quantity, SurfaceSource, colormap_names
    from app.views.main_window import DEFAULT_SOURCE

    checked, explicit = requested_panes(args)
    doc = window.doc
    doc.panes_asked = explicit
    if explicit or args.screenshot:  # otherwise the panes remembered from the last session stay
        doc.set_pane_count(len(checked))
        for i, pane in enumerate(checked):
            doc.set_pane(i, method=pane.method, range=pane.range, radius=pane.radius, features=pane.features,
                         knn=pane.knn)
    if args.difference or explicit or args.screenshot:
        doc.set_difference(args.difference)
    try:  # not given: the last session's (a snapshot starts from empty settings, so from the defaults)
        quantity = None if args.quantity is None else Quantity(args.quantity)
        layer = None if args.show is None else Layer(args.show)
    except ValueError:
        raise ValueError(f"unknown quantity {args.quantity!r} or --show {args.show!r}; quantities: "
                         f"{', '.join(q.value for q in Quantity)}; show: {', '.join(x.value for x in Layer)}") from None
    changes = dict(show_directions=args.directions, show_borders=args.borders)
    if args.point_size is not None:
        from app.model.inputs import POINT_SIZES

        if not POINT_SIZES[0] <= args.point_size <= POINT_SIZES[1]:
            raise ValueError(f"--point-size must be {POINT_SIZES[0]} to {POINT_SIZES[1]} pixels; got {args.point_size:g}")
        changes["point_size"] = float(args.point_size)
    if quantity is not None:
        changes["quantity"] = quantity
    if args.cmap:
        if args.cmap not in colormap_names():
            raise ValueError(f"unknown colour map {args.cmap!r}; choose one of {', '.join(colormap_names())}")
        key = "diverging_cmap" if args.cmap in colormap_names("diverging") else "sequential_cmap"
        changes[key] = args.cmap
    if args.limits:
        lo, hi = (float(x) for x in args.limits.split(","))
        changes.update(limit_mode=LimitMode.MANUAL, manual=(lo, hi), lock_limits=True)  # asked for: keep them
    doc.display.update(**changes)
    window.pending_layer = layer  # applied once the source (and its truth) is there
    if args.mesh:
        if args.surface:
            raise ValueError("give either a mesh file or --surface, not both")
        return FileSource(str(Path(args.mesh).expanduser()))
    from app.model.inputs import samplings

    if args.sample is not None and args.sample not in samplings():
        raise ValueError(f"unknown sampling {args.sample!r}; choose one of {', '.join(samplings())}")
    if args.surface or args.param or args.random or args.vertices or args.sample:
        name = args.surface or DEFAULT_SOURCE.name
        surfaces = SURFACES
        if name not in surfaces:
            raise ValueError(f"unknown surface {name!r}; choose one of {', '.join(surfaces)}")
        params = {}
        for item in args.param:
            key, _, value = item.partition("=")
            params[key.strip()] = float(value)
        n = args.vertices or getattr(surfaces[name], "default_vertices", DEFAULT_SOURCE.n_vertices)
        return SurfaceSource(name=name, params=params, n_vertices=n, irregularity=args.irregularity,
                             noise=args.noise, seed=args.seed, random_params=args.random, sampling=args.sample)
    return DEFAULT_SOURCE


def main(argv: list[str] | None = None) -> int:
    """Run the viewer; with ``--screenshot`` render once, save the window image and exit.

    Returns
    -------
    int
        0 on success; 1 when loading or estimating failed in snapshot mode; 2 for bad arguments.
    """
    parser = build_parser()
    args = parser.parse_args(argv)
    from app.heap import tune_allocator

    tune_allocator()  # before the first large buffer (the preload's), so that each is returned when freed
    preloaded = _preload(args)
    try:
        from PySide6.QtCore import QSettings
        from PySide6.QtWidgets import QApplication
    except ImportError as exc:  # pragma: no cover
        print(f"curvlab: the viewer needs the gui extra (pip install 'curvlab[gui]'): {exc}", file=sys.stderr)
        return 2
    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("curvlab")
    app.setOrganizationName("curvlab")
    from app.views.main_window import MainWindow

    settings = None
    if args.screenshot:  # snapshots do not read or change the user's settings
        tmp = tempfile.mkdtemp(prefix="curvlab-")
        settings = QSettings(str(Path(tmp) / "snapshot.ini"), QSettings.Format.IniFormat)
    window = MainWindow(settings=settings)
    try:
        source = configure(window, args)
    except ValueError as exc:
        window.close()
        parser.exit(2, f"curvlab: error: {exc}\n")
    if args.screenshot:
        from app.snapshot import Snapshot

        w, h = _snapshot_size(args.size, parser)
        window.fit_to(w, h)  # no larger than the screen it opens on
        if (window.width(), window.height()) != (w, h) and args.size:
            print(f"curvlab: the screen holds {window.width()}x{window.height()}, not {w}x{h}", file=sys.stderr)
        window.requested_size = (window.width(), window.height())
        snapshot = Snapshot(window, args.screenshot, timeout_s=args.timeout, wait_for_advice=args.advise)
        window.show()
        window.open_source_then(source, loaded=_matching(preloaded, source))
        if args.advise:
            window.advise()  # runs once the source has loaded
        snapshot.start()
        app.exec()
        return snapshot.status
    window.show()
    window.open_source_then(source, loaded=_matching(preloaded, source))
    if args.advise:
        window.advise()
    return app.exec()


SNAPSHOT_SIZE = (1400, 860)
"""The snapshot window's size unless ``--size`` says otherwise (and the screen has the room)."""


def _snapshot_size(text, parser) -> tuple[int, int]:
    """``--size WxH`` as integers (:data:`SNAPSHOT_SIZE` when not given)."""
    if not text:
        return SNAPSHOT_SIZE
    w, _, h = text.lower().partition("x")
    try:
        size = int(w), int(h)
    except ValueError:
        size = (0, 0)
    if min(size) <= 0:
        parser.exit(2, f"curvlab: error: --size must be WxH in pixels, e.g. 1400x860; got {text!r}\n")
    return size


def _preload(args):
    """``(FileSource, future)``: the mesh file of ``args`` read (and its normals computed) in a thread
    while the window is built, or None without a file.

    When the command line sets the panes (as a snapshot always does), pane A's estimate follows in
    the same thread: it is the first thing the window would compute, and the window's imports
    leave the second core idle meanwhile.
    """
    if not args.mesh or args.surface:
        return None
    from app.controller.sources import EarlyEstimate, preload
    from app.model.sources import FileSource

    source = FileSource(str(Path(args.mesh).expanduser()))
    early = None
    try:
        panes, explicit = requested_panes(args)
    except ValueError:
        panes, explicit = [], False  # configure() reports it once the window is there
    if panes and (explicit or args.screenshot):
        early = EarlyEstimate(panes[0].method, panes[0].estimate_kwargs())
    return source, preload(source, early)


def _matching(preloaded, source):
    """The preload's future if it is of ``source``, else None (``source`` loads as usual)."""
    return preloaded[1] if preloaded is not None and preloaded[0] == source else None


if __name__ == "__main__":
    raise SystemExit(main())
