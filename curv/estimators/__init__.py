"""Curvature estimators; importing this package registers all of them in :data:`ESTIMATORS`."""

from . import meyer, csm, goldfeather, rusinkiewicz, mru  # noqa: F401  (registration side effects, paper order)
from . import jet  # noqa: F401
from . import icc  # noqa: F401
from .registry import ESTIMATORS, EstimatorSpec, all_variants, get_spec, register

__all__ = ["ESTIMATORS", "EstimatorSpec", "get_spec", "register", "all_variants"]
