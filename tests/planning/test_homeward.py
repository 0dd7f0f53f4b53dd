"""The way home planned when a flight ends early (planning/homeward.py): clearance on the
predicted flown path, separation on one clock, the vehicle that left kept out, waits,
refusals."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from ftlbo_mav.ardupilot.flight_path import fly_path
from ftlbo_mav.planning.homeward import (
    INSIDE_MARGIN_M,
    KeepOut,
    World,
    _at,
    descent,
    layers,
    plan_return,
)
from ftlbo_mav.planning.predicted import FlightModel

MODEL = FlightModel(speed_m_s=5.0)


def _world(centres=(), radii=(), *, band=(2.0, 7.0), separation=2.0, clearance=1.0,
           pair_error=0.0) -> World:
    return World(centres=np.array(centres, float).reshape(-1, 2), radii=np.array(radii, float),
                 clearance_m=clearance, area_lower=np.array([0.0, 0.0]),
                 area_upper=np.array([100.0, 60.0]), band=band, min_separation_m=separation,
                 model=MODEL, pair_error_m=pair_error)


def _clearance(route, world: World) -> float:
    d = np.hypot(*(route.positions[:, None, :2] - world.centres[None]).transpose(2, 0, 1))
    return float((d - world.radii).min())


def _separation(a, b) -> float:
    t = np.union1d(a.times, b.times)
    return float(np.linalg.norm(_at(a, t) - _at(b, t), axis=1).min())


def test_layers_fill_the_band_from_the_top_and_repeat_when_it_is_full():
    assert layers((2.0, 7.0), 3, 2.0).tolist() == [7.0, 5.0, 3.0]
    assert layers((2.0, 5.0), 3, 2.0).tolist() == [5.0, 3.0, 5.0]


def test_descent_is_wpnav_speed_dn_above_land_alt_low_and_land_speed_below():
    t, z = descent(MODEL, 14.0)  # 4 m at 1.5 m/s, then 10 m at 0.5 m/s
    assert z[0] == 14.0 and z[-1] == 0.0
    assert t[-1] == pytest.approx(4 / 1.5 + 10 / 0.5, abs=0.03)
    assert np.interp(4 / 1.5, t, z) == pytest.approx(10.0, abs=0.05)


def test_crossing_vehicles_go_home_on_their_own_layers_around_a_tree():
    world = _world([[50.0, 30.0]], [3.0])
    positions = {0: np.array([80.0, 40.0, 4.0]), 1: np.array([80.0, 20.0, 4.0])}
    landings = {0: np.array([10.0, 20.0]), 1: np.array([10.0, 40.0])}  # their paths cross
    plan = plan_return(positions, landings, world)
    assert not plan.refused
    a, b = plan.routes[0], plan.routes[1]
    assert {a.layer_m, b.layer_m} == {7.0, 5.0}
    for r, j in ((a, 0), (b, 1)):
        assert r.points[0].tolist() == positions[j].tolist()
        assert r.points[1, 2] == r.layer_m and np.allclose(r.points[1, :2], positions[j][:2])
        assert np.allclose(r.positions[-1], [*landings[j], 0.0])  # on the ground at home
        assert _clearance(r, world) >= world.clearance_m - 1e-6
        # the predicted flight is ArduCopter's (the copter model) through its points
        flown = fly_path(r.points, nav=MODEL.nav, speed_m_s=5.0, holds_s=r.holds_s)
        assert np.allclose(r.positions[:len(flown.positions)], flown.positions)
    assert plan.separation_m >= 2.0
    assert _separation(a, b) >= 2.0


def test_the_vehicle_that_left_is_kept_out():
    world = _world()
    gone = KeepOut(np.array([50.0, 30.0]), 8.0)  # right on the straight line home
    plan = plan_return({0: np.array([85.0, 30.0, 4.0])}, {0: np.array([10.0, 30.0])}, world,
                       keep_out=(gone,))
    route = plan.routes[0]
    d = np.hypot(*(route.positions[:, :2] - gone.centre).T)
    assert d.min() >= gone.radius_m - 1e-6
    assert len(route.points) > 3  # it goes round


def test_one_layer_for_all_makes_the_later_one_wait_until_the_way_is_clear():
    world = _world(band=(4.0, 5.0), separation=3.0)  # room for one layer only
    positions = {0: np.array([80.0, 40.0, 4.5]), 1: np.array([80.0, 20.0, 4.0])}
    landings = {0: np.array([10.0, 20.0]), 1: np.array([10.0, 40.0])}
    plan = plan_return(positions, landings, world)
    assert not plan.refused
    assert plan.routes[0].layer_m == plan.routes[1].layer_m == 5.0
    assert plan.routes[1].wait_s > 0 and plan.routes[0].wait_s == 0
    assert _separation(plan.routes[0], plan.routes[1]) >= 3.0 - 1e-9


def test_a_vehicle_stopped_inside_the_clearance_still_goes_home():
    world = _world([[50.0, 30.0]], [3.0])
    here = np.array([53.6, 30.0, 4.0])  # 0.6 m from the surface: inside the 1 m clearance
    plan = plan_return({0: here}, {0: np.array([90.0, 30.0])}, world)
    route = plan.routes[0]
    assert _clearance(route, world) >= 0.6 - INSIDE_MARGIN_M - 1e-6  # no closer than that


def test_a_landing_point_walled_in_is_refused_with_the_reason():
    ring = [[20.0 + 6 * math.cos(a), 30.0 + 6 * math.sin(a)] for a in np.linspace(0, 6.2, 12)]
    world = _world(ring, [2.5] * 12)
    plan = plan_return({0: np.array([80.0, 30.0, 4.0])}, {0: np.array([20.0, 30.0])}, world)
    assert 0 in plan.refused and not plan.routes
    assert "no way home" in plan.refused[0]


def test_a_landing_point_in_the_clearance_is_refused():
    world = _world([[20.0, 30.0]], [2.0])
    plan = plan_return({0: np.array([80.0, 30.0, 4.0])}, {0: np.array([22.5, 30.0])}, world)
    assert "landing point" in plan.refused[0]


def test_the_others_keep_clear_of_a_vehicle_landing_where_it_stopped():
    # vehicle 1 has no way home (walled in): it lands where it stopped, right on vehicle
    # 0's line home on vehicle 0's layer; vehicle 0 waits until it is down, or goes round
    ring = [[20.0 + 6 * math.cos(a), 30.0 + 6 * math.sin(a)] for a in np.linspace(0, 6.2, 12)]
    world = _world(ring, [2.5] * 12, band=(4.0, 5.0), separation=2.0)
    positions = {0: np.array([90.0, 50.0, 5.0]), 1: np.array([60.0, 50.0, 5.0])}
    landings = {0: np.array([40.0, 50.0]), 1: np.array([20.0, 30.0])}
    plan = plan_return(positions, landings, world)
    assert set(plan.refused) == {1}
    t, z = descent(MODEL, 5.0)
    down = np.column_stack([np.full(len(t), 60.0), np.full(len(t), 50.0), z])
    route = plan.routes[0]
    at = np.clip(np.searchsorted(route.times, t, side="right") - 1, 0, len(route.times) - 1)
    assert np.linalg.norm(route.positions[at] - down, axis=1).min() >= 2.0 - 1e-9


def test_a_route_planned_late_keeps_clear_of_the_routes_already_flying_on_their_clock():
    world = _world(band=(4.0, 5.0), separation=3.0)  # one layer: the clock keeps them apart
    first = plan_return({0: np.array([80.0, 40.0, 4.5])}, {0: np.array([10.0, 20.0])}, world)
    flying = first.routes[0]
    for elapsed in (0.0, 6.0):
        late = plan_return({1: np.array([80.0, 20.0, 4.0])}, {1: np.array([10.0, 40.0])},
                           world, flying=(flying,), elapsed_s=elapsed)
        route = late.routes[1]
        t = np.union1d(route.times, flying.times - elapsed)
        ahead = replace(flying, times=flying.times - elapsed)
        assert np.linalg.norm(_at(route, t) - _at(ahead, t), axis=1).min() >= 3.0 - 1e-9
    # the one flying for 6 s is further on its way: the late one waits less, if at all
    early = plan_return({1: np.array([80.0, 20.0, 4.0])}, {1: np.array([10.0, 40.0])}, world,
                        flying=(flying,), elapsed_s=0.0).routes[1]
    assert route.wait_s <= early.wait_s


def test_a_late_route_takes_a_layer_the_flying_ones_leave():
    world = _world()  # layers 7, 5, 3
    first = plan_return({0: np.array([80.0, 40.0, 6.0])}, {0: np.array([10.0, 20.0])}, world)
    assert first.routes[0].layer_m == 7.0
    late = plan_return({1: np.array([80.0, 20.0, 6.5])}, {1: np.array([10.0, 40.0])}, world,
                       flying=(first.routes[0],), elapsed_s=3.0)
    assert late.routes[1].layer_m == 5.0


def _orchard(rows: int = 40, per_row: int = 30):
    """Rows of trees 7 m apart (north-south), 3 m apart along a row, 12 m headlands: an
    orchard of rows x per_row trees; and a survey's snake through every aisle."""
    x = 7.0 * (1 + np.arange(rows))
    y = 12.0 + 3.0 * np.arange(per_row)
    centres = np.array([(a, b) for a in x for b in y])
    aisles = np.concatenate([[3.5], x + 3.5])
    top, bottom = y[-1] + 6.0, y[0] - 6.0
    snake = []
    for k, a in enumerate(aisles):
        ends = [(a, bottom), (a, top)] if k % 2 == 0 else [(a, top), (a, bottom)]
        snake += ends
    path = np.array([(e, n, 4.0) for e, n in snake])
    area = (np.array([0.0, 0.0]), np.array([x[-1] + 7.0, y[-1] + 12.0]))
    return centres, np.full(len(centres), 0.5), path, area


def test_among_thousands_of_trees_the_way_home_runs_through_the_planned_path():
    import time

    centres, radii, path, (lo, hi) = _orchard()
    world = World(centres=centres, radii=radii, clearance_m=1.0, area_lower=lo, area_upper=hi,
                  band=(2.0, 7.0), min_separation_m=2.0, model=MODEL)
    assert len(centres) >= 1000
    here = np.array([path[41, 0], 60.0, 4.0])  # in the middle of an aisle, far from home
    home = path[0, :2]
    t = time.perf_counter()
    plan = plan_return({0: here}, {0: home}, world, roadmaps={0: path})
    seconds = time.perf_counter() - t
    route = plan.routes[0]
    # through points of its own planned path (an aisle's end, the headland), not round
    # every tree: the roadmap's points, on its layer
    inner = route.points[2:-1, :2]
    assert len(inner) and all(np.min(np.hypot(*(path[:, :2] - p).T)) < 1e-9 for p in inner)
    assert _clearance(route, world) >= world.clearance_m - 1e-6
    assert np.allclose(route.positions[-1], [*home, 0.0])
    print(f"way home among {len(centres)} trees: {seconds:.2f} s")
