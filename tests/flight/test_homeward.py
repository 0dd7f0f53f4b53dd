"""The flight side of the collective return (flight/homeward.py): the plan's world, the
keep-out of a vehicle that left, and the mission home as uploaded."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pytest

from ftlbo_mav.flight.homeward import (
    ESCAPE_MARGIN_M,
    GoingHome,
    escape,
    keep_out,
    landing_out_of_reach,
    return_world,
)
from ftlbo_mav.mission.items import (
    CMD_DO_CHANGE_SPEED,
    CMD_DO_SET_CAM_TRIGG_DIST,
    CMD_NAV_LAND,
    CMD_NAV_WAYPOINT,
    build_return,
)


@dataclass
class Status:
    lat_deg: float | None = None
    lon_deg: float | None = None
    alt_m: float = 5.0
    position_t: float = 0.0
    ground_speed_m_s: float = 0.0
    clock_rate: float = 1.0
    gps_jump_m: float = 0.0
    gps_jump_enu: tuple[float, float] = (0.0, 0.0)


@dataclass
class StandIn:
    name: str = "uav2"
    sysid: int = 2
    status: Status = field(default_factory=Status)


def test_the_world_is_the_plans(planned):
    w = return_world(planned)
    assert w.band == (2.0, 7.0) and w.min_separation_m == 2.0
    assert w.clearance_m == pytest.approx(1.5)  # 1 m clearance + the rtk-float 0.5 m
    assert w.model.speed_m_s == 5.0
    assert np.allclose(w.area_lower, [0.0, 0.0], atol=1e-3)
    assert w.area_upper[0] == pytest.approx(86.38, abs=0.01)
    assert len(w.centres) == len(planned.centres) == len(w.radii)


def test_the_keep_out_grows_with_the_age_of_the_last_position_in_the_vehicles_seconds(planned):
    lat, lon, _ = planned.frame.to_lla(np.array([30.0, 20.0, 5.0]))
    v = StandIn(status=Status(lat_deg=float(lat), lon_deg=float(lon), position_t=10.0))
    k = keep_out(planned, v, 12.0)  # 2 s old, 5 m/s at the least
    assert np.allclose(k.centre, [30.0, 20.0], atol=1e-6)
    assert k.radius_m == pytest.approx(2.0 + planned.navigation.pair_m + 10.0)
    v.status.ground_speed_m_s, v.status.clock_rate = 8.0, 3.0  # a simulator run 3x
    assert keep_out(planned, v, 12.0).radius_m == pytest.approx(
        2.0 + planned.navigation.pair_m + 8.0 * 6.0)
    assert keep_out(planned, StandIn(), 12.0) is None  # never placed


def test_the_mission_home_starts_where_it_hovers_and_lands_at_home():
    items = build_return(home=(12.0, 109.0), path=[(12.1, 109.1, 6.0), (12.1, 109.1, 7.0),
                                                   (12.2, 109.2, 7.0)],
                         holds_s=[0, 4, 0], land=(12.3, 109.3), speed_m_s=5.0)
    assert [it.command for it in items] == [CMD_NAV_WAYPOINT, CMD_NAV_WAYPOINT,
                                            CMD_DO_CHANGE_SPEED, CMD_NAV_WAYPOINT,
                                            CMD_NAV_WAYPOINT, CMD_NAV_LAND]
    assert [it.seq for it in items] == list(range(6))
    assert items[0].frame == 0 and items[0].current == 1  # home, as Mission Planner has it
    assert (items[1].lat_deg, items[1].alt_m) == (12.1, 6.0)  # AUTO starts here (item 1)
    assert items[2].param2 == 5.0
    assert items[3].param1 == 4 and items[3].alt_m == 7.0  # its wait on its layer
    assert (items[5].lat_deg, items[5].lon_deg, items[5].alt_m) == (12.3, 109.3, 0.0)
    with pytest.raises(ValueError):
        build_return(home=(0, 0), path=[(0, 0, 1)], holds_s=[0], land=(0, 0))
    # a survey copter turns its camera off where it starts home, before its speed
    surveying = build_return(home=(12.0, 109.0), path=[(12.1, 109.1, 6.0), (12.2, 109.2, 7.0)],
                             holds_s=[0, 0], land=(12.3, 109.3), speed_m_s=5.0, camera_off=True)
    assert [it.command for it in surveying][:4] == [CMD_NAV_WAYPOINT, CMD_NAV_WAYPOINT,
                                                    CMD_DO_SET_CAM_TRIGG_DIST,
                                                    CMD_DO_CHANGE_SPEED]
    assert surveying[2].param1 == 0.0


def test_the_uploaded_mission_is_the_planned_route(planned):
    home = GoingHome(planned, [StandIn() for _ in range(3)])
    from ftlbo_mav.planning.homeward import plan_return

    here = {0: np.array([19.4, 13.3, 6.0]), 2: np.array([16.4, 13.3, 3.0])}
    home.plan = plan_return(here, {j: planned.paths[j][0][:2] for j in here},
                            return_world(planned))
    items = home.mission(0)
    route = home.plan.routes[0]
    waypoints = [it for it in items[1:] if it.command == CMD_NAV_WAYPOINT]
    assert len(waypoints) == len(route.points)
    enu = planned.frame.to_enu(lat_deg=[w.lat_deg for w in waypoints],
                               lon_deg=[w.lon_deg for w in waypoints],
                               alt_m=[w.alt_m for w in waypoints])
    assert np.allclose(enu, route.points, atol=1e-3)
    land = planned.frame.to_enu(lat_deg=items[-1].lat_deg, lon_deg=items[-1].lon_deg)
    assert np.allclose(land[:2], planned.paths[0][0][:2], atol=1e-3)


def test_a_copter_still_on_the_ground_at_home_has_nothing_to_fly(planned):
    # stopped in its take-off before liftoff: ArduCopter refuses AUTO there (Missing
    # Takeoff Cmd, seen on SITL), so no route is planned; the policy lands it
    lat, lon, _ = planned.frame.to_lla(np.append(planned.paths[0][0][:2], 0.1))
    on_ground = StandIn("uav1", 1, Status(lat_deg=float(lat), lon_deg=float(lon), alt_m=0.1))
    home = GoingHome(planned, [on_ground, StandIn(), StandIn()])
    refused = home.start([0], [], 0.0)
    assert refused == {0: "still on the ground at its home"}
    assert not home.plan.routes


def test_a_route_is_started_only_from_where_it_begins_and_on_a_fresh_position(planned):
    """Through a rough radio the position a route was planned from can be old and the
    copter not stopped yet (SITL: started 5 m off, into a tree's fence)."""
    import time

    from ftlbo_mav.planning.homeward import plan_return

    stand_in = StandIn("uav1", 1)
    home = GoingHome(planned, [stand_in, StandIn(), StandIn()])
    here = {0: np.array([19.4, 13.3, 6.0])}
    home.plan = plan_return(here, {0: planned.paths[0][0][:2]}, return_world(planned))

    def at(east_north, age_s=0.0):
        lat, lon, _ = planned.frame.to_lla(np.array([*east_north, 6.0]))
        stand_in.status = Status(lat_deg=float(lat), lon_deg=float(lon), alt_m=6.0,
                                 position_t=time.monotonic() - age_s)
        return home._off_start(0)

    assert at((19.4, 13.3)) is None
    assert at((19.7, 13.5)) is None  # 0.36 m: within what a stopped copter holds
    assert "2.0 m from where the route begins" in at((21.4, 13.3))
    assert "1.5 s old" in at((19.4, 13.3), age_s=1.5)


def test_rtl_is_refused_where_its_line_crosses_another_vehicles_route_home(planned):
    """RTL climbs where it is and flies straight home, through the layers of the others'
    routes (SITL: a copter sent to RTL for want of a route came 0.65 m from one on its
    route): a line that passes within 2 m of a route lands instead."""
    from ftlbo_mav.ardupilot.fence import rtl_target
    from ftlbo_mav.flight.watch import rally_points, rtl_line_problem

    here = np.array([5.0, 40.0, 3.0])  # north-west of the trees: its line home runs south
    home = np.asarray(planned.paths[1][0][:2], float)
    rally = rally_points(planned, 1)
    k = rtl_target(here[:2], home, rally)
    target = home if k is None else rally[k]
    assert rtl_line_problem(planned, 1, here, []) is None
    mid = (here[:2] + target) / 2  # a route across the middle of its line, on a layer
    crossing = np.array([[mid[0] - 15.0, mid[1], 7.0], [mid[0] + 15.0, mid[1], 7.0]])
    why = rtl_line_problem(planned, 1, here, [], routes=[crossing])
    assert why is not None and "another vehicle's route home" in why
    far = crossing + np.array([0.0, 60.0, 0.0])
    assert rtl_line_problem(planned, 1, here, [], routes=[far]) is None
    # nor may it cross the reach of a copter whose position is in doubt
    from ftlbo_mav.planning.homeward import KeepOut

    reach = KeepOut(mid, 3.0)
    why = rtl_line_problem(planned, 1, here, [], reaches=[("uav3", reach)])
    assert why is not None and "crosses the reach of uav3" in why
    assert rtl_line_problem(planned, 1, here, [], reaches=[("uav3", KeepOut(
        mid + np.array([0.0, 60.0]), 3.0))]) is None


def _placed(planned, east, north, **status):
    lat, lon, _ = planned.frame.to_lla(np.array([east, north, 5.0]))
    return StandIn(status=Status(lat_deg=float(lat), lon_deg=float(lon), **status))


def test_a_copter_in_doubt_is_kept_out_where_its_jump_makes_it_drift(planned):
    # its GPS jumped 3 m east: held on its estimate it drifts up to 3 m west, truly
    v = _placed(planned, 30.0, 20.0, gps_jump_m=3.0, gps_jump_enu=(3.0, 0.0))
    k = keep_out(planned, v, 0.0, doubt_m=3.0)
    assert np.allclose(k.centre, [28.5, 20.0], atol=1e-6)
    assert k.radius_m == pytest.approx(2.0 + planned.navigation.pair_m + 1.5)
    # from here to 3 m west, every point it may truly be, min_separation away and more
    for west in (0.0, 1.5, 3.0):
        assert np.hypot(*(k.centre - [30.0 - west, 20.0])) + 2.0 <= k.radius_m + 1e-9
    # a doubt without a jump (its accuracy) is a disc around where it says it is
    k = keep_out(planned, _placed(planned, 30.0, 20.0), 0.0, doubt_m=1.2)
    assert np.allclose(k.centre, [30.0, 20.0]) and k.radius_m == pytest.approx(
        2.0 + planned.navigation.pair_m + 1.2)


def test_a_copter_inside_the_reach_first_leaves_it_away_from_the_others(planned):
    reach = keep_out(planned, _placed(planned, 30.0, 20.0), 0.0, doubt_m=1.0)
    here = np.array([32.0, 20.0, 3.0])
    out = escape(here, [reach], planned)
    assert out[2] == 3.0  # at its own height
    assert np.hypot(*(out[:2] - reach.centre)) == pytest.approx(
        reach.radius_m + ESCAPE_MARGIN_M, abs=1e-6)
    assert out[0] > 32.0  # straight out, away from the one in doubt
    # another vehicle where that line goes: round the reach, clear of it
    other = np.array([34.5, 20.0])
    moved = escape(here, [reach], planned, [other])
    assert np.hypot(*(moved[:2] - other)) >= 2.0 + planned.navigation.pair_m
    assert escape(np.array([40.0, 20.0, 3.0]), [reach], planned) is None  # out of reach
    # at or above the one in doubt (5 m): it climbs clear of wherever that drifts below
    up = escape(np.array([32.0, 20.0, 5.2]), [reach], planned)
    assert up[2] == pytest.approx(min(5.0 + 2.0 + planned.navigation.pair_m, planned.band[1]))


def test_a_landing_point_in_the_reach_moves_out_clear_of_the_others(planned):
    reach = keep_out(planned, _placed(planned, 30.0, 20.0), 0.0, doubt_m=1.0)
    land = np.array([31.0, 20.0])
    out = landing_out_of_reach(land, [reach], planned, [np.array([35.0, 20.0])])
    assert np.hypot(*(out - reach.centre)) > reach.radius_m
    assert np.hypot(*(out - [35.0, 20.0])) >= 2.0 + planned.navigation.pair_m
    assert landing_out_of_reach(np.array([40.0, 20.0]), [reach], planned, []) is None
