"""FTLBO from a class seeded with geometric routes: the near-optimal default planner.

Ten random waypoints rarely find the right gaps between trees, so a class of random
students settles well above the shortest feasible path (~25% on the shipped example).
Here part of the class starts on the shortest tangent routes around the
formation-inflated obstacles (:mod:`..geometric`), already resampled to the waypoint
count: the shortest route itself, perturbed copies of it, and perturbed copies of the
alternative routes. The rest of the class is random, and the paper's FTLBO
(:func:`.ftlbo.ftlbo`) refines the whole class with the same budget and rules. When no
route exists (or none is given) this is plain FTLBO.

Choices: ``SEED_FRACTION`` (20%) of the class is seeded: every seed route once as it is,
then perturbed copies, half of the first (clear, shortest) seed, the rest of the
alternatives in turn; perturbations are
normal with ``SIGMA_HORIZONTAL`` (0.25 m) east/north and ``SIGMA_VERTICAL`` (0.1 m) up,
drawn from the injected generator. Early stop: once the best cost has improved by less
than 1e-6 (relative) over ``PATIENCE`` (30) iterations, the run ends (the budget is an
upper limit; the comparison's baselines always spend all of it).
"""

from __future__ import annotations

import numpy as np

from .base import Objective, OptimizerResult, Progress
from .ftlbo import ftlbo

SEED_FRACTION = 0.2
SIGMA_HORIZONTAL = 0.25
SIGMA_VERTICAL = 0.1
PATIENCE = 30
"""Stop once the best cost improved by less than 1e-6 (relative) in this many iterations."""


def seeded_class(seeds: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """``count`` students ``(count, D)`` from seed routes ``(R, D)`` (flattened ``(m, 3)``
    waypoints, best first): every seed once unchanged (a seed hugging the obstacles is
    rarely still clear after a perturbation), then perturbed copies, half of them of the
    first seed, the rest of the others in turn."""
    seeds = np.atleast_2d(seeds)
    R, D = seeds.shape
    sigma = np.tile([SIGMA_HORIZONTAL, SIGMA_HORIZONTAL, SIGMA_VERTICAL], D // 3)
    exact = min(R, count)
    copies = count - exact
    half = copies // 2
    which = np.zeros(copies, int)
    if R > 1:
        which[half:] = 1 + np.arange(copies - half) % (R - 1)
    students = seeds[which] + rng.normal(size=(copies, D)) * sigma
    return np.concatenate([seeds[:exact], students])


def ftlbo_seeded(
    objective: Objective,
    *,
    students: int,
    iterations: int,
    rng: np.random.Generator,
    progress: Progress | None = None,
    seeds: np.ndarray | None = None,
) -> OptimizerResult:
    """FTLBO whose initial class holds ``seeds`` ``(R, D)`` routes and perturbed copies.

    Same budget and evaluation counting as :func:`.ftlbo.ftlbo`, but it stops early once
    the best cost has stalled for ``PATIENCE`` iterations: a seeded class usually starts
    next to the optimum, and the remaining budget would buy nothing (the plan's
    ``evaluations`` tells how much was spent).
    """
    initial = None
    if seeds is not None and len(seeds):
        count = max(1, int(round(SEED_FRACTION * students)))
        initial = seeded_class(np.asarray(seeds, float), count, rng)
    return ftlbo(objective, students=students, iterations=iterations, rng=rng,
                 progress=progress, initial=initial, patience=PATIENCE)


ftlbo_seeded.wants_seeds = True  # the planner passes the geometric seed routes
