"""Camera footprint, ground sample distance, spacing from the side overlap (pure)."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.planning.camera import Camera, formation_gaps, trigger_distance, widest_spacing

ONE_INCH = Camera(sensor_width_mm=13.2, sensor_height_mm=8.8, focal_length_mm=8.8,
                  image_width_px=5472, image_height_px=3648, front_overlap=0.7,
                  side_overlap=0.6)


def test_footprint_and_gsd_as_qgroundcontrol_computes_them():
    across, along = ONE_INCH.footprint(20.0)
    assert (float(across), float(along)) == pytest.approx((30.0, 20.0))  # 13.2 * 20 / 8.8
    assert float(ONE_INCH.gsd(20.0)) == pytest.approx(20 * 13.2 * 100 / (8.8 * 5472))
    assert ONE_INCH.altitude_for_gsd(float(ONE_INCH.gsd(20.0))) == pytest.approx(20.0)
    portrait = Camera(**{**vars(ONE_INCH), "landscape": False})
    across, along = portrait.footprint(20.0)
    assert (float(across), float(along)) == pytest.approx((20.0, 30.0))
    assert float(portrait.gsd(20.0)) == pytest.approx(20 * 8.8 * 100 / (8.8 * 3648))


def test_the_widest_spacing_overlaps_the_outer_strips_by_the_side_overlap():
    across, widths = np.array([0.0, 3.0, -3.0]), np.array([33.0, 28.5, 28.5])
    spacing = widest_spacing(across, widths, 0.6)
    assert spacing == pytest.approx(6.0 + 28.5 * 0.4)
    # the eastern UAV of one lane and the western one of the next overlap by 60 %
    east, west = 3.0 + 28.5 / 2, spacing - 3.0 - 28.5 / 2
    assert (east - west) / 28.5 == pytest.approx(0.6)
    assert widest_spacing(np.zeros(1), np.array([10.0]), 0.0) == pytest.approx(10.0)


def test_neighbouring_uavs_too_far_apart_for_the_overlap_are_named():
    across, widths = np.array([0.0, 9.0, -1.0]), np.full(3, 10.0)
    assert formation_gaps(across, widths, 0.2) == [(0, 1, 9.0, pytest.approx(0.1))]
    assert formation_gaps(across, widths, 0.1) == []
    assert trigger_distance(20.0, 0.75) == pytest.approx(5.0)
