"""``plan(scenario) -> Plan``: the centroid path, every UAV's path, cost and feasibility.

A scenario's route runs start -> via points -> goal; each leg between two route points
is planned on its own (:func:`plan_leg`: its bound and seed routes, the optimizer, with
``waypoints = "auto"`` the waypoint count; among many trees in its window, :mod:`.window`)
and the legs are joined into one path (:func:`.plans.combine`). Every plan then goes
through one loop, :func:`.repair.until_kept`: plan, predict the flown path, repair what
the prediction found (corner stops, a survey swinging out of the area), until kept. A
plan too large for memory, time or a mission is refused before anything is allocated
(:func:`check_size`). Pure computation: no files, no printing (progress goes to optional
callbacks).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..errors import BadInput
from ..scenario import AUTO, PlannerSettings, Scenario
from .cost import INFEASIBLE, CostTerms, cost_terms, search_cost
from .feasibility import violations
from .geometric import lower_bound, shortest_routes
from .optimizers import OPTIMIZERS, Objective
from .optimizers.base import OptimizerResult, Progress
from .plans import Leg, Plan, combine, spread_repeats
from .problem import PlanningProblem, problem_from_scenario
from .repair import Attempt, better, fly_as_arducopter, until_kept
from .seeds import RouteChains, seed_waypoints
from .turns import check_survey_turns
from .window import WINDOW_FROM, leg_sizes, leg_window

AUTO_TARGET = 0.0008
"""``waypoints = "auto"``: a leg's plan may be this much (relative) above its bound."""
AUTO_LOOSE_TARGET = 0.005
"""``waypoints = "auto"``: the looser target :func:`plan` also plans with, keeping the
plan the copters fly better: fewer waypoints, fewer corners to slow down at and to cut
near the trees (among the Nha Trang orchard's 87 GIS trees 2 waypoints and a 27.6 s
flight rather than 5 waypoints, 4 corners moved and 30.9 s; the orchard survey 186 s
rather than 199 s, its path 0.06 % longer)."""
AUTO_TRIES = 4
"""``waypoints = "auto"``: waypoint counts planned per leg, from the geometric choice up,
before the best plan is kept even though it misses :data:`AUTO_TARGET`."""
AUTO_MAX = 256
"""``waypoints = "auto"``: the most waypoints looked at for one leg."""
AUTO_NO_ROUTE = PlannerSettings().waypoints
"""``waypoints = "auto"`` on a leg with no route (nothing to measure against): the
paper's 10."""


LegDone = Callable[[int, int, Leg], None]
"""``on_leg(index, legs, leg)``: called after each leg is planned (index 0-based)."""


def plan(
    scenario: Scenario,
    *,
    algorithm: str | None = None,
    seed: int | None = None,
    iterations: int | None = None,
    students: int | None = None,
    waypoints: int | str | None = None,
    progress: Progress | None = None,
    notice: Callable[[str], None] | None = None,
    on_leg: LegDone | None = None,
    relay: bool = True,
) -> Plan:
    """Plan the centroid path for ``scenario``; keyword arguments override its ``[planner]``.

    Every leg (start -> via 1 -> ... -> goal) is planned on its own with the chosen
    algorithm and waypoints (``"auto"``: per leg, see :func:`plan_leg`); one random
    generator, seeded with ``seed``, serves the legs in turn. ``progress`` is called per
    iteration of each leg's optimizer, ``on_leg`` after each leg. ``notice(line)`` is
    called before optimizing a leg for which no route exists (the formation cannot pass
    between the obstacles inside the area); the plan is still attempted. ``relay=False``:
    a survey's lanes are flown as the scenario lays them, never laid again further in
    (a sortie of lanes laid for the whole survey: :mod:`.sorties`).
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
    _check_settings(settings)
    check_survey_turns(scenario)  # a lane the formation cannot reach: before any planning
    check_size(scenario, settings)
    base = problem_from_scenario(scenario, waypoints=_count(settings))

    def attempt_with(target: float, report: bool) -> Attempt:
        def attempt(current: Scenario, widened: np.ndarray, first: bool) -> Plan:
            problem = problem_from_scenario(current, waypoints=_count(settings)) \
                if current is not scenario else base
            first = first and report
            legs = _plan_legs(current, settings, replace(problem, radii=problem.radii + widened),
                              progress=progress if first else None,
                              notice=notice if first else None,
                              on_leg=on_leg if first else None, target=target)
            return fly_as_arducopter(combine(current, settings, legs))
        return attempt

    if settings.waypoints != AUTO:
        return until_kept(scenario, len(base.radii), attempt_with(AUTO_TARGET, True),
                          relay=relay)
    # auto: the legs with few corners (AUTO_LOOSE_TARGET), and the legs nearest their
    # bounds (AUTO_TARGET); the one the copters are predicted to fly better is kept
    # (.repair.better: feasible, fewer stops, the shorter flight): more corners can make a
    # shorter path a slower flight, or corners cut into the clearance moved out
    loose = until_kept(scenario, len(base.radii), attempt_with(AUTO_LOOSE_TARGET, True),
                       relay=relay)
    if all(_tight_already(leg) for leg in loose.legs):
        return loose  # planned with AUTO_TARGET, every leg would be the same
    tight = until_kept(scenario, len(base.radii), attempt_with(AUTO_TARGET, False),
                       relay=relay)
    return replace(tight if better(tight, loose) else loose,
                   seconds=loose.seconds + tight.seconds)


def _plan_legs(scenario: Scenario, settings: PlannerSettings, base: PlanningProblem, *,
               progress: Progress | None, notice: Callable[[str], None] | None,
               on_leg: LegDone | None, target: float = AUTO_TARGET) -> list[Leg]:
    """Every leg of the route on ``base`` (one generator seeded with ``settings.seed``
    serving the legs in turn); ``target``: the auto waypoints' (:func:`plan_leg`)."""
    points, names = scenario.route_enu(), scenario.route_names()
    rng = np.random.default_rng(settings.seed)
    count = len(points) - 1
    legs = []
    for k in range(count):
        problem = replace(base, start=points[k], goal=points[k + 1])
        where = f"leg {k + 1}/{count} ({names[k]} -> {names[k + 1]}): " if count > 1 else ""
        leg = plan_leg(problem, settings, rng=rng, progress=progress, names=names[k : k + 2],
                       notice=None if notice is None else (lambda line, w=where: notice(w + line)),
                       target=target)
        legs.append(leg)
        if on_leg is not None:
            on_leg(k, count, leg)
    return legs


def route_lower_bound(scenario: Scenario) -> float | None:
    """The sum of the legs' lower bounds (metres): no feasible centroid path through
    every via point is shorter; ``None`` when some leg has no route."""
    points = scenario.route_enu()
    base = problem_from_scenario(scenario, waypoints=1)
    total = 0.0
    for k in range(len(points) - 1):
        bound = lower_bound(replace(base, start=points[k], goal=points[k + 1]))
        if bound is None:
            return None
        total += bound
    return total


def _check_settings(settings: PlannerSettings) -> None:
    if settings.algorithm not in OPTIMIZERS:
        raise ValueError(
            f"unknown algorithm {settings.algorithm!r}; known: {', '.join(sorted(OPTIMIZERS))}"
        )
    m = settings.waypoints
    if m != AUTO and (isinstance(m, bool) or not isinstance(m, int) or m < 1):
        raise ValueError(f'waypoints must be an integer >= 1 or "{AUTO}", got {m!r}')


MEMORY_LIMIT_BYTES = 1 << 30
"""The most the optimizer's arrays may take (the class and its trial copies)."""
WORK_LIMIT = 5e10
"""The most UAV-segment x obstacle checks one plan may need: about 20 minutes at the ~40
million a second of this 2-core machine (README, "Speed")."""
MISSION_ITEMS_LIMIT = 65_535
"""MAVLink's MISSION_COUNT is 16 bits."""
_POPULATION_COPIES = 8  # class, trial class, elites, costs...: a generous count


class PlanTooLarge(BadInput):
    """A plan whose size would need more memory or time than is sane; said before
    anything is allocated."""


def check_size(scenario: Scenario, settings: PlannerSettings, *, repeats: int = 1) -> None:
    """Refuse, before allocating, a plan that needs more than :data:`MEMORY_LIMIT_BYTES`,
    :data:`WORK_LIMIT` checks (over ``repeats`` plans: a comparison's runs) or
    :data:`MISSION_ITEMS_LIMIT` items per mission."""
    legs = len(scenario.via) + 1
    auto = settings.waypoints == AUTO
    m = (AUTO_MAX + AUTO_TRIES) if auto else int(settings.waypoints)  # most per leg
    typical = AUTO_TRIES * AUTO_NO_ROUTE if auto else m  # waypoints optimized per leg
    what = ((f"{repeats} runs x " if repeats > 1 else "")
            + f"{settings.students} students x {'auto' if auto else m} waypoints x "
            f"{settings.iterations} iterations x {legs} leg{'s' if legs > 1 else ''} x "
            f"{scenario.uav_count} UAVs x {max(len(scenario.obstacles), 1)} obstacles")
    if len(scenario.obstacles) >= WINDOW_FROM:
        what += " (each leg among those within its reach)"
    memory = settings.students * m * 3 * 8 * _POPULATION_COPIES
    if memory > MEMORY_LIMIT_BYTES:
        raise PlanTooLarge(f"{scenario.source}: {what} would need about "
                           f"{memory / 2**30:.1f} GiB for the optimizer's class (at most "
                           f"{MEMORY_LIMIT_BYTES / 2**30:g} GiB): fewer students or waypoints")
    # each leg among the obstacles it is planned among (its window, .window); with auto,
    # a leg whose straight line is clear is planned with one waypoint
    obstacles, straight = leg_sizes(problem_from_scenario(scenario, waypoints=1),
                                    scenario.route_enu())
    per_leg = np.where(straight, 1, typical) if auto else np.full(len(obstacles), typical)
    work = (float(repeats) * settings.students * settings.iterations * scenario.uav_count
            * float(((per_leg + 1) * np.maximum(obstacles, 1)).sum()))
    if work > WORK_LIMIT:
        raise PlanTooLarge(f"{scenario.source}: {what} is {work:.1e} segment-obstacle checks "
                           f"(at most {WORK_LIMIT:.0e}, about 20 minutes here): fewer "
                           "students, iterations or waypoints")
    items = legs * (m + 1) + 1 + 4  # home, takeoff, speed, path points, end
    if not auto and items > MISSION_ITEMS_LIMIT:
        raise PlanTooLarge(f"{scenario.source}: {what} makes missions of {items} items; "
                           f"MAVLink counts at most {MISSION_ITEMS_LIMIT}: fewer waypoints")


def _count(settings: PlannerSettings) -> int:
    """The waypoint count to build problems with (``auto`` picks its own per leg)."""
    return AUTO_NO_ROUTE if settings.waypoints == AUTO else int(settings.waypoints)


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
    """Run ``settings.algorithm`` on the one-leg ``problem`` and package the result
    (``scenario`` is only carried along; ``settings.waypoints = "auto"`` chooses the
    count, else ``problem.waypoints`` is used), planned again as :func:`plan` does while
    its corners need stops. See :func:`plan_leg`."""
    _check_settings(settings)
    # problem's radii include the scenario's clearance and allowance (problem_from_scenario)
    own = problem.radii - scenario.kept_clearance_m

    def attempt(_scenario: Scenario, widened: np.ndarray, first: bool) -> Plan:
        rng = np.random.default_rng(settings.seed)
        leg = plan_leg(replace(problem, radii=problem.radii + widened), settings, rng=rng,
                       progress=progress if first else None, notice=notice if first else None)
        return fly_as_arducopter(combine(scenario, settings, [leg]), own_radii=own)

    return until_kept(scenario, len(problem.radii), attempt, relay=False)


def plan_leg(
    problem: PlanningProblem,
    settings: PlannerSettings,
    *,
    rng: np.random.Generator,
    progress: Progress | None = None,
    notice: Callable[[str], None] | None = None,
    names: tuple[str, str] = ("start", "goal"),
    target: float = AUTO_TARGET,
) -> Leg:
    """Plan one leg, from ``problem.start`` to ``problem.goal``.

    Fixed ``settings.waypoints``: ``problem.waypoints`` waypoints (the paper's setting).
    ``"auto"``: the fewest waypoints whose seed polygon near the shortest route
    (:class:`.seeds.RouteChains`) is within ``target`` (:data:`AUTO_TARGET`) of the leg's
    bound; that
    count is planned, and if the plan misses the target the next counts up to
    :data:`AUTO_TRIES` in all; the first plan within the target is kept, else the
    feasible one nearest the bound. ``Leg.seconds`` is the optimizer's wall time; for a
    seeded optimizer, and with ``"auto"``, it includes the routes (and the seeds).
    """
    auto = settings.waypoints == AUTO
    t_routes = time.perf_counter()
    window = leg_window(problem, count=SEED_ROUTES,
                        routes=lambda p, count: shortest_routes(p, count=count))
    searched = None if window.problem is problem else window.problem
    where = window.problem
    routes = (window.routes if window.routes is not None
              else shortest_routes(problem, count=SEED_ROUTES))
    bound = lower_bound(where, routes[0]) if routes else None
    chains = [RouteChains(where, r) for r in routes] if auto else None
    choice = _auto_count(chains[0], bound, target) if auto and routes else None
    tight = (choice if target == AUTO_TARGET else _auto_count(chains[0], bound, AUTO_TARGET)
             ) if auto and routes else None
    route_seconds = time.perf_counter() - t_routes
    if not routes and notice is not None:
        notice(NO_ROUTE)
    seeded = getattr(OPTIMIZERS[settings.algorithm], "wants_seeds", False)
    if not auto:
        leg = _optimize(problem, settings, rng, routes, None, progress, searched=searched)
        extra = route_seconds if seeded else 0.0
        return replace(leg, start_name=names[0], goal_name=names[1], lower_bound_length=bound,
                       seconds=leg.seconds + extra)
    first = choice if choice is not None else AUTO_NO_ROUTE
    tries: list[Leg] = []
    for m in range(first, min(first + AUTO_TRIES, AUTO_MAX + 1)):
        leg = _optimize(replace(problem, waypoints=m), settings, rng, routes, chains, progress,
                        searched=None if searched is None else replace(searched, waypoints=m))
        tries.append(replace(leg, lower_bound_length=bound))
        if bound is None or (leg.feasible and leg.cost.length <= (1 + target) * bound):
            break
    kept = tries[-1]
    if bound is not None and not (kept.feasible
                                  and kept.cost.length <= (1 + target) * bound):
        feasible = [t for t in tries if t.feasible]
        kept = min(feasible, key=lambda t: t.cost.length) if feasible else kept
    return replace(kept, start_name=names[0], goal_name=names[1], tight_count=tight,
                   target=target,
                   tried=tuple(t.waypoints for t in tries),
                   evaluations=sum(t.evaluations for t in tries),
                   seconds=route_seconds + sum(t.seconds for t in tries))


def _tight_already(leg: Leg) -> bool:
    """Whether ``leg``, planned with :data:`AUTO_LOOSE_TARGET`, is what :data:`AUTO_TARGET`
    plans: the same first count, and its plan within that target already."""
    bound = leg.lower_bound_length
    return (bound is None or not leg.tried
            or (leg.tried[0] == leg.tight_count and leg.waypoints == leg.tight_count
                and leg.feasible and leg.cost.length <= (1 + AUTO_TARGET) * bound))


def _auto_count(chains: RouteChains, bound: float, target: float = AUTO_TARGET) -> int | None:
    """The fewest waypoints whose clear chain is within ``target`` of ``bound``;
    else the count of the shortest clear chain found; ``None`` when none is clear."""
    m = 8
    while True:
        lengths = chains.lengths(m)
        within = np.flatnonzero(lengths <= (1 + target) * bound)
        if len(within):
            return int(within[0]) + 1
        if m >= AUTO_MAX:
            return int(np.argmin(lengths)) + 1 if np.isfinite(lengths).any() else None
        m = min(2 * m, AUTO_MAX)


def _optimize(problem: PlanningProblem, settings: PlannerSettings, rng: np.random.Generator,
              routes: list, chains: list | None, progress: Progress | None, *,
              searched: PlanningProblem | None = None) -> Leg:
    """One optimizer run on ``searched`` (default ``problem``; its ``waypoints``), the
    result's violations found on ``problem``; names and bound left blank."""
    whole, problem = problem, searched if searched is not None else problem
    m = problem.waypoints
    lower, upper = problem.bounds()

    def cost(x: np.ndarray) -> np.ndarray:
        return search_cost(problem, x.reshape(-1, m, 3))

    objective = Objective(cost, lower, upper)
    optimizer = OPTIMIZERS[settings.algorithm]
    t0 = time.perf_counter()
    extra = {}
    result = None
    if getattr(optimizer, "wants_seeds", False):  # timed: the seeds are part of this planner
        seeds = seed_waypoints(problem, routes=routes, chains=chains)
        extra["seeds"] = seeds.reshape(len(seeds), 3 * m)
        result = _seed_at_optimum(problem, objective, extra["seeds"][0], settings.iterations,
                                  progress) if len(seeds) else None
    if result is None:
        result = optimizer(
            objective,
            students=settings.students,
            iterations=settings.iterations,
            rng=rng,
            progress=progress,
            **extra,
        )
    seconds = time.perf_counter() - t0
    best = spread_repeats(problem, result.x.reshape(1, m, 3))
    terms = CostTerms(*(float(t[0]) for t in cost_terms(problem, best)))
    centroid = problem.full_paths(best)[0]
    return Leg(
        start_name="start",
        goal_name="goal",
        problem=whole,
        centroid=centroid,
        cost=terms,
        violations=tuple(violations(whole, centroid)),
        history=np.where(result.history >= INFEASIBLE, np.inf, result.history),
        evaluations=result.evaluations,
        seconds=seconds,
        searched=searched,
    )


def _seed_at_optimum(problem: PlanningProblem, objective: Objective, seed: np.ndarray,
                     iterations: int, progress: Progress | None) -> OptimizerResult | None:
    """The seed ``(3 m,)`` as the optimizer's result when no path can cost less, else
    ``None``. Every path is at least as long as the straight line from start to goal, and
    the safety and task terms are never negative: a seed with both terms 0 (no cylinder
    in the leg's window, every UAV inside the altitude band) and the straight line's
    length (to 1e-12, the rounding of its waypoints on the line) is the optimum, which
    FTLBO would keep (it only takes a student that costs less) after its ``PATIENCE``
    iterations of some 200 evaluations each. A survey's turns between aisles are such
    legs: half the legs of issue 51's orchard."""
    if len(problem.radii) and problem.weights[1] != 0:
        return None  # every R/d is positive: the safety term is never 0
    x = objective.clip(seed[None, :])
    terms = cost_terms(problem, x.reshape(1, -1, 3))
    straight = float(np.linalg.norm(problem.goal - problem.start))
    if not (terms.safety[0] == 0.0 and terms.task[0] == 0.0
            and terms.total[0] <= problem.weights[0] * straight * (1 + 1e-12)):
        return None
    cost = float(search_cost(problem, x.reshape(1, -1, 3))[0])
    if progress is not None:
        progress(iterations, iterations, cost)
    return OptimizerResult(x[0].copy(), cost, np.full(iterations, cost), 1)
