"""Curvature estimators; importing this package registers all of them in :data:`ESTIMATORS`."""

from . import meyer, csm, goldfeather, rusinkiewicz, mru  # noqa: F401  (registration side effects, paper order)
from . import jet  # noqa: F401
from . import icc  # noqa: F401
from . import clipping_pair  # noqa: F401  (the pass csm and icc share)
from .registry import (DEFAULT_ESTIMATOR, DEFAULT_ESTIMATORS, ESTIMATORS, SHARED_PASSES, EstimatorSpec, all_variants,
                       default_estimator, get_spec, input_kind, polygon_estimators, point_estimators, refusal, register)

__all__ = ["ESTIMATORS", "SHARED_PASSES", "EstimatorSpec", "DEFAULT_ESTIMATOR", "DEFAULT_ESTIMATORS", "default_estimator",
           "input_kind", "get_spec", "register", "all_variants", "polygon_estimators", "point_estimators", "refusal"]
