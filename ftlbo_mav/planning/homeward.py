"""The way home when a flight ends early: every vehicle's route, planned at that moment.

When a flight ends before its goal (a vehicle lost, a mode taken over, a failsafe, a
battery short), the vehicles ``fly`` still answers for are stopped where they are; from
there each flies home on a route of its own, planned here, as an uploaded mission that
ArduCopter flies as :mod:`..ardupilot.flight_path` predicts:

- **Its own height.** Every vehicle gets a layer of the altitude band, layers at least
  ``min_separation`` apart, the highest layer to the vehicle that is highest now. From
  where it stopped it climbs (or descends) straight to its layer, flies its route there
  and comes down at its landing point (NAV_LAND). Two vehicles on different layers never
  come closer than the layers' spacing however their routes cross; they meet only where
  one climbs or descends through the other's layer, and the clock below says when.
- **Its route.** The shortest way from above where it stopped to above its landing point
  around every obstacle grown by the kept clearance (:func:`.geometric.shortest_route`,
  one vehicle, no formation; among thousands of trees within the planner's leg window,
  :func:`.window.leg_window`), as the fewest waypoints whose legs stay clear and within
  :data:`ROUTE_SLACK` of it (:class:`.seeds.RouteChains`), then flown through the copter
  model and its corners moved until the *predicted flown* path keeps the clearance
  (:func:`.predicted.keep_clearance`, as a plan's). The vehicle that left (its last known
  position, grown by how far it can have moved) is one more obstacle.
- **Its moment.** All start together; every pair of predicted flights (climb, route,
  hold, descent at NAV_LAND's speeds, standing on the ground after it) is compared on
  one clock, the pair error of the navigation budget taken off their horizontal
  distance (:func:`..gnss.true_distance`). A vehicle that would come closer than
  ``min_separation`` to one planned before it waits on its layer before it goes (a hold
  of whole seconds at its first point, NAV_WAYPOINT's param1), longer until it does not,
  up to :data:`MAX_WAIT_S`.

A vehicle for which no such route exists (no way around, nowhere to wait) is refused, with
the reason (``fly`` then sends it to RTL where RTL's straight line is safe, else LAND where
it stopped; the others keep clear of that descent). Pure computation, metres ENU and
seconds.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..ardupilot.flight_path import STEP_S
from ..gnss import true_distance
from .discs import Discs, _in_rectangle, centroid_rectangle
from .geometric import shortest_route, shortest_routes
from .predicted import FlightModel, keep_clearance, predict
from .problem import PlanningProblem
from .proximity import nearest_samples
from .seeds import RouteChains
from .tangents import segments_clear
from .window import leg_window

ROUTE_SLACK = 0.02
"""A route's waypoints: the fewest whose clear chain is within this share of the
shortest route's length (or the shortest chain found)."""
MAX_WAYPOINTS = 16
"""Waypoints a route home gets at most."""
MAX_WAIT_S = 60
"""The longest a vehicle waits on its layer for the others to pass (whole seconds)."""
WAIT_STEP_S = 2
"""Waits tried: 0, this, twice this, ... up to :data:`MAX_WAIT_S`."""
INSIDE_MARGIN_M = 0.5
"""A vehicle that stopped inside an obstacle's kept clearance (or the keep-out of the
vehicle that left) may come this much closer than where it is, no more: room for the
first metres of its way out (a route cannot begin on the edge it must keep)."""


@dataclass(frozen=True)
class KeepOut:
    """A vehicle that left the plan: ``centre (2,)`` its last known position, ENU, and
    ``radius_m`` around it that the routes keep out of."""

    centre: np.ndarray
    radius_m: float
    alt_m: float | None = None  # its height above home, where known


@dataclass(frozen=True, eq=False)
class World:
    """The flight's world at the moment of the return: the obstacles ``centres (K, 2)``
    with their own ``radii (K,)``, the ``clearance_m`` kept from their surfaces on the
    flown path (with the navigation budget), the area ``area_lower``/``area_upper``
    ``(2,)``, the altitude band ``band`` (metres above home), ``min_separation_m``
    between vehicles, ``pair_error_m`` (two vehicles' combined horizontal error at 95 %)
    and the copters' ``model``."""

    centres: np.ndarray
    radii: np.ndarray
    clearance_m: float
    area_lower: np.ndarray
    area_upper: np.ndarray
    band: tuple[float, float]
    min_separation_m: float
    model: FlightModel = FlightModel()
    pair_error_m: float = 0.0


@dataclass(frozen=True, eq=False)
class Route:
    """One vehicle's way home. ``points (P, 3)``: where it stopped, above it on its
    layer, the route's waypoints, above its landing point (ENU, altitude above home);
    ``holds_s (P,)``: whole seconds held at each (its wait at point 1); ``land (3,)`` the
    landing point on the ground; ``layer_m``; ``clearance_m`` the smallest predicted
    distance of its flown path to an obstacle's surface; ``times (T,)``, ``positions
    (T, 3)`` its predicted flight on the common clock, to standing on the ground."""

    points: np.ndarray
    holds_s: np.ndarray
    land: np.ndarray
    layer_m: float
    clearance_m: float
    times: np.ndarray
    positions: np.ndarray

    @property
    def wait_s(self) -> float:
        return float(self.holds_s[1]) if len(self.holds_s) > 1 else 0.0

    @property
    def seconds(self) -> float:
        """Predicted seconds from the start of the return to standing on the ground."""
        return float(self.times[-1])


@dataclass(frozen=True, eq=False)
class ReturnPlan:
    """Every vehicle's way home: ``routes`` (vehicle -> :class:`Route`), ``refused``
    (vehicle -> why it has none: it lands where it stopped), ``separation_m`` the
    smallest predicted distance between two of them (inf for fewer than two), and
    ``seconds`` the planning took."""

    routes: dict[int, Route] = field(default_factory=dict)
    refused: dict[int, str] = field(default_factory=dict)
    separation_m: float = math.inf
    seconds: float = 0.0


def layers(band: tuple[float, float], count: int, spacing_m: float) -> np.ndarray:
    """``(count,)`` altitudes from the top of ``band`` down, ``spacing_m`` apart, as many
    distinct ones as fit (then again from the top: those share a layer and are kept apart
    by the clock)."""
    lo, hi = band
    fit = max(int(math.floor((hi - lo) / spacing_m + 1e-9)) + 1, 1) if spacing_m > 0 else count
    return np.array([hi - (i % fit) * spacing_m for i in range(count)], float)


def descent(model: FlightModel, alt_m: float) -> tuple[np.ndarray, np.ndarray]:
    """NAV_LAND's descent from ``alt_m`` above the landing point: ``(times (T,), heights
    (T,))`` on :data:`STEP_S`, WPNAV_SPEED_DN (or LAND_SPEED_HIGH) above LAND_ALT_LOW,
    LAND_SPEED below (ArduCopter/mode.cpp Mode::land_run_vertical_control), after the
    release's hold (Navigation.land_descent_delay_s)."""
    nav = model.nav
    fast, slow = nav.land_descent_speed(), abs(nav.land_speed)
    hold = nav.land_descent_delay_s
    alt = max(alt_m, 0.0)
    low = min(alt, nav.land_alt_low)
    t_fast = (alt - low) / fast
    t = np.arange(0.0, hold + t_fast + low / slow + STEP_S, STEP_S)
    d = np.maximum(t - hold, 0.0)
    z = np.where(d <= t_fast, alt - fast * d, low - slow * (d - t_fast))
    return t, np.maximum(z, 0.0)


def plan_return(positions: dict[int, np.ndarray], landings: dict[int, np.ndarray],
                world: World, *, keep_out: tuple[KeepOut, ...] = (),
                flying: tuple[Route, ...] = (), elapsed_s: float = 0.0,
                roadmaps: dict[int, np.ndarray] | None = None) -> ReturnPlan:
    """The routes home of the vehicles at ``positions`` (vehicle -> ``(3,)`` ENU, where
    each stopped) to ``landings`` (vehicle -> ``(2,)`` or ``(3,)``, its landing point on
    the ground), every one kept clear of the obstacles, the ``keep_out`` discs and, on one
    clock, of the others (module notes). A vehicle refused lands where it stopped: the
    others' routes keep clear of its descent there too. ``flying``: routes home planned
    before and started ``elapsed_s`` ago (a vehicle answered late, its link back): the new
    ones keep clear of them too, on the same clock, and take the layers they leave.
    ``roadmaps``: per vehicle, points known to be clear (its planned path, ``(P, 3)``):
    among :data:`ROADMAP_FROM` obstacles or more, its way home is sought through them
    first (:func:`_through_roadmap`)."""
    t0 = time.perf_counter()
    order = sorted(positions, key=lambda j: -float(positions[j][2]))  # highest first
    taken = {r.layer_m for r in flying}
    free = [h for h in layers(world.band, len(order) + len(taken), world.min_separation_m)
            if h not in taken] or [world.band[1]]
    heights = [free[i % len(free)] for i in range(len(order))]
    found: dict[int, Route] = {}
    refused: dict[int, str] = {}
    for j, layer in zip(order, heights):
        land = np.append(np.asarray(landings[j], float)[:2], 0.0)
        route, why = _route(np.asarray(positions[j], float), land, float(layer), world,
                            keep_out, (roadmaps or {}).get(j))
        if route is None:
            refused[j] = why
        else:
            found[j] = route
    # on one clock: the vehicles landing where they stopped first, then each route in turn
    scheduled: dict = {("flying", i): replace(r, times=r.times - elapsed_s)
                       for i, r in enumerate(flying)}
    scheduled.update({j: _landing_here(np.asarray(positions[j], float), world)
                      for j in refused})
    routes: dict[int, Route] = {}
    for j, route in found.items():
        timed, why = _in_turn(route, scheduled, world)
        if timed is None:
            refused[j] = why
            scheduled[j] = _landing_here(np.asarray(positions[j], float), world)
        else:
            routes[j] = scheduled[j] = timed
    flights = list(routes.values())
    separation = min((_closest(a, b, world.pair_error_m)
                      for i, a in enumerate(flights) for b in flights[i + 1:]),
                     default=math.inf)
    return ReturnPlan(routes, refused, float(separation), time.perf_counter() - t0)


def _landing_here(here: np.ndarray, world: World) -> Route:
    """A vehicle that lands where it stopped (LAND: straight down), as a route."""
    t, z = descent(world.model, float(here[2]))
    positions = np.column_stack([np.broadcast_to(here[:2], (len(t), 2)), z])
    return Route(points=here[None], holds_s=np.zeros(1), land=np.append(here[:2], 0.0),
                 layer_m=float(here[2]), clearance_m=math.nan, times=t, positions=positions)


def _route(here: np.ndarray, land: np.ndarray, layer: float, world: World,
           keep_out: tuple[KeepOut, ...], roadmap: np.ndarray | None = None
           ) -> tuple[Route | None, str]:
    """One vehicle's route and its predicted flight (no wait), or None and why."""
    kept = world.clearance_m
    centres = np.vstack([np.asarray(world.centres, float).reshape(-1, 2)]
                        + [np.asarray(k.centre, float)[None, :2] for k in keep_out])
    # the distance every point of the flown path keeps from each centre; a keep-out is
    # kept as it is (its "own" radius is what is left after the clearance, maybe < 0)
    grown = np.concatenate([np.asarray(world.radii, float) + kept,
                            [k.radius_m for k in keep_out]])
    # where it is now it may stay: an obstacle whose kept clearance it is inside (or the
    # keep-out of the vehicle that left) may come INSIDE_MARGIN_M closer than that
    reach = np.hypot(*(centres - here[:2]).T) - INSIDE_MARGIN_M
    grown = np.where(grown > reach, np.maximum(reach, 0.0), grown)
    own = grown - kept
    if np.any(np.hypot(*(centres - land[:2]).T) <= grown):
        return None, "its landing point is within the clearance of an obstacle"
    start, goal = np.array([*here[:2], layer]), np.array([*land[:2], layer])
    problem = PlanningProblem(start=start, goal=goal, offsets=np.zeros((1, 3)),
                              centres=centres, radii=grown, h_min=world.band[0],
                              h_max=world.band[1], area_lower=np.asarray(world.area_lower),
                              area_upper=np.asarray(world.area_upper), waypoints=1,
                              weights=np.ones(3))
    waypoints = None
    if roadmap is not None and len(centres) >= ROADMAP_FROM:
        where, where_own = problem, own
        waypoints = _through_roadmap(problem, roadmap)
    if waypoints is None:
        # the shortest route, among thousands of trees planned among those it can reach
        # (the planner's leg window: exact for the shortest route)
        window = leg_window(problem, count=1,
                            routes=lambda p, count: shortest_routes(p, count=count))
        if window.routes is None:
            where, where_own, found = problem, own, shortest_route(problem)
        else:
            where, where_own = window.problem, own[window.kept]
            found = window.routes[0] if window.routes else None
        if found is None:
            return None, "no way home around the obstacles"
        waypoints = _waypoints(where, found)
    path = np.vstack([here, start, waypoints, goal])
    fixed = np.zeros(len(path), bool)
    fixed[[0, 1, -1]] = True
    kept_path = keep_clearance(replace(where, start=here, waypoints=len(path) - 2), path,
                               model=world.model, obstacle_radii=where_own, clearance_m=kept,
                               fixed=fixed)
    clearance = math.inf
    if len(own):  # judged against every obstacle (a corner moved may leave the window)
        d, _ = nearest_samples(kept_path.prediction.positions[0, :, :2], centres)
        clearance = float((d - own).min())
    if clearance < kept - 1e-6:
        return None, (f"its predicted flown path home comes {clearance:.2f} m from an "
                      f"obstacle (clearance {kept:g} m)")
    route = Route(points=kept_path.centroid, holds_s=kept_path.holds_s, land=land,
                  layer_m=layer, clearance_m=clearance, times=np.zeros(0),
                  positions=np.zeros((0, 3)))
    return _flown(route, world, kept_path.prediction), ""


ROADMAP_FROM = 1000
"""Obstacles from which a vehicle's way home is first sought through the points of its own
planned path (:func:`_through_roadmap`) rather than on the tangent graph, whose
candidates grow with the square of the obstacles (an orchard of thousands of trees)."""


def _through_roadmap(problem: PlanningProblem, roadmap: np.ndarray) -> np.ndarray | None:
    """Waypoints ``(m, 3)`` at the problem's altitude from its start to its goal through
    the points of ``roadmap`` ``(P, 3)`` (the vehicle's planned path: each of its points
    kept clear of every obstacle by the plan), every straight link between two of them
    that enters no grown obstacle (all links tested at once, through the obstacles' grid)
    a road, the shortest chain of roads found by Dijkstra; None when no chain joins them.
    Not the shortest way home, a safe one found in milliseconds among thousands of
    trees: along an orchard's aisle to its end, along the headland, home."""
    start, goal = problem.start[:2], problem.goal[:2]
    nodes = np.vstack([start, np.asarray(roadmap, float)[:, :2], goal])
    n = len(nodes)
    i, j = np.triu_indices(n, 1)
    discs = Discs(problem.centres, problem.radii, np.arange(len(problem.radii)),
                  np.zeros(len(problem.radii), int))
    clear = segments_clear(nodes[i], nodes[j], discs)
    inside = _in_rectangle(nodes, *centroid_rectangle(problem))
    ok = clear & inside[i] & inside[j]
    weight = np.full((n, n), np.inf)
    length = np.hypot(*(nodes[i] - nodes[j]).T)
    weight[i[ok], j[ok]] = weight[j[ok], i[ok]] = length[ok]
    dist = np.full(n, np.inf)
    prev = np.full(n, -1)
    done = np.zeros(n, bool)
    dist[0] = 0.0
    while True:  # Dijkstra on the dense matrix: n is a few hundred
        u = int(np.argmin(np.where(done, np.inf, dist)))
        if done[u] or not np.isfinite(dist[u]) or u == n - 1:
            break
        done[u] = True
        better = dist[u] + weight[u] < dist
        dist[better], prev[better] = dist[u] + weight[u][better], u
    if not np.isfinite(dist[-1]):
        return None
    chain, k = [], int(prev[-1])
    while k > 0:
        chain.append(k)
        k = int(prev[k])
    points = nodes[chain[::-1]]
    return np.column_stack([points, np.full(len(points), problem.start[2])])


def _waypoints(problem: PlanningProblem, route) -> np.ndarray:
    """The fewest waypoints ``(m, 3)`` of a clear chain within :data:`ROUTE_SLACK` of the
    route (none where the straight line is clear)."""
    if all(arc is None for arc in route.arcs) and len(route.nodes) == 2:
        return np.zeros((0, 3))
    chains = RouteChains(problem, route)
    lengths = chains.lengths(MAX_WAYPOINTS)
    within = np.flatnonzero(lengths <= (1 + ROUTE_SLACK) * route.length)
    m = int(within[0]) + 1 if len(within) else int(np.argmin(lengths)) + 1
    polygon, _clear = chains.polygon(m)  # not clear: the prediction below refuses it
    return polygon


def _flown(route: Route, world: World, prediction=None) -> Route:
    """``route`` with its predicted flight on the return's clock: the flight to above its
    landing point (``prediction``, or flown now with its holds), then NAV_LAND's
    descent, then standing there."""
    if prediction is None:
        prediction = predict(route.points[None], model=world.model,
                             centres=np.zeros((0, 2)), radii=np.zeros(0),
                             holds_s=route.holds_s)
    t_air, p_air = prediction.times, prediction.positions[0]
    t_down, z_down = descent(world.model, float(route.points[-1, 2]))
    down = np.column_stack([np.broadcast_to(route.land[:2], (len(t_down), 2)), z_down])
    times = np.concatenate([t_air, t_air[-1] + t_down[1:]])
    positions = np.vstack([p_air, down[1:]])
    return replace(route, times=times, positions=positions)


def _at(route: Route, times: np.ndarray) -> np.ndarray:
    """Where ``route``'s vehicle is at ``times`` (on the ground at its end after)."""
    idx = np.clip(np.searchsorted(route.times, times, side="right") - 1, 0,
                  len(route.times) - 1)
    return route.positions[idx]


def _closest(a: Route, b: Route, pair_error_m: float) -> float:
    """The smallest true distance between two predicted flights at the same instant."""
    t = np.union1d(a.times, b.times)
    d = _at(a, t) - _at(b, t)
    return float(true_distance(np.hypot(d[:, 0], d[:, 1]), d[:, 2], pair_error_m).min())


def _in_turn(route: Route, planned: dict[int, Route], world: World
             ) -> tuple[Route | None, str]:
    """``route`` with the shortest wait on its layer that keeps ``min_separation`` from
    every route planned before it, or None and why."""
    need = world.min_separation_m
    for wait in range(0, MAX_WAIT_S + 1, WAIT_STEP_S):
        trial = route
        if wait:
            holds = route.holds_s.copy()
            holds[1] = wait
            trial = _flown(replace(route, holds_s=holds), world)
        worst = min((_closest(trial, other, world.pair_error_m) for other in planned.values()),
                    default=math.inf)
        if worst >= need - 1e-9:
            return trial, ""
    return None, (f"no wait of up to {MAX_WAIT_S} s on its layer keeps {need:g} m from the "
                  "others' routes home")
