"""``plan(scenario) -> Plan``: the centroid path, every UAV's path, cost and feasibility.

Pure computation: no files, no printing (progress goes to an optional callback).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from ..scenario import PlannerSettings, Scenario
from .cost import INFEASIBLE, CostTerms, cost_terms, search_cost
from .feasibility import violations
from .optimizers import OPTIMIZERS, Objective
from .optimizers.base import Progress
from .problem import PlanningProblem, problem_from_scenario


@dataclass(frozen=True, eq=False)
class Plan:
    """A planned formation flight.

    ``centroid``: ``(m+2, 3)`` metres ENU, start to goal.
    ``uav_paths``: ``(N, m+2, 3)`` metres ENU: ``centroid + offset_n`` (eq. 4).
    """

    scenario: Scenario
    settings: PlannerSettings
    problem: PlanningProblem
    centroid: np.ndarray
    uav_paths: np.ndarray
    cost: CostTerms
    violations: tuple[str, ...]
    history: np.ndarray
    evaluations: int
    seconds: float

    @property
    def feasible(self) -> bool:
        return not self.violations

    def lla(self, enu: np.ndarray) -> np.ndarray:
        """ENU ``(..., 3)`` -> ``(..., 3)`` rows of (lat_deg, lon_deg, alt_m above home)."""
        lat, lon, alt = self.scenario.frame.to_lla(enu)
        return np.stack([lat, lon, alt], axis=-1)


def plan(
    scenario: Scenario,
    *,
    algorithm: str | None = None,
    seed: int | None = None,
    iterations: int | None = None,
    students: int | None = None,
    waypoints: int | None = None,
    progress: Progress | None = None,
) -> Plan:
    """Plan the centroid path for ``scenario``; keyword arguments override its ``[planner]``."""
    settings = scenario.planner
    overrides = {
        "algorithm": algorithm,
        "seed": seed,
        "iterations": iterations,
        "students": students,
        "waypoints": waypoints,
    }
    settings = replace(settings, **{k: v for k, v in overrides.items() if v is not None})
    if settings.algorithm not in OPTIMIZERS:
        raise ValueError(
            f"unknown algorithm {settings.algorithm!r}; known: {', '.join(sorted(OPTIMIZERS))}"
        )
    problem = problem_from_scenario(scenario, waypoints=settings.waypoints)
    return solve(problem, scenario, settings, progress=progress)


def solve(
    problem: PlanningProblem,
    scenario: Scenario,
    settings: PlannerSettings,
    *,
    progress: Progress | None = None,
) -> Plan:
    """Run ``settings.algorithm`` on ``problem`` and package the result."""
    m = problem.waypoints
    lower, upper = problem.bounds()

    def cost(x: np.ndarray) -> np.ndarray:
        return search_cost(problem, x.reshape(-1, m, 3))

    objective = Objective(cost, lower, upper)
    rng = np.random.default_rng(settings.seed)
    t0 = time.perf_counter()
    result = OPTIMIZERS[settings.algorithm](
        objective,
        students=settings.students,
        iterations=settings.iterations,
        rng=rng,
        progress=progress,
    )
    seconds = time.perf_counter() - t0
    best = result.x.reshape(1, m, 3)
    terms = CostTerms(*(float(t[0]) for t in cost_terms(problem, best)))
    centroid = problem.full_paths(best)[0]
    return Plan(
        scenario=scenario,
        settings=settings,
        problem=problem,
        centroid=centroid,
        uav_paths=centroid[None, :, :] + problem.offsets[:, None, :],
        cost=terms,
        violations=tuple(violations(problem, centroid)),
        history=np.where(result.history >= INFEASIBLE, np.inf, result.history),
        evaluations=result.evaluations,
        seconds=seconds,
    )
