"""Standard errors of the least-squares fits and the models of their noise (docs/UNCERTAINTY.md).

The fits (``nc``, ``qs``, ``an``, ``mru``, ``jet``) compute their standard errors only when asked
(``curv.estimate(..., standard_errors=True)``); then they hand this package what the fit produced:
its normal matrix (or its factor), its residual, the sums of its rows and the gradients of k1 and
k2 over its unknowns. The modules, by job:

- :mod:`~curv.uncertainty.parts`: the per-vertex parts a fit leaves (:class:`Errors`);
- :mod:`~curv.uncertainty.propagation`: the propagation through the eigen step and the noise level of
  the 3-unknown fits (the centre's shared error, the frame's tilt, nc's weighted equations);
- :mod:`~curv.uncertainty.factored`: the same for a fit of K unknowns from its Cholesky factor (an, jet);
- :mod:`~curv.uncertainty.normals_model`: the errors the neighbours' normals take from noisy heights
  (``noise_model="normals"``);
- :mod:`~curv.uncertainty.noise_models`: the choice of model (:data:`NOISE_MODELS`) and the sampled one;
- :mod:`~curv.uncertainty.pooling`: the noise level pooled over each vertex and its edge neighbours.
"""

from .noise_models import DEFAULT_NOISE_MODEL, NOISE_MODELS, checked_noise_model
from .parts import Errors
from .propagation import eigen_bias

__all__ = ["NOISE_MODELS", "DEFAULT_NOISE_MODEL", "checked_noise_model", "Errors", "eigen_bias"]
