"""Which estimator suits a mesh: the advisor and the builder of its table."""
