"""Each copter held to the plan's navigation budget (pure): the pre-flight refusals,
one reason each with the figures, and the departures in flight: a degraded fix or
accuracy or EKF that lasts, and a GPS position that jumps further than the copter's
velocity carries it."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import ardupilotmega as R

from ftlbo_mav.ardupilot.failsafes import NAVIGATION, departure_text
from ftlbo_mav.ardupilot.gps import EKF_POS_HORIZ_ABS
from ftlbo_mav.flight.departures import DepartureWatch, Seen
from ftlbo_mav.flight.navigation import (
    M_PER_DEGREE,
    PERSIST_S,
    EkfReport,
    GpsReport,
    NavigationWatch,
    jump_vector,
    preflight_problems,
    report_jump,
)
from ftlbo_mav.gnss import CLASSES, NO_BUDGET, budget

HEALTHY = EkfReport(flags=0x33F, pos_horiz_variance=0.02)
FLOAT = CLASSES["rtk-float"]


def gps(fix=6, acc=0.3, east=0.0, north=0.0, v=(0.0, 0.0), t=0.0, sats=12) -> GpsReport:
    return GpsReport(fix, acc, sats, east, north, v, t)


def test_a_copter_within_the_budget_may_fly():
    assert preflight_problems(FLOAT, gps(), HEALTHY) == []


@pytest.mark.parametrize(("report", "ekf", "words"), [
    (gps(acc=1.5), HEALTHY, "GPS accuracy 1.50 m, worse than the plan's budget 0.5 m"),
    (gps(fix=3), HEALTHY, "3D fix, the plan's [navigation] rtk-float needs RTK float"),
    (gps(acc=None), HEALTHY, "reports no accuracy"),
    (None, HEALTHY, "no GPS_RAW_INT received"),
    (gps(), None, "no EKF_STATUS_REPORT received"),
    (gps(), EkfReport(0x33F & ~EKF_POS_HORIZ_ABS, 0.02), "no absolute horizontal position"),
    (gps(), EkfReport(0x33F, 0.85), "EKF position variance 0.85, at or over"),
])
def test_a_copter_short_of_the_budget_is_refused_with_its_figures(report, ekf, words):
    problems = preflight_problems(FLOAT, report, ekf)
    assert len(problems) == 1 and words in problems[0]


def test_a_plan_without_a_budget_asks_only_for_a_3d_fix_and_an_ekf():
    assert preflight_problems(NO_BUDGET, gps(fix=3, acc=None), HEALTHY) == []
    assert preflight_problems(NO_BUDGET, gps(fix=2), HEALTHY)


def test_a_shortfall_counts_once_it_lasts():
    w = NavigationWatch(1, FLOAT)
    assert w.check(0, gps(acc=0.9, t=0.0), HEALTHY, 10.0) is None
    assert w.check(0, gps(acc=0.9, t=0.5), HEALTHY, 10.0 + PERSIST_S / 2) is None
    why = w.check(0, gps(acc=0.9, t=1.0), HEALTHY, 10.0 + PERSIST_S)
    assert why is not None and "GPS accuracy 0.90 m" in why
    assert w.check(0, gps(acc=0.9, t=1.5), HEALTHY, 12.0) is None  # said once


def test_a_brief_shortfall_is_not_a_departure():
    w = NavigationWatch(1, FLOAT)
    assert w.check(0, gps(acc=0.9, t=0.0), HEALTHY, 10.0) is None
    assert w.check(0, gps(acc=0.3, t=0.5), HEALTHY, 10.5) is None
    assert w.check(0, gps(acc=0.9, t=1.0), HEALTHY, 11.0) is None


def raw(north_m=0.0, east_m=0.0, t=0.0, v=(0.0, 0.0), fix=6):
    lat0, lon0 = 12.0, 109.0
    speed = float(np.hypot(*v))
    cog = int(round(np.degrees(np.arctan2(v[0], v[1])) % 360 * 100))
    return R.MAVLink_gps_raw_int_message(
        int(t * 1e6), fix, int(round((lat0 + north_m / M_PER_DEGREE) * 1e7)),
        int(round((lon0 + east_m / (M_PER_DEGREE * np.cos(np.radians(lat0)))) * 1e7)), 0,
        100, 100, int(round(speed * 100)), cog, 10)


def test_moving_at_speed_is_no_glitch_but_a_jump_is():
    jumps, east, prev = [], 0.0, None
    for k in range(10):  # 5 m/s east, reports 0.5 s apart
        cur = raw(east_m=east, v=(5.0, 0.0), t=0.5 * k)
        jumps.append(report_jump(prev, cur))
        prev, east = cur, east + 2.5
    assert max(jumps) < 0.05
    assert report_jump(prev, raw(east_m=east, north_m=3.0, v=(5.0, 0.0), t=5.0)) == (
        pytest.approx(3.0, abs=0.05))
    # which way: north, the copter's own motion east taken out
    assert jump_vector(prev, raw(east_m=east, north_m=3.0, v=(5.0, 0.0), t=5.0)) == (
        pytest.approx([0.0, 3.0], abs=0.05))
    assert report_jump(prev, raw(east_m=east, t=5.0 + 10.0)) == 0.0  # too far apart
    assert report_jump(prev, raw(east_m=40.0, t=5.0, fix=1)) == 0.0  # no fix


def test_a_copter_speeding_up_across_a_silence_is_no_glitch_but_a_jump_in_one_still_is():
    """The emulator's uav1 through the rough-day radio: from a hover to 3 m/s east, 3 m
    on in 2.8 s without a report; the mean velocity puts it 4.2 m on, and ArduCopter's
    lean limit can carry a copter that far from the guess (5.7 m/s/s x 2.8^2 / 4)."""
    hover = raw(t=10.0)
    assert report_jump(hover, raw(east_m=3.0, v=(3.06, 0.0), t=12.8)) == 0.0
    # a 3 m jump across a 1 s silence is more than acceleration carries: all of it counts
    cruise = raw(v=(3.0, 0.0), t=10.0)
    assert jump_vector(cruise, raw(east_m=3.0, north_m=3.0, v=(3.0, 0.0), t=11.0)) == (
        pytest.approx([0.0, 3.0], abs=0.05))


def test_a_jump_larger_than_the_budget_or_a_metre_is_a_glitch():
    w = NavigationWatch(1, FLOAT)
    assert w.check(0, gps(), HEALTHY, 1.0, jump_m=0.8) is None
    why = w.check(0, gps(), HEALTHY, 1.1, jump_m=3.0)
    assert why is not None and "jumped 3.0 m" in why
    loose = NavigationWatch(1, budget("gps"))
    assert loose.glitch_m == pytest.approx(CLASSES["gps"].horizontal_m)
    assert loose.check(0, gps(fix=3, acc=1.5), HEALTHY, 1.0, jump_m=3.0) is None


def test_arducopters_glitch_and_variance_texts_are_navigation_departures():
    assert departure_text("GPS Glitch or Compass error") == NAVIGATION
    assert departure_text("EKF variance") == NAVIGATION
    assert departure_text("Glitch cleared") is None


def test_the_departure_watch_reports_a_glitch_in_the_air_only():
    w = DepartureWatch(1, navigation=FLOAT)
    base = dict(mode="AUTO", asked_mode="AUTO", asked_t=0.0, heard_t=1.0, link_up=True,
                alt_m=5.0, position=np.zeros(3), ekf=HEALTHY, gps=gps())
    assert w.check([Seen(armed=True, **base)], 1.0) == []
    (e,) = w.check([Seen(armed=True, gps_jump_m=3.0, **base)], 1.1)
    assert e.kind == NAVIGATION and not e.vehicle_chose and "jumped 3.0 m" in e.detail
    ground = DepartureWatch(1, navigation=FLOAT)
    assert ground.check([Seen(armed=False, gps_jump_m=3.0, **base)], 1.1) == []
