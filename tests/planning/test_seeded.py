"""The seeded FTLBO default planner: near the bound, feasible, deterministic, no route."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.planning.optimizers import DEFAULT_ALGORITHM, OPTIMIZERS, Objective
from ftlbo_mav.planning.optimizers.seeded import ftlbo_seeded, seeded_class
from ftlbo_mav.planning.planner import NO_ROUTE, plan
from ftlbo_mav.scenario import ALGORITHMS, PlannerSettings, load_scenario, parse_scenario

from ..conftest import EXAMPLE, SMALL


def test_the_seeded_planner_is_the_default_and_every_algorithm_is_accepted():
    assert PlannerSettings().algorithm == DEFAULT_ALGORITHM == "ftlbo-seeded"
    assert set(ALGORITHMS) == set(OPTIMIZERS)
    assert parse_scenario(SMALL).planner.algorithm == DEFAULT_ALGORITHM


def test_seeded_class_keeps_every_seed_and_perturbs_copies():
    seeds = np.arange(12.0).reshape(2, 6)
    students = seeded_class(seeds, 6, np.random.default_rng(0))
    assert np.array_equal(students[:2], seeds)  # every seed once, unchanged
    assert np.allclose(students[2:4], seeds[0], atol=2.0) and not np.array_equal(
        students[2], seeds[0])
    assert np.allclose(students[4:], seeds[1], atol=2.0)


def test_same_seed_same_result_and_plain_ftlbo_without_seeds():
    def objective():
        return Objective(lambda x: ((x - 1) ** 2).sum(axis=1), -np.ones(6) * 5, np.ones(6) * 5)

    seeds = np.ones((1, 6)) * 0.9
    a, b = (ftlbo_seeded(objective(), students=10, iterations=20, rng=np.random.default_rng(2),
                         seeds=seeds) for _ in range(2))
    assert np.array_equal(a.x, b.x) and np.array_equal(a.history, b.history)
    assert a.history[0] <= 6 * 0.01 + 1e-12  # the seed is in the first class
    plain = ftlbo_seeded(objective(), students=10, iterations=20, rng=np.random.default_rng(2))
    assert plain.history[0] > a.history[0]


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_example_default_plan_is_feasible_and_within_one_percent_of_the_bound(seed):
    scenario = load_scenario(EXAMPLE)
    result = plan(scenario, algorithm=DEFAULT_ALGORITHM, seed=seed)
    assert result.feasible, result.violations
    assert result.lower_bound_length is not None
    assert 1.0 < result.length_ratio < 1.01
    assert result.evaluations <= 100 + 150 * 201  # early stop: never more than the budget
    assert result.history.shape == (150,)


def test_same_seed_same_plan():
    scenario = load_scenario(EXAMPLE)
    a, b = (plan(scenario, algorithm=DEFAULT_ALGORITHM, seed=4, iterations=40) for _ in range(2))
    assert np.array_equal(a.centroid, b.centroid)


BLOCKED = SMALL.replace("radius = 3.0", "radius = 27.5")  # covers the area north-south


def test_no_route_is_said_in_one_line_before_optimizing():
    scenario = parse_scenario(BLOCKED)
    lines = []
    result = plan(scenario, notice=lines.append)
    assert lines == [NO_ROUTE] and "\n" not in NO_ROUTE
    assert result.lower_bound_length is None and result.length_ratio is None


@pytest.mark.slow
def test_example_thirty_seeds_median_within_one_percent_all_feasible():
    scenario = load_scenario(EXAMPLE)
    plans = [plan(scenario, algorithm=DEFAULT_ALGORITHM, seed=s) for s in range(30)]
    assert all(p.feasible for p in plans)
    assert np.median([p.length_ratio for p in plans]) < 1.01


@pytest.mark.slow
@pytest.mark.parametrize("trial", range(6))
def test_random_fields_no_feasible_plan_beats_the_bound(trial):
    rng = np.random.default_rng(100 + trial)
    trees = "\n".join(
        f"[[obstacles]]\nlat = {12.2331044 + rng.uniform(0.00005, 0.0004):.7f}\n"
        f"lon = {109.1144313 + rng.uniform(0.0001, 0.0007):.7f}\nradius = {rng.uniform(1, 3):.2f}"
        for _ in range(6)
    )
    text = SMALL.split("[[obstacles]]")[0] + trees + "\n[planner]\nseed = 0\n"
    try:
        scenario = parse_scenario(text)
    except ScenarioError:  # a tree on the start or goal: not a valid field
        pytest.skip("random tree on the start or goal")
    for algorithm in ("ftlbo", DEFAULT_ALGORITHM):
        result = plan(scenario, algorithm=algorithm, iterations=60)
        if result.lower_bound_length is None:
            assert not result.feasible
        elif result.feasible:
            assert result.cost.length > result.lower_bound_length


def test_plan_command_says_no_route_in_one_line(tmp_path):
    from click.testing import CliRunner

    from ftlbo_mav.cli import main

    path = tmp_path / "blocked.toml"
    path.write_text(BLOCKED)
    result = CliRunner().invoke(main, ["plan", str(path), "-o", str(tmp_path / "out"),
                                       "--iterations", "3", "-q"])
    assert result.exit_code == 1
    assert result.stderr.splitlines()[0] == NO_ROUTE  # before anything else
    assert "no route: no lower bound" in result.stdout
    assert "Traceback" not in result.output


def orchard(rng: np.random.Generator, offsets: np.ndarray):
    """A random orchard on the example's area: 5-11 trees of radius 2-4.5 m (+1 m
    clearance) between start and goal."""
    from ftlbo_mav.planning.problem import PlanningProblem

    start, goal = np.array([8.0, 12.0, 4.0]), np.array([80.0, 40.0, 4.0])
    centres, radii, count = [], [], rng.integers(5, 12)
    while len(centres) < count:
        c, r = rng.uniform([15, 5], [75, 45]), rng.uniform(2.0, 4.5)
        if min(np.linalg.norm(c - start[:2]), np.linalg.norm(c - goal[:2])) > r + 7.0:
            centres.append(c)
            radii.append(r)
    return PlanningProblem(
        start=start, goal=goal, offsets=offsets, centres=np.array(centres),
        radii=np.array(radii) + 1.0, h_min=2.0, h_max=7.0, area_lower=np.array([0.0, 0.0]),
        area_upper=np.array([86.0, 49.5]), waypoints=10, weights=np.ones(3))


@pytest.mark.slow
@pytest.mark.parametrize("trial", range(6))
def test_random_orchards_default_plan_within_one_percent_or_no_route(trial):
    from ftlbo_mav.formation import regular_formation
    from ftlbo_mav.planning.planner import solve

    formations = [np.array([[0, 0, 2], [3, 0, -1], [-3, 0, -1]], float),
                  regular_formation(count=4, radius_m=3.0, plane="horizontal"),
                  regular_formation(count=6, radius_m=4.0, plane="horizontal")]
    problem = orchard(np.random.default_rng(50 + trial), formations[trial % 3])
    result = solve(problem, load_scenario(EXAMPLE),
                   PlannerSettings(algorithm=DEFAULT_ALGORITHM, seed=trial))
    if result.lower_bound_length is None:
        assert not result.feasible  # no route: nothing flyable either
    else:
        assert result.feasible, result.violations
        assert result.length_ratio < 1.01


def test_a_leg_whose_seed_is_the_optimum_is_not_optimized():
    """No cylinder near the leg, the seed on the straight line, every UAV inside the band:
    no path costs less, so FTLBO is not run (1 evaluation) and the plan is that line; a
    leg with a tree in its window is optimized as before."""
    from ftlbo_mav.planning.planner import _seed_at_optimum
    from ftlbo_mav.planning.problem import PlanningProblem

    open_field = PlanningProblem(
        start=np.array([0.0, 0.0, 4.0]), goal=np.array([30.0, 40.0, 6.0]),
        offsets=np.zeros((1, 3)), centres=np.zeros((0, 2)), radii=np.zeros(0), h_min=2.0,
        h_max=7.0, area_lower=np.full(2, -10.0), area_upper=np.full(2, 60.0), waypoints=1,
        weights=np.ones(3))
    objective = Objective(lambda x: x.sum(axis=1), *(b.ravel() for b in open_field.bounds()))
    seed = (open_field.start + open_field.goal) / 2
    result = _seed_at_optimum(open_field, objective, seed, 150, None)
    assert result is not None and result.evaluations == 1
    assert result.cost == pytest.approx(np.linalg.norm(open_field.goal - open_field.start))
    # off the line: longer than the straight line, optimized
    assert _seed_at_optimum(open_field, objective, seed + [5.0, 0, 0], 150, None) is None
    treed = replace(open_field, centres=np.array([[40.0, 10.0]]), radii=np.array([1.0]))
    assert _seed_at_optimum(treed, objective, seed, 150, None) is None
    # a formation taller than the band: the task term is never 0
    tall = replace(open_field, offsets=np.array([[0.0, 0.0, -3.0], [0.0, 0.0, 3.0]]))
    assert _seed_at_optimum(tall, objective, seed, 150, None) is None
