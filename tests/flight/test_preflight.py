"""The pre-flight line for a vehicle whose [vehicle] parameters are not the plan's."""

from __future__ import annotations

from ftlbo_mav.flight.preflight import vehicle_param_problem


def test_no_difference_no_problem():
    assert vehicle_param_problem([]) is None


def test_a_value_the_plan_sets_one_sentence_naming_both_values_and_the_remedy():
    assert vehicle_param_problem([("WPNAV_ACCEL", 500.0, 250.0)]) == (
        "WPNAV_ACCEL is 500 on the vehicle, the plan sets 250 "
        "(`ftlbo-mav upload` sets the values the scenario names)")


def test_several_values_and_one_not_answered():
    line = vehicle_param_problem([("WPNAV_ACCEL", 500.0, 250.0), ("WPNAV_JERK", 2.0, 1.0),
                                  ("WPNAV_RADIUS", None, 100.0)])
    assert line.startswith("WPNAV_ACCEL is 500 on the vehicle, the plan sets 250; WPNAV_JERK "
                           "is 2 on the vehicle, the plan sets 1; WPNAV_RADIUS not answered")
    assert "\n" not in line
