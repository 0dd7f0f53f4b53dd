"""The emulator's GPS error: a wander of the set size and correlation, the same whatever
the message timing; steps from SITL's own knobs; what each message reports (the estimate
in GLOBAL_POSITION_INT and GPS_RAW_INT with its fix and accuracy, the truth in
SIM_STATE)."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.gps import SITL_GPS_ACCURACY_M
from ftlbo_mav.geo import LocalFrame
from ftlbo_mav.sim.gps import METRES_PER_DEGREE, GpsError, GpsErrorOptions
from ftlbo_mav.sim.vehicle import Vehicle, VehicleOptions

HOME = (12.2332099, 109.1145051, 0.0)


def test_the_wander_has_its_size_and_correlation():
    g = GpsError(GpsErrorOptions(wander_m=0.7, correlation_s=30.0, seed=3), {})
    t = np.arange(0.0, 40_000.0, 1.0)
    e = np.array([g.error(x) for x in t])
    assert e.std(axis=0) == pytest.approx([0.7, 0.7], rel=0.1)
    lag = 30
    rho = np.corrcoef(e[:-lag, 0], e[lag:, 0])[0, 1]
    assert rho == pytest.approx(np.exp(-1.0), abs=0.08)


def test_the_wander_is_the_same_whatever_the_order_it_is_asked_in():
    a = GpsError(GpsErrorOptions(wander_m=1.0, seed=5), {})
    b = GpsError(GpsErrorOptions(wander_m=1.0, seed=5), {})
    times = [0.3, 17.2, 5.5, 100.0]
    first = [a.error(t) for t in times]
    [b.error(t) for t in sorted(times, reverse=True)]
    assert np.allclose(first, [b.error(t) for t in times])
    other = GpsError(GpsErrorOptions(wander_m=1.0, seed=6), {})
    assert not np.allclose(first, [other.error(t) for t in times])


def test_sim_gps_glitch_is_a_step_that_the_copter_flies_out_of():
    params = {"SIM_GPS_GLITCH_X": 0.0, "SIM_GPS_GLITCH_Y": 0.0}
    g = GpsError(GpsErrorOptions(), params, lat_deg=HOME[0])
    params["SIM_GPS_GLITCH_X"] = 3.0 / METRES_PER_DEGREE
    g.param_changed(10.0)
    assert np.allclose(g.error(9.9), 0) and np.allclose(g.error(10.0), [0.0, 3.0])
    assert np.allclose(g.transient(10.0), [0.0, 3.0])
    assert np.allclose(g.transient(20.0), [0.0, 3.0 * np.exp(-10.0 / g.response_s)])


def _vehicle(**gps) -> Vehicle:
    return Vehicle(sysid=1, home=HOME, options=VehicleOptions(gps=GpsErrorOptions(**gps)))


def _en(v: Vehicle, msg, frame: LocalFrame) -> np.ndarray:
    lat, lon = (msg.lat_int, msg.lon_int) if msg.get_type() == "SIM_STATE" else (msg.lat,
                                                                                 msg.lon)
    return frame.to_enu(lat_deg=lat * 1e-7, lon_deg=lon * 1e-7)[:2]


def test_gps_raw_int_reports_sitls_fix_and_accuracy_until_told_otherwise():
    v = _vehicle()
    raw = v.message(R.MAVLINK_MSG_ID_GPS_RAW_INT, 30.0)
    assert raw.fix_type == 6 and raw.h_acc == round(SITL_GPS_ACCURACY_M * 1000)
    v.autopilot.set_param("SIM_GPS_ACC", 1.5)
    assert v.message(R.MAVLINK_MSG_ID_GPS_RAW_INT, 31.0).h_acc == 1500
    three_d = _vehicle(fix_type=3, satellites=7).message(R.MAVLINK_MSG_ID_GPS_RAW_INT, 30.0)
    assert (three_d.fix_type, three_d.satellites_visible) == (3, 7)
    ekf = v.message(R.MAVLINK_MSG_ID_EKF_STATUS_REPORT, 30.0)
    assert ekf.flags & R.EKF_POS_HORIZ_ABS and ekf.pos_horiz_variance < 0.8


def test_the_estimate_is_where_it_flies_the_truth_is_off_by_the_error():
    v = _vehicle(wander_m=1.0, seed=2)
    frame = LocalFrame(origin_lat_deg=HOME[0], origin_lon_deg=HOME[1])
    t = 60.0
    est = _en(v, v.message(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, t), frame)
    raw = _en(v, v.message(R.MAVLINK_MSG_ID_GPS_RAW_INT, t), frame)
    true = _en(v, v.message(R.MAVLINK_MSG_ID_SIM_STATE, t), frame)
    assert np.allclose(est, 0.0, atol=0.01) and np.allclose(raw, est, atol=0.01)
    assert np.allclose(est - true, v.gps.error(t - v.boot_time), atol=0.02)


def test_home_is_where_it_believed_it_was_when_it_armed_and_rtl_lands_it_there():
    """ArduCopter/AP_Arming.cpp AP_Arming_Copter::arm: home (not locked) is reset to the
    current location, the estimate. A copter whose GPS reads 1 m east of where it stands
    arms with home 1 m east of its boot position; RTL brings its estimate back there,
    which is where it truly took off."""
    from ftlbo_mav.sim.modes.common import GUIDED, RTL

    gps = GpsErrorOptions(glitches=((0.0, 1.0, 0.0),))  # 1 m east from boot on
    v = Vehicle(sysid=1, home=HOME, boot_time=0.0, options=VehicleOptions(gps=gps))
    ap = v.autopilot
    t = 0.0
    while t < 30.0:  # on the ground while EKF3 takes the error up (about 5 s)
        t += 0.05
        v.tick(t)
    assert ap.set_mode(GUIDED, t) and ap.arm(t) is None
    v.tick(t)
    home = v.message(R.MAVLINK_MSG_ID_HOME_POSITION, t)
    est = v.message(R.MAVLINK_MSG_ID_GLOBAL_POSITION_INT, t)
    assert (home.latitude, home.longitude) == (est.lat, est.lon)
    frame = LocalFrame(*HOME[:2])
    east = frame.to_enu(lat_deg=[home.latitude * 1e-7], lon_deg=[home.longitude * 1e-7])[0, 0]
    assert east == pytest.approx(1.0, abs=0.03)
    ap.takeoff(4.0)
    while ap.position[2] < 3.9:
        t += 0.05
        v.tick(t)
    assert ap.goto(np.array([20.0, 5.0, 4.0]))
    while np.linalg.norm(ap.position - [20.0, 5.0, 4.0]) > 0.05:
        t += 0.05
        v.tick(t)
    assert ap.set_mode(RTL, t)
    while ap.armed and t < 300.0:
        t += 0.05
        v.tick(t)
    assert not ap.armed
    truth = v.message(R.MAVLINK_MSG_ID_SIM_STATE, t)
    landed = frame.to_enu(lat_deg=[truth.lat_int * 1e-7], lon_deg=[truth.lon_int * 1e-7])[0]
    assert np.hypot(*landed[:2]) < 0.05  # where it truly took off
