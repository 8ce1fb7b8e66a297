"""The mesh and point-cloud models and what every layer above them asks: connectivity, ranges, crease rule, results, reasons, errors, kernels' threading."""
