"""Curvature estimators; importing this package registers all of them in :data:`ESTIMATORS`."""

from . import meyer, csm, goldfeather, rusinkiewicz, mru  # noqa: F401  (registration side effects, paper order)
from . import jet  # noqa: F401
from . import icc  # noqa: F401
from .registry import (DEFAULT_ESTIMATOR, ESTIMATORS, EstimatorSpec, all_variants, get_spec, polygon_estimators, point_estimators,
                       refusal, register)

__all__ = ["ESTIMATORS", "EstimatorSpec", "DEFAULT_ESTIMATOR", "get_spec", "register", "all_variants",
           "polygon_estimators", "point_estimators", "refusal"]
