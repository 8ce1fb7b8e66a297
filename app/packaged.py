"""Files of the top-level ``resources/`` folder (icons, colour-map presets, small sample meshes).

Installed, the folder is package data of ``app`` (``app.resources``, see pyproject's
``package-dir``); in a source checkout it is read where it lies.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["resource", "sample_names"]

_CHECKOUT = Path(__file__).resolve().parent.parent / "resources"


def resource(name: str):
    """A readable path (``Traversable``) to ``resources/<name>``; ``FileNotFoundError`` if absent."""
    try:
        item = resources.files("app.resources").joinpath(name)
        if item.is_file():
            return item
    except ModuleNotFoundError:
        pass
    path = _CHECKOUT / name
    if not path.is_file():
        raise FileNotFoundError(f"curvlab resource {name!r} is missing (looked in app.resources and {_CHECKOUT})")
    return path


def sample_names() -> list[str]:
    """File names of the small sample meshes in ``resources/samples`` (sorted)."""
    try:
        folder = resources.files("app.resources").joinpath("samples")
        if folder.is_dir():
            return sorted(p.name for p in folder.iterdir() if p.is_file())
    except ModuleNotFoundError:
        pass
    folder = _CHECKOUT / "samples"
    return sorted(p.name for p in folder.iterdir() if p.is_file()) if folder.is_dir() else []
