"""Each copter held to the plan's navigation budget (pure): the pre-flight refusals,
one reason each with the figures, and the departures in flight: a degraded fix or
accuracy or EKF that lasts, and a GPS position that jumps further than the copter's
velocity carries it."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.ardupilot.failsafes import NAVIGATION, departure_text
from ftlbo_mav.ardupilot.gps import EKF_POS_HORIZ_ABS
from ftlbo_mav.flight.departures import DepartureWatch, Seen
from ftlbo_mav.flight.navigation import (
    PERSIST_S,
    EkfReport,
    GpsReport,
    NavigationWatch,
    preflight_problems,
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


def test_moving_at_speed_is_no_glitch_but_a_jump_is():
    w = NavigationWatch(1, FLOAT)
    east = 0.0
    for k in range(10):  # 5 m/s east, reports 0.5 s apart
        assert w.check(0, gps(east=east, v=(5.0, 0.0), t=0.5 * k), HEALTHY, 0.5 * k) is None
        east += 2.5
    why = w.check(0, gps(east=east + 3.0, v=(5.0, 0.0), t=5.0), HEALTHY, 5.0)
    assert why is not None and "jumped 3.0 m" in why


def test_a_wander_slower_than_the_glitch_threshold_is_not_a_glitch():
    w = NavigationWatch(1, budget("gps"))
    assert w.glitch_m == pytest.approx(CLASSES["gps"].horizontal_m)
    for k in range(20):
        assert w.check(0, gps(fix=3, acc=1.5, east=0.2 * k, t=0.5 * k), HEALTHY, 0.5 * k) is None


def test_arducopters_glitch_and_variance_texts_are_navigation_departures():
    assert departure_text("GPS Glitch or Compass error") == NAVIGATION
    assert departure_text("EKF variance") == NAVIGATION
    assert departure_text("Glitch cleared") is None


def test_the_departure_watch_reports_a_glitch_in_the_air_only():
    w = DepartureWatch(1, navigation=FLOAT)
    base = dict(mode="AUTO", asked_mode="AUTO", asked_t=0.0, heard_t=1.0, link_up=True,
                alt_m=5.0, position=np.zeros(3), ekf=HEALTHY)
    assert w.check([Seen(armed=True, gps=gps(t=0.0), **base)], 1.0) == []
    (e,) = w.check([Seen(armed=True, gps=gps(east=3.0, t=0.5), **base)], 1.1)
    assert e.kind == NAVIGATION and not e.vehicle_chose and "jumped 3.0 m" in e.detail
    ground = DepartureWatch(1, navigation=FLOAT)
    ground.check([Seen(armed=False, gps=gps(t=0.0), **base)], 1.0)
    assert ground.check([Seen(armed=False, gps=gps(east=3.0, t=0.5), **base)], 1.1) == []
