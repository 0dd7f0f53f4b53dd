"""Whether a survey's formation can go from each route point to the next at all.

A row of trees whose canopies (each widened by the clearance and the navigation budget,
``R_k`` of :class:`.problem.PlanningProblem`) overlap for the formation is a wall; the
formation gets from one aisle to the next only around the row's ends, through the
headland between the last trees and the area's edge. When the formation is deeper
(along the row) than that gap, at both ends, no path exists, and planning it (issue 51:
minutes, then an infeasible plan) is refused before it starts, naming the headland and
by how much it is short.

Pure geometry in the centroid's space (:mod:`.discs`): every UAV ``n`` and cylinder
``k`` make a disc of radius ``R_k`` at ``c_k - offset_n``; the centroid stays outside
every disc and inside the area shrunk by the formation (:func:`.discs.centroid_rectangle`).
Discs that touch (``|c_i - c_j| <= R_i + R_j``, meeting at a point inside the rectangle)
join one blob. A blob that meets the rectangle's north and south sides separates every
point west of all its discs from every point east of them: a path between them inside
the rectangle would have to cross the blob (two connected closed sets, one joining the
rectangle's west and east sides, the other its north and south sides, meet). The same
for a blob from the west side to the east one, north and south of it. Nothing else is
refused: a point within a blob's extent, or a gap a hair wide, is left to the planner.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ScenarioError
from ..scenario import Scenario
from .discs import _touching_pairs_grid, centroid_rectangle
from .problem import PlanningProblem, problem_from_scenario


class SurveyBlocked(ScenarioError):
    """A survey leg the formation cannot fly: a wall of trees between its ends reaches
    (for the formation) both sides of the area. Exit code 2, like every scenario error."""


@dataclass(frozen=True)
class Wall:
    """A blob of formation discs that closes the area across: ``axis`` 0 when it runs
    north-south (its ends ``"north"``/``"south"``), 1 east-west (``"east"``/``"west"``);
    ``low``, ``high`` the centroid coordinates (east for ``axis`` 0) its discs span;
    ``short_m`` per end (low side first: south or west) how far the formation falls short
    of passing there (metres, > 0 for both); ``trees`` its cylinders' indices."""

    axis: int
    low: float
    high: float
    short_m: tuple[float, float]
    trees: np.ndarray


def walls(problem: PlanningProblem) -> list[Wall]:
    """The blobs of ``problem``'s formation discs that join two opposite sides of the
    centroid's rectangle (module notes), with what the formation lacks at their ends."""
    K, N = len(problem.radii), problem.uav_count
    if K == 0:
        return []
    lo, hi = centroid_rectangle(problem)
    if np.any(lo > hi):
        return []
    centres = (problem.centres[None, :, :] - problem.offsets[:, None, :2]).reshape(-1, 2)
    radii = np.tile(np.asarray(problem.radii, float), N)
    cylinder = np.tile(np.arange(K), N)
    # only the discs that reach into the rectangle
    near = np.hypot(*(np.clip(centres, lo, hi) - centres).T) <= radii
    centres, radii, cylinder = centres[near], radii[near], cylinder[near]
    if len(radii) < 2:
        return _spanning(centres, radii, cylinder, np.arange(len(radii)), lo, hi)
    i, j = _touching_pairs_grid(centres, radii)
    d = np.hypot(*(centres[j] - centres[i]).T)
    # the point of the centre line in both discs: inside the rectangle, the two discs'
    # pieces of it (each convex) are joined there
    witness = centres[i] + (centres[j] - centres[i]) * (radii[i] / np.maximum(d, 1e-12))[:, None]
    joined = (d <= radii[i] + radii[j]) & np.all((witness >= lo) & (witness <= hi), axis=1)
    return _spanning(centres, radii, cylinder, _components(len(radii), i[joined], j[joined]),
                     lo, hi)


def _components(count: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """A label ``(count,)`` per node of the graph with edges ``(i, j)``: equal labels,
    one component (the smallest index in it)."""
    label = np.arange(count)
    while True:
        low = label.copy()
        np.minimum.at(low, i, label[j])
        np.minimum.at(low, j, label[i])
        low = low[low]  # pointer jumping: chains of a row collapse in few rounds
        if np.array_equal(low, label):
            return label
        label = low


def _spanning(centres, radii, cylinder, label, lo, hi) -> list[Wall]:
    found = []
    for blob in np.unique(label):
        members = label == blob
        c, r = centres[members], radii[members]
        for axis in (0, 1):  # 0: north-south wall (spans axis 1), 1: east-west wall
            across = 1 - axis
            reach_low = float((c[:, across] - r).min())
            reach_high = float((c[:, across] + r).max())
            short_low, short_high = lo[across] - reach_low, reach_high - hi[across]
            if short_low >= 0.0 and short_high >= 0.0:
                found.append(Wall(axis, float((c[:, axis] - r).min()),
                                  float((c[:, axis] + r).max()), (short_low, short_high),
                                  np.unique(cylinder[members])))
    return found


def separating(wall: Wall, a: np.ndarray, b: np.ndarray) -> bool:
    """Whether ``wall`` lies between the centroid points ``a`` and ``b`` ``(2,)``: one
    before all its discs, the other beyond them."""
    x, y = float(a[wall.axis]), float(b[wall.axis])
    return (x < wall.low and y > wall.high) or (y < wall.low and x > wall.high)


ENDS = (("south", "north"), ("west", "east"))
DEPTH = ("north-south", "east-west")


def check_survey_turns(scenario: Scenario) -> None:
    """:func:`check_turns` on ``scenario``'s route when it has survey lanes (a plain
    route that cannot be flown is still planned, and said so: ``planner.NO_ROUTE``)."""
    if scenario.survey is None or not scenario.survey.lanes:
        return
    check_turns(problem_from_scenario(scenario, waypoints=1), scenario.route_enu(),
                scenario.route_names(), source=scenario.source,
                kept_clearance_m=scenario.kept_clearance_m)


def check_turns(problem: PlanningProblem, points: np.ndarray, names: tuple[str, ...], *,
                source: str, kept_clearance_m: float) -> None:
    """Raise :class:`SurveyBlocked` for the first leg between consecutive ``points
    (L+1, 3)`` (centroid, metres ENU; named ``names``) that a wall of ``problem``
    separates, naming the wall's two ends and by how much the formation is short there.

    ``kept_clearance_m``: the clearance and navigation budget in ``problem.radii`` (said
    in the message)."""
    points = np.asarray(points, float)
    lo, hi = centroid_rectangle(problem)
    found = walls(problem)
    if not found:
        return
    for k in range(len(points) - 1):
        a, b = points[k, :2], points[k + 1, :2]
        if not (np.all((a >= lo) & (a <= hi)) and np.all((b >= lo) & (b <= hi))):
            continue
        for wall in found:
            if separating(wall, a, b):
                raise SurveyBlocked(source, "survey", _message(
                    problem, wall, k, len(points) - 1, names[k], names[k + 1],
                    kept_clearance_m))


def _message(problem: PlanningProblem, wall: Wall, leg: int, legs: int, first: str,
             second: str, kept_clearance_m: float) -> str:
    across = 1 - wall.axis
    depth = float(np.ptp(problem.offsets[:, across]))
    trees = wall.trees
    origin = problem.area_lower
    radius = problem.radii[trees] - kept_clearance_m
    ends = []
    for side, short in zip(ENDS[wall.axis], wall.short_m):
        sign = -1.0 if side in ("south", "west") else 1.0
        reaches = problem.centres[trees, across] + sign * problem.radii[trees]
        last = int(trees[np.argmax(sign * reaches)])
        edge = (problem.area_lower if sign < 0 else problem.area_upper)[across]
        free = sign * (edge - (problem.centres[last, across] + sign * problem.radii[last]))
        east, north = problem.centres[last] - origin
        ends.append(f"the {side} headland (its last tree at {east:.1f} m east, {north:.1f} m "
                    f"north of the area's south-west corner) leaves {free:.2f} m between "
                    f"that tree's reach and the area's {side} edge, {short:.2f} m short")
    return (f"leg {leg + 1}/{legs} ({first} -> {second}) cannot be flown: {len(trees)} trees "
            f"({radius.min():.2f}-{radius.max():.2f} m radius, kept {kept_clearance_m:.2f} m "
            f"clear: clearance and navigation budget) close the way from the area's "
            f"{ENDS[wall.axis][0]} edge to its {ENDS[wall.axis][1]} edge for the formation, "
            f"{depth:.2f} m deep {DEPTH[wall.axis]}: {'; '.join(ends)} "
            f"(widen the headlands, or fly a formation less deep {DEPTH[wall.axis]})")
