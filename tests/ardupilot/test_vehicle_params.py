"""The plan's [vehicle] parameters compared with what a vehicle holds, as AP_Param keeps
them (REAL32 a float32, integer types cast)."""

from __future__ import annotations

import numpy as np

from ftlbo_mav.ardupilot.navigation import (
    Navigation,
    param_matches,
    vehicle_param_differences,
    vehicle_params,
)


def f32(x: float) -> float:
    return float(np.float32(x))


def test_a_float32_read_back_of_the_planned_value_matches():
    planned = vehicle_params(Navigation())
    # what PARAM_VALUE carries: every value as a float32 (0.15 is 0.15000000596...)
    onboard = {name: f32(v) for name, v in planned.items()}
    assert f32(0.15) != 0.15
    assert vehicle_param_differences(planned, onboard) == []


def test_plan_json_six_decimals_match_the_float32_the_vehicle_was_given():
    # a user set WPNAV_JERK 1.2345678 on the vehicle and re-planned with it: plan.json
    # writes 1.234568 (vehicle_params rounds to 6 decimals)
    planned = vehicle_params(Navigation(wp_jerk=1.2345678))
    assert planned["WPNAV_JERK"] == 1.234568
    assert param_matches("WPNAV_JERK", planned["WPNAV_JERK"], f32(1.2345678))


def test_a_different_value_or_a_silent_vehicle_is_a_difference():
    planned = vehicle_params(Navigation())
    onboard = {name: f32(v) for name, v in planned.items()}
    onboard["WPNAV_ACCEL"] = 500.0
    onboard["WPNAV_JERK"] = f32(1.001)  # the smallest change that shapes a path is seen
    del onboard["ATC_INPUT_TC"]
    assert vehicle_param_differences(planned, onboard) == [
        ("WPNAV_ACCEL", 500.0, 250.0), ("WPNAV_JERK", f32(1.001), 1.0),
        ("ATC_INPUT_TC", None, 0.15)]


def test_integer_parameters_compare_as_the_whole_number_ardupilot_keeps():
    assert param_matches("RTL_ALT", 1500.0, 1500.0)  # INT32
    assert param_matches("RTL_ALT", 1500.7, 1500.0)  # AP_Param casts on set
    assert not param_matches("RTL_ALT", 1500.0, 1501.0)


def test_the_param_types_written_out_are_mavlinks():
    from pymavlink.dialects.v20 import ardupilotmega as R

    from ftlbo_mav.ardupilot import navigation

    assert (navigation.REAL32, navigation.INT8, navigation.INT16, navigation.INT32) == (
        R.MAV_PARAM_TYPE_REAL32, R.MAV_PARAM_TYPE_INT8, R.MAV_PARAM_TYPE_INT16,
        R.MAV_PARAM_TYPE_INT32)
