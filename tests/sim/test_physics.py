"""ArduCopter's waypoint navigation as the emulator flies it (physics, scurve)."""

import numpy as np
import pytest

from ftlbo_mav.ardupilot.navigation import DEFAULTS, Navigation
from ftlbo_mav.ardupilot.scurve import SCurve
from ftlbo_mav.sim.physics import FlightLimits, WaypointNav, varied

from ..conformance.replay import load

NAV = Navigation()


def _leg(length: float, speed: float = NAV.wp_speed) -> SCurve:
    jerk, snap = NAV.scurve_jerk_snap()
    leg = SCurve()
    leg.calculate_track(np.zeros(3), np.array([length, 0.0, 0.0]), speed, NAV.wp_speed_up,
                        NAV.wp_speed_dn, NAV.wp_accel, NAV.wp_accel_z, snap, jerk)
    return leg


def _peak(leg: SCurve) -> float:
    return max(leg.state_at(t)[2] for t in np.arange(0.0, leg.time_end(), 0.01))


def test_the_defaults_are_what_arducopter_4_5_6_answered():
    params = load("flight.json")["params"]
    for name, d in DEFAULTS.items():
        if name in params:
            assert params[name]["value"] == d.value, name
            assert params[name]["param_type"] == d.type, name
    assert Navigation().with_params(Navigation().to_params()) == Navigation()


def test_jerk_and_snap_follow_calc_scurve_jerk_and_snap():
    jerk, snap = NAV.scurve_jerk_snap()
    assert jerk == 1.0
    assert snap == pytest.approx(1.0 * np.pi / (2 * 0.15) / 2)  # ATC_INPUT_TC 0.15, halved


def test_a_ten_metre_leg_peaks_near_2_8_m_s_although_wpnav_speed_is_10():
    leg = _leg(10.0)
    assert 2.7 <= _peak(leg) <= 2.95  # flight.json: 2.75-2.92 m/s on the ~10 m legs
    _j, _a, v, x = leg.state_at(leg.time_end())
    assert x == pytest.approx(10.0, abs=1e-6) and v == pytest.approx(0.0, abs=1e-6)
    accel = max(abs(leg.state_at(t)[1]) for t in np.arange(0, leg.time_end(), 0.01))
    assert accel < 2.5  # jerk-limited well below WPNAV_ACCEL
    long = _leg(200.0)
    assert _peak(long) == pytest.approx(10.0, abs=1e-3)  # a long one reaches WPNAV_SPEED


def test_a_zero_length_leg_is_done_at_once_and_a_centimetre_takes_about_a_second():
    assert _leg(0.0).finished() and _leg(0.0).time_end() == 0.0
    assert 0.9 <= _leg(0.02).time_end() <= 1.4


def _fly_leg(length: float, speed_change: float | None, at: float) -> tuple[float, float]:
    nav = WaypointNav(NAV, np.zeros(3))
    nav.set_destination(np.array([length, 0.0, 0.0]))
    t, peak = 0.0, 0.0
    while not nav.reached:
        if speed_change is not None and abs(t - at) < 1e-9:
            nav.set_speed_xy(speed_change)
        nav.advance(0.01, nav.target)
        t = round(t + 0.01, 6)
        peak = max(peak, float(np.linalg.norm(nav.target_vel)))
        assert t < 60
    assert nav.target[0] == pytest.approx(length, abs=1e-6)
    return t, peak


def test_a_speed_above_the_legs_peak_changes_nothing_one_below_slows_it():
    base_t, base_peak = _fly_leg(16.0, None, 0.0)
    assert _fly_leg(16.0, 5.0, 1.0) == pytest.approx((base_t, base_peak), abs=0.011)
    slow_t, slow_peak = _fly_leg(16.0, 3.0, 0.0)  # flight_speed.json: 3.65 -> 2.98 m/s
    assert slow_peak == pytest.approx(3.0, abs=0.05) and slow_t > base_t + 0.3
    # SCurve::set_speed_max cannot shorten an acceleration that has no constant part,
    # nor slow a leg with no cruise left: mid-way up this short leg it changes nothing
    assert _fly_leg(16.0, 3.0, 1.0)[1] == pytest.approx(base_peak)
    cruising_t, cruising_peak = _fly_leg(200.0, 3.0, 8.0)  # slowed while cruising
    assert cruising_peak > 9.0 and _fly_leg(200.0, None, 0.0)[0] + 5 < cruising_t


def test_a_fast_waypoint_cuts_the_corner_inside_the_waypoint_radius():
    nav = WaypointNav(NAV, np.zeros(3))
    corner, end = np.array([10.0, 0, 0]), np.array([10.0, 10.0, 0])
    nav.set_destination(corner)
    nav.set_destination_next(end)
    closest, reached_at = np.inf, None
    for _ in range(3000):
        nav.advance(0.01, nav.target)
        closest = min(closest, float(np.linalg.norm(nav.target - corner)))
        if nav.reached and reached_at is None:
            reached_at = nav.target.copy()
            nav.set_destination(end)
    assert 0.02 < closest < NAV.wp_radius  # flight.json passes its corners 0.01-0.14 m off
    assert np.linalg.norm(nav.target - end) < 1e-6


def test_variation_is_seeded_and_small():
    a = varied(FlightLimits(), np.random.default_rng(3))
    b = varied(FlightLimits(), np.random.default_rng(3))
    assert a == b
    assert 0.0 <= a.start_latency_s <= 0.3
    assert abs(a.jerk_factor - 1.0) <= 0.05 and a.jerk_factor != 1.0
    assert a.nav == FlightLimits().nav  # its parameters are the fleet's


@pytest.mark.parametrize("seed", range(6))
def test_a_legs_pieces_end_in_order_and_any_search_start_finds_the_same_piece(seed):
    """state_at starts its search where the last one ended (the pieces' end times never
    go down, through speed changes too): any order of times gives what a fresh leg does."""
    rng = np.random.default_rng(seed)
    leg = _leg(float(rng.uniform(0.5, 80.0)), float(rng.uniform(1.0, 12.0)))
    for _ in range(3):
        ends = [q.end_time for q in leg.p]
        assert ends == sorted(ends)
        times = rng.uniform(-1.0, leg.time_end() + 1.0, 200)
        for t in np.concatenate([np.sort(times), times]):
            fresh = leg.copy()
            fresh._hint = 0
            assert leg.state_at(float(t)) == fresh.state_at(float(t))
        leg.set_speed_max(float(rng.uniform(1.0, 12.0)), NAV.wp_speed_up, NAV.wp_speed_dn)
        leg.set_origin_speed_max(float(rng.uniform(0.0, 5.0)))
