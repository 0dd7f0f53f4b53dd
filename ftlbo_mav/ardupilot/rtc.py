"""ArduPilot's clock of the day (AP_RTC), by which a start gate opens: set once, from the
first GPS fix, and a few tens of milliseconds behind GPS time on some copters.

- **Set once.** ``AP_GPS::update_instance`` hands AP_RTC the time of every 3D fix
  (``AP_RTC::set_utc_usec(time_epoch_usec(), SOURCE_GPS)``), but ``set_utc_usec`` returns
  at once when ``type >= rtc_source_type``: after the first GPS time it takes no other
  (libraries/AP_RTC/AP_RTC.cpp, ArduCopter 4.5.6). From then on the clock runs on the
  flight controller's own microseconds, ``rtc_shift`` fixed.
- **Behind by what that fix's message was.** ``AP_GPS::time_epoch_usec`` is the fix's GPS
  time plus the time since its message was taken in (libraries/AP_GPS/AP_GPS.cpp); the
  time between the fix and its message reaching the driver is not in it, so the clock is
  behind GPS time by that much, a different amount on every copter and every boot.
- **What it moves.** A start gate (MAV_CMD_NAV_DELAY with a time of day,
  ``ModeAuto::do_nav_delay`` -> ``AP_RTC::get_time_utc``, ArduCopter/mode_auto.cpp) opens
  when that clock reads the time: a copter whose clock is 70 ms behind begins its legs
  70 ms after the others, 0.35 m behind its slot at 5 m/s. SYSTEM_TIME reports the same
  clock (``GCS_MAVLINK::send_system_time``).

Measured on ArduCopter 4.5.6 SITL (copter.parm, three copters, legs begun at one GPS
time): :data:`RECORDED_BEGAN_AFTER_FIRST_MS`, when each copter truly began its legs
after the first of its flight (``python -m sitl.truth``: SIM2's true motion on GPS time,
fifteen flights of 2026-12-07 kept by ``benchmarks/flight.py --keep``; held in
``tests/data/ardupilot-4.5.6/timed_starts.json``). The emulator's copters of a real fleet
(``vary``) draw their lag from them (:func:`draw_rtc_lag_s`).
"""

from __future__ import annotations

import numpy as np

RECORDED_BEGAN_AFTER_FIRST_MS: tuple[tuple[int, int, int], ...] = (
    (13, 0, 3), (37, 10, 0), (12, 0, 2), (0, 10, 10), (3, 0, 75),  # good-day radio
    (2, 0, 0), (0, 2, 70), (35, 0, 30), (5, 0, 0), (3, 0, 5),      # rough-day radio
    (15, 10, 0), (0, 15, 0), (70, 10, 0), (0, 45, 27), (98, 0, 17),  # 5 m/s wind, TCP
)
"""Per flight, how many milliseconds after its first copter each of the three truly
began its GPS-time-gated legs (module notes)."""


def draw_rtc_lag_s(rng: np.random.Generator) -> float:
    """How far one copter's AP_RTC is behind GPS time, seconds: one of the recorded
    copters' lags, drawn (:data:`RECORDED_BEGAN_AFTER_FIRST_MS`; the first of each flight
    counts as 0, so the draws are lags behind the earliest, as the recordings are)."""
    lags = np.array(RECORDED_BEGAN_AFTER_FIRST_MS, float).ravel()
    return float(rng.choice(lags)) / 1000.0
