"""The original teaching-learning-based optimization (Rao, Savsani & Vakharia 2011).

One iteration is a teacher phase and a learner phase, each with greedy acceptance; no
mutation, no elitism, one partner per student (the paper's baseline "TLBO", Table 2).

- Teacher phase: ``S_new = S + r * (T - TF * A)`` (the paper's eq. 12, shared with FTLBO:
  :func:`.ftlbo.teacher_step`), ``TF`` in {1, 2} per student, ``r`` per variable.
- Learner phase (eq. 13, as Rao et al. write it): student ``i`` draws one partner
  ``k != i``; ``S_new = S_i + r * (S_i - S_k)`` when ``i`` is the better of the two, else
  ``S_i + r * (S_k - S_i)``.

Like :mod:`.ftlbo`, each phase updates the whole class at once and evaluates it in one
vectorized call; candidates are clipped to the bounds. The run stops at FTLBO's budget
(:func:`.base.evaluation_budget`): TLBO spends 2S per own iteration, so it gets a partial
last phase (only the first students of that phase are moved) and its history is kept on
FTLBO's clock (:class:`.base.BudgetTracker`).
"""

from __future__ import annotations

import numpy as np

from .base import BudgetTracker, Objective, OptimizerResult, Progress, greedy
from .ftlbo import teacher_step


def learner_step(x: np.ndarray, f: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Rao's learner phase for the class ``x (S, D)`` with costs ``f (S,)``.

    Every student learns from one partner ``k != i`` drawn for the whole vector.
    """
    S, D = x.shape
    partner = (np.arange(S) + rng.integers(1, S, size=S)) % S
    x_partner = x[partner]
    better = (f < f[partner])[:, None]
    direction = np.where(better, x - x_partner, x_partner - x)
    return x + rng.random((S, D)) * direction


def _phase(objective, x, f, x_new, remaining):
    """Evaluate and accept ``x_new``, only its first ``remaining`` rows if the budget ends."""
    n = min(len(x), remaining)
    if n == len(x):
        return greedy(x, f, x_new, objective(x_new))
    x, f = x.copy(), f.copy()
    x[:n], f[:n] = greedy(x[:n], f[:n], x_new[:n], objective(x_new[:n]))
    return x, f


def tlbo(
    objective: Objective,
    *,
    students: int,
    iterations: int,
    rng: np.random.Generator,
    progress: Progress | None = None,
) -> OptimizerResult:
    """Minimize ``objective`` with the original TLBO within FTLBO's evaluation budget."""
    tracker = BudgetTracker(objective, students=students, iterations=iterations,
                            progress=progress)
    x = objective.random(rng, students)
    f = objective(x)
    while tracker.remaining > 0:
        teacher = x[np.argmin(f)]
        x_new = objective.clip(teacher_step(x, teacher, rng))
        x, f = _phase(objective, x, f, x_new, tracker.remaining)
        tracker.record(f.min())
        if tracker.remaining == 0:
            break
        x_new = objective.clip(learner_step(x, f, rng))
        x, f = _phase(objective, x, f, x_new, tracker.remaining)
        tracker.record(f.min())
    best = int(np.argmin(f))
    history = tracker.finish(float(f[best]))
    return OptimizerResult(x[best].copy(), float(f[best]), history, objective.evaluations)
