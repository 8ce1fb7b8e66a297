"""The viewer's document model: plain Python objects emitting events; no Qt, no VTK.

Qt widgets subscribe to the :class:`~app.model.events.Event` attributes and push user edits back
through the model's setters, as in napari's layer/_qt split.
"""

from .colour import Colormap, LimitMode, colormap, colormap_names, compute_limits, map_colours
from .document import Document, Pane
from .display import Display, Layer
from .events import Event
from .quantities import Quantity
from .sources import FileSource, SurfaceSource

__all__ = [
    "Colormap", "LimitMode", "colormap", "colormap_names", "compute_limits", "map_colours",
    "Document", "Pane", "Display", "Layer", "Event", "Quantity", "FileSource", "SurfaceSource",
]
