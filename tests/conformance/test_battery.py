"""The emulator's battery against ArduCopter 4.5.6 SITL (tests/data/ardupilot-4.5.6/
battery.json, ``python -m sitl.battery``): the parameters, MAV_CMD_BATTERY_RESET and what
BATTERY_STATUS says after it, the current SITL's quad draws hovering and cruising, the
charge a hover uses, and the low and critical failsafes: the text, when it comes, and the
mode taken."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.sim.modes.common import GUIDED, LAND, RTL
from ftlbo_mav.sim.vehicle import Vehicle

DATA = json.loads((Path(__file__).resolve().parents[1] / "data" / "ardupilot-4.5.6"
                   / "battery.json").read_text())
HOME = (12.2332099, 109.1145051, 0.0)
RESET = R.MAV_CMD_BATTERY_RESET
FIELDS = ("current_consumed", "energy_consumed", "battery_remaining", "voltages0",
          "time_remaining", "charge_state")


def _reset(label: str) -> dict:
    return next(r for r in DATA["battery_resets"] if r["label"].startswith(label))


def _status(v: Vehicle, t: float) -> dict:
    m = v.message(R.MAVLINK_MSG_ID_BATTERY_STATUS, t)
    return {"current_consumed": m.current_consumed, "energy_consumed": m.energy_consumed,
            "battery_remaining": m.battery_remaining, "voltages0": m.voltages[0],
            "time_remaining": m.time_remaining, "charge_state": m.charge_state}


class Flight:
    """One emulated copter flown offline, as the recording flew SITL's."""

    def __init__(self) -> None:
        self.v = Vehicle(sysid=1, home=HOME, boot_time=0.0)
        self.ap = self.v.autopilot
        self.t = 30.0
        self.texts: list[tuple[float, str]] = []
        self.run(30.0)

    def run(self, seconds: float, step: float = 0.02) -> None:
        end = self.t + seconds
        while self.t < end - 1e-9:
            self.t += step
            for m in self.ap.advance(self.t):
                if m.get_type() == "STATUSTEXT":
                    self.texts.append((self.t, m.text))

    def take_off(self, alt_m: float = 10.0) -> None:
        assert self.ap.set_mode(GUIDED, self.t) and self.ap.arm(self.t) is None
        assert self.ap.command(R.MAV_CMD_NAV_TAKEOFF, [0] * 6 + [alt_m], self.t)[0] == 0
        self.run(15.0)

    def current_a(self) -> float:
        return self.v.message(R.MAVLINK_MSG_ID_SYS_STATUS, self.t).current_battery / 100.0


def test_the_battery_parameters_are_sitls_with_copter_parm():
    ap = Vehicle(sysid=1, home=HOME).autopilot
    for name in ("BATT_MONITOR", "BATT_CAPACITY", "BATT_LOW_MAH", "BATT_CRT_MAH",
                 "BATT_LOW_VOLT", "BATT_CRT_VOLT", "BATT_FS_LOW_ACT", "BATT_FS_CRT_ACT",
                 "BATT_LOW_TIMER"):
        assert ap.get_param(name)[0] == pytest.approx(DATA["params_after_boot"][name]), name


def test_a_reset_on_the_ground_is_what_battery_status_says_after_it():
    f = Flight()
    recorded = _reset("b:")
    assert f.ap.command(RESET, [1, 60, 0, 0, 0, 0, 0], f.t)[0] == recorded["result"]
    assert _status(f.v, f.t) == {k: recorded["battery_status_after"][k] for k in FIELDS}


def test_a_reset_below_the_low_threshold_while_armed_is_silent_as_on_sitl():
    """AP_BattMonitor_Backend::reset_remaining sets the failsafe state itself: charge
    state LOW, no text, no mode change (recorded for 15 s)."""
    f = Flight()
    f.take_off()
    f.ap.set_param("BATT_LOW_MAH", 1980)
    f.ap.set_param("BATT_FS_LOW_ACT", 2)
    recorded = _reset("f: armed, below")
    assert DATA["failsafes"][0]["fired"] is False
    f.ap.command(RESET, [1, 50, 0, 0, 0, 0, 0], f.t)
    f.run(recorded["battery_status_after"]["t"] - recorded["t_sent"])  # hovering on
    status = _status(f.v, f.t)
    assert status["current_consumed"] == recorded["battery_status_after"]["current_consumed"]
    assert status["charge_state"] == recorded["battery_status_after"]["charge_state"] == 2
    assert status["battery_remaining"] == recorded["battery_status_after"]["battery_remaining"]
    before = len(f.texts)
    f.run(15.0)
    assert f.texts[before:] == [] and f.ap.mode == GUIDED


def test_hover_and_cruise_draw_sitls_current_and_a_hover_uses_its_charge():
    s = DATA["summary"]
    f = Flight()
    assert f.current_a() == 0.0 == s["disarmed_ground"]["median_sys_status_current_A"]
    f.take_off()
    hover = s["current_hover_10m"]["median_sys_status_current_A"]
    assert f.current_a() == pytest.approx(hover, abs=0.05)
    before = f.ap.battery.consumed_mah
    f.run(20.0)
    used = f.ap.battery.consumed_mah - before
    assert used == pytest.approx(s["mAh_per_phase"]["c_hover_20s"]["current_consumed_delta_mAh"],
                                 abs=3)
    f.ap.goto(f.ap.position + np.array([0.0, 100.0, 0.0]))
    speeds, amps = [], []
    for _ in range(200):
        f.run(0.1)
        speeds.append(float(np.hypot(*f.ap.velocity[:2])))
        amps.append(f.current_a())
    fast = np.array(speeds) >= 0.9 * max(speeds)
    cruise = s["current_cruise_at_speed"]["median_sys_status_current_A"]
    assert np.median(np.array(amps)[fast]) == pytest.approx(cruise, rel=0.02)


@pytest.mark.parametrize("which", ["low", "critical"])
def test_a_battery_running_low_in_flight_warns_and_takes_its_action_as_on_sitl(which):
    """Reset just above the threshold, as the recording did: the consumption crosses it
    about ten seconds later; the text, then "Battery Failsafe", and RTL (low, action 2)
    or LAND (critical, action 1) at that moment."""
    failsafe = next(x for x in DATA["failsafes"] if x["label"].startswith(which + ": consumption"))
    f = Flight()
    f.take_off()
    if which == "low":
        f.ap.set_param("BATT_LOW_MAH", 1980)
        f.ap.set_param("BATT_FS_LOW_ACT", 2)
        percent, mode = 62.367, RTL
    else:
        f.ap.set_param("BATT_CRT_MAH", 990)
        f.ap.set_param("BATT_FS_CRT_ACT", 1)
        percent, mode = 32.367, LAND
    t0, before = f.t, len(f.texts)
    f.ap.command(RESET, [1, percent, 0, 0, 0, 0, 0], f.t)
    f.run(12.0)
    (t_low, low), (t_fs, fs) = f.texts[before:before + 2]
    recorded = failsafe["text"]["text"]

    def words(text: str) -> str:
        return re.sub(r"used \d+ mAh", "used N mAh", text)

    def used(text: str) -> int:
        return int(re.search(r"used (\d+) mAh", text).group(1))

    assert words(low) == words(recorded) and abs(used(low) - used(recorded)) <= 3, low
    assert fs == "Battery Failsafe"
    assert t_low - t0 == pytest.approx(failsafe["text_after_reset_s"], abs=0.3)
    taken = failsafe["mode_changes_after_reset"][0]
    assert f.ap.mode == mode == {"RTL": RTL, "LAND": LAND}[taken["mode"]]
    assert t_fs == t_low and taken["after_reset_s"] == pytest.approx(t_low - t0, abs=0.3)
