"""The emulated copter's flight state machine, without sockets."""

import numpy as np
import pytest

from ftlbo_mav.ardupilot.commands import BootTimeline
from ftlbo_mav.mission.items import build_mission
from ftlbo_mav.sim.autopilot import (
    AUTO,
    GUIDED,
    LAND,
    RTL,
    Autopilot,
    AutopilotOptions,
    LocalTangent,
)
from ftlbo_mav.sim.physics import FlightLimits, step_towards

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
    t, _ = _run(ap, 0.0, lambda a: abs(a.position[2] - 4.0) < 0.02)
    assert np.allclose(ap.position[:2], 0, atol=1e-6)
    assert ap.set_current(2) and ap.set_mode(AUTO, t)
    t, log = _run(ap, t, lambda a: not a.armed)
    reached = [m.seq for m in log if m.get_type() == "MISSION_ITEM_REACHED"]
    assert reached == [2, 3, 4, 5, 6]
    texts = [m.text for m in log if m.get_type() == "STATUSTEXT"]
    assert texts == ["Mission: 2 WP", "Mission: 3 WP", "Mission: 4 WP", "Mission: 5 WP",
                     "Mission: 6 Land", "Land complete", "Disarming motors"]
    assert np.allclose(ap.position, [20, 10, 0], atol=0.15)
    assert not ap.armed and any(m.get_type() == "STATUSTEXT" for m in log)


def test_rtl_climbs_returns_home_and_lands():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(4.0)
    ap._target = np.array([20.0, 5.0, 4.0])
    t, _ = _run(ap, 0.0, lambda a: np.linalg.norm(a.position - [20, 5, 4]) < 0.05)
    assert ap.set_mode(RTL, t)
    peak = 0.0

    def home_and_down(a):
        nonlocal peak
        peak = max(peak, a.position[2])
        return not a.armed

    _run(ap, t, home_and_down)
    assert peak == pytest.approx(15.0, abs=0.2)
    assert np.allclose(ap.position, 0, atol=0.15)


def test_land_mode_descends_where_it_is():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.takeoff(3.0)
    t, _ = _run(ap, 0.0, lambda a: a.position[2] > 2.99)
    ap.set_mode(LAND, t)
    t2, _ = _run(ap, t, lambda a: not a.armed)
    assert t2 - t == pytest.approx(3.0 / 0.5, abs=0.5)  # LAND_SPEED 0.5 m/s


def test_auto_disarm_on_the_ground():
    ap = Autopilot(home=HOME, boot_time=0.0)
    ap.set_mode(GUIDED, 0.0)
    ap.arm(0.0)
    ap.advance(9.0)
    assert ap.armed
    ap.advance(10.5)
    assert not ap.armed


def test_physics_respects_limits():
    limits = FlightLimits(speed_m_s=5.0, accel_m_s2=2.5, climb_m_s=2.5)
    pos, vel = np.zeros(3), np.zeros(3)
    speeds = []
    for _ in range(1000):
        new_pos, new_vel = step_towards(pos, vel, np.array([100.0, 0, 10]), 0.02, limits)
        assert np.linalg.norm(new_vel - vel) <= 2.5 * 0.02 + 1e-9
        pos, vel = new_pos, new_vel
        speeds.append(np.hypot(*vel[:2]))
        assert vel[2] <= 2.5 + 1e-9
    assert max(speeds) == pytest.approx(5.0, abs=1e-6)


def test_local_tangent_round_trip_and_scale():
    t = LocalTangent(*HOME)
    lat, lon = t.to_latlon(30.0, -20.0)
    assert np.allclose(t.to_en(lat, lon), (30.0, -20.0))
    # 1e-5 degree of latitude is about 1.106 m at 12 degrees north
    assert t.to_en(HOME[0] + 1e-5, HOME[1])[1] == pytest.approx(1.1061, abs=1e-3)
