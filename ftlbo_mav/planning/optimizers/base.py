"""What every optimizer shares: the objective wrapper that counts evaluations, and results.

An optimizer is a function ``(objective, *, students, iterations, rng, progress) ->
OptimizerResult``. It draws every random number from the injected ``rng``
(``numpy.random.Generator``), so the same seed gives the same result, and evaluates the
cost only through ``objective``, which counts every evaluated candidate the same way for
every algorithm (a fair budget in comparisons).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

Progress = Callable[[int, int, float], None]
"""``progress(iteration, iterations, best_cost)``, called once per iteration."""


class Objective:
    """A vectorized cost over flat decision vectors, with bounds and an evaluation counter.

    ``cost``: ``(S, D) -> (S,)``; ``lower``, ``upper``: ``(D,)``.
    """

    def __init__(self, cost: Callable[[np.ndarray], np.ndarray], lower, upper) -> None:
        self._cost = cost
        self.lower = np.asarray(lower, float).ravel()
        self.upper = np.asarray(upper, float).ravel()
        if self.lower.shape != self.upper.shape or np.any(self.lower > self.upper):
            raise ValueError("bounds must have one shape and lower <= upper")
        self.evaluations = 0

    @property
    def dimension(self) -> int:
        return self.lower.size

    def __call__(self, x: np.ndarray) -> np.ndarray:
        x = np.atleast_2d(x)
        self.evaluations += x.shape[0]
        return np.asarray(self._cost(x), float)

    def clip(self, x: np.ndarray) -> np.ndarray:
        return np.clip(x, self.lower, self.upper)

    def random(self, rng: np.random.Generator, count: int) -> np.ndarray:
        """``count`` uniform random points in the bounds (the paper's initialisation)."""
        return self.lower + rng.random((count, self.dimension)) * (self.upper - self.lower)


@dataclass(frozen=True)
class OptimizerResult:
    """Best decision vector ``x (D,)``, its cost, the best cost after each iteration."""

    x: np.ndarray
    cost: float
    history: np.ndarray
    evaluations: int


class Optimizer(Protocol):
    def __call__(
        self,
        objective: Objective,
        *,
        students: int,
        iterations: int,
        rng: np.random.Generator,
        progress: Progress | None = None,
    ) -> OptimizerResult: ...


def greedy(x_old, f_old, x_new, f_new):
    """Keep each new candidate only if it is strictly better (TLBO's acceptance)."""
    better = f_new < f_old
    return np.where(better[:, None], x_new, x_old), np.where(better, f_new, f_old)


def evaluation_budget(students: int, iterations: int) -> int:
    """FTLBO's evaluations for a run: the budget every algorithm gets in a comparison.

    The initial class, then per iteration the teacher phase (``students``), one chaotic
    mutant and the learner phase (``students``).
    """
    return students + iterations * (2 * students + 1)


class BudgetTracker:
    """Stops an optimizer at FTLBO's budget and records its history on FTLBO's clock.

    Algorithms spend different numbers of evaluations per own iteration (TLBO 2S, a GA or
    PSO S), so a comparison counts in *FTLBO iterations*: iteration ``i`` ends when
    ``students + i * (2 * students + 1)`` evaluations are spent. ``record(best)`` is
    called after every evaluated batch; the best cost so far is written into every
    checkpoint the batch reached (a batch crossing a checkpoint is credited to it, so the
    history is at most one batch ahead of the clock), and ``progress`` is called once per
    checkpoint.
    """

    def __init__(
        self,
        objective: Objective,
        *,
        students: int,
        iterations: int,
        progress: Progress | None = None,
    ) -> None:
        self.objective = objective
        self.iterations = iterations
        self.budget = objective.evaluations + evaluation_budget(students, iterations)
        start = objective.evaluations + students
        self.checkpoints = start + (2 * students + 1) * np.arange(1, iterations + 1)
        self.history = np.full(iterations, np.inf)
        self.progress = progress
        self._next = 0

    @property
    def remaining(self) -> int:
        """Evaluations left in the budget."""
        return max(self.budget - self.objective.evaluations, 0)

    def record(self, best: float) -> None:
        spent = self.objective.evaluations
        while self._next < self.iterations and spent >= self.checkpoints[self._next]:
            self.history[self._next] = best
            self._next += 1
            if self.progress is not None:
                self.progress(self._next, self.iterations, float(best))

    def finish(self, best: float) -> np.ndarray:
        """Fill checkpoints not reached (only if the budget was left unspent); the history."""
        while self._next < self.iterations:
            self.history[self._next] = best
            self._next += 1
            if self.progress is not None:
                self.progress(self._next, self.iterations, float(best))
        return self.history
