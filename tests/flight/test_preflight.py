"""The pre-flight line for a vehicle whose [vehicle] parameters are not the plan's."""

from __future__ import annotations

from ftlbo_mav.flight.preflight import vehicle_param_problem


def test_no_difference_no_problem():
    assert vehicle_param_problem([]) is None


def test_one_parameter_one_sentence_naming_both_values_and_both_remedies():
    assert vehicle_param_problem([("WPNAV_ACCEL", 500.0, 250.0)]) == (
        "WPNAV_ACCEL is 500 on the vehicle, the plan predicted its path with 250 "
        "(set it: `ftlbo-mav upload` does, or re-plan with [vehicle] WPNAV_ACCEL = 500)")


def test_several_parameters_and_one_not_answered():
    line = vehicle_param_problem([("WPNAV_ACCEL", 500.0, 250.0), ("WPNAV_JERK", 2.0, 1.0),
                                  ("ATC_INPUT_TC", None, 0.15)])
    assert line.startswith("WPNAV_ACCEL is 500 on the vehicle, the plan predicted its path "
                           "with 250; WPNAV_JERK is 2 on the vehicle, the plan predicted its "
                           "path with 1; ATC_INPUT_TC not answered")
    assert line.endswith("re-plan with [vehicle] WPNAV_ACCEL = 500, WPNAV_JERK = 2)")
    assert "\n" not in line
