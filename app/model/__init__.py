"""The viewer's document model: plain Python objects emitting events; no Qt, no VTK.

Qt widgets subscribe to the model's psygnal signals and push user edits back through the model's
setters, as in napari's layer/_qt split.
"""

from .advice import FEATURE_LABELS, AdviceRecord, feature_rows, ranking_rows
from .colors import Colormap, LimitMode, colormap, colormap_names, compute_limits, format_limit, map_colours
from .display import Display, Layer
from .document import Document, MeshChange, Pane, default_panes, pane_letter
from .export import ExportPayload, export_payload
from .quantities import Quantity
from .readout import readout_columns, readout_rows
from .scalars import relative_error
from .sources import FileSource, SurfaceSource
from .text import count_text

__all__ = [
    "AdviceRecord", "FEATURE_LABELS", "feature_rows", "ranking_rows",
    "Colormap", "LimitMode", "colormap", "colormap_names", "compute_limits", "format_limit", "map_colours",
    "Document", "MeshChange", "Pane", "default_panes", "pane_letter", "Display", "Layer", "ExportPayload",
    "export_payload", "Quantity", "readout_columns", "readout_rows", "relative_error", "FileSource",
    "SurfaceSource", "count_text",
]
