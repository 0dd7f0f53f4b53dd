from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.planning.optimizers import Objective, ftlbo
from ftlbo_mav.planning.optimizers.ftlbo import (
    chaotic_mutation,
    learner_step_multi_subject,
    logistic_sequence,
    teacher_step,
)
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.scenario import load_scenario


def sphere_objective(dim: int = 6) -> Objective:
    return Objective(lambda x: (x**2).sum(axis=1), -np.ones(dim) * 5, np.ones(dim) * 5)


def test_same_seed_same_result_different_seed_different_result():
    runs = [
        ftlbo(sphere_objective(), students=10, iterations=20, rng=np.random.default_rng(s))
        for s in (7, 7, 8)
    ]
    assert np.array_equal(runs[0].x, runs[1].x)
    assert np.array_equal(runs[0].history, runs[1].history)
    assert not np.array_equal(runs[0].x, runs[2].x)


def test_evaluation_budget_history_and_convergence():
    objective = sphere_objective()
    result = ftlbo(objective, students=20, iterations=60, rng=np.random.default_rng(0))
    assert result.evaluations == objective.evaluations == 20 + 60 * (2 * 20 + 1)
    assert result.history.shape == (60,)
    assert np.all(np.diff(result.history) <= 0)  # the best never gets worse
    assert result.cost == result.history[-1] < 1e-3
    assert np.all(np.abs(result.x) <= 5)


def test_progress_is_reported_every_iteration():
    calls = []
    ftlbo(sphere_objective(), students=6, iterations=5, rng=np.random.default_rng(0),
          progress=lambda it, total, best: calls.append((it, total)))
    assert calls == [(i, 5) for i in range(1, 6)]


def test_teacher_step_is_eq_12():
    rng_a, rng_b = np.random.default_rng(3), np.random.default_rng(3)
    x = np.random.default_rng(0).random((5, 4))
    teacher = x[2]
    new = teacher_step(x, teacher, rng_a)
    tf = rng_b.integers(1, 3, size=(5, 1))
    w0 = rng_b.random((5, 4))
    assert np.allclose(new, x + w0 * (teacher - tf * x.mean(axis=0)))


def test_learner_step_moves_towards_better_partners_only():
    x = np.array([[0.0], [10.0]])
    f = np.array([1.0, 2.0])  # student 0 is better
    new = learner_step_multi_subject(x, f, np.random.default_rng(0))
    assert new[0, 0] <= 0.0  # moves away from the worse partner
    assert 0.0 <= new[1, 0] <= 10.0  # moves towards the better one


def test_logistic_sequence_and_chaotic_mutation():
    values, last = logistic_sequence(0.3, 50)
    assert np.all((values >= 0) & (values <= 1)) and last == values[-1]
    assert values[0] == pytest.approx(4 * 0.3 * 0.7)
    best = np.zeros(50)
    same, _ = chaotic_mutation(best, 0.0, 0.3, np.random.default_rng(0))
    assert np.array_equal(same, best)  # mu = 0: nothing mutates
    moved, _ = chaotic_mutation(best, 1.0, 0.3, np.random.default_rng(0))
    assert np.allclose(moved, 2 * values - 1)  # mu = 1: every variable by z = 2 X_n - 1


def test_same_seed_same_plan(small_path):
    scenario = load_scenario(small_path)
    a, b = plan(scenario, seed=5), plan(scenario, seed=5)
    assert np.array_equal(a.centroid, b.centroid)
    assert a.cost == b.cost


def test_example_plan_is_feasible_and_keeps_the_formation(example_path):
    scenario = load_scenario(example_path)
    result = plan(scenario, algorithm="ftlbo", waypoints=10, iterations=60)  # the paper's FTLBO
    assert result.feasible, result.violations
    assert result.evaluations == 100 + 60 * 201
    assert np.isfinite(result.cost.total)
    # every UAV's path is the centroid path plus its offset, from start to goal
    assert np.allclose(result.uav_paths - result.centroid, scenario.offsets_m[:, None, :])
    assert np.allclose(result.centroid[0], scenario.start_enu())
    assert np.allclose(result.centroid[-1], scenario.goal_enu())
    # the straight line crosses the trees: the planned path detours
    straight = np.linalg.norm(scenario.goal_enu() - scenario.start_enu())
    assert result.cost.length > straight * 1.02
