"""A leg's window: among thousands of trees, plan each leg among the few it can reach.

A leg from ``a`` to ``b`` whose shortest route is ``L*`` long is planned as well among
the obstacles near it as among all of them. The window makes "near" exact. Every path
from ``a`` to ``b`` of length at most ``L`` lies inside the ellipse with foci ``a`` and
``b`` whose points have ``|p - a| + |p - b| <= L``. The window of reach ``L`` is the
leg's problem with

- the area cut down to the ellipse's bounding box (the centroid's box, the UAVs' area
  around it), so the optimizer's waypoints, and with them every candidate's segments
  (the box is convex and holds start and goal), stay inside it, and
- only the cylinders one of whose formation discs (:func:`.discs.formation_discs`:
  centre ``c_k - offset_n``, radius ``R_k``) reaches into that box.

For every path inside the box the window and the whole problem agree on every
obstacle: a candidate is clear in the window exactly when it is clear. Paths no longer
than ``L`` lie in the ellipse, so in the box: when the window's shortest route is at
most ``L`` long it is the whole problem's shortest route, and the lower bound is exact
(:func:`leg_window` widens the reach until it is). A plan's feasibility is still judged
on the whole problem (after :mod:`.predicted` moves corners, a point may leave the box).

The safety term of the cost (the paper's eq. 9, a mean of ``R/d`` over the obstacles)
is then the mean over the window's obstacles: the ones the leg's candidates can come
near. Used from :data:`WINDOW_FROM` cylinders on; below, every leg sees every obstacle
as the paper has it.

Pure computation on :class:`.problem.PlanningProblem`, metres ENU.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .cost import _axes
from .discs import Discs, centroid_rectangle
from .geometric import Route
from .problem import PlanningProblem
from .tangents import segments_clear

WINDOW_FROM = 200
"""Cylinders from which legs are planned in their windows (below: among all)."""
WINDOW_SLACK = 0.005
"""The reach is this much longer than the shortest route (relative), so that plans a
little longer than the bound (``waypoints = "auto"`` keeps them within 0.5%) lie in the
window too."""
WINDOW_MIN_M = 1.0
"""And at least this much longer (metres): short legs get room to bend. A leg whose
straight line is clear has that line for its route, and its window reaches this much
beyond the line's length alone (the plans kept lie along the line)."""
WINDOW_SHARE = 0.5
"""A leg whose straight line is blocked is planned among all cylinders when its window
would still hold more than this share of them (its route then needs one tangent graph,
not one per widening)."""
MAX_WIDENINGS = 8
"""Times the reach is widened at most before the window is the whole problem."""


@dataclass(frozen=True, eq=False)
class Window:
    """One leg's window: ``problem`` (the leg's obstacles and area cut down), ``kept``
    ``(K',)`` the indices of its cylinders in the whole problem's, ``reach_m`` (``L``),
    and the routes found in it (shortest first; ``[]``: no route), ``None`` when they
    are still to be computed."""

    problem: PlanningProblem
    kept: np.ndarray
    reach_m: float
    routes: list[Route] | None = None

    @property
    def whole(self) -> bool:
        """Whether the window is the whole problem (nothing left out)."""
        return self.reach_m == math.inf


def ellipse_box(a: np.ndarray, b: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """The bounding box ``(lower (2,), upper (2,))`` of the points ``p`` with
    ``|p - a| + |p - b| <= reach`` (``reach >= |b - a|``)."""
    a, b = np.asarray(a, float)[:2], np.asarray(b, float)[:2]
    d = float(np.hypot(*(b - a)))
    half_major = 0.5 * max(reach, d)
    half_minor = math.sqrt(max(half_major ** 2 - (0.5 * d) ** 2, 0.0))
    u = (b - a) / d if d > 0 else np.array([1.0, 0.0])
    half = np.hypot(half_major * u, half_minor * u[::-1])
    middle = 0.5 * (a + b)
    return middle - half, middle + half


def cut(problem: PlanningProblem, reach: float) -> Window:
    """The window of ``problem``'s leg (start to goal) of reach ``reach`` metres."""
    lo, hi = ellipse_box(problem.start, problem.goal, reach)
    rect_lo, rect_hi = centroid_rectangle(problem)
    lo, hi = np.maximum(lo, rect_lo), np.minimum(hi, rect_hi)
    # every cylinder one of whose formation discs reaches into the centroid's box
    axes = _axes(problem).reshape(problem.uav_count, -1, 2)  # (N, K, 2)
    gap = np.maximum(np.maximum(lo - axes, axes - hi), 0.0)
    kept = np.flatnonzero((np.hypot(gap[..., 0], gap[..., 1]) < problem.radii).any(axis=0))
    # the UAVs' area around the centroid's box (PlanningProblem.bounds takes it back off)
    off_lo, off_hi = problem.offsets.min(axis=0)[:2], problem.offsets.max(axis=0)[:2]
    sub = replace(problem, centres=problem.centres[kept], radii=problem.radii[kept],
                  area_lower=np.maximum(problem.area_lower, lo + off_lo),
                  area_upper=np.minimum(problem.area_upper, hi + off_hi))
    return Window(sub, kept, float(reach))


def _all(problem: PlanningProblem) -> Window:
    return Window(problem, np.arange(len(problem.radii)), math.inf)


def every_disc(problem: PlanningProblem) -> Discs:
    """Every formation disc of ``problem``, none left out (:func:`.discs.formation_discs`
    drops the ones that change no route, at a cost; a segment clear of these is clear of
    those)."""
    N, K = problem.uav_count, len(problem.radii)
    return Discs(_axes(problem), np.tile(problem.radii, N), np.tile(np.arange(K), N),
                 np.repeat(np.arange(N), K))


def straight_clear(problem: PlanningProblem) -> bool:
    """Whether the formation flies from start to goal in a straight line without
    entering any cylinder's disc (every UAV's segment against every cylinder)."""
    return bool(segments_clear(problem.start[None, :2], problem.goal[None, :2],
                               every_disc(problem))[0])


def leg_window(problem: PlanningProblem, *, routes, count: int = 1) -> Window:
    """The leg's window, its reach long enough that its shortest route is the whole
    problem's (module notes), with the routes found in it.

    ``routes(problem, count)`` finds up to ``count`` routes in a problem, shortest first
    (:func:`.geometric.shortest_routes`). Below :data:`WINDOW_FROM` cylinders the
    window is the whole problem. When the straight line is clear it is the shortest
    route, and the only one returned (no graph is built)."""
    if len(problem.radii) < WINDOW_FROM:
        return replace(_all(problem), routes=None)
    a, b = problem.start[:2].astype(float), problem.goal[:2].astype(float)
    straight = float(np.hypot(*(b - a)))
    rect_lo, rect_hi = centroid_rectangle(problem)
    if _inside(a, rect_lo, rect_hi) and _inside(b, rect_lo, rect_hi) and straight_clear(problem):
        # the route is the line whatever the window; the plans kept lie along it
        window = cut(problem, straight + WINDOW_MIN_M)
        line = Route(straight, np.array([a, b]), (None,), every_disc(window.problem))
        return replace(window, routes=[line])
    reach = _reach(straight)
    for _ in range(MAX_WIDENINGS):
        window = cut(problem, reach)
        if len(window.kept) > WINDOW_SHARE * len(problem.radii):
            break  # hardly smaller than the whole: a graph here and another there cost more
        found = routes(window.problem, count)
        if found and found[0].length * (1 + WINDOW_SLACK) <= reach + 1e-9:
            return replace(window, routes=found)
        if len(window.kept) == len(problem.radii) and _covers(window.problem, problem):
            return replace(_all(problem), routes=found)  # the window was everything
        # longer than the reach: widen it to the route found; no route: double it
        reach = _reach(found[0].length) if found else 2.0 * reach
    return replace(_all(problem), routes=None)


def leg_sizes(problem: PlanningProblem, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each leg between consecutive ``points (L+1, 3)``: how many cylinders it is
    planned among (its first window's, the reach of the straight line; all of them below
    :data:`WINDOW_FROM`) and whether its straight line is clear: ``(L,)`` ints and
    ``(L,)`` bools (what :func:`.planner.check_size` counts)."""
    legs = [replace(problem, start=a, goal=b) for a, b in zip(points[:-1], points[1:])]
    straight = np.array([straight_clear(leg) for leg in legs], bool)
    K = len(problem.radii)
    if K < WINDOW_FROM:
        return np.full(len(legs), K), straight
    reach = [float(np.hypot(*(leg.goal[:2] - leg.start[:2]))) for leg in legs]
    reach = [r + WINDOW_MIN_M if clear else _reach(r) for r, clear in zip(reach, straight)]
    kept = np.array([len(cut(leg, r).kept) for leg, r in zip(legs, reach)])
    return np.where(~straight & (kept > WINDOW_SHARE * K), K, kept), straight


def _reach(length: float) -> float:
    return length * (1 + WINDOW_SLACK) + WINDOW_MIN_M


def _inside(p: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    return bool(np.all(p >= lo) and np.all(p <= hi))


def _covers(window: PlanningProblem, problem: PlanningProblem) -> bool:
    return bool(np.all(window.area_lower <= problem.area_lower)
                and np.all(window.area_upper >= problem.area_upper))
