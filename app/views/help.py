"""Help texts, derived from the registries (estimators, ranges, quantities)."""

from __future__ import annotations

from html import escape

from curv import __version__
from curv.core import ranges
from curv.estimators import ESTIMATORS
from curv.core.quantities import QUANTITIES

from app.model.region import REST_NOTE

__all__ = ["about_text", "guide_text"]

PAPER = "Multivariate analysis of curvature estimators"


def about_text() -> str:
    """Version, the paper, licences."""
    import PySide6

    try:
        import vtk
        vtk_version = vtk.vtkVersion.GetVTKVersion()
    except Exception:  # version display only
        vtk_version = "?"
    return (f"<h3>curvlab {__version__}</h3>"
            f"<p>Curvature estimation and inspection on surface meshes: every estimator and range of "
            f"<i>{PAPER}</i>, with analytic surfaces to check them against.</p>"
            "<p>curvlab is MIT licensed. It runs on numpy, scipy, numba (BSD), trimesh, meshio, plyfile (MIT), "
            f"Qt for Python {PySide6.__version__} (LGPLv3), VTK {vtk_version}, pyvista, pyvistaqt (BSD/MIT) and "
            "superqt (BSD).</p>")


def guide_text() -> str:
    """A short guide: ranges, then one line per estimator and per quantity, from the registries."""
    rows = []
    for name, spec in ESTIMATORS.items():
        named = escape(ranges.describe_ranges(spec))
        rows.append(f"<tr><td><b>{name}</b></td><td>{escape(spec.title)}</td><td>{named}</td>"
                    f"<td>{'triangles' if spec.triangles_only else 'polygons'}</td><td>{escape(spec.reference)}</td></tr>")
    with_normals = ", ".join(n for n, spec in ESTIMATORS.items() if spec.uses_normals and ranges.takes_any_range(spec))
    fixed = " and ".join(n for n, spec in ESTIMATORS.items() if not ranges.takes_any_range(spec))
    quantities = "".join(f"<li><b>{escape(q.title)}</b>: {escape(q.formula)}</li>" for q in QUANTITIES.values())
    return ("<h3>Ranges</h3><p>Range <b>Rk</b> (paper §4.1): the support of vertex p is every vertex connected "
            "to p within k × the longest edge of p's 1-ring. Estimators that also use their neighbours' normals "
            f"({with_normals}) collect within (k − 1) × that length. Support-based estimators take any real k "
            f"from their smallest range (e.g. R2.5), or a fixed <b>radius</b> in mesh units; {fixed} use their "
            "fixed 1-ring.</p><p><b>Options</b> (under the range): the options of the active pane's estimator, "
            "the default marked (e.g. the jet's degree, weights and width), and on a mesh its <b>Normals</b>: the "
            "mesh's vertex normals or normals fitted at R2-R4. Each choice computes that call.</p>"
            "<h3>Estimators</h3><table cellspacing=4><tr><th>name</th><th>method</th><th>ranges</th>"
            "<th>faces</th><th>reference</th></tr>" + "".join(rows) + "</table>"
            "<h3>Advice</h3><p><b>Estimate › Advise</b> (Ctrl+Shift+A) measures the mesh's noise, irregularity "
            "and density and ranks every estimator and range by the median relative error the paper's study "
            "predicts for such a mesh. <b>Apply</b> in the Advice panel puts the selected row (the recommendation "
            "unless you pick another) into the active pane and computes it. Advice belongs to the mesh it was "
            "computed for: on another mesh it is marked stale until you advise again.</p>"
            "<h3>Quantities</h3><ul>" + quantities + "</ul>"
            "<p>Magenta vertices are invalid (border-affected, degenerate, singular fit, on a crease): their "
            "reason shows in the picked-vertex readout.</p>"
            "<h3>Creases and regions</h3><p><b>Feature angle</b> (under the range) makes edges sharper than "
            "the angle creases for the active pane: supports stop there and vertices on them read 'on a crease "
            "(feature edge)'. <b>Borders and features</b> draws them. The <b>Region</b> dock computes every "
            "pane only around the picked vertex or in view; " + REST_NOTE[0].lower() + REST_NOTE[1:] + "</p>")
