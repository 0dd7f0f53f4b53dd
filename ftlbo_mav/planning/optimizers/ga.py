"""A real-coded genetic algorithm: the paper's "GA" baseline (Table 2).

The paper does not say which GA it ran; this is the textbook real-coded one (Deb):

- selection: binary tournament (the better of two students drawn with replacement);
- crossover: simulated binary crossover (SBX, distribution index 15) with probability
  0.9 per pair, each variable crossed with probability 0.5;
- mutation: polynomial mutation (distribution index 20), each variable with probability
  ``1 / D``, the step scaled by the variable's range;
- elitism of one: the best student is copied unchanged into the next generation, the
  other ``S - 1`` places are taken by children (generational replacement).

Children are clipped to the bounds. A generation costs ``S - 1`` evaluations; the run
stops at FTLBO's budget (:func:`.base.evaluation_budget`), the last generation is cut to
the evaluations left, and the history is kept on FTLBO's clock
(:class:`.base.BudgetTracker`).
"""

from __future__ import annotations

import numpy as np

from .base import BudgetTracker, Objective, OptimizerResult, Progress

CROSSOVER_PROBABILITY = 0.9
SBX_ETA = 15.0
MUTATION_ETA = 20.0


def tournament(f: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Indices of ``count`` binary-tournament winners among costs ``f (S,)``."""
    a = rng.integers(0, len(f), size=count)
    b = rng.integers(0, len(f), size=count)
    return np.where(f[a] <= f[b], a, b)


def sbx_crossover(
    p1: np.ndarray, p2: np.ndarray, rng: np.random.Generator, *, eta: float = SBX_ETA,
    probability: float = CROSSOVER_PROBABILITY,
) -> tuple[np.ndarray, np.ndarray]:
    """Simulated binary crossover of parent pairs ``p1, p2 (P, D)`` -> two children each."""
    P, D = p1.shape
    u = rng.random((P, D))
    beta = np.where(
        u <= 0.5, (2.0 * u) ** (1.0 / (eta + 1.0)), (0.5 / (1.0 - u)) ** (1.0 / (eta + 1.0))
    )
    cross = (rng.random((P, 1)) < probability) & (rng.random((P, D)) < 0.5)
    beta = np.where(cross, beta, 1.0)  # beta = 1: the children are the parents
    c1 = 0.5 * ((1.0 + beta) * p1 + (1.0 - beta) * p2)
    c2 = 0.5 * ((1.0 - beta) * p1 + (1.0 + beta) * p2)
    return c1, c2


def polynomial_mutation(
    x: np.ndarray, lower: np.ndarray, upper: np.ndarray, rng: np.random.Generator, *,
    eta: float = MUTATION_ETA, probability: float | None = None,
) -> np.ndarray:
    """Polynomial mutation of ``x (P, D)``; each variable with ``probability`` (1/D)."""
    P, D = x.shape
    probability = 1.0 / D if probability is None else probability
    u = rng.random((P, D))
    delta = np.where(
        u < 0.5,
        (2.0 * u) ** (1.0 / (eta + 1.0)) - 1.0,
        1.0 - (2.0 * (1.0 - u)) ** (1.0 / (eta + 1.0)),
    )
    mutate = rng.random((P, D)) < probability
    return x + np.where(mutate, delta * (upper - lower), 0.0)


def ga(
    objective: Objective,
    *,
    students: int,
    iterations: int,
    rng: np.random.Generator,
    progress: Progress | None = None,
) -> OptimizerResult:
    """Minimize ``objective`` with a real-coded GA within FTLBO's evaluation budget."""
    tracker = BudgetTracker(objective, students=students, iterations=iterations,
                            progress=progress)
    x = objective.random(rng, students)
    f = objective(x)
    while tracker.remaining > 0:
        count = min(students - 1, tracker.remaining)
        pairs = (count + 1) // 2
        parents = x[tournament(f, 2 * pairs, rng)]
        c1, c2 = sbx_crossover(parents[:pairs], parents[pairs:], rng)
        children = np.concatenate([c1, c2])[:count]
        children = objective.clip(
            polynomial_mutation(children, objective.lower, objective.upper, rng)
        )
        f_children = objective(children)
        elite = int(np.argmin(f))
        keep = np.setdiff1d(np.arange(students), [elite])[: students - 1 - count]
        x = np.concatenate([x[[elite]], x[keep], children])
        f = np.concatenate([f[[elite]], f[keep], f_children])
        tracker.record(f.min())
    best = int(np.argmin(f))
    history = tracker.finish(float(f[best]))
    return OptimizerResult(x[best].copy(), float(f[best]), history, objective.evaluations)
