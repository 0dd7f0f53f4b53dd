"""The flown path, predicted: what every UAV's mission makes ArduCopter fly, and whether
that keeps the plan's promises.

A plan's waypoints are not the path flown: ArduCopter rounds every corner
(:mod:`ftlbo_mav.ardupilot.flight_path`). :func:`predict` flies each UAV's own path
(start, waypoints, goal; its corners, its speed, its holds) through that model, all
starting together as ``fly`` starts them, and measures on the predicted paths what the
plan promises: the clearance from every obstacle, the area, the altitude band and the
separation between UAVs at the same instant. :func:`keep_clearance` changes a centroid
path until the predicted paths keep the clearance (see there).

Pure computation, metres ENU and seconds.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..ardupilot.flight_path import FlownPath, fly_groups
from ..ardupilot.navigation import Navigation
from ..gnss import largest_error_for, true_distance
from .feasibility import violations as segment_violations
from .problem import PlanningProblem
from .proximity import nearest_samples

_TOL = 1e-6
PUSH_MARGIN_M = 0.02
"""A corner moved to keep the clearance is moved this much further than the shortfall."""
MAX_ROUNDS = 12
"""Rounds of :func:`keep_clearance` (predict, change the corners that cut in) at most."""
MAX_PUSHES = 4
"""Times one corner is moved before the copters are made to stop at it instead."""
HOLD_S = 1
"""The hold (whole seconds, NAV_WAYPOINT param1) that makes a copter stop at a corner."""


@dataclass(frozen=True)
class FlightModel:
    """How the copters fly a plan: ArduCopter's parameters (the scenario's
    ``[vehicle]``) and the cruise speed (``[mission] speed``; None: WPNAV_SPEED);
    ``navs``: each UAV's own parameters and release (a fleet of different copters;
    None: ``nav`` for every UAV)."""

    nav: Navigation = Navigation()
    speed_m_s: float | None = None
    navs: tuple[Navigation, ...] | None = None

    @classmethod
    def of_fleet(cls, navs: Sequence[Navigation], speed_m_s: float | None) -> FlightModel:
        """One copter's parameters per UAV: ``navs`` only where they differ."""
        navs = tuple(navs)
        return cls(nav=navs[0], speed_m_s=speed_m_s,
                   navs=None if len(set(navs)) == 1 else navs)


@dataclass(frozen=True, eq=False)
class Prediction:
    """The predicted flight of N UAVs on a common clock (0: the first leg begins).

    ``times``: ``(T,)`` s; ``positions``: ``(N, T, 3)`` metres ENU (a UAV that has
    arrived stays at its goal); ``reached``: ``(N, P)`` when each UAV reached each point;
    ``clearance``: ``(N,)`` each UAV's smallest horizontal distance to any obstacle's
    surface (inf without obstacles); ``obstacle_clearance``: ``(K,)`` the smallest over
    the UAVs, per obstacle; ``separation``: ``(N,)`` each UAV's smallest 3D distance to
    any other at the same instant (inf for one UAV); ``worst``: per UAV ``(time index,
    obstacle index)`` of its smallest clearance (-1 without obstacles);
    ``true_separation``: ``(N,)`` the smallest the separation can truly be within the
    navigation budget (:func:`predict`'s ``pair_error_m``)."""

    times: np.ndarray
    positions: np.ndarray
    reached: np.ndarray
    clearance: np.ndarray
    obstacle_clearance: np.ndarray
    separation: np.ndarray
    worst: np.ndarray
    true_separation: np.ndarray | None = None

    @property
    def leg_seconds(self) -> np.ndarray:
        """``(N, P-1)`` seconds from each point to the next."""
        return np.diff(self.reached, axis=1)

    @property
    def seconds(self) -> np.ndarray:
        """``(N,)`` seconds from the first leg's start to the goal."""
        return self.reached[:, -1]


def _common_clock(shapes: list[FlownPath], group: np.ndarray, shift: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Every UAV's positions ``(N, T, 3)`` on the longest clock (they share the step; a
    UAV that has arrived stays at its goal)."""
    longest = max(shapes, key=lambda f: len(f.times))
    T = len(longest.times)
    padded = np.empty((len(shapes), T, 3))
    for g, f in enumerate(shapes):
        padded[g, : len(f.times)] = f.positions
        padded[g, len(f.times):] = f.positions[-1]
    return longest.times, padded[group] + shift[:, None, :]


def _clearances(padded: np.ndarray, group: np.ndarray, shift: np.ndarray,
                centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, ...]:
    """Per UAV its smallest distance to any cylinder's surface and where ``(N, 2)`` (time
    index, obstacle index; the earliest, then the first obstacle, on a tie), and per
    cylinder the smallest over the UAVs: from the nearest sample of each flown shape to
    each cylinder's axis moved by minus the UAV's shift (:func:`.proximity.nearest_samples`),
    never the full ``(N, T, K)`` array."""
    N, K = len(group), len(radii)
    surface = np.empty((N, K))
    when = np.empty((N, K), int)
    for g in range(len(padded)):
        members = np.flatnonzero(group == g)
        seen = (centres[None, :, :] - shift[members, None, :2]).reshape(-1, 2)
        d, t = nearest_samples(padded[g, :, :2], seen)
        surface[members] = d.reshape(len(members), K) - radii
        when[members] = t.reshape(len(members), K)
    clearance = surface.min(axis=1)
    worst = np.empty((N, 2), int)
    for n in range(N):
        ties = np.flatnonzero(surface[n] == clearance[n])
        k = int(ties[np.lexsort((ties, when[n, ties]))[0]])
        worst[n] = when[n, k], k
    return clearance, worst, surface.min(axis=0)


def _separations(positions: np.ndarray, group: np.ndarray, shift: np.ndarray,
                 pair_error_m: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Per UAV its smallest 3D distance to any other at the same instant ``(N,)``, and
    the smallest it can truly be when their horizontal positions are off by up to
    ``pair_error_m`` between them (:func:`~ftlbo_mav.gnss.true_distance`): within a group
    of translated paths those distances never change (the difference of their shifts);
    across groups they are measured one UAV at a time (memory ``(N, T)``)."""
    N = len(group)
    out = np.full(N, np.inf)
    true = np.full(N, np.inf)
    if N < 2:
        return out, true
    same = group[:, None] == group[None, :]
    apart = shift[:, None] - shift[None, :]
    mates = same & ~np.eye(N, dtype=bool)
    out = np.where(mates, np.linalg.norm(apart, axis=-1), np.inf).min(axis=1)
    true = np.where(mates, true_distance(np.hypot(apart[..., 0], apart[..., 1]), apart[..., 2],
                                         pair_error_m), np.inf).min(axis=1)
    for n in range(N):
        other = np.flatnonzero(~same[n])
        if len(other):
            d = positions[other] - positions[n][None]
            out[n] = min(out[n], float(np.linalg.norm(d, axis=-1).min()))
            true[n] = min(true[n], float(true_distance(np.hypot(d[..., 0], d[..., 1]),
                                                        d[..., 2], pair_error_m).min()))
    return out, true


def predict(paths: np.ndarray, *, model: FlightModel, centres: np.ndarray,
            radii: np.ndarray, holds_s: np.ndarray | None = None,
            pair_error_m: float = 0.0) -> Prediction:
    """Fly every UAV's path ``(N, P, 3)`` (holds ``(P,)`` whole seconds, default none)
    and measure it against the cylinders ``centres`` ``(K, 2)``, ``radii`` ``(K,)``
    (their own radii, no clearance); ``pair_error_m``: the navigation budget's combined
    error of two copters, for ``true_separation``."""
    shapes, group, shift = fly_groups(paths, nav=model.nav, speed_m_s=model.speed_m_s,
                                      holds_s=holds_s, navs=model.navs)
    times, pos = _common_clock(shapes, group, shift)
    N = pos.shape[0]
    radii = np.asarray(radii, float)
    if len(radii):
        own = _common_clock(shapes, np.arange(len(shapes)), np.zeros((len(shapes), 3)))[1]
        clearance, worst, per_obstacle = _clearances(own, group, shift,
                                                     np.asarray(centres, float), radii)
    else:
        worst = np.full((N, 2), -1)
        clearance = np.full(N, np.inf)
        per_obstacle = np.zeros(0)
    separation, true_separation = _separations(pos, group, shift, pair_error_m)
    reached = np.array([shapes[g].reached for g in group])
    return Prediction(times=times, positions=pos, reached=reached, clearance=clearance,
                      obstacle_clearance=per_obstacle, separation=separation, worst=worst,
                      true_separation=true_separation)


def predicted_violations(problem: PlanningProblem, prediction: Prediction, *,
                         clearance_m: float, obstacle_radii: np.ndarray,
                         min_separation_m: float, limit: int = 20) -> list[str]:
    """What the predicted flight breaks, in sentences (empty: nothing): a UAV closer
    than ``clearance_m`` to an obstacle's surface, outside the area or the altitude band
    (between its start and its goal), or two UAVs closer than ``min_separation_m`` at the
    same instant."""
    out: list[str] = []
    p = prediction
    for n in np.flatnonzero(p.clearance < clearance_m - _TOL):
        i, k = p.worst[n]
        out.append(f"UAV {n + 1}'s predicted flown path passes {p.clearance[n]:.2f} m from "
                   f"obstacle {k + 1}'s surface {p.times[i]:.1f} s into its legs (needs "
                   f"{clearance_m:.2f} m: ArduCopter cuts the corner)")
    outside = (beyond_area(problem, p.positions) > _TOL).any(axis=2)
    for n in np.flatnonzero(outside.any(axis=1)):
        i = int(np.argmax(outside[n]))
        out.append(f"UAV {n + 1}'s predicted flown path leaves the area {p.times[i]:.1f} s "
                   "into its legs")
    z = p.positions[:, :, 2]
    band = (z < problem.h_min - _TOL) | (z > problem.h_max + _TOL)
    for n in np.flatnonzero(band.any(axis=1)):
        i = int(np.argmax(band[n]))
        out.append(f"UAV {n + 1}'s predicted flown path is at {z[n, i]:.2f} m, outside the "
                   f"altitude band [{problem.h_min:g}, {problem.h_max:g}] m, "
                   f"{p.times[i]:.1f} s into its legs")
    true = p.separation if p.true_separation is None else p.true_separation
    for n in np.flatnonzero(true < min_separation_m - _TOL):
        truly = ("" if true[n] == p.separation[n] else
                 f", truly as close as {true[n]:.2f} m within the navigation budget")
        out.append(f"UAV {n + 1} is predicted {p.separation[n]:.2f} m from another UAV"
                   f"{truly} (needs {min_separation_m:g} m)")
    if len(out) > limit:
        out = out[: limit - 1] + [f"... and {len(out) - limit + 1} more"]
    return out


@dataclass(frozen=True, eq=False)
class Kept:
    """What :func:`keep_clearance` did: the centroid path ``(P, 3)``, the holds ``(P,)``,
    the prediction of the result, how many corners it moved (``moved``, counting each
    move) and made stops (``stops``), the rounds it took, and ``stopped_for``: ``(K,)``
    per obstacle the most metres a corner made a stop fell short of it (0: none)."""

    centroid: np.ndarray
    holds_s: np.ndarray
    prediction: Prediction
    moved: int
    stops: int
    rounds: int
    stopped_for: np.ndarray


def _corner(reached: np.ndarray, t: float, fixed: np.ndarray) -> int | None:
    """The corner (a point index, neither end) a UAV turns at time ``t``: the point it
    reached nearest that time."""
    inner = np.arange(1, len(reached) - 1)
    if not len(inner):
        return None
    return int(inner[np.argmin(np.abs(reached[inner] - t))])


def _moved(problem: PlanningProblem, path: np.ndarray, j: int, shift: np.ndarray,
           fixed: np.ndarray) -> np.ndarray | None:
    """``path`` with corner ``j`` moved by ``shift`` (horizontal), else with it and its
    movable neighbours moved together (a corner in a cluster of close points, as around a
    tree the polyline hugs), whichever keeps the polyline feasible first; None if neither
    does."""
    for run in ([j], [i for i in (j - 1, j, j + 1) if not fixed[i]]):
        if fixed[j]:
            continue
        trial = path.copy()
        trial[run, :2] += shift
        if not segment_violations(problem, trial, limit=1):
            return trial
    return None


def beyond_area(problem: PlanningProblem, positions: np.ndarray) -> np.ndarray:
    """How far ``positions`` ``(..., 3)`` lie past the area's sides, ``(..., 4)`` metres:
    past its lower east and north sides, then its upper ones (<= 0: inside)."""
    xy = positions[..., :2]
    return np.concatenate([problem.area_lower - xy, xy - problem.area_upper], axis=-1)


def _area_shortfalls(problem: PlanningProblem, p: Prediction) -> list:
    """Per UAV whose predicted path leaves the area: ``(uav, time index, inward (2,),
    metres)`` of its furthest excursion, the unit vector back in and how far (plus
    :data:`PUSH_MARGIN_M`)."""
    beyond = beyond_area(problem, p.positions)
    out = []
    for n in np.flatnonzero(beyond.max(axis=(1, 2)) > _TOL):
        t_i, side = np.unravel_index(int(np.argmax(beyond[n])), beyond[n].shape)
        inward = np.zeros(2)
        inward[side % 2] = 1.0 if side < 2 else -1.0
        out.append((int(n), int(t_i), inward, float(beyond[n, t_i, side]) + PUSH_MARGIN_M))
    return out


def keep_clearance(problem: PlanningProblem, centroid: np.ndarray, *, model: FlightModel,
                   obstacle_radii: np.ndarray, clearance_m: float,
                   fixed: np.ndarray | None = None, pair_error_m: float = 0.0) -> Kept:
    """Change the centroid path until every UAV's predicted flown path keeps
    ``clearance_m`` from every obstacle's surface (``obstacle_radii``: the cylinders' own
    radii at ``problem.centres``) and stays inside the area.

    Each round predicts the flight; where a UAV comes too close it finds the corner it
    was turning at and moves that corner (the centroid's point, so every UAV's) straight
    away from the obstacle by the shortfall plus :data:`PUSH_MARGIN_M`, if the moved
    polyline still keeps the clearance segment by segment, inside the area and the band
    (:func:`..feasibility.violations`), else together with its neighbours; where a UAV
    swings out of the area the corner it turns at moves back in the same way (one that
    cannot is left to the plan's violations: a stop would be overshot). A corner too
    close to an obstacle that cannot be moved (a via point, a move that breaks the
    polyline either way, or one moved :data:`MAX_PUSHES` times) becomes a stop: a hold
    of :data:`HOLD_S` s, so that every copter stops on it and the polyline's clearance
    is flown. ``fixed``: ``(P,)`` True for points that may not move (the start,
    via points and the goal always are); ``pair_error_m``: passed to :func:`predict`."""
    path = np.array(centroid, float)
    P = len(path)
    fixed = np.zeros(P, bool) if fixed is None else np.array(fixed, bool)
    fixed[[0, -1]] = True
    holds = np.zeros(P)
    pushes = np.zeros(P, int)
    stopped_for = np.zeros(len(obstacle_radii))
    moved = stops = 0
    rounds = 0
    while True:
        uavs = path[None] + problem.offsets[:, None]
        pred = predict(uavs, model=model, centres=problem.centres, radii=obstacle_radii,
                       holds_s=holds, pair_error_m=pair_error_m)
        short = pred.clearance < clearance_m - _TOL
        outside = _area_shortfalls(problem, pred)
        if (not short.any() and not outside) or rounds >= MAX_ROUNDS:
            break
        rounds += 1
        # the worst shortfall at each corner, over the UAVs that cut in
        worst: dict[int, tuple[float, np.ndarray, int]] = {}
        for n, t_i, inward, need in outside:  # a swing out of the area: the corner moves in
            j = _corner(pred.reached[n], pred.times[t_i], fixed)
            if (j is not None and holds[j] == 0 and pushes[j] < MAX_PUSHES
                    and (j not in worst or need > worst[j][0])):
                worst[j] = (need, inward, -1)
        for n in np.flatnonzero(short):
            t_i, k = pred.worst[n]
            j = _corner(pred.reached[n], pred.times[t_i], fixed)
            if j is None or (holds[j] > 0 and pushes[j] >= MAX_PUSHES):
                continue  # a stop still overshot towards the tree is moved, while it can be
            where = pred.positions[n, t_i, :2]
            away = where - problem.centres[k]
            away = away / max(float(np.linalg.norm(away)), 1e-9)
            need = clearance_m - pred.clearance[n] + PUSH_MARGIN_M
            if j not in worst or need > worst[j][0]:
                worst[j] = (need, away, int(k))
        if not worst:
            break
        for j, (need, away, k) in sorted(worst.items()):
            trial = _moved(problem, path, j, away * need, fixed) if pushes[j] < MAX_PUSHES else None
            if trial is not None:
                path, pushes[j], moved = trial, pushes[j] + 1, moved + 1
            elif k >= 0 and holds[j] == 0:
                holds[j] = HOLD_S
                stops += 1
                stopped_for[k] = max(stopped_for[k], need)
            else:  # a stop that cannot move, or a swing out of the area (a stop would be
                pushes[j] = MAX_PUSHES  # overshot too): left to the plan's violations
    return Kept(centroid=path, holds_s=holds, prediction=pred, moved=moved, stops=stops,
                rounds=rounds, stopped_for=stopped_for)


def formation_room(prediction: Prediction, *, min_separation_m: float,
                   navigation_m: float) -> float:
    """How far from its slot each copter may be (metres, both of a pair towards each
    other) with ``min_separation_m`` still kept where they truly are: half of what the
    predicted flight's closest pair has beyond ``min_separation_m`` and two copters'
    combined navigation error (``sqrt(2) x navigation_m``); 0 when it has nothing."""
    if prediction.positions.shape[0] < 2:
        return math.inf
    closest = float(np.min(prediction.separation))
    return max((closest - min_separation_m - math.sqrt(2.0) * navigation_m) / 2.0, 0.0)


def navigation_room(prediction: Prediction, *, clearance_m: float,
                    min_separation_m: float) -> float:
    """The largest navigation budget (metres at 95 %, per copter) with which the
    predicted flight still keeps ``clearance_m`` from every obstacle and
    ``min_separation_m`` between copters where they truly are: the clearance it keeps
    beyond ``clearance_m``, and the separation room shared by two copters' errors
    (:func:`~ftlbo_mav.gnss.largest_error_for`), the smaller; 0 when it keeps neither."""
    p = prediction
    room = float(p.clearance.min()) - clearance_m if len(p.clearance) else np.inf
    N = p.positions.shape[0]
    for n in range(N - 1):
        d = p.positions[n + 1:] - p.positions[n][None]
        pair = largest_error_for(np.hypot(d[..., 0], d[..., 1]), d[..., 2], min_separation_m)
        room = min(room, pair / np.sqrt(2.0))
    return max(float(room), 0.0)
