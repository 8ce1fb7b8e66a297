"""Geometry on a mesh or cloud below the estimators: vertex normals, support neighbourhoods, smoothing, repair, regions."""
