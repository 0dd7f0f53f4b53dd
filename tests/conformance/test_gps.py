"""The emulator's GPS against ArduCopter 4.5.6 SITL (tests/data/ardupilot-4.5.6/gps.json):
what GPS_RAW_INT and EKF_STATUS_REPORT report, SIM_GPS_ACC as the accuracy, and a 3 m
SIM_GPS_GLITCH_X step: the receiver's reading jumps at once, the EKF's estimate follows
over seconds (the truth stays; in flight the controller holds the estimate, so the truth
moves instead)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.sim.vehicle import EKF_HEALTHY_FLAGS, Vehicle

DATA = json.loads((Path(__file__).resolve().parents[1] / "data" / "ardupilot-4.5.6"
                   / "gps.json").read_text())
HOME = (12.2332099, 109.1145051, 0.0)
M_PER_E7 = 0.0111319  # metres north per 1e-7 degree


def _of(kind: str) -> list[dict]:
    return [s for s in DATA["samples"] if s["type"] == kind]


def _recorded_north(kind: str, field: str = "lat") -> tuple[np.ndarray, np.ndarray]:
    rows = _of(kind)
    return np.array([r["t"] for r in rows]), np.array([r[field] for r in rows], float)


def test_fix_accuracy_satellites_and_ekf_flags_are_sitls():
    raw = _of("GPS_RAW_INT")
    v = Vehicle(sysid=1, home=HOME)
    ours = v.message(R.MAVLINK_MSG_ID_GPS_RAW_INT, 30.0)
    assert (ours.fix_type, ours.satellites_visible, ours.h_acc) == (
        raw[0]["fix_type"], raw[0]["satellites_visible"], raw[0]["h_acc"])
    set_at = next(e["t"] for e in DATA["events"] if e["param_set"] == "SIM_GPS_ACC")
    after = next(r for r in raw if r["t"] > set_at + 0.5)
    v.autopilot.set_param("SIM_GPS_ACC", 1.5)
    assert v.message(R.MAVLINK_MSG_ID_GPS_RAW_INT, 31.0).h_acc == after["h_acc"] == 1500
    assert _of("EKF_STATUS_REPORT")[-1]["flags"] == EKF_HEALTHY_FLAGS


def test_a_glitch_jumps_the_reading_and_the_estimate_follows_as_ekf3_does():
    on, off = (e["t"] for e in DATA["events"] if e["param_set"] == "SIM_GPS_GLITCH_X")
    t_true, true = _recorded_north("SIM_STATE", "lat_int")
    t_est, est = _recorded_north("GLOBAL_POSITION_INT")
    t_raw, raw = _recorded_north("GPS_RAW_INT")
    base = np.interp(on - 0.5, t_true, true)
    v = Vehicle(sysid=1, home=HOME, boot_time=0.0)
    v.autopilot.params["SIM_GPS_GLITCH_X"] = 3.0 / (M_PER_E7 * 1e7)
    v.gps.param_changed(on)
    for t in np.arange(on + 0.5, off, 0.5):  # after the first report of the step
        truth = v.message(R.MAVLINK_MSG_ID_SIM_STATE, t).lat_int
        ours_est = (v.message(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, t).lat - truth) * M_PER_E7
        ours_raw = (v.message(R.MAVLINK_MSG_ID_GPS_RAW_INT, t).lat - truth) * M_PER_E7
        sitl_est = (np.interp(t, t_est, est) - base) * M_PER_E7
        sitl_raw = (np.interp(t, t_raw, raw) - base) * M_PER_E7
        assert abs(ours_raw - sitl_raw) < 0.05, t  # the reading: the whole step at once
        assert abs(ours_est - sitl_est) < 0.35, (t, ours_est, sitl_est)  # the EKF's lag
    assert np.interp(off - 0.1, t_true, true) == base  # SITL's truth never moved


def test_on_the_ground_the_estimate_moves_and_the_truth_stays_as_on_sitl():
    on, off = (e["t"] for e in DATA["events"] if e["param_set"] == "SIM_GPS_GLITCH_X")
    t_true, true = _recorded_north("SIM_STATE", "lat_int")
    t_est, est = _recorded_north("GLOBAL_POSITION_INT")
    v = Vehicle(sysid=1, home=HOME, boot_time=0.0)
    v.tick(on - 0.5)
    truth0 = v.message(R.MAVLINK_MSG_ID_SIM_STATE, on - 0.5).lat_int
    est0 = v.message(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, on - 0.5).lat
    v.autopilot.params["SIM_GPS_GLITCH_X"] = 3.0 / (M_PER_E7 * 1e7)
    v.gps.param_changed(on)
    base_true, base_est = np.interp(on - 0.5, t_true, true), np.interp(on - 0.5, t_est, est)
    for t in np.arange(on + 0.5, off, 0.5):
        v.tick(t)
        assert v.message(R.MAVLINK_MSG_ID_SIM_STATE, t).lat_int == truth0  # as SITL's
        moved = (v.message(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, t).lat - est0) * M_PER_E7
        sitl_moved = (np.interp(t, t_est, est) - base_est) * M_PER_E7
        assert abs(moved - sitl_moved) < 0.35, (t, moved, sitl_moved)
    assert np.interp(off - 0.1, t_true, true) == base_true


def test_a_copter_placed_at_home_believes_it_is_at_home_plus_its_gps_error():
    from ftlbo_mav.sim.gps import GpsErrorOptions
    from ftlbo_mav.sim.vehicle import VehicleOptions

    v = Vehicle(sysid=1, home=HOME, boot_time=0.0,
                options=VehicleOptions(gps=GpsErrorOptions(wander_m=1.0, seed=3)))
    v.tick(20.0)
    error = v.gps.error(20.0)
    truth = v.message(R.MAVLINK_MSG_ID_SIM_STATE, 20.0)
    est = v.message(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, 20.0)
    assert abs(truth.lat_int - round(HOME[0] * 1e7)) <= 1
    assert abs((est.lat - truth.lat_int) * M_PER_E7 - error[1]) < 0.02
    assert np.hypot(*error) > 0.1  # the draw is not a zero error
