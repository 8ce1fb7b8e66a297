"""Small study settings shared by the study tests."""

from __future__ import annotations

import pytest

from curv.study import StudySettings


@pytest.fixture
def tiny_settings() -> StudySettings:
    """4 meshes of 817 vertices (217 often has no vertex clear of the border by R4), 3 variants."""
    return StudySettings(samples=2, densities=(817,), noise=(0.0, 1.0), irregularity=(14.0,),
                         functions=("quadratic",), estimators=("nc:R1", "mru:R2,R3"), seed=7)

