"""procam.datasheet: throw ratio and lens shift against their definitions, and the exact round trip."""

import numpy as np
import pytest

from procam import datasheet, models


@pytest.mark.parametrize("tr, sh, sv", [(1.5, 0.0, 50.0), (0.8, -3.0, 58.0), (2.1, 5.5, -12.0)])
def test_datasheet_numbers_round_trip_exactly(tr, sh, sv):
    K = datasheet.intrinsic_matrix(1920, 1080, throw_ratio=tr, shift_h=sh, shift_v=sv)
    v = datasheet.datasheet_view(K, (1920, 1080))
    assert v.throw_ratio == pytest.approx(tr, abs=1e-12)
    assert v.shift_h_pct == pytest.approx(sh, abs=1e-9) and v.shift_v_pct == pytest.approx(sv, abs=1e-9)
    assert v.offset_pct == pytest.approx(2 * sv) and v.aspect == 1.0


def test_throw_ratio_is_distance_over_image_width():
    """A screen square to the lens axis at distance D: the image the panel throws on it is D / throw ratio wide."""
    K = datasheet.intrinsic_matrix(1280, 800, throw_ratio=1.2, shift_v=50.0)
    D = 2000.0
    left = np.linalg.solve(K, [-0.5, 400.0, 1.0]) * D          # rays through the panel's left and right edges
    right = np.linalg.solve(K, [1279.5, 400.0, 1.0]) * D
    assert D / (right[0] - left[0]) == pytest.approx(1.2)


def test_half_shift_puts_the_bottom_edge_on_the_axis_and_the_image_above():
    K = datasheet.intrinsic_matrix(1920, 1080, throw_ratio=1.0, shift_v=50.0)
    assert K[1, 2] == pytest.approx(1080 - 0.5)          # the axis through the bottom edge of the panel
    # every panel row projects above the axis (y < 0 in the projector frame: up)
    ys = (np.arange(1080) - K[1, 2]) / K[1, 1]
    assert np.all(ys <= 0)


def test_field_of_view_of_a_centred_lens():
    K = models.intrinsic_matrix(1000.0, 499.5, 299.5)
    v = datasheet.datasheet_view(K, (1000, 600))
    assert v.fov_h_deg == pytest.approx(2 * np.degrees(np.arctan(0.5)))
    assert v.fov_v_deg == pytest.approx(2 * np.degrees(np.arctan(0.3)))
    assert v.shift_h_pct == pytest.approx(0.0) and v.shift_v_pct == pytest.approx(0.0)
