"""What planning returns: a :class:`Leg` (one leg, planned on its own), a :class:`Plan`
(the legs flown as one continuous path, :func:`combine`), and what a plan says of itself
(feasible, its length over the bound, the corners it stops at, the survey lanes' points,
how far a UAV may stray from its slot).

:func:`.planner.plan` makes them and :func:`.repair.until_kept` judges them on the path
ArduCopter flies; the mission files (``mission/``), the plots and ``fly`` read them.
Values only: no planning here.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..energy import MissionCharge
from ..scenario import PlannerSettings, Scenario
from .cost import CostTerms
from .predicted import Prediction, formation_room
from .problem import PlanningProblem


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
    """With ``"auto"``: the count :data:`.planner.AUTO_TARGET` starts from
    (:func:`.planner.plan` skips the plan with it when every leg has it and is within it
    already: the same plan)."""

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
    judged; None for a plan made without it (:func:`combine` alone, before
    :func:`.repair.fly_as_arducopter`)."""
    corners_moved: int = 0
    """Corner moves :func:`.predicted.keep_clearance` made (each move counted)."""
    predict_seconds: float = 0.0
    """Wall seconds of predicting the flown paths and keeping the clearance (in
    ``seconds`` too)."""
    stopped_for: np.ndarray | None = None
    """``(K,)`` metres by which corners made stops fell short of each obstacle."""
    replans: int = 0
    """Times the route was planned again to avoid corner stops (:data:`.repair.REPLANS`); the
    best of the plans is kept, ``seconds`` counts them all."""
    charges: tuple[MissionCharge, ...] | None = None
    """Each UAV's predicted battery use (:mod:`ftlbo_mav.energy`), when the scenario
    has a ``[battery]``; a mission that would land below the reserve is a violation."""
    lanes_inset_m: float = 0.0
    """How much further inside the area than its margin the survey's lanes were laid
    so that the copters' predicted swings stay inside (:data:`.repair.SURVEY_RELAYS`; 0:
    not)."""

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


REPEAT_M = 0.1  # waypoints closer than this are one point (ArduCopter: a leg of its own)


def spread_repeats(problem: PlanningProblem, best: np.ndarray) -> np.ndarray:
    """``best`` ``(1, m, 3)`` with waypoints that repeat a point (within :data:`REPEAT_M`:
    a straight leg's waypoint the optimizer left on or by its start or goal) spread
    evenly along the straight line to the next point (to the goal's from the one before):
    the same path within that, without legs of next to no length. ArduCopter flies a
    zero-length leg as an S-curve of its own whose end differs from copter to copter with
    their residual errors: on 4.6.3 SITL three Solos surveying the orchard at 3 m/s, one
    began the next leg 0.3 s after the others at a lane end of two such legs, 0.7 m from
    its slot, in two flights of two; planned without them, 0.06 m worst (2026-12-07,
    ``benchmarks/fleet.py --fleet solo-4.6.3 --scenario missions/orchard-survey.toml``)."""
    path = problem.full_paths(best)[0]
    n = len(path)
    same = np.linalg.norm(np.diff(path, axis=0), axis=1) <= REPEAT_M
    if not same.any():
        return best
    path = path.copy()
    i = 0
    while i < n - 1:
        if not same[i]:
            i += 1
            continue
        j = i
        while j < n - 1 and same[j]:
            j += 1
        # path[i..j] are one point
        if j < n - 1:  # spread path[i+1..j] towards path[j+1]
            a, b, moved = path[i], path[j + 1], range(i + 1, j + 1)
        else:  # the goal's repeats: spread path[i..j-1] from path[i-1]
            a, b, moved = path[i - 1], path[j], range(i, j) if i > 0 else ()
        for k, idx in enumerate(moved, 1):
            path[idx] = a + (b - a) * (k / (j - i + 1))
        i = j + 1
    return path[1:-1][None]
