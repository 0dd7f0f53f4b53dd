"""ArduPilot's battery monitor (ftlbo_mav/ardupilot/battery.py): the failsafe types and
their order, the voltage timer, priorities, and BATTERY_RESET against the recording."""

from __future__ import annotations

import json
from pathlib import Path

from ftlbo_mav.ardupilot.battery import (
    ACTION_LAND,
    ACTION_NONE,
    ACTION_RTL,
    BATTERY_PARAM_DEFAULTS,
    CRITICAL,
    LOW,
    NONE,
    BatteryMonitor,
    remaining_pct,
)

DATA = json.loads((Path(__file__).resolve().parents[1] / "data" / "ardupilot-4.5.6"
                   / "battery.json").read_text())


def params(**changed) -> dict:
    return {name: d.value for name, d in BATTERY_PARAM_DEFAULTS.items()} | changed


def test_the_remaining_per_cent_is_whole_and_held_to_0_100():
    assert remaining_pct(3300, 1651) == 49  # recorded after a 50 % reset, drawing on
    assert remaining_pct(3300, 4000) == 0 and remaining_pct(3300, -10) == 100


def test_every_reset_gives_the_consumed_charge_sitl_reported():
    for r in DATA["battery_resets"]:
        if r["armed"]:
            continue  # drawing on while the next report is made
        b = BatteryMonitor()
        b.reset(r["param2_percent"], params(), 0.0)
        after = r["battery_status_after"]
        assert int(b.consumed_mah) == after["current_consumed"], r["label"]
        assert int(b.consumed_wh * 36) == after["energy_consumed"], r["label"]


def test_capacity_thresholds_act_at_once_and_critical_comes_first():
    p = params(BATT_LOW_MAH=1000, BATT_CRT_MAH=500, BATT_FS_LOW_ACT=ACTION_RTL,
               BATT_FS_CRT_ACT=ACTION_LAND)
    b = BatteryMonitor(consumed_mah=2301)
    assert b.check(p, 0.0, armed=False) is None  # only while armed
    text, action = b.check(p, 0.0, armed=True)
    assert text == "Battery 1 is low 12.60V used 2301 mAh" and action == ACTION_RTL
    assert b.check(p, 0.1, armed=True) is None  # reached: not again
    b.consumed_mah = 2801
    text, action = b.check(p, 0.2, armed=True)
    assert text.startswith("Battery 1 is critical") and action == ACTION_LAND
    assert b.failsafe == CRITICAL


def test_a_low_voltage_must_last_longer_than_the_timer():
    p = params(BATT_LOW_VOLT=11.0)
    b = BatteryMonitor(voltage=10.8)
    assert b.failsafe_type(p, 0.0) == NONE
    assert b.failsafe_type(p, 10.0) == NONE
    assert b.failsafe_type(p, 10.1) == LOW
    b.voltage = 11.5  # recovered: the timer starts again
    assert b.failsafe_type(p, 10.2) == NONE
    assert BatteryMonitor(voltage=10.8).failsafe_type(params(BATT_LOW_VOLT=11.0,
                                                             BATT_LOW_TIMER=0), 99) == NONE


def test_a_less_urgent_action_after_a_more_urgent_one_is_only_announced():
    p = params(BATT_LOW_MAH=1000, BATT_CRT_MAH=500, BATT_FS_LOW_ACT=ACTION_NONE,
               BATT_FS_CRT_ACT=ACTION_RTL)
    b = BatteryMonitor(consumed_mah=2900, highest_priority=1)  # a LAND taken before
    text, action = b.check(p, 0.0, armed=True)
    assert text.startswith("Battery 1 is critical") and action == -1


def test_a_reset_below_a_threshold_sets_the_state_silently():
    p = params(BATT_LOW_MAH=1980, BATT_FS_LOW_ACT=ACTION_RTL)
    b = BatteryMonitor()
    b.reset(50, p, 0.0)
    assert b.failsafe == LOW and b.charge_state() == 2
    assert b.check(p, 0.1, armed=True) is None
