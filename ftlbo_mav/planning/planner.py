"""``plan(scenario) -> Plan``: the centroid path, every UAV's path, cost and feasibility.

Pure computation: no files, no printing (progress goes to an optional callback).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..scenario import PlannerSettings, Scenario
from .cost import INFEASIBLE, CostTerms, cost_terms, search_cost
from .feasibility import violations
from .geometric import lower_bound, shortest_routes
from .optimizers import OPTIMIZERS, Objective
from .optimizers.base import Progress
from .problem import PlanningProblem, problem_from_scenario
from .seeds import seed_waypoints


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
    lower_bound_length: float | None = None
    """Metres no feasible centroid path can beat (:func:`.geometric.lower_bound`);
    ``None`` when no route exists for the formation."""

    @property
    def feasible(self) -> bool:
        return not self.violations

    @property
    def length_ratio(self) -> float | None:
        """Centroid length over the lower bound (1.0 is the best possible)."""
        if not self.lower_bound_length:
            return None
        return float(self.cost.length / self.lower_bound_length)

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
    notice: Callable[[str], None] | None = None,
) -> Plan:
    """Plan the centroid path for ``scenario``; keyword arguments override its ``[planner]``.

    ``notice(line)`` is called before optimizing when no route exists (the formation
    cannot pass between the obstacles inside the area); the plan is still attempted.
    """
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
    return solve(problem, scenario, settings, progress=progress, notice=notice)


SEED_ROUTES = 4
"""Routes computed per plan: the shortest (the lower bound) and alternatives (seeds)."""

NO_ROUTE = (
    "no route: the formation cannot pass between the obstacles inside the area with the "
    "clearance; every plan will be infeasible (widen the area, reduce the clearance or the "
    "formation)"
)


def solve(
    problem: PlanningProblem,
    scenario: Scenario,
    settings: PlannerSettings,
    *,
    progress: Progress | None = None,
    notice: Callable[[str], None] | None = None,
) -> Plan:
    """Run ``settings.algorithm`` on ``problem`` and package the result.

    ``Plan.seconds`` is the optimizer's wall time; for a seeded optimizer it includes the
    routes and seeds (the lower bound alone is not counted for the others).
    """
    t_routes = time.perf_counter()
    routes = shortest_routes(problem, count=SEED_ROUTES)
    route_seconds = time.perf_counter() - t_routes
    bound = lower_bound(problem, routes[0]) if routes else None
    if not routes and notice is not None:
        notice(NO_ROUTE)
    m = problem.waypoints
    lower, upper = problem.bounds()

    def cost(x: np.ndarray) -> np.ndarray:
        return search_cost(problem, x.reshape(-1, m, 3))

    objective = Objective(cost, lower, upper)
    rng = np.random.default_rng(settings.seed)
    optimizer = OPTIMIZERS[settings.algorithm]
    t0 = time.perf_counter()
    extra = {}
    seeded = getattr(optimizer, "wants_seeds", False)
    if seeded:  # timed: the routes and the seeds are part of this planner
        seeds = seed_waypoints(problem, routes=routes)
        extra["seeds"] = seeds.reshape(len(seeds), 3 * m)
    result = optimizer(
        objective,
        students=settings.students,
        iterations=settings.iterations,
        rng=rng,
        progress=progress,
        **extra,
    )
    seconds = time.perf_counter() - t0 + (route_seconds if seeded else 0.0)
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
        lower_bound_length=bound,
    )
