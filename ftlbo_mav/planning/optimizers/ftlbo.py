"""Formation teaching-learning-based optimization (the paper's FTLBO, section 3).

One iteration:

1. Teacher phase (eq. 12): ``S_new = S + w0 * (T - lambda * A)`` for every student,
   greedy acceptance.
2. Chaotic mutation around the best student (eqs. 14-17) and elite replacement of the
   worst student when the mutant is better (eq. 18).
3. Multi-subject learner phase (eq. 19): every decision variable of a student learns from
   its own randomly drawn partner, greedy acceptance.

Choices where the paper is ambiguous (NOTES 6-7):

- The teacher and learner phases update the whole class at once and evaluate it in one
  vectorized call (Rao's text updates students one after the other); ``w0`` is drawn per
  student and per variable, ``lambda`` (the teaching factor) per student.
- Eq. 15's ``xi`` is the evaluation counter (as in the pseudo-code), so the mutation
  probability ``mu = 1 - xi/xi_max`` falls linearly from 1 to 0 over the run; ``xi_max``
  is the run's evaluation budget.
- One mutant per iteration (the pseudo-code's ``xi = xi + 1``); its variable k moves by
  ``z_k = 2 X_n - 1`` metres (eq. 16) with probability ``mu``, where the logistic map
  (eq. 17) advances once per variable and carries over between iterations.
- Eq. 19 writes ``|S_ij - S_kj|``, which would only ever move a variable upwards. We read
  it as Rao and Patel's learner step: move away from the partner when the student is the
  better of the two, towards it otherwise.
- Candidates are clipped to the bounds after every move.
"""

from __future__ import annotations

import numpy as np

from .base import Objective, OptimizerResult, Progress, greedy

STALL_TOLERANCE = 1e-6
"""Relative improvement below which an iteration window counts as stalled (``patience``)."""

# Fixed points and short cycles of the logistic map that a random start must avoid.
_LOGISTIC_TRAPS = (0.0, 0.25, 0.5, 0.75, 1.0)


def teacher_step(x: np.ndarray, teacher: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Eq. 12 for the whole class ``x (S, D)``; ``teacher (D,)`` is the best student."""
    S, D = x.shape
    mean = x.mean(axis=0)
    teaching_factor = rng.integers(1, 3, size=(S, 1))  # lambda in {1, 2}
    w0 = rng.random((S, D))
    return x + w0 * (teacher - teaching_factor * mean)


def learner_step_multi_subject(
    x: np.ndarray, f: np.ndarray, rng: np.random.Generator
) -> np.ndarray:
    """Eq. 19: variable j of student i learns from its own partner ``k_ij != i``."""
    S, D = x.shape
    partner = (np.arange(S)[:, None] + rng.integers(1, S, size=(S, D))) % S
    x_partner = np.take_along_axis(x, partner, axis=0)
    better = (f[:, None] < f[partner])
    direction = np.where(better, x - x_partner, x_partner - x)
    return x + rng.random((S, D)) * direction


def logistic_sequence(x0: float, count: int) -> tuple[np.ndarray, float]:
    """``count`` values of the logistic map ``X <- 4 X (1 - X)`` (eq. 17) after ``x0``.

    Returns the values and the last one, to carry the sequence on.
    """
    values = np.empty(count)
    x = x0
    for i in range(count):
        x = 4.0 * x * (1.0 - x)
        values[i] = x
    return values, x


def chaotic_mutation(
    best: np.ndarray, mu: float, chaos: float, rng: np.random.Generator
) -> tuple[np.ndarray, float]:
    """Eqs. 14-16: mutate each variable of ``best (D,)`` by ``z = 2 X_n - 1`` with prob. ``mu``.

    Returns the mutant and the chaotic state to carry on.
    """
    values, chaos = logistic_sequence(chaos, best.size)
    z = 2.0 * values - 1.0
    mutate = rng.random(best.size) < mu
    return np.where(mutate, best + z, best), chaos


def _chaos_seed(rng: np.random.Generator) -> float:
    x = rng.random()
    while min(abs(x - t) for t in _LOGISTIC_TRAPS) < 1e-6:
        x = rng.random()
    return x


def ftlbo(
    objective: Objective,
    *,
    students: int,
    iterations: int,
    rng: np.random.Generator,
    progress: Progress | None = None,
    initial: np.ndarray | None = None,
    patience: int | None = None,
) -> OptimizerResult:
    """Minimize ``objective`` with FTLBO; budget ``students + iterations * (2 * students + 1)``.

    ``initial``: optional ``(I, D)`` students (``I <= students``) that replace the first
    random ones of the initial class (clipped to the bounds); the paper's FTLBO starts
    from random students only.

    ``patience``: stop early once the best cost has improved by less than
    ``STALL_TOLERANCE`` (relative) over the last ``patience`` iterations; the history's
    remaining iterations then repeat the final best. ``None`` (the paper) spends the
    whole budget.
    """
    budget = students + iterations * (2 * students + 1)
    x = objective.random(rng, students)
    if initial is not None:
        initial = objective.clip(np.atleast_2d(np.asarray(initial, float)))[:students]
        x[: len(initial)] = initial
    f = objective(x)
    chaos = _chaos_seed(rng)
    history = np.empty(iterations)
    for it in range(iterations):
        # 1. Teacher phase.
        teacher = x[np.argmin(f)]
        x_new = objective.clip(teacher_step(x, teacher, rng))
        x, f = greedy(x, f, x_new, objective(x_new))

        # 2. Chaotic mutation of the best, elite replacement of the worst.
        mu = 1.0 - objective.evaluations / budget
        mutant, chaos = chaotic_mutation(x[np.argmin(f)], mu, chaos, rng)
        if chaos in _LOGISTIC_TRAPS:  # float round-off can land the map on a fixed point
            chaos = _chaos_seed(rng)
        mutant = objective.clip(mutant)
        f_mutant = objective(mutant[None, :])[0]
        worst = int(np.argmax(f))
        if f_mutant < f[worst]:
            x[worst], f[worst] = mutant, f_mutant

        # 3. Multi-subject learner phase.
        x_new = objective.clip(learner_step_multi_subject(x, f, rng))
        x, f = greedy(x, f, x_new, objective(x_new))

        history[it] = f.min()
        if progress is not None:
            progress(it + 1, iterations, float(history[it]))
        if (
            patience is not None
            and it >= patience
            and history[it] >= history[it - patience] - STALL_TOLERANCE * abs(history[it])
        ):
            history[it + 1 :] = history[it]
            if progress is not None and it + 1 < iterations:
                progress(iterations, iterations, float(history[it]))
            break
    best = int(np.argmin(f))
    return OptimizerResult(x[best].copy(), float(f[best]), history, objective.evaluations)
