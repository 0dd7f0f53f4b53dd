"""What every optimizer shares: the objective wrapper that counts evaluations, and results.

An optimizer is a function ``(objective, *, students, iterations, rng, progress) ->
OptimizerResult``. It draws every random number from the injected ``rng``
(``numpy.random.Generator``), so the same seed gives the same result, and evaluates the
cost only through ``objective``, which counts every evaluated candidate the same way for
every algorithm (a fair budget in comparisons).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol

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
