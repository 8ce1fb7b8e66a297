"""The options a pane can set beside its estimator and range, as rows for the viewer's controls.

Each option an estimator declares (:attr:`curv.estimators.EstimatorSpec.options`, with the allowed
values) is one row whose default is the estimator's own (its keyword default); on a mesh a Normals
row chooses the mesh's vertex normals or normals fitted at a range (``normals="fit"``,
``fit_range=k``). A pane keeps only the options that differ from the defaults, so a pane set back to
the defaults is the same result as one never changed (:attr:`app.model.Pane.key`).
"""

from __future__ import annotations

import inspect
from dataclasses import dataclass

from curv.core import ranges
from curv.estimators import ESTIMATORS

__all__ = ["OptionRow", "option_rows", "options_with", "FIT_RANGES", "NORMALS_TIP"]

FIT_RANGES = (2, 3, 4)
"""The ranges the Normals row offers for fitted normals (the advisor's candidates use these)."""

NORMALS_TIP = ("<b>Normals</b> the estimator orients its fits with (and an, mru, icc read at the neighbours): "
               "the mesh's vertex normals (Max weights, the paper's protocol) or normals of a local jet fit at "
               "the range given, steadier on noisy meshes.")

_TIPS = {
    "degree": "<b>Degree</b> of the jet (height polynomial) fitted at each vertex: 2 is a quadric; 3 and 4 "
              "follow the surface further out and win on clean, finely sampled surfaces, at more cost and "
              "more neighbours needed.",
    "weights": "<b>Weights</b> of the jet's neighbours: uniform, or smooth ((1 - d²/r²)⁴, falling to 0 at the "
               "ball's edge), which lowers the error a wide range brings on noisy surfaces.",
    "width": "<b>Width</b> of the jet's ball: fixed (the range's ball) or adaptive, a choice per point among "
             "narrower balls by intersecting their confidence intervals (for wide ranges on noisy scans; "
             "about 4x the cost).",
    "noise_model": "<b>Noise model</b> of the standard errors (Uncertainty layer): sampled (measured at 2000 "
                   "vertices and applied to all), independent equations, or normals (that model at every "
                   "vertex, slower). The curvatures do not change.",
    "from_measures": "<b>From measures</b>: icc's principal curvatures from its mean and Gaussian measures "
                     "(yes) or from its tensor's eigenvalues (no).",
}


@dataclass(frozen=True)
class OptionRow:
    """One control of the Options rows.

    Attributes
    ----------
    name : str
        Keyword of :func:`curv.estimate` (``"degree"``), or ``"fit_range"`` for the Normals row.
    label : str
        The row's label (``"Degree"``).
    choices : tuple
        The values it offers; for the Normals row None (the mesh's normals) and the fit ranges.
    texts : tuple of str
        What each choice reads as, the default marked.
    default : object
        The choice a pane without this option has.
    tooltip : str
    """

    name: str
    label: str
    choices: tuple
    texts: tuple
    default: object
    tooltip: str

    def text_of(self, value) -> str:
        """What ``value`` reads as in this row (also a value the row does not offer, e.g. a fit range
        of 2.5 from a saved session)."""
        if value in self.choices:
            return self.texts[self.choices.index(value)]
        return f"fitted at {ranges.range_label(value)}" if self.name == "fit_range" else _value_text(value)

    def current(self, options: tuple):
        """The choice ``options`` (a pane's) select in this row."""
        opts = dict(options)
        if self.name == "fit_range":
            return opts.get("fit_range", 2) if opts.get("normals") == "fit" else None
        return opts.get(self.name, self.default)


def _value_text(value) -> str:
    return {True: "yes", False: "no"}.get(value, str(value)) if isinstance(value, bool) else str(value)


def _declared_default(spec, name: str, allowed: tuple):
    """The estimator's keyword default of option ``name`` (its function's signature owns it)."""
    parameter = inspect.signature(spec.function).parameters.get(name)
    if parameter is None or parameter.default is inspect.Parameter.empty:
        return allowed[0]
    return parameter.default


def option_rows(method: str, *, points: bool) -> list[OptionRow]:
    """The option rows of estimator ``method``: its declared options, then Normals on a mesh."""
    spec = ESTIMATORS[method]
    rows = []
    for name, allowed in spec.options.items():
        default = _declared_default(spec, name, tuple(allowed))
        texts = tuple(_value_text(v) + (" (default)" if v == default else "") for v in allowed)
        rows.append(OptionRow(name, name.replace("_", " ").capitalize(), tuple(allowed), texts, default,
                              _TIPS.get(name, f"Option {name} of {method} (curv.estimate's {name}=)")))
    if not points:
        texts = ("mesh vertex normals (default)", *(f"fitted at {ranges.range_label(k)}" for k in FIT_RANGES))
        rows.append(OptionRow("fit_range", "Normals", (None, *FIT_RANGES), texts, None, NORMALS_TIP))
    return rows


def options_with(options: tuple, row: OptionRow, value) -> tuple:
    """A pane's ``options`` with ``row`` set to ``value``; a default leaves the option out."""
    opts = dict(options)
    if row.name == "fit_range":
        opts.pop("normals", None)
        opts.pop("fit_range", None)
        if value is not None:
            opts.update(normals="fit", fit_range=int(value))
    elif value == row.default:
        opts.pop(row.name, None)
    else:
        opts[row.name] = value
    return tuple(sorted(opts.items()))
