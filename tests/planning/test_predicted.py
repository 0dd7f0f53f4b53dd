"""Feasibility on the predicted flown path, and the planner keeping the clearance there."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftlbo_mav.mission.export import plan_files
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.planning.predicted import (
    FlightModel,
    keep_clearance,
    predict,
    predicted_violations,
)
from ftlbo_mav.planning.problem import PlanningProblem
from ftlbo_mav.scenario import load_scenario

CLEARANCE = 1.0
OWN = np.array([1.0])
# a right-angle corner at (30, 10) with a tree inside it, 2.01 m from both legs: the
# polyline keeps 1.01 m from its surface, the corner flown through cuts ~1.4 m inside
PATH = np.array([[5.0, 10.0, 5.0], [30.0, 10.0, 5.0], [30.0, 35.0, 5.0]])
TREE = np.array([[27.99, 12.01]])
MODEL = FlightModel(speed_m_s=5.0)


def _problem(offsets=((0.0, 0.0, 0.0),)) -> PlanningProblem:
    return PlanningProblem(
        start=PATH[0], goal=PATH[-1], offsets=np.array(offsets, float), centres=TREE,
        radii=OWN + CLEARANCE, h_min=2.0, h_max=8.0, area_lower=np.array([0.0, 0.0]),
        area_upper=np.array([50.0, 50.0]), waypoints=1, weights=np.ones(3))


def test_the_flown_corner_cuts_in_where_the_polyline_keeps_the_clearance():
    problem = _problem()
    flown = predict(PATH[None], model=MODEL, centres=TREE, radii=OWN)
    assert flown.clearance[0] < CLEARANCE - 0.3
    said = predicted_violations(problem, flown, clearance_m=CLEARANCE, obstacle_radii=OWN,
                                min_separation_m=2.0)
    assert len(said) == 1 and "predicted flown path passes" in said[0]


def test_the_planner_moves_the_corner_until_the_flown_path_keeps_the_clearance():
    kept = keep_clearance(_problem(), PATH, model=MODEL, obstacle_radii=OWN,
                          clearance_m=CLEARANCE)
    assert kept.moved >= 1 and kept.stops == 0
    assert kept.prediction.clearance[0] >= CLEARANCE - 1e-6
    assert np.allclose(kept.centroid[[0, -1]], PATH[[0, -1]])  # the ends stay


def test_a_corner_that_may_not_move_becomes_a_stop():
    kept = keep_clearance(_problem(), PATH, model=MODEL, obstacle_radii=OWN,
                          clearance_m=CLEARANCE, fixed=np.array([True, True, True]))
    assert kept.stops == 1 and kept.holds_s[1] >= 1
    assert kept.prediction.clearance[0] >= CLEARANCE - 1e-6
    assert np.array_equal(kept.centroid, PATH)


def test_separation_is_measured_at_the_same_instant():
    offsets = ((0.0, 0.0, 0.0), (0.0, -2.5, 0.0))
    flown = predict(PATH[None] + np.array(offsets)[:, None], model=MODEL, centres=TREE,
                    radii=OWN)
    assert flown.separation == pytest.approx([2.5, 2.5], abs=1e-6)
    said = predicted_violations(_problem(offsets), flown, clearance_m=0.0,
                                obstacle_radii=OWN, min_separation_m=3.0)
    assert sum("from another UAV" in s for s in said) == 2


def test_the_example_keeps_its_clearance_on_the_flown_path_without_an_allowance(example_path):
    scenario = load_scenario(example_path)
    assert scenario.mission.corner_allowance_m == 0.0
    result = plan(scenario)
    assert result.feasible, result.violations
    assert result.prediction.clearance.min() >= scenario.clearance_m - 1e-6
    doc = json.loads(plan_files(result)["plan.json"])
    for n, uav in enumerate(doc["uavs"]):
        assert uav["predicted_clearance_m"] == pytest.approx(result.prediction.clearance[n],
                                                             abs=1e-4)
        assert uav["predicted_separation_m"] >= scenario.min_separation_m
        assert len(uav["predicted_leg_seconds"]) == len(uav["waypoints"]) - 1
    assert doc["predicted"]["min_clearance_m"] >= scenario.clearance_m - 1e-4
    assert doc["vehicle"]["WPNAV_ACCEL"] == 250.0


def test_a_corner_stop_is_the_waypoints_hold_in_every_mission(example_path):
    from dataclasses import replace

    from ftlbo_mav.mission.waypoints import parse_waypoints

    result = plan(load_scenario(example_path))
    holds = np.zeros(len(result.centroid))
    holds[1] = 1
    files = plan_files(replace(result, holds_s=holds))
    for n in (1, 2, 3):
        items = parse_waypoints(files[f"uav{n}.waypoints"])
        wps = [it for it in items[2:] if it.command == 16]
        assert [it.param1 for it in wps] == list(holds)
    assert json.loads(files["plan.json"])["predicted"]["holds_s"] == [0, 1, 0, 0]


def _measured_in_full(paths, model, centres, radii):
    """The flight measured on the full (N, T, K) and (N, N, T) arrays: the oracle."""
    from ftlbo_mav.ardupilot.flight_path import fly_paths

    flown = fly_paths(paths, nav=model.nav, speed_m_s=model.speed_m_s)
    T = max(len(f.times) for f in flown)
    pos = np.stack([np.vstack([f.positions, np.repeat(f.positions[-1:], T - len(f.times), 0)])
                    for f in flown])
    surface = np.linalg.norm(pos[:, :, None, :2] - centres[None, None], axis=-1) - radii
    flat = surface.reshape(len(paths), -1)
    worst = np.stack(np.unravel_index(flat.argmin(axis=1), surface.shape[1:]), axis=1)
    gap = np.linalg.norm(pos[:, None] - pos[None, :], axis=-1)
    gap[np.arange(len(paths)), np.arange(len(paths))] = np.inf
    return flat.min(axis=1), worst, surface.min(axis=(0, 1)), gap.min(axis=(1, 2))


@pytest.mark.parametrize("seed", range(4))
def test_the_measures_are_those_of_the_full_arrays(seed):
    """predict measures clearance and separation without the (N, T, K) array (nearest
    samples per flown shape, separations per group of translated paths): the same
    figures and the same worst instants as the full arrays, also for a UAV whose path
    is not a translation of the others'."""
    rng = np.random.default_rng(seed)
    base = np.cumsum(np.vstack([[0, 0, 5], rng.normal(0, 20, (4, 3)) * [1, 1, 0.05]]), axis=0)
    paths = base[None] + rng.normal(0, 3, (5, 3))[:, None] * [1, 1, 0.1]
    if seed % 2:
        paths[2, 2] += [3.0, 1.0, 0.0]
    centres, radii = rng.uniform(-40, 40, (30, 2)), rng.uniform(1, 3, 30)
    model = FlightModel(speed_m_s=5.0)
    p = predict(paths, model=model, centres=centres, radii=radii)
    clearance, worst, per_obstacle, separation = _measured_in_full(paths, model, centres, radii)
    assert np.allclose(p.clearance, clearance, atol=1e-9)
    assert (p.worst == worst).all()
    assert np.allclose(p.obstacle_clearance, per_obstacle, atol=1e-9)
    assert np.allclose(p.separation, separation, atol=1e-9)
