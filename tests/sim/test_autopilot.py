"""The emulated copter's flight state machine, without sockets."""

import numpy as np
import pytest

from ftlbo_mav.ardupilot.commands import BootTimeline
from ftlbo_mav.mission.items import build_mission
from ftlbo_mav.sim.autopilot import Autopilot, AutopilotOptions, LocalTangent
from ftlbo_mav.sim.modes.common import AUTO, GUIDED, LAND, RTL
from ftlbo_mav.sim.physics import FlightLimits, varied

HOME = (12.2332099, 109.1145051)


def _mission(end="land"):
    t = LocalTangent(*HOME)
    points = [(0, 0, 4), (10, 0, 4), (10, 10, 5), (20, 10, 4)]
    path = [(*t.to_latlon(e, n), a) for e, n, a in points]
    return build_mission(home=HOME, takeoff_alt_m=4.0, path=path, end_action=end), points


def _run(ap, t, until, dt=0.1, limit=300.0):
    log = []
    while not until(ap) and t < limit:
        t += dt
        log += ap.advance(t)
    return t, log


def test_arming_waits_for_the_boot_timeline_and_modes_change_freely_while_disarmed():
    boot = BootTimeline(ready_s=0.5, storage_s=0.5, gps_fix_s=1.0, home_s=2.0, prearm_s=4.0,
                        armable_s=5.0)
    ap = Autopilot(home=HOME, boot_time=0.0, options=AutopilotOptions(boot=boot))
    assert [t for _, t in ap.arm(1.0)] == ["Arm: AHRS: waiting for home"]
    assert [t for _, t in ap.arm(3.0)] == ["Arm: Need Position Estimate"]
    assert ap.set_mode(GUIDED, 3.0)  # disarmed: Copter::set_mode skips its checks
    assert ap.arm(5.0) is None and ap.armed


def test_guided_takeoff_then_auto_flies_the_mission_and_lands_at_the_goal():
    items, points = _mission()
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mission(items)
    assert not ap.takeoff(4.0)  # not armed yet
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    assert ap.takeoff(4.0)
    t, _ = _run(ap, 0.0, lambda a: abs(a.position[2] - 4.0) < 0.05, dt=0.02)
    assert np.allclose(ap.position[:2], 0, atol=1e-6)
    assert ap.set_current(2) and ap.set_mode(AUTO, t)
    t, log = _run(ap, t, lambda a: not a.armed)
    reached = [m.seq for m in log if m.get_type() == "MISSION_ITEM_REACHED"]
    assert reached == [2, 3, 4, 5, 6]  # the landing ends in the disarm, not a reached item
    texts = [m.text for m in log if m.get_type() == "STATUSTEXT"]
    # the start gate without a clock (no GPS time): no delay
    assert texts == ["Mission: 2 WP", "Reached command #2", "Mission: 3 Delay",
                     "Delaying 0 sec", "Mission: 4 WP",
                     "Reached command #4", "Mission: 5 WP", "Reached command #5",
                     "Mission: 6 WP", "Reached command #6", "Mission: 7 Land",
                     "Disarming motors", "Mission: 1 Takeoff"]
    assert np.allclose(ap.position, [20, 10, 0], atol=0.05)
    assert ap.current == 1


def test_guided_takeoff_leaves_the_ground_after_about_three_seconds_and_climbs_under_2_m_s():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    assert ap.takeoff(6.0, 0.0)
    t, climb, liftoff, ninety, peak, trough = 0.0, 0.0, None, None, 0.0, 9.0
    while t < 12.0:
        t += 0.02
        ap.advance(t)
        climb = max(climb, ap.velocity[2])
        peak = max(peak, ap.position[2])
        if t > 9.0:
            trough = min(trough, ap.position[2])
        if liftoff is None and ap.position[2] >= 0.1:
            liftoff = t
        if ninety is None and ap.position[2] >= 5.4:
            ninety = t
    # flight.json: 0.1 m up 3.29 s after NAV_TAKEOFF, 90 % at 6.99 s, climb up to 1.96 m/s
    assert 2.7 <= liftoff <= 3.4
    assert ninety == pytest.approx(6.99, abs=0.7)
    assert 1.7 <= climb <= 2.2
    # the copter behind its target overshoots and comes back below it (4.5.6 / 4.6.3:
    # 6.049 / 6.023 m, then 5.974 / 5.975 m near 9.6 s), then settles on it
    assert 6.01 <= peak <= 6.06
    assert 5.96 <= trough <= 5.99
    assert ap.position[2] == pytest.approx(6.0, abs=0.01)


def test_rtl_climbs_returns_home_waits_and_lands():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(4.0)
    t, _ = _run(ap, 0.0, lambda a: a.position[2] > 3.9, dt=0.02)
    assert ap.goto(np.array([20.0, 5.0, 4.0]))
    t, _ = _run(ap, t, lambda a: np.linalg.norm(a.position - [20, 5, 4]) < 0.01)
    assert ap.set_mode(RTL, t)
    peak, at_home = 0.0, None

    def home_and_down(a):
        nonlocal peak, at_home
        peak = max(peak, a.position[2])
        if at_home is None and np.linalg.norm(a.position[:2]) < 0.3 and a.position[2] > 14.9:
            at_home = a.time  # back over home at RTL_ALT (passing it: the copter overshoots)
        return not a.armed

    t_end, _ = _run(ap, t, home_and_down)
    assert peak == pytest.approx(15.0, abs=0.01)  # RTL_ALT
    assert np.allclose(ap.position, 0, atol=0.01)
    # RTL_LOIT_TIME 5 s at home, then 15 m down (1.5 m/s above LAND_ALT_LOW, then
    # LAND_SPEED) and the land detector
    assert t_end - at_home > 5.0 + 5.0 / 1.5 + 10 / 0.5


def test_land_mode_descends_where_it_is_at_land_speed_and_disarms_after_touchdown():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(3.0)
    t, _ = _run(ap, 0.0, lambda a: a.position[2] > 2.95, dt=0.02)
    ap.set_mode(LAND, t)
    rates = []

    def down(a):
        rates.append(-a.velocity[2])
        return a.position[2] <= 0.0

    t1, _ = _run(ap, t, down, dt=0.02)
    assert max(rates) == pytest.approx(0.475, abs=0.01)  # recorded 0.46-0.48 m/s
    t2, _ = _run(ap, t1, lambda a: not a.armed, dt=0.02)
    assert t2 - t1 == pytest.approx(2.1, abs=0.05)  # touchdown to disarm, recorded


def test_auto_disarm_on_the_ground():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.advance(9.0)
    assert ap.armed
    ap.advance(10.5)
    assert not ap.armed


def test_parameters_are_arducopters_and_wpnav_speed_applies_in_flight():
    ap = Autopilot(home=HOME, boot_time=0.0)
    assert ap.get_param("WPNAV_SPEED") == (1000.0, 9)
    assert ap.get_param("LAND_ALT_LOW") == (1000.0, 4)
    assert ap.get_param("NO_SUCH_PARAM") is None
    assert not ap.set_param("WPNAV_SPEED", float("nan"))
    assert ap.set_param("RTL_ALT", 2000.7) and ap.get_param("RTL_ALT")[0] == 2000.0  # INT32
    assert ap.nav_params().rtl_alt == 20.0


def test_local_tangent_round_trip_and_scale():
    t = LocalTangent(*HOME)
    lat, lon = t.to_latlon(30.0, -20.0)
    assert np.allclose(t.to_en(lat, lon), (30.0, -20.0))
    # 1e-5 degree of latitude is about 1.106 m at 12 degrees north
    assert t.to_en(HOME[0] + 1e-5, HOME[1])[1] == pytest.approx(1.1061, abs=1e-3)


def test_the_start_gate_holds_until_its_second_of_gps_time():
    """ModeAuto::do_nav_delay with the second of the minute (AP_RTC::get_time_utc): the
    copter holds where it is and begins the next leg on the first step after that
    second; "Delaying N sec" says the whole seconds."""
    from dataclasses import replace

    items, _ = _mission()
    gate = 3
    items = [replace(it, param4=37.0) if it.seq == gate else it for it in items]
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.utc_offset_s = 1_764_936_000.0 + 20.25  # its clock reads hh:mm:20.25 at t = 0
    ap.set_mission(items)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(4.0)
    # hovering (a copter still climbing would hold its stopping point above itself)
    t, _ = _run(ap, 0.0, lambda a: abs(a.position[2] - 4.0) < 0.05
                and abs(a.velocity[2]) < 0.005, dt=0.02)
    ap.set_current(gate)
    ap.set_mode(AUTO, t)
    t_auto = t
    at_start = ap.position.copy()
    t, log = _run(ap, t, lambda a: a.current > gate, dt=0.005)
    due = 37.0 - 20.25  # the copter's seconds at which its clock reads :37
    assert due < t <= due + 0.01
    assert np.allclose(ap.position, at_start, atol=0.02)  # held there until then
    texts = [m.text for m in log if m.get_type() == "STATUSTEXT"]
    assert texts[:2] == ["Mission: 3 Delay", f"Delaying {int(due - t_auto)} sec"]
    assert [m.seq for m in log if m.get_type() == "MISSION_ITEM_REACHED"] == [gate]


def _mission_seconds(ap: Autopilot) -> float:
    """GUIDED takeoff, then AUTO from item 2 until item 5: the seconds it flew."""
    items, _ = _mission()
    ap.set_mission(items)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(4.0)
    t0, _ = _run(ap, 0.0, lambda a: abs(a.position[2] - 4.0) < 0.05, dt=0.02)
    ap.set_current(2)
    ap.set_mode(AUTO, t0)
    t, _ = _run(ap, t0, lambda a: a.current >= 5, dt=0.02)
    return t - t0


def test_the_copter_flies_with_the_wpnav_values_it_holds():
    default = _mission_seconds(Autopilot(home=HOME, boot_time=0.0))
    brisk = Autopilot(home=HOME, boot_time=0.0)
    assert brisk.set_param("WPNAV_ACCEL", 500.0) and brisk.set_param("WPNAV_JERK", 5.0)
    assert brisk.get_param("WPNAV_ACCEL") == (500.0, 9)
    assert _mission_seconds(brisk) < 0.8 * default  # 10 m legs: jerk-limited


def test_a_varied_airframe_holds_the_fleets_parameters_and_flies_a_little_differently():
    varied_ = varied(FlightLimits(), np.random.default_rng(1))
    ap = Autopilot(home=HOME, boot_time=0.0, options=AutopilotOptions(limits=varied_))
    assert ap.get_param("WPNAV_JERK") == (1.0, 9)
    assert ap.nav_params().wp_jerk == pytest.approx(varied_.jerk_factor)
