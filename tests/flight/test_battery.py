"""A vehicle's charge held to its mission (ftlbo_mav/flight/battery.py)."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.energy import Battery, MissionCharge
from ftlbo_mav.flight.battery import (
    ASSUMED_HOVER_MIN,
    BatteryWatch,
    CopterBattery,
    MissionBattery,
    own_batteries,
    preflight_problem,
    waypoint_seqs,
)
from ftlbo_mav.mission.items import build_mission

MISSION = build_mission(home=(12.0, 109.0), takeoff_alt_m=5.0,
                        path=[(12.0, 109.0, 5.0), (12.0001, 109.0, 5.0), (12.0002, 109.0, 5.0)],
                        speed_m_s=5.0)
WAYPOINTS = waypoint_seqs(MISSION)
PLAN = MissionBattery(Battery(capacity_mah=3300, hover_current_a=28.0, reserve_pct=25),
                      (300.0,), (np.array([280.0, 150.0, 60.0]),))


def test_the_need_follows_the_current_item():
    seqs = [it.seq for it in MISSION]
    takeoff, first = 1, 2  # home, takeoff, the start point, DO_CHANGE_SPEED, ...
    assert PLAN.need_mah(0, takeoff, WAYPOINTS) == 300.0
    assert PLAN.need_mah(0, first, WAYPOINTS) == 300.0
    second = next(it.seq for it in MISSION if it.seq > 3 and it.command == 16)
    assert PLAN.need_mah(0, second, WAYPOINTS) == 280.0  # from the start point on
    assert PLAN.need_mah(0, seqs[-1], WAYPOINTS) == 60.0  # the landing


def test_preflight_needs_the_mission_and_the_reserve():
    assert preflight_problem(PLAN, 0, 35) is None  # 1155 >= 300 + 825
    why = preflight_problem(PLAN, 0, 30)
    assert why.startswith("battery at 30 % (990 of 3300 mAh)") and "1125 mAh (34 %)" in why
    assert "reports no battery" in preflight_problem(PLAN, 0, None)


def test_in_flight_less_than_the_rest_and_half_the_reserve_is_a_departure():
    watch = BatteryWatch(PLAN, [MISSION])
    landing = MISSION[-1].seq
    assert watch.check(0, 15, landing) is None  # 495 >= 60 + 412.5
    why = watch.check(0, 14, landing)
    assert why.startswith("14 % left (462 mAh): the rest of its mission needs 60 mAh")
    assert watch.check(0, None, landing) is None and watch.check(0, 1, -1) is None


# -- without a [battery]: each copter's own ----------------------------------------------

SITL_QUAD = CopterBattery.from_params({"BATT_MONITOR": 4, "BATT_CAPACITY": 3300,
                                       "BATT_LOW_MAH": 0, "BATT_CRT_MAH": 0,
                                       "BATT_FS_LOW_ACT": 0, "BATT_FS_CRT_ACT": 0})
CHARGE = MissionCharge(20.0, 100.0, 30.0, np.array([130.0, 80.0, 30.0]), 33.0)


def test_a_copter_keeps_its_own_floor_else_a_quarter_of_its_capacity():
    assert SITL_QUAD.reserve()[0] == 825.0 and "25 % of its BATT_CAPACITY" in SITL_QUAD.reserve()[1]
    low = CopterBattery(4, 5200.0, low_mah=1000.0, crt_mah=500.0)
    assert low.reserve() == (1000.0, "its BATT_LOW_MAH 1000 mAh")
    assert CopterBattery(4, 5200.0, crt_mah=500.0).reserve()[0] == 500.0
    # a value a copter did not answer is off, as ArduPilot's 0
    assert CopterBattery.from_params({"BATT_MONITOR": 4, "BATT_CAPACITY": None}).watched is False


def test_without_a_table_the_mission_is_charged_at_the_assumed_hover_and_refused_below():
    own = own_batteries([SITL_QUAD], [CHARGE])
    assert own.assumed_a[0] == 3.3 / (ASSUMED_HOVER_MIN / 60.0)
    assert own.preflight_problem(0, 30) is None  # 990 >= 150 + 825
    why = own.preflight_problem(0, 29)  # 957 < 975
    assert why.startswith("battery at 29 % (957 of 3300 mAh): its mission needs about 150 mAh "
                          "(33 s at 16.5 A, 12 minutes of hover")
    assert why.endswith("975 mAh (30 %)")


def test_a_copter_that_cannot_be_watched_is_said_not_refused():
    own = own_batteries([CopterBattery(0, 3300.0), CopterBattery(4, 0.0), SITL_QUAD],
                        [CHARGE] * 3)
    assert own.preflight_problem(0, 5) is None and "BATT_MONITOR 0" in own.unwatched(0, 5)
    assert own.preflight_problem(1, 5) is None and "no BATT_CAPACITY" in own.unwatched(1, 5)
    assert own.preflight_problem(2, None) is None and "reports no battery" in own.unwatched(2, None)
    assert own.unwatched(2, 50) is None


def test_in_flight_the_need_goes_with_the_current_the_copter_draws():
    own = own_batteries([SITL_QUAD], [CHARGE])
    watch = BatteryWatch(own, [MISSION])
    landing = MISSION[-1].seq
    # 30 mAh to land at 16.5 A assumed; 432 mAh (13 %) covers it and half of 825
    assert watch.check(0, 14, landing) is None
    # drawing twice that for 4 s (SITL's quad draws 28 A): the need doubles
    for k in range(41):
        watch.check(0, 14, landing, current_a=33.0, now=k * 0.1)
    assert watch.measured_a(0) == pytest.approx(33.0)
    why = watch.check(0, 13, landing, current_a=33.0, now=4.1)
    assert why == ("13 % left (429 mAh): the rest of its mission needs 60 mAh at the 33.0 A it "
                   "draws and it would land below half its reserve (25 % of its "
                   "BATT_CAPACITY, as no BATT_LOW_MAH is set)")
    # a monitor that measures no current (0 A reported) leaves the assumed current
    quiet = BatteryWatch(own, [MISSION])
    for k in range(41):
        quiet.check(0, 14, landing, current_a=0.0, now=k * 0.1)
    assert quiet.measured_a(0) is None
    # with the plan's [battery] the plan's model goes on: what it draws changes nothing
    planned = BatteryWatch(PLAN, [MISSION])
    for k in range(41):
        planned.check(0, 15, landing, current_a=80.0, now=k * 0.1)
    assert planned.check(0, 15, landing) is None


def test_its_own_low_battery_announced_with_no_action_is_a_departure():
    quiet = own_batteries([SITL_QUAD], [CHARGE])
    acting = own_batteries([CopterBattery(4, 3300.0, low_mah=1000.0, low_action=2)], [CHARGE])
    low, failsafe = "Battery 1 is low 12.60V used 2301 mAh", "Battery Failsafe"
    watch = BatteryWatch(quiet, [MISSION])
    assert watch.text_kind(0, low, None) == "battery"
    assert watch.text_kind(0, failsafe, "failsafe") == "battery"  # it flies on in AUTO
    watch = BatteryWatch(acting, [MISSION])  # its RTL is its own: a failsafe it chose
    assert watch.text_kind(0, low, None) is None
    assert watch.text_kind(0, failsafe, "failsafe") == "failsafe"
    # with the plan's [battery], as before
    assert BatteryWatch(PLAN, [MISSION]).text_kind(0, failsafe, "failsafe") == "failsafe"
