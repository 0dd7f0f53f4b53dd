"""The original TLBO baseline: determinism, FTLBO's budget, the learner step."""

from __future__ import annotations

import numpy as np

from ftlbo_mav.planning.optimizers import Objective, evaluation_budget, tlbo
from ftlbo_mav.planning.optimizers.tlbo import learner_step


def sphere(dim: int = 6) -> Objective:
    return Objective(lambda x: (x**2).sum(axis=1), -np.ones(dim) * 5, np.ones(dim) * 5)


def test_same_seed_same_result_different_seed_different_result():
    runs = [tlbo(sphere(), students=10, iterations=15, rng=np.random.default_rng(s))
            for s in (3, 3, 4)]
    assert np.array_equal(runs[0].x, runs[1].x)
    assert np.array_equal(runs[0].history, runs[1].history)
    assert not np.array_equal(runs[0].x, runs[2].x)


def test_spends_exactly_ftlbos_budget_and_converges():
    objective = sphere()
    calls = []
    result = tlbo(objective, students=20, iterations=60, rng=np.random.default_rng(0),
                  progress=lambda it, total, best: calls.append(it))
    assert result.evaluations == objective.evaluations == evaluation_budget(20, 60)
    assert calls == list(range(1, 61))
    assert result.history.shape == (60,)
    assert np.all(np.diff(result.history) <= 0)
    assert result.cost == result.history[-1] < 1e-3
    assert np.all(np.abs(result.x) <= 5)


def test_learner_step_moves_away_from_worse_and_towards_better_partner():
    x = np.array([[0.0, 0.0], [10.0, 10.0]])
    f = np.array([1.0, 2.0])
    new = learner_step(x, f, np.random.default_rng(0))
    assert np.all(new[0] <= 0.0)  # student 0 is better: moves away from student 1
    assert np.all((new[1] >= 0.0) & (new[1] <= 10.0))  # student 1 moves towards student 0
