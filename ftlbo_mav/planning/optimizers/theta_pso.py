"""theta-PSO: the angle-encoded particle swarm of Hoang, Phung et al. (IROS 2018), NOTES 9.

Particles move in phase-angle space ``theta in [-pi/2, pi/2]^D`` and are mapped to
positions by ``x = (ub - lb) / 2 * sin(theta) + (ub + lb) / 2``, so every particle is
always inside the bounds. The velocity update is the standard inertia-weight PSO in
angle space:

    v <- w v + c1 r1 (pbest - theta) + c2 r2 (gbest - theta),   theta <- theta + v

Choices (the IROS paper's usual settings): ``w`` falls linearly from 0.9 to 0.4 over the
evaluation budget, ``c1 = c2 = 1.5``, velocities clamped to ``+-0.2 pi`` and angles to
``[-pi/2, pi/2]``; angles start uniform in their range, velocities at zero; ``r1, r2``
per particle and variable. An iteration costs ``S`` evaluations; the run stops at FTLBO's
budget (:func:`.base.evaluation_budget`), the last iteration moves only the particles the
budget still pays for, and the history is kept on FTLBO's clock
(:class:`.base.BudgetTracker`).
"""

from __future__ import annotations

import numpy as np

from .base import BudgetTracker, Objective, OptimizerResult, Progress

INERTIA = (0.9, 0.4)
C1 = C2 = 1.5
MAX_VELOCITY = 0.2 * np.pi
HALF_PI = 0.5 * np.pi


def angle_to_position(theta: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """``x = (ub - lb)/2 sin(theta) + (ub + lb)/2`` for angles ``(P, D)``."""
    return 0.5 * (upper - lower) * np.sin(theta) + 0.5 * (upper + lower)


def velocity_step(
    v: np.ndarray, theta: np.ndarray, pbest: np.ndarray, gbest: np.ndarray, w: float,
    rng: np.random.Generator,
) -> np.ndarray:
    """The inertia-weight velocity update in angle space, clamped to ``+-MAX_VELOCITY``."""
    r1 = rng.random(theta.shape)
    r2 = rng.random(theta.shape)
    v = w * v + C1 * r1 * (pbest - theta) + C2 * r2 * (gbest - theta)
    return np.clip(v, -MAX_VELOCITY, MAX_VELOCITY)


def theta_pso(
    objective: Objective,
    *,
    students: int,
    iterations: int,
    rng: np.random.Generator,
    progress: Progress | None = None,
) -> OptimizerResult:
    """Minimize ``objective`` with theta-PSO (``students`` particles), FTLBO's budget."""
    tracker = BudgetTracker(objective, students=students, iterations=iterations,
                            progress=progress)
    lower, upper = objective.lower, objective.upper
    theta = rng.uniform(-HALF_PI, HALF_PI, size=(students, objective.dimension))
    v = np.zeros_like(theta)
    f = objective(angle_to_position(theta, lower, upper))
    pbest, f_pbest = theta.copy(), f.copy()
    total = tracker.remaining
    while tracker.remaining > 0:
        n = min(students, tracker.remaining)
        w = INERTIA[0] - (INERTIA[0] - INERTIA[1]) * (1.0 - tracker.remaining / total)
        g = pbest[np.argmin(f_pbest)]
        v[:n] = velocity_step(v[:n], theta[:n], pbest[:n], g, w, rng)
        theta[:n] = np.clip(theta[:n] + v[:n], -HALF_PI, HALF_PI)
        f_new = objective(angle_to_position(theta[:n], lower, upper))
        improved = f_new < f_pbest[:n]
        pbest[:n][improved] = theta[:n][improved]
        f_pbest[:n][improved] = f_new[improved]
        tracker.record(f_pbest.min())
    best = int(np.argmin(f_pbest))
    history = tracker.finish(float(f_pbest[best]))
    x = angle_to_position(pbest[best], lower, upper)
    return OptimizerResult(x, float(f_pbest[best]), history, objective.evaluations)
