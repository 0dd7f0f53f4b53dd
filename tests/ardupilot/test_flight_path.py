"""The flown-path model (ardupilot.flight_path) on small cases; what it is measured
against is ArduCopter SITL (tests/conformance/test_flown_path.py)."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.ardupilot.flight_path import fly_path, fly_paths
from ftlbo_mav.ardupilot.navigation import Navigation, vehicle_navigation

CORNER = np.array([[0.0, 0.0, 5.0], [30.0, 0.0, 5.0], [30.0, 30.0, 5.0]])


def _inside(path) -> float:
    """How far the flown path comes inside the right-angle corner at (30, 0)."""
    xy = path.positions[:, :2]
    return float(np.max(np.minimum(30.0 - xy[:, 0], xy[:, 1])))


def test_a_straight_leg_is_flown_on_the_line_from_rest_to_rest():
    path = fly_path(CORNER[:2], speed_m_s=5.0)
    assert np.abs(path.positions[:, 1]).max() < 1e-9
    # the copter overshoots its stop (behind its target by its drag, it is still moving
    # when the target stops) and comes back to rest on it
    assert 0.2 < path.positions[:, 0].max() - 30.0 < 0.6
    assert np.allclose(path.positions[-1], CORNER[1], atol=0.01)
    assert path.reached[1] < path.seconds
    speed = np.linalg.norm(np.diff(path.positions, axis=0), axis=1) / np.diff(path.times)
    assert 4.9 < speed.max() <= 5.1  # the DO_CHANGE_SPEED speed


def test_on_its_target_the_copter_would_stop_dead():
    path = fly_path(CORNER[:2], speed_m_s=5.0, airframe=None)
    assert path.positions[:, 0].max() == pytest.approx(30.0)
    assert path.reached[1] == pytest.approx(path.seconds)


def test_a_corner_flown_through_is_cut_more_the_faster_it_is_flown():
    slow = _inside(fly_path(CORNER, speed_m_s=1.5))
    fast = _inside(fly_path(CORNER, speed_m_s=5.0))
    assert 0.05 < slow < fast - 0.3


def test_a_hold_stops_the_copter_on_the_corner():
    held = fly_path(CORNER, speed_m_s=8.0, holds_s=[0, 1, 0])
    assert _inside(held) < 0.01
    through = fly_path(CORNER, speed_m_s=8.0)
    assert held.reached[1] - through.reached[1] > 1.0  # the hold and the stop cost time


def test_the_waypoint_radius_and_corner_acceleration_bound_the_cut():
    # SCurve::advance_target_along_track begins the next leg only within WPNAV_RADIUS of
    # the corner and below WPNAV_ACCEL_C
    default = _inside(fly_path(CORNER, nav=Navigation(), speed_m_s=5.0))
    tight = _inside(fly_path(CORNER, nav=vehicle_navigation({"WPNAV_RADIUS": 50.0}),
                             speed_m_s=5.0))
    gentle = _inside(fly_path(CORNER, nav=vehicle_navigation({"WPNAV_ACCEL_C": 100.0}),
                              speed_m_s=5.0))
    assert tight < default / 2 and gentle < default / 2


def test_translated_paths_are_flown_once_and_moved():
    offsets = np.array([[0.0, 0.0, 0.0], [3.0, -2.0, 1.0]])
    two = fly_paths(CORNER[None] + offsets[:, None])
    alone = fly_path(CORNER + offsets[1])
    assert np.allclose(two[1].positions, alone.positions, atol=1e-5)
    assert np.array_equal(two[1].reached, alone.reached)


def test_bad_points_are_refused():
    with pytest.raises(ValueError):
        fly_path(np.zeros((1, 3)))


def test_vehicle_parameters_are_arducopters_names_and_ranges():
    assert vehicle_navigation({"WPNAV_SPEED": 800.0}).wp_speed == 8.0
    with pytest.raises(ValueError, match="WPNAV_SPED"):
        vehicle_navigation({"WPNAV_SPED": 800.0})
    with pytest.raises(ValueError, match=r"\[50, 500\]"):
        vehicle_navigation({"WPNAV_ACCEL": 5000.0})
