"""The colour bar under a pane's mesh (VTK's scalar bar, styled to read over any mesh)."""

from __future__ import annotations

from vtkmodules.vtkCommonCore import vtkLookupTable
from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor

from app.model.colors import LABEL_FORMAT

__all__ = ["scalar_bar", "BAR_WIDTH_PX", "BAR_FRACTION", "BAR_STRIP_PX"]

BAR_WIDTH_PX = 420
BAR_FRACTION = 0.8
BAR_STRIP_PX = 70
"""Height of the colour bar's strip under the mesh, in pixels (less in very small panes)."""


def scalar_bar(lut: vtkLookupTable) -> vtkScalarBarActor:
    """A horizontal scalar bar of ``lut``, labels under it, clipping swatches at its ends."""
    bar = vtkScalarBarActor()
    bar.SetLookupTable(lut)
    bar.SetOrientationToHorizontal()
    bar.SetPosition(0.1, 0.01)
    bar.SetWidth(BAR_FRACTION)
    bar.SetHeight(0.16)
    bar.SetMaximumHeightInPixels(BAR_STRIP_PX)
    bar.SetMaximumWidthInPixels(BAR_WIDTH_PX)
    bar.SetNumberOfLabels(3)
    bar.SetBarRatio(0.28)
    bar.SetTextPositionToPrecedeScalarBar()  # labels under the bar
    bar.SetTextPad(3)
    bar.SetBelowRangeAnnotation("")
    bar.SetAboveRangeAnnotation("")
    bar.SetLabelFormat(LABEL_FORMAT)  # the same digits as the histogram and the limit fields
    bar.DrawAboveRangeSwatchOn()  # clipped values: the darkened end colours beside the bar
    bar.DrawBelowRangeSwatchOn()
    bar.DrawBackgroundOn()  # labels stay readable over a dark mesh
    bar.GetBackgroundProperty().SetColor(1.0, 1.0, 1.0)
    bar.GetBackgroundProperty().SetOpacity(0.82)
    bar.UnconstrainedFontSizeOn()
    for prop in (bar.GetTitleTextProperty(), bar.GetLabelTextProperty()):
        prop.SetColor(0.1, 0.1, 0.1)
        prop.ShadowOff()
        prop.ItalicOff()
        prop.BoldOff()
        prop.SetFontSize(12)
    label = bar.GetLabelTextProperty()  # the end labels overhang the bar: each gets its own light box
    label.SetBackgroundColor(1.0, 1.0, 1.0)
    label.SetBackgroundOpacity(0.85)
    return bar
