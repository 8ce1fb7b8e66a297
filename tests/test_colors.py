"""curv.colors.apply_table: the entry each value gets, shading beyond the limits, invalid vertices."""

import numpy as np

from curv.colors import CLIP_MARGIN, CLIP_SHADE, INVALID_RGBA, apply_table, colour_table


def test_values_take_the_nearest_entry_and_the_ends_beyond_the_limits():
    table = colour_table("viridis", 5)  # entries at -1, -0.5, 0, 0.5, 1
    values = np.array([-1.0, -0.74, -0.76, 0.0, 0.26, 1.0, -1.0 - CLIP_MARGIN, 3.0, -3.0])
    rgba = apply_table(values, (-1.0, 1.0), table)
    np.testing.assert_array_equal(rgba[:, :3], table[[0, 1, 0, 2, 3, 4, 0, 4, 0]])
    assert (rgba[:, 3] == 255).all()


def test_clip_shade_darkens_only_beyond_the_margin():
    table = colour_table("coolwarm", 256)
    margin = CLIP_MARGIN * 2.0
    values = np.array([1.0 + 0.5 * margin, 1.0 + 2 * margin, -1.0 - 2 * margin, 0.0])
    rgba = apply_table(values, (-1.0, 1.0), table, clip_shade=CLIP_SHADE)
    np.testing.assert_array_equal(rgba[0, :3], table[-1])
    np.testing.assert_array_equal(rgba[1, :3], (table[-1] * CLIP_SHADE).astype(np.uint8))
    np.testing.assert_array_equal(rgba[2, :3], (table[0] * CLIP_SHADE).astype(np.uint8))
    np.testing.assert_array_equal(rgba[3, :3], table[128])


def test_non_finite_and_invalid_vertices_get_the_invalid_colour_in_place():
    table = colour_table("coolwarm", 256)
    values = np.array([0.1, np.nan, np.inf, 0.2])
    out = np.zeros((4, 4), np.uint8)
    result = apply_table(values, (-1.0, 1.0), table, valid=np.array([True, True, True, False]), out=out,
                         clip_shade=CLIP_SHADE)
    assert result is out
    assert (out[1:] == INVALID_RGBA).all()
    assert not (out[0] == INVALID_RGBA).all()
