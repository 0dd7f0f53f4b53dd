"""The real-coded GA baseline: determinism, budget, elitism, operators."""

from __future__ import annotations

import numpy as np

from ftlbo_mav.planning.optimizers import Objective, evaluation_budget, ga
from ftlbo_mav.planning.optimizers.ga import polynomial_mutation, sbx_crossover, tournament


def sphere(dim: int = 6) -> Objective:
    return Objective(lambda x: (x**2).sum(axis=1), -np.ones(dim) * 5, np.ones(dim) * 5)


def test_same_seed_same_result_different_seed_different_result():
    runs = [ga(sphere(), students=10, iterations=15, rng=np.random.default_rng(s))
            for s in (3, 3, 4)]
    assert np.array_equal(runs[0].x, runs[1].x)
    assert np.array_equal(runs[0].history, runs[1].history)
    assert not np.array_equal(runs[0].x, runs[2].x)


def test_spends_exactly_ftlbos_budget_and_elitism_keeps_the_best():
    objective = sphere()
    result = ga(objective, students=20, iterations=60, rng=np.random.default_rng(0))
    assert result.evaluations == objective.evaluations == evaluation_budget(20, 60)
    assert result.history.shape == (60,)
    assert np.all(np.diff(result.history) <= 0)  # elitism of one: never worse
    assert result.cost == result.history[-1] < 0.5
    assert np.all(np.abs(result.x) <= 5)


def test_operators():
    rng = np.random.default_rng(0)
    f = np.array([3.0, 1.0, 2.0])
    winners = tournament(f, 1000, rng)
    assert np.bincount(winners, minlength=3).argmax() == 1  # the best wins most
    assert not np.any(winners == 0) or np.mean(winners == 0) < 0.2  # the worst rarely
    p1, p2 = np.zeros((500, 4)), np.ones((500, 4))
    c1, c2 = sbx_crossover(p1, p2, rng)
    assert np.allclose(c1 + c2, p1 + p2)  # SBX keeps the parents' mean
    x = np.zeros((200, 10))
    mutated = polynomial_mutation(x, -np.ones(10), np.ones(10), rng)
    changed = np.mean(mutated != 0)
    assert 0.03 < changed < 0.2  # about 1/D of the variables
    assert np.all(np.abs(mutated) <= 2.0)
