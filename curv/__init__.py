"""curv: curvature estimation on surface meshes and point clouds (numpy, scipy; numba kernels).

>>> import curv
>>> res = curv.estimate(mesh, method="mru", range=2)   # doctest: +SKIP
"""

from __future__ import annotations

import importlib

from .core.errors import CurvError, CurvWarning, EstimatorError, LoadError, MeshError, RadiusWarning
from .core.mesh import Mesh, MeshReport
from .core.pointcloud import PointCloud
from .core.quantities import QUANTITIES
from .core.result import Curvature, Principal
from .core.validity import Reason

__version__ = "0.1.0"

# Heavier parts load on first use so that `import curv` stays cheap.
_LAZY = {
    "estimate": ("curv.api", "estimate"),
    "iter_estimate": ("curv.api", "iter_estimate"),
    "prepare": ("curv.preparation", "prepare"),
    "estimate_ranges": ("curv.api", "estimate_ranges"),
    "estimate_table": ("curv.api", "estimate_table"),
    "ESTIMATORS": ("curv.estimators", "ESTIMATORS"),
    "vertex_normals": ("curv.geometry.normals", "vertex_normals"),
    "load": ("curv.io", "load"),
    "save_ply": ("curv.io", "save_ply"),
    "save_vtu": ("curv.io", "save_vtu"),
    "save_vtp": ("curv.io", "save_vtp"),
    "save_result": ("curv.io", "save_result"),
    "as_mesh": ("curv.convert", "as_mesh"),
    "as_input": ("curv.convert", "as_input"),
    "surfaces": ("curv.surfaces", None),
    "advise": ("curv.advice.advisor", "advise"),
    "iter_advise": ("curv.advice.advising", "iter_advise"),
    "Advice": ("curv.advice.advisor", "Advice"),
    "Candidate": ("curv.advice.advisor", "Candidate"),
    "features": ("curv.core.features", None),
    "feature_edges": ("curv.core.features", "feature_edges"),
    "feature_vertices": ("curv.core.features", "feature_vertices"),
    "feature_corners": ("curv.core.features", "feature_corners"),
    "dihedral_angles": ("curv.core.features", "dihedral_angles"),
    "suggest_threshold": ("curv.core.features", "suggest_threshold"),
}

__all__ = [
    "Mesh", "MeshReport", "PointCloud", "Curvature", "Principal", "Reason", "QUANTITIES",
    "CurvError", "MeshError", "LoadError", "EstimatorError", "CurvWarning", "RadiusWarning", *_LAZY,
]


def __getattr__(name):
    try:
        module, attr = _LAZY[name]
    except KeyError:
        raise AttributeError(f"module 'curv' has no attribute {name!r}") from None
    mod = importlib.import_module(module)
    value = mod if attr is None else getattr(mod, attr)
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
