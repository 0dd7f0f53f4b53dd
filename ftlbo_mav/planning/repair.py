"""Plan, predict, repair, until kept: a plan judged on, and changed for, the path
ArduCopter flies, and the one loop every plan goes through (:func:`until_kept`).

:func:`fly_as_arducopter` predicts every UAV's flown path (:mod:`.predicted`, the
copters of the scenario's fleet: :func:`flight_model`), moves the corners the copters cut
or makes them stop there until the clearance is kept, and adds what the flown path
violates (and each UAV's battery, with a ``[battery]``). :func:`until_kept` plans again
around what that found: obstacles widened where corners needed stops, a survey's lanes
laid further in where the copters swing out of the area. :func:`fleet_lags` says where a
fleet of unlike copters drifts apart. The planning itself is the caller's ``attempt``
(:func:`.planner.plan`, :func:`.planner.solve`).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from ..ardupilot.flight_path import stepwise_budget
from ..energy import charge_problem, mission_charges
from ..errors import ScenarioError
from ..formation import slot_errors
from ..scenario import Scenario, relay_lanes
from .cost import CostTerms, cost_terms
from .feasibility import violations
from .plans import Leg, Plan, combine
from .predicted import FlightModel, beyond_area, keep_clearance, predict, predicted_violations
from .problem import problem_from_scenario
from .window import straight_clear

Attempt = Callable[[Scenario, np.ndarray, bool], Plan]
"""``attempt(scenario, widened, first)``: the route of ``scenario`` planned with its
obstacles ``widened`` ``(K,)`` metres, judged on the flown path (:func:`fly_as_arducopter`);
``first``: the first attempt (the one that reports progress)."""


def until_kept(scenario: Scenario, obstacles: int, attempt: Attempt, *,
               relay: bool = True) -> Plan:
    """Plan, predict, repair, until kept: the one loop every plan goes through.

    0. a survey whose legs are all clear straight lines has its lanes laid further in by
       the swing out of the area its straight route is predicted to make
       (:func:`_straight_excursion`), as step 3 would after a first plan;
    1. ``attempt``: plan the route and predict its flown path (the corners the copters
       cut moved, or made stops, until the clearance is kept);
    2. keep the best plan so far (:func:`better`: feasible, fewer corner stops, shorter
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
    if relay and current.survey is not None and current.survey.lanes:
        probe = _straight_excursion(scenario)
        if probe is not None and (probe[0].max() > 0 or probe[1].max() > 0):
            inset_lo, inset_hi = _further_in(probe[0]), _further_in(probe[1])
            try:
                current = relay_lanes(scenario, inset_lower_m=inset_lo, inset_upper_m=inset_hi)
            except ScenarioError:  # no room for it: planned as laid, and judged
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
        improved = best is None or better(result, best)
        if improved:
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
            inset_lo, inset_hi = inset_lo + _further_in(out_lo), inset_hi + _further_in(out_hi)
            current = relay_lanes(scenario, inset_lower_m=inset_lo, inset_upper_m=inset_hi)
            relays, relaid = relays + 1, True
            continue
        break
    return replace(best, seconds=seconds, replans=max(best.replans, replans))


def _further_in(out: np.ndarray) -> np.ndarray:
    """How much further in the lanes are laid for a swing ``out`` (2,) metres past the
    area's sides (<= 0: none): that and :data:`SURVEY_RELAY_MARGIN_M`, on the sides it
    crosses."""
    return np.where(out > 0, out + SURVEY_RELAY_MARGIN_M, 0.0)


def _straight_excursion(scenario: Scenario) -> tuple[np.ndarray, np.ndarray] | None:
    """How far (metres, east and north past the area's lower and upper sides; <= 0: not
    at all) the copters are predicted to swing out of the area flying the survey's route
    as straight lines, each leg through its middle (a plan of every leg's straight line
    with one waypoint, what the planner makes of legs whose straight line is clear);
    ``None`` when one leg's straight line is not clear (its plan bends: no guess).

    :func:`until_kept` lays the lanes that much further in before the first plan: the
    swing of a formation turning between lanes is known before planning, and the survey
    is not planned twice for it (issue 51's orchard: 20 s -> 13 s). The plan is still
    judged on its own flown path and laid again when it swings out."""
    problem = problem_from_scenario(scenario, waypoints=1)
    points = scenario.route_enu()
    if not all(straight_clear(replace(problem, start=a, goal=b))
               for a, b in zip(points[:-1], points[1:])):
        return None
    centroid = np.empty((2 * len(points) - 1, 3))
    centroid[0::2], centroid[1::2] = points, (points[:-1] + points[1:]) / 2
    _centres, own = scenario.obstacles_enu()
    prediction = predict(centroid[None] + problem.offsets[:, None, :],
                         model=flight_model(scenario), centres=problem.centres, radii=own,
                         pair_error_m=scenario.navigation.pair_m)
    beyond = beyond_area(problem, prediction.positions).reshape(-1, 4).max(axis=0)
    return beyond[:2], beyond[2:]


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


def better(a: Plan, b: Plan) -> bool:
    """Feasible first, then fewer corner stops, then the shorter predicted flight."""
    def key(p: Plan):
        t = float(p.prediction.seconds.max()) if p.prediction is not None else np.inf
        return (not p.feasible, p.corner_stops, t)
    return key(a) < key(b)


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
