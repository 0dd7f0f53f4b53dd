"""A leg's window (planning/window.py): exact for every candidate inside it, the same
shortest route as the whole problem, and what the planner and its admission check do
with it among thousands of trees."""

from __future__ import annotations

import json
from dataclasses import replace

import numpy as np
import pytest

from ftlbo_mav.planning import window as W
from ftlbo_mav.planning.feasibility import violations
from ftlbo_mav.planning.geometric import shortest_routes
from ftlbo_mav.planning.planner import WORK_LIMIT, check_size, plan_leg
from ftlbo_mav.planning.problem import PlanningProblem
from ftlbo_mav.scenario import PlannerSettings, load_scenario


def strip(*, trees: int, seed: int = 0, length: float = 600.0) -> PlanningProblem:
    """A 600 m x 60 m strip of ``trees`` random trees (radius + clearance 1.5-2.5 m),
    three UAVs in a triangle, a leg of 100 m through the middle of it."""
    rng = np.random.default_rng(seed)
    start, goal = np.array([250.0, 30.0, 4.0]), np.array([350.0, 34.0, 4.0])
    centres, radii = [], []
    while len(centres) < trees:
        c = rng.uniform([0.0, 0.0], [length, 60.0])
        r = float(rng.uniform(1.5, 2.5))
        if min(np.hypot(*(c - start[:2])), np.hypot(*(c - goal[:2]))) > r + 4.0:
            centres.append(c)
            radii.append(r)
    return PlanningProblem(
        start=start, goal=goal,
        offsets=np.array([[0.0, 1.5, 0.0], [-1.3, -0.75, 0.0], [1.3, -0.75, 0.0]]),
        centres=np.array(centres), radii=np.array(radii), h_min=2.0, h_max=7.0,
        area_lower=np.array([0.0, 0.0]), area_upper=np.array([length, 60.0]),
        waypoints=6, weights=np.ones(3))


def test_the_ellipse_lies_in_its_box_and_touches_each_side():
    a, b = np.array([3.0, -2.0]), np.array([40.0, 25.0])
    reach = 1.1 * np.hypot(*(b - a))
    lo, hi = W.ellipse_box(a, b, reach)
    # the ellipse |p-a| + |p-b| = reach, sampled: inside the box, reaching every side
    d = np.hypot(*(b - a))
    u = (b - a) / d
    v = np.array([-u[1], u[0]])
    t = np.linspace(0.0, 2 * np.pi, 20001)
    major, minor = reach / 2, np.sqrt((reach / 2) ** 2 - (d / 2) ** 2)
    p = (a + b) / 2 + np.outer(major * np.cos(t), u) + np.outer(minor * np.sin(t), v)
    assert np.allclose(np.hypot(*(p - a).T) + np.hypot(*(p - b).T), reach)
    assert np.all(p >= lo - 1e-9) and np.all(p <= hi + 1e-9)
    np.testing.assert_allclose(p.min(axis=0), lo, atol=1e-5)
    np.testing.assert_allclose(p.max(axis=0), hi, atol=1e-5)


def test_every_cylinder_left_out_has_every_disc_outside_the_box():
    problem = strip(trees=400)
    window = W.cut(problem, 110.0)
    assert 0 < len(window.kept) < 400
    lower, upper = window.problem.bounds()
    lo, hi = lower[0, :2], upper[0, :2]  # the centroid's box
    out = np.setdiff1d(np.arange(400), window.kept)
    axes = problem.centres[None, out] - problem.offsets[:, None, :2]
    # the nearest point of the box to every left-out disc's centre is outside that disc
    nearest = np.clip(axes, lo, hi)
    assert np.all(np.hypot(*(nearest - axes).transpose(2, 0, 1)) >= problem.radii[out])
    # and a random candidate inside the box is judged alike by the window and the whole
    rng = np.random.default_rng(1)
    for _ in range(40):
        path = np.vstack([problem.start, np.column_stack(
            [rng.uniform(lo, hi, (6, 2)), np.full(6, 4.0)]), problem.goal])
        assert bool(violations(window.problem, path)) == bool(violations(problem, path))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_windows_route_is_the_whole_problems(seed):
    problem = strip(trees=W.WINDOW_FROM + 40, seed=seed)
    window = W.leg_window(problem, count=1, routes=lambda p, count: shortest_routes(p, count=count))
    whole = shortest_routes(problem)[0]
    assert not window.whole and len(window.kept) < len(problem.radii) / 2
    assert window.routes[0].length == pytest.approx(whole.length, rel=1e-9)
    assert window.routes[0].length <= window.reach_m


def test_a_clear_straight_leg_is_its_line_without_a_graph():
    problem = strip(trees=W.WINDOW_FROM + 100)
    aside = np.abs(problem.centres[:, 1] - 30.0) > 6.0  # an aisle along the strip
    lane = replace(problem, start=np.array([5.0, 30.0, 4.0]), goal=np.array([595.0, 30.0, 4.0]),
                   centres=problem.centres[aside], radii=problem.radii[aside])
    assert len(lane.radii) >= W.WINDOW_FROM and W.straight_clear(lane)

    def no_graph(p, count):
        raise AssertionError("a graph was built")

    window = W.leg_window(lane, count=4, routes=no_graph)
    (route,) = window.routes
    assert route.length == pytest.approx(590.0) and route.arcs == (None,)
    assert window.reach_m == pytest.approx(590.0 + W.WINDOW_MIN_M)


def test_a_leg_in_its_window_is_judged_on_the_whole_problem():
    problem = strip(trees=W.WINDOW_FROM + 40)
    leg = plan_leg(problem, PlannerSettings(waypoints="auto", seed=0),
                   rng=np.random.default_rng(0))
    assert leg.searched is not None and len(leg.searched.radii) < len(problem.radii)
    assert len(leg.problem.radii) == len(problem.radii)
    assert leg.feasible and violations(problem, leg.centroid) == []
    assert leg.cost.length <= (1 + 0.005) * leg.lower_bound_length
    # below WINDOW_FROM nothing changes: every leg sees every obstacle
    few = replace(problem, centres=problem.centres[:50], radii=problem.radii[:50])
    assert plan_leg(few, PlannerSettings(waypoints="auto", seed=0),
                    rng=np.random.default_rng(0)).searched is None


def _orchard(folder, *, rows: int, per_row: int):
    """An orchard as a tree-detection tool exports it: Points with a radius, north-south
    rows 7 m apart, trees 3 m apart; three UAVs in a column surveying every aisle."""
    from ftlbo_mav.geo import LocalFrame

    lat0, lon0 = 12.2331044, 109.1144313
    frame = LocalFrame(lat0, lon0)
    e, n = np.meshgrid((np.arange(rows) + 1) * 7.0, 12.0 + np.arange(per_row) * 3.0,
                       indexing="ij")
    lat, lon, _ = frame.to_lla(np.stack([e, n, np.zeros_like(e)], axis=-1))
    features = [{"type": "Feature", "properties": {"radius": 1.0},
                 "geometry": {"type": "Point", "coordinates": [float(x), float(y)]}}
                for x, y in zip(lon.ravel(), lat.ravel())]
    (folder / "trees.geojson").write_text(json.dumps({"type": "FeatureCollection",
                                                      "features": features}))
    width, length = (rows + 1) * 7.0, 24.0 + (per_row - 1) * 3.0
    (lat_b,), (lon_b,), _ = frame.to_lla([[width, length, 0.0]])
    (s_lat,), (s_lon,), _ = frame.to_lla([[3.5, 5.0, 0.0]])
    # the goal beyond the last lane's end (north with an odd number of lanes)
    (g_lat,), (g_lon,), _ = frame.to_lla([[width - 3.5, length - 5.0 if rows % 2 == 0 else 5.0,
                                           0.0]])
    path = folder / "orchard.toml"
    path.write_text("\n".join([
        'name = "orchard"', 'obstacles_file = "trees.geojson"',
        "[area]", f"corner_a = [{lat0}, {lon0}]", f"corner_b = [{lat_b:.8f}, {lon_b:.8f}]",
        "min_altitude = 2.0", "max_altitude = 7.0",
        "[start]", f"lat = {s_lat:.8f}", f"lon = {s_lon:.8f}", "alt = 4.0",
        "[goal]", f"lat = {g_lat:.8f}", f"lon = {g_lon:.8f}", "alt = 4.0",
        "[formation]", "offsets = [[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, -4.0, 0.0]]",
        "clearance = 1.0", "[navigation]", "horizontal_error = 0.0",
        "[survey]", "spacing = 7.0", "heading = 0.0", "margin = 3.5",
        "[planner]", 'waypoints = "auto"', ""]))
    return load_scenario(path)


def test_the_admission_check_counts_each_leg_among_its_window(tmp_path):
    # the orchard: 4,800 trees, 61 lanes; refused before as 8.2e+11 checks
    scenario = _orchard(tmp_path, rows=60, per_row=80)
    assert len(scenario.obstacles) == 4800 and len(scenario.survey.lanes) == 61
    settings = scenario.planner
    legs = len(scenario.via) + 1
    naive = (settings.students * settings.iterations * legs * 2 * scenario.uav_count * 4800)
    assert naive > WORK_LIMIT
    check_size(scenario, settings)  # admitted: each leg among its own few hundred trees
    # a plan that is too large for what it really does is still refused, saying so
    with pytest.raises(Exception, match="within its reach"):
        check_size(scenario, replace(settings, students=2000, iterations=2000))


def test_an_orchard_survey_is_planned_lane_by_lane_in_windows(tmp_path):
    # 240 trees in 8 rows (from WINDOW_FROM on, windows): every aisle flown, each lane
    # planned among the trees beside it, the flown path predicted against every tree
    from ftlbo_mav.planning.planner import plan

    scenario = _orchard(tmp_path, rows=8, per_row=30)
    assert len(scenario.obstacles) == 240 >= W.WINDOW_FROM
    p = plan(scenario)
    assert p.feasible, p.violations
    lanes = [leg for leg in p.legs if leg.start_name.endswith("start")
             and leg.goal_name.endswith("end")]
    assert len(lanes) == len(p.scenario.survey.lanes) == 9
    for leg in lanes:  # a lane among the two rows beside it and their neighbours' edges
        assert leg.searched is not None and len(leg.searched.radii) <= 4 * 30
        assert leg.length_ratio <= 1.005  # "auto": within 0.5% of its bound
    # the prediction measures every tree, and keeps the clearance from each of them
    assert len(p.prediction.obstacle_clearance) == 240
    assert p.prediction.obstacle_clearance.min() >= scenario.clearance_m - 1e-6
    assert p.prediction.reached.shape[1] == len(p.centroid)  # every lane's ends reached
