"""A start gate opens by each copter's own clock of the day (AP_RTC, set once from its
first GPS fix): on ArduCopter 4.5.6 SITL copters began their GPS-time-gated legs up to
98 ms apart (tests/data/ardupilot-4.5.6/timed_starts.json, read from their DataFlash logs
with ``python -m sitl.truth``). The emulator's copters of a real fleet carry such a lag
(ftlbo_mav/ardupilot/rtc.py), and a gate opens that much later for them."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.commands import nav_delay_ms
from ftlbo_mav.ardupilot.rtc import RECORDED_BEGAN_AFTER_FIRST_MS, draw_rtc_lag_s
from ftlbo_mav.mission.items import CMD_NAV_DELAY, MissionItem
from ftlbo_mav.sim.physics import FlightLimits, varied
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions

RECORDED = json.loads((Path(__file__).resolve().parents[1] / "data" / "ardupilot-4.5.6"
                       / "timed_starts.json").read_text())["flights"]
HOME = (12.2332099, 109.1145051, 0.0)


def test_the_lags_drawn_are_the_recorded_copters():
    assert [tuple(f["began_after_first_ms"]) for f in RECORDED] == list(
        RECORDED_BEGAN_AFTER_FIRST_MS)
    recorded = {ms / 1000 for f in RECORDED for ms in f["began_after_first_ms"]}
    rng = np.random.default_rng(3)
    drawn = [draw_rtc_lag_s(rng) for _ in range(300)]
    assert set(drawn) <= recorded and len(set(drawn)) > 10
    assert max(drawn) == pytest.approx(0.098)


def test_a_copter_whose_clock_lags_opens_its_gate_that_much_later():
    """The same gate (second 30 of the minute), asked at the same GPS instant: a copter
    whose AP_RTC is 70 ms behind waits 70 ms longer, and reports that clock in SYSTEM_TIME."""
    gate = MissionItem(seq=3, command=CMD_NAV_DELAY, param1=-1, param2=-1, param3=-1,
                       param4=30)
    utc_at_boot = 1_765_000_000.250  # GPS time 0.25 s past a whole second
    waits, system_time = [], []
    for lag in (0.0, 0.07):
        v = Vehicle(sysid=1, home=HOME, utc_offset_s=utc_at_boot,
                    options=VehicleOptions(limits=FlightLimits(rtc_lag_s=lag)))
        waits.append(nav_delay_ms(gate, v.autopilot.utc_ms()))
        system_time.append(v.message(R.MAVLINK_MSG_ID_SYSTEM_TIME, 5.0).time_unix_usec)
    assert waits[1] - waits[0] == 70
    assert system_time[0] - system_time[1] == 70_000


def test_a_real_fleet_in_the_emulator_carries_the_recorded_lags():
    limits = [varied(FlightLimits(), np.random.default_rng([0, 0x7A, i])) for i in range(30)]
    lags = {round(x.rtc_lag_s * 1000) for x in limits}
    assert lags <= {ms for f in RECORDED for ms in f["began_after_first_ms"]}
    assert len(lags) > 5 and FlightLimits().rtc_lag_s == 0.0  # ArduPilot's own: recorded
