"""The planning problem in the scenario's local ENU frame: plain arrays, no geodesy."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..scenario import Scenario


@dataclass(frozen=True, eq=False)
class PlanningProblem:
    """Everything the cost and the optimizers need, in metres ENU.

    ``start``, ``goal``: ``(3,)`` the centroid's start ``P_s`` and goal ``P_f``.
    ``offsets``: ``(N, 3)`` each UAV's offset from the centroid.
    ``centres``: ``(K, 2)`` cylinder axes (east, north).
    ``radii``: ``(K,)`` cylinder radius *plus the scenario's clearance*, its navigation
    budget and its ``[mission] corner_allowance`` (``Scenario.kept_clearance_m``): the
    radius every check uses (clearance 0 is the paper exactly).
    ``h_min``, ``h_max``: altitude band for every UAV waypoint.
    ``area_lower``, ``area_upper``: ``(2,)`` horizontal area bounds.
    ``waypoints``: ``m``, the number of free waypoints between start and goal.
    ``weights``: ``(3,)`` the paper's alpha, beta, gamma (eq. 5).
    """

    start: np.ndarray
    goal: np.ndarray
    offsets: np.ndarray
    centres: np.ndarray
    radii: np.ndarray
    h_min: float
    h_max: float
    area_lower: np.ndarray
    area_upper: np.ndarray
    waypoints: int
    weights: np.ndarray

    @property
    def uav_count(self) -> int:
        return len(self.offsets)

    @property
    def dimension(self) -> int:
        return 3 * self.waypoints

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Decision-variable bounds, each shape ``(m, 3)``.

        The paper bounds the search by the area and the altitude band (its pseudo-code's
        LB/UB). We bound the centroid so that every UAV is inside them: horizontally the
        area shrunk by the formation's extent, vertically the band shrunk by the
        formation's vertical offsets. The task cost (eq. 10) is then zero for every
        candidate; it still acts when the formation is taller than the band, where the
        vertical bound falls back to the band's centre for the formation's mid-height.
        """
        lo, hi = self.offsets.min(axis=0), self.offsets.max(axis=0)
        xy_lo = self.area_lower - lo[:2]
        xy_hi = self.area_upper - hi[:2]
        z_lo, z_hi = self.h_min - lo[2], self.h_max - hi[2]
        if z_lo > z_hi:  # taller than the band: no centroid altitude keeps every UAV in it
            z_lo = z_hi = (self.h_min + self.h_max - lo[2] - hi[2]) / 2
        lower = np.tile(np.append(xy_lo, z_lo), (self.waypoints, 1))
        upper = np.tile(np.append(xy_hi, z_hi), (self.waypoints, 1))
        return lower, upper

    def full_paths(self, waypoints: np.ndarray) -> np.ndarray:
        """Centroid paths ``(S, m+2, 3)`` from waypoints ``(S, m, 3)``: start, W_1..W_m, goal."""
        waypoints = np.asarray(waypoints, float)
        S = waypoints.shape[0]
        start = np.broadcast_to(self.start, (S, 1, 3))
        goal = np.broadcast_to(self.goal, (S, 1, 3))
        return np.concatenate([start, waypoints, goal], axis=1)


def problem_from_scenario(scenario: Scenario, *, waypoints: int | None = None) -> PlanningProblem:
    """Convert a scenario to its ENU planning problem."""
    centres, radii = scenario.obstacles_enu()
    lower, upper = scenario.area_bounds_enu()
    w = scenario.planner.weights
    return PlanningProblem(
        start=scenario.start_enu(),
        goal=scenario.goal_enu(),
        offsets=scenario.offsets_m,
        centres=centres,
        # the clearance kept where the copters truly are: plus the navigation budget
        # (and the corners ArduCopter's S-curve cuts come out of the allowance)
        radii=radii + scenario.kept_clearance_m,
        h_min=scenario.min_altitude_m,
        h_max=scenario.max_altitude_m,
        area_lower=lower,
        area_upper=upper,
        waypoints=waypoints if waypoints is not None else scenario.planner.waypoints,
        weights=np.array([w.length, w.safety, w.task], dtype=float),
    )
