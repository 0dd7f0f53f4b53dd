"""theta-PSO: determinism, budget, the angle encoding."""

from __future__ import annotations

import numpy as np

from ftlbo_mav.planning.optimizers import Objective, evaluation_budget, theta_pso
from ftlbo_mav.planning.optimizers.theta_pso import MAX_VELOCITY, angle_to_position, velocity_step


def sphere(dim: int = 6) -> Objective:
    return Objective(lambda x: ((x - 1.0) ** 2).sum(axis=1), -np.ones(dim) * 5, np.ones(dim) * 5)


def test_same_seed_same_result_different_seed_different_result():
    runs = [theta_pso(sphere(), students=10, iterations=15, rng=np.random.default_rng(s))
            for s in (3, 3, 4)]
    assert np.array_equal(runs[0].x, runs[1].x)
    assert np.array_equal(runs[0].history, runs[1].history)
    assert not np.array_equal(runs[0].x, runs[2].x)


def test_spends_exactly_ftlbos_budget_and_converges_inside_the_bounds():
    objective = sphere()
    result = theta_pso(objective, students=20, iterations=60, rng=np.random.default_rng(0))
    assert result.evaluations == objective.evaluations == evaluation_budget(20, 60)
    assert np.all(np.diff(result.history) <= 0)
    assert result.cost == result.history[-1] < 1e-2
    assert np.all(np.abs(result.x) <= 5)
    assert objective(result.x)[0] == result.cost


def test_angle_encoding_maps_the_angle_range_onto_the_bounds():
    lower, upper = np.array([-2.0, 10.0]), np.array([4.0, 11.0])
    theta = np.array([[-np.pi / 2, -np.pi / 2], [0.0, 0.0], [np.pi / 2, np.pi / 2]])
    x = angle_to_position(theta, lower, upper)
    assert np.allclose(x, [lower, (lower + upper) / 2, upper])


def test_velocity_is_clamped():
    rng = np.random.default_rng(0)
    theta = np.zeros((5, 3))
    v = velocity_step(np.full((5, 3), 10.0), theta, theta + 1, theta[0] - 1, 0.9, rng)
    assert np.all(np.abs(v) <= MAX_VELOCITY)
