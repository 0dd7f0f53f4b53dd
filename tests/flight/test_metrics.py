import numpy as np
import pytest

from ftlbo_mav.flight.metrics import formation_error, min_clearance, min_separation, slot_errors

OFFSETS = np.array([[0.0, 0.0, 2.0], [3.0, 0.0, -1.0], [-3.0, 0.0, -1.0]])


def test_a_translated_formation_has_no_error():
    positions = OFFSETS + [40.0, -7.0, 4.0]
    assert formation_error(positions, OFFSETS) == pytest.approx(0.0)
    assert min_separation(positions) == pytest.approx(np.sqrt(18))


def test_one_uav_off_its_slot():
    positions = OFFSETS + [10.0, 10.0, 4.0]
    positions[1, 0] += 0.9  # the centroid moves by 0.3 m east
    errors = slot_errors(positions, OFFSETS)
    assert errors == pytest.approx([0.3, 0.6, 0.3])
    assert formation_error(positions, OFFSETS) == pytest.approx(np.sqrt((0.09 + 0.36 + 0.09) / 3))


def test_over_time_shapes():
    track = np.stack([OFFSETS + [t, 0, 4] for t in range(5)])
    assert formation_error(track, OFFSETS).shape == (5,)
    assert min_separation(track).shape == (5,)


def test_clearance_is_to_the_surface_and_negative_inside():
    positions = np.array([[0.0, 0.0, 3.0], [10.0, 0.0, 3.0]])
    centres = np.array([[0.0, 5.0], [10.0, 1.0]])
    radii = np.array([2.0, 2.0])
    assert min_clearance(positions, centres, radii) == pytest.approx(-1.0)
    assert min_clearance(positions[:1], centres[:1], radii[:1]) == pytest.approx(3.0)
    assert min_clearance(positions, np.zeros((0, 2)), np.zeros(0)) == np.inf
