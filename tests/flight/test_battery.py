"""A vehicle's charge held to its mission (ftlbo_mav/flight/battery.py)."""

from __future__ import annotations

import numpy as np

from ftlbo_mav.energy import Battery
from ftlbo_mav.flight.battery import BatteryWatch, MissionBattery, preflight_problem, waypoint_seqs
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
