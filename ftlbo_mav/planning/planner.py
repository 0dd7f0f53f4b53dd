"""``plan(scenario) -> Plan``: the centroid path, every UAV's path, cost and feasibility.

A scenario's route runs start -> via points -> goal; each leg between two route points
is planned on its own (:func:`plan_leg`; among many trees in its window, :mod:`.window`)
and the legs are joined into one path (:func:`combine`). Every plan then goes through
one loop, :func:`until_kept`: plan, predict the flown path, repair what the prediction
found (corner stops, a survey swinging out of the area), until kept. Pure computation:
no files, no printing (progress goes to optional callbacks).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from ..ardupilot.flight_path import stepwise_budget
from ..energy import MissionCharge, charge_problem, mission_charges
from ..errors import BadInput
from ..formation import slot_errors
from ..scenario import AUTO, PlannerSettings, Scenario, relay_lanes
from .cost import INFEASIBLE, CostTerms, cost_terms, search_cost
from .feasibility import violations
from .geometric import lower_bound, shortest_routes
from .optimizers import OPTIMIZERS, Objective
from .optimizers.base import Progress
from .predicted import (
    FlightModel,
    Prediction,
    beyond_area,
    formation_room,
    keep_clearance,
    predict,
    predicted_violations,
)
from .problem import PlanningProblem, problem_from_scenario
from .seeds import RouteChains, seed_waypoints
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


@dataclass(frozen=True, eq=False)
class Leg:
    """One leg of a plan: the centroid from one route point (start or via) to the next.

    ``problem``: the leg's own problem (its start, goal and waypoint count ``m``), on
    which its violations are found. ``searched``: the problem the optimizer searched,
    when that was the leg's window (:mod:`.window`: the obstacles it can reach, the area
    near it); the cost is that problem's. None: ``problem`` itself.
    ``centroid``: ``(m+2, 3)`` metres ENU. ``tried``: with ``waypoints = "auto"``, the
    waypoint counts planned, in order (the last one kept is ``waypoints``); else empty.
    ``evaluations`` and ``seconds`` count every try.
    """

    start_name: str
    goal_name: str
    problem: PlanningProblem
    centroid: np.ndarray
    cost: CostTerms
    violations: tuple[str, ...]
    history: np.ndarray
    evaluations: int
    seconds: float
    lower_bound_length: float | None = None
    tried: tuple[int, ...] = ()
    searched: PlanningProblem | None = None
    target: float | None = None
    """With ``"auto"``: the target it was planned to (relative, over the bound)."""
    tight_count: int | None = None
    """With ``"auto"``: the count :data:`AUTO_TARGET` starts from (:func:`plan` skips the
    plan with it when every leg has it and is within it already: the same plan)."""

    @property
    def waypoints(self) -> int:
        return self.problem.waypoints

    @property
    def cost_problem(self) -> PlanningProblem:
        """The problem the leg's cost is measured on (the searched one)."""
        return self.searched if self.searched is not None else self.problem

    @property
    def feasible(self) -> bool:
        return not self.violations

    @property
    def length_ratio(self) -> float | None:
        if not self.lower_bound_length:
            return None
        return float(self.cost.length / self.lower_bound_length)


@dataclass(frozen=True, eq=False)
class Plan:
    """A planned formation flight: one or more legs flown as one continuous path.

    ``centroid``: ``(P, 3)`` metres ENU, start, every leg's waypoints and via points,
    goal (``P = sum(m_k + 1) + 1``). ``uav_paths``: ``(N, P, 3)``: ``centroid +
    offset_n`` (eq. 4). ``problem``: the whole route's (start, goal, ``P - 2`` points).
    ``cost``, ``evaluations``, ``seconds``, ``lower_bound_length`` are the legs' sums;
    ``history`` the sum of the legs' best costs per iteration.
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
    """Metres no feasible centroid path can beat (:func:`.geometric.lower_bound`, summed
    over the legs); ``None`` when some leg has no route for the formation."""
    legs: tuple[Leg, ...] = ()
    holds_s: np.ndarray | None = None
    """``(P,)`` whole seconds each UAV holds at each point (its waypoint's param1): the
    corners the planner made the copters stop at to keep the clearance; None: none."""
    prediction: Prediction | None = None
    """Every UAV's predicted flown path (:mod:`.predicted`), on which feasibility is
    judged; None for a plan made without it (:func:`combine` alone)."""
    corners_moved: int = 0
    """Corner moves :func:`.predicted.keep_clearance` made (each move counted)."""
    predict_seconds: float = 0.0
    """Wall seconds of predicting the flown paths and keeping the clearance (in
    ``seconds`` too)."""
    stopped_for: np.ndarray | None = None
    """``(K,)`` metres by which corners made stops fell short of each obstacle."""
    replans: int = 0
    """Times the route was planned again to avoid corner stops (:data:`REPLANS`); the
    best of the plans is kept, ``seconds`` counts them all."""
    charges: tuple[MissionCharge, ...] | None = None
    """Each UAV's predicted battery use (:mod:`ftlbo_mav.energy`), when the scenario
    has a ``[battery]``; a mission that would land below the reserve is a violation."""
    lanes_inset_m: float = 0.0
    """How much further inside the area than its margin the survey's lanes were laid
    so that the copters' predicted swings stay inside (:data:`SURVEY_RELAYS`; 0: not)."""

    @property
    def feasible(self) -> bool:
        return not self.violations

    @property
    def formation_bound_m(self) -> float:
        """How far from its slot a UAV may be in flight before ``fly`` counts it a
        departure: ``[formation] max_error``, and never more than the predicted flight's
        separation room allows (:func:`.predicted.formation_room`)."""
        sc = self.scenario
        if self.prediction is None:
            return sc.max_formation_error_m
        room = formation_room(self.prediction, min_separation_m=sc.min_separation_m,
                              navigation_m=sc.navigation.horizontal_m)
        return min(sc.max_formation_error_m, room)

    @property
    def corner_stops(self) -> int:
        """Corners where the copters are made to stop (a hold) to keep the clearance."""
        return 0 if self.holds_s is None else int((self.holds_s > 0).sum())

    @property
    def length_ratio(self) -> float | None:
        """Centroid length over the lower bound (1.0 is the best possible)."""
        if not self.lower_bound_length:
            return None
        return float(self.cost.length / self.lower_bound_length)

    def lane_points(self) -> list[tuple[int, int]]:
        """Each survey lane's entry and exit as indices into the paths (the lanes' ends
        are the last via points, two a lane; a leg of ``m`` waypoints adds ``m + 1``
        points after its start); empty without lanes."""
        survey = self.scenario.survey
        if survey is None or not survey.lanes:
            return []
        starts = np.cumsum([0] + [leg.waypoints + 1 for leg in self.legs])  # route -> index
        first = len(self.scenario.via) - 2 * len(survey.lanes) + 1  # lane 1's entry (route)
        return [(int(starts[first + 2 * k]), int(starts[first + 2 * k + 1]))
                for k in range(len(survey.lanes))]

    @property
    def waypoint_count(self) -> int:
        """Points between start and goal: every leg's waypoints and the via points."""
        return len(self.centroid) - 2

    def lla(self, enu: np.ndarray) -> np.ndarray:
        """ENU ``(..., 3)`` -> ``(..., 3)`` rows of (lat_deg, lon_deg, alt_m above home)."""
        lat, lon, alt = self.scenario.frame.to_lla(enu)
        return np.stack([lat, lon, alt], axis=-1)


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
    # (_better: feasible, fewer stops, the shorter flight): more corners can make a
    # shorter path a slower flight, or corners cut into the clearance moved out
    loose = until_kept(scenario, len(base.radii), attempt_with(AUTO_LOOSE_TARGET, True),
                       relay=relay)
    if all(_tight_already(leg) for leg in loose.legs):
        return loose  # planned with AUTO_TARGET, every leg would be the same
    tight = until_kept(scenario, len(base.radii), attempt_with(AUTO_TARGET, False),
                       relay=relay)
    return replace(tight if _better(tight, loose) else loose,
                   seconds=loose.seconds + tight.seconds)


Attempt = Callable[[Scenario, np.ndarray, bool], Plan]
"""``attempt(scenario, widened, first)``: the route of ``scenario`` planned with its
obstacles ``widened`` ``(K,)`` metres, judged on the flown path (:func:`fly_as_arducopter`);
``first``: the first attempt (the one that reports progress)."""


def until_kept(scenario: Scenario, obstacles: int, attempt: Attempt, *,
               relay: bool = True) -> Plan:
    """Plan, predict, repair, until kept: the one loop every plan goes through.

    1. ``attempt``: plan the route and predict its flown path (the corners the copters
       cut moved, or made stops, until the clearance is kept);
    2. keep the best plan so far (:func:`_better`: feasible, fewer corner stops, shorter
       flight);
    3. repair what the prediction found, the first that applies, and go to 1:

       - corners where the copters had to stop: the obstacles they fell short of are
         widened by that much, so the polyline keeps away from them and its corners can
         be flown through (at most :data:`REPLANS` times);
       - a survey whose copters swing out of the area where they turn into or out of a
         lane: the lanes are laid that much (and :data:`SURVEY_RELAY_MARGIN_M`) further in
         (at most :data:`SURVEY_RELAYS` times, and only while the plans get better);

       else stop.

    The plan kept carries every attempt's ``seconds``, the re-plans made (``replans``)
    and how far in its lanes were laid (``lanes_inset_m``).
    """
    with stepwise_budget():  # every flight this plan predicts counts toward one budget
        return _until_kept(scenario, obstacles, attempt, relay=relay)


def _until_kept(scenario: Scenario, obstacles: int, attempt: Attempt, *, relay: bool) -> Plan:
    current, widened = scenario, np.zeros(obstacles)
    inset_lo, inset_hi = np.zeros(2), np.zeros(2)
    best: Plan | None = None
    replans = relays = 0
    seconds = 0.0
    relaid = False
    while True:
        result = attempt(current, widened, best is None)
        seconds += result.seconds
        result = replace(result, replans=replans,
                         lanes_inset_m=float(max(inset_lo.max(), inset_hi.max())))
        better = best is None or _better(result, best)
        if better:
            best = result
        elif relaid:  # laying the lanes further in did not help: keep what was best
            break
        stopped = result.stopped_for
        if (replans < REPLANS and result.corner_stops and stopped is not None
                and stopped.any()):
            widened, replans, relaid = widened + stopped, replans + 1, False
            continue
        out_lo, out_hi = _area_excursion(result)
        if (relay and relays < SURVEY_RELAYS and current.survey is not None
                and current.survey.lanes and (out_lo.max() > 0 or out_hi.max() > 0)):
            inset_lo = inset_lo + np.where(out_lo > 0, out_lo + SURVEY_RELAY_MARGIN_M, 0.0)
            inset_hi = inset_hi + np.where(out_hi > 0, out_hi + SURVEY_RELAY_MARGIN_M, 0.0)
            current = relay_lanes(scenario, inset_lower_m=inset_lo, inset_upper_m=inset_hi)
            relays, relaid = relays + 1, True
            continue
        break
    return replace(best, seconds=seconds, replans=max(best.replans, replans))


SURVEY_RELAYS = 2
"""Times at most the survey's lanes are laid again, further inside the area, when the
copters are predicted to swing out of it (:func:`until_kept`)."""
SURVEY_RELAY_MARGIN_M = 0.05


def _area_excursion(p: Plan) -> tuple[np.ndarray, np.ndarray]:
    """How far (metres, east and north; <= 0: not at all) the predicted flight goes past
    the area's lower and upper sides."""
    if p.prediction is None:
        return np.zeros(2), np.zeros(2)
    beyond = beyond_area(p.problem, p.prediction.positions).reshape(-1, 4).max(axis=0)
    return beyond[:2], beyond[2:]


REPLANS = 2
"""Re-plans at most when the planner had to make the copters stop at corners: each plans
again with the obstacles those corners cut in on widened by what they fell short, so
that the polyline keeps away from them and its corners can be flown through."""


def _better(a: Plan, b: Plan) -> bool:
    """Feasible first, then fewer corner stops, then the shorter predicted flight."""
    def key(p: Plan):
        t = float(p.prediction.seconds.max()) if p.prediction is not None else np.inf
        return (not p.feasible, p.corner_stops, t)
    return key(a) < key(b)


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


def flight_model(scenario: Scenario) -> FlightModel:
    """How the scenario's copters fly: each UAV's own copter (``[vehicle]``, its release
    and parameters) and the cruise speed."""
    fleet = scenario.fleet()
    if all(c is fleet[0] for c in fleet):  # one copter for all (the same object)
        return FlightModel(nav=fleet[0].nav, speed_m_s=scenario.mission.speed_m_s)
    return FlightModel.of_fleet([c.nav for c in fleet], scenario.mission.speed_m_s)


def fly_as_arducopter(plan: Plan, *, own_radii: np.ndarray | None = None) -> Plan:
    """``plan`` judged on, and changed for, the path ArduCopter flies.

    A plan whose polyline is feasible is handed to :func:`.predicted.keep_clearance`
    (corners moved or made stops until every UAV's predicted flown path keeps the
    clearance plus the corner allowance), its legs take the changed points, and the
    predicted flight's violations (clearance, area, altitude band, separation at the
    same instant) join the polyline's. An infeasible polyline is left as it is and only
    predicted. ``own_radii``: ``(K,)`` the radii of ``plan.problem``'s cylinders without
    any clearance (default: the scenario's obstacles)."""
    t0 = time.perf_counter()
    sc = plan.scenario
    model = flight_model(sc)
    keep = sc.kept_clearance_m
    if own_radii is None:
        _centres, own_radii = sc.obstacles_enu()
    holds = np.zeros(len(plan.centroid))
    legs, moved = list(plan.legs), 0
    stopped_for = None
    if plan.feasible:
        firsts = np.cumsum([0] + [leg.waypoints + 1 for leg in plan.legs])
        fixed = np.zeros(len(plan.centroid), bool)
        fixed[firsts] = True  # the start, every via point, the goal
        kept = keep_clearance(plan.problem, plan.centroid, model=model, obstacle_radii=own_radii,
                              clearance_m=keep, fixed=fixed, pair_error_m=sc.navigation.pair_m)
        holds, prediction, moved = kept.holds_s, kept.prediction, kept.moved
        stopped_for = kept.stopped_for
        if moved:
            legs = [_with_centroid(leg, kept.centroid[a : b + 1])
                    for leg, a, b in zip(plan.legs, firsts[:-1], firsts[1:])]
            plan = combine(sc, plan.settings, legs)
    else:
        prediction = predict(plan.uav_paths, model=model, centres=plan.problem.centres,
                             radii=own_radii, pair_error_m=sc.navigation.pair_m)
    flown = predicted_violations(plan.problem, prediction, clearance_m=keep,
                                 obstacle_radii=own_radii, min_separation_m=sc.min_separation_m)
    charges = None
    if sc.battery is not None:
        homes = plan.uav_paths[:, 0] * np.array([1.0, 1.0, 0.0])  # each on the ground below
        charges = tuple(mission_charges(sc.battery, sc.vehicle, prediction,
                                        end_action=sc.mission.end_action, homes=homes))
        flown = list(flown) + [why for n, c in enumerate(charges)
                               if (why := charge_problem(f"uav{n + 1}", c, sc.battery))]
    seconds = time.perf_counter() - t0
    return replace(plan, violations=plan.violations + tuple(flown), holds_s=holds,
                   prediction=prediction, corners_moved=moved, predict_seconds=seconds,
                   seconds=plan.seconds + seconds, stopped_for=stopped_for, charges=charges)


def fleet_lags(plan: Plan) -> list[str]:
    """Where a fleet of copters that fly differently drift apart on their own: each UAV
    predicted farther from its slot (the flown centroid plus its offset, at the same
    instant) than ``[formation] max_error``, in sentences (empty: a fleet of alike
    copters, or one that keeps together). Not a violation: ``fly``'s formation keeper
    makes up a lag along the track by pausing the leaders (ArduCopter 4.5.6 SITL, a Solo
    among two default copters, the example: 0.30 m worst with the keeper, where this
    prediction without it says 1.75 m)."""
    p, sc = plan.prediction, plan.scenario
    if p is None or len({c.nav for c in sc.fleet()}) < 2:
        return []
    errors = slot_errors(p.positions.transpose(1, 0, 2), plan.problem.offsets).T  # (N, T)
    out = []
    for n in np.flatnonzero(errors.max(axis=1) > sc.max_formation_error_m + 1e-9):
        i = int(np.argmax(errors[n]))
        out.append(f"UAV {n + 1} is predicted {errors[n, i]:.2f} m from its slot "
                   f"{p.times[i]:.1f} s into its legs without fly's formation keeper: its "
                   "copter flies unlike the others ([vehicle]); the keeper's waits make up a "
                   "lag along the track")
    return out


def _with_centroid(leg: Leg, centroid: np.ndarray) -> Leg:
    """``leg`` with its points moved: cost and polyline violations recomputed."""
    if np.array_equal(centroid, leg.centroid):
        return leg
    best = centroid[None, 1:-1]
    terms = CostTerms(*(float(t[0]) for t in cost_terms(leg.cost_problem, best)))
    return replace(leg, centroid=centroid, cost=terms,
                   violations=tuple(violations(leg.problem, centroid)))


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
    if getattr(optimizer, "wants_seeds", False):  # timed: the seeds are part of this planner
        seeds = seed_waypoints(problem, routes=routes, chains=chains)
        extra["seeds"] = seeds.reshape(len(seeds), 3 * m)
    result = optimizer(
        objective,
        students=settings.students,
        iterations=settings.iterations,
        rng=rng,
        progress=progress,
        **extra,
    )
    seconds = time.perf_counter() - t0
    best = result.x.reshape(1, m, 3)
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


def combine(scenario: Scenario, settings: PlannerSettings, legs: list[Leg]) -> Plan:
    """The legs ``[Leg, ...]`` (each starting where the previous ended) as one Plan."""
    centroid = np.concatenate([legs[0].centroid] + [leg.centroid[1:] for leg in legs[1:]])
    whole = replace(legs[0].problem, start=centroid[0], goal=centroid[-1],
                    waypoints=len(centroid) - 2)
    many = len(legs) > 1
    messages = tuple(
        (f"leg {k + 1} ({leg.start_name} -> {leg.goal_name}): {v}" if many else v)
        for k, leg in enumerate(legs) for v in leg.violations
    )
    bounds = [leg.lower_bound_length for leg in legs]
    with np.errstate(invalid="ignore"):
        history = np.sum([leg.history for leg in legs], axis=0)
    return Plan(
        scenario=scenario,
        settings=settings,
        problem=whole,
        centroid=centroid,
        uav_paths=centroid[None, :, :] + whole.offsets[:, None, :],
        cost=CostTerms(*(float(sum(leg.cost[i] for leg in legs)) for i in range(4))),
        violations=messages,
        history=history,
        evaluations=sum(leg.evaluations for leg in legs),
        seconds=sum(leg.seconds for leg in legs),
        lower_bound_length=None if any(b is None for b in bounds) else float(sum(bounds)),
        legs=tuple(legs),
    )
