"""Seed waypoints for the seeded planner: clear ``m``-waypoint polygons near short routes.

A route (:mod:`.geometric`) is a smooth curve of tangent segments and arcs; a plan has
``m`` waypoints joined by straight legs. :func:`route_waypoints` finds the shortest chain
of at most ``m`` vertices near the route whose legs all stay clear, and
:func:`seed_waypoints` does so for the shortest route and its alternatives.
All arrays are metres ENU; angles in radians, counter-clockwise from east.
"""

from __future__ import annotations

import math

import numpy as np

from .discs import Discs, centroid_rectangle
from .geometric import Arc, Route, shortest_routes, straighter_routes
from .problem import PlanningProblem
from .tangents import segments_clear


def _arc_vertices(arc: Arc, radius: float, count: int) -> np.ndarray:
    """``count`` vertices of the polygon circumscribed about the arc, ``(count, 2)``
    relative to the disc centre: its sides are tangent to the circle of ``radius``."""
    half = abs(arc.sweep) / (2 * count)
    angles = arc.start + arc.sweep * (2 * np.arange(count) + 1) / (2 * count)
    return radius / math.cos(half) * np.column_stack([np.cos(angles), np.sin(angles)])


def _excess(radius: float, sweep: float, count: int) -> float:
    """Extra length of ``count`` circumscribed sides over the arc itself."""
    if count == 0:
        return math.inf
    half = abs(sweep) / (2 * count)
    if half >= 0.5 * math.pi - 1e-3:
        return math.inf
    return radius * (2 * count * math.tan(half) - abs(sweep))


def _allocated_polygon(route: Route, waypoints: int, margin: float) -> np.ndarray:
    """Fallback of :func:`route_waypoints` when no clear polygon of ``m`` vertices follows
    the route: each arc gets vertices of a polygon circumscribed about it (radius +
    ``margin``), each added vertex to the arc whose excess length it cuts most; with more
    arcs than waypoints the widest arcs are kept and the others' corners cut (the seed
    is then infeasible and left to the optimizer). Horizontal ``(m, 2)``."""
    m = waypoints
    arcs = [(i, a) for i, a in enumerate(route.arcs) if a is not None and abs(a.sweep) > 1e-9]
    if not arcs:
        return _resample(route.polyline(), m)
    arcs.sort(key=lambda ia: -abs(ia[1].sweep))
    arcs = arcs[:m]
    radii = [float(route.discs.radii[a.disc]) + margin for _, a in arcs]
    counts = [1] * len(arcs)
    for _ in range(m - len(arcs)):
        gains = [
            _excess(r, a.sweep, k) - _excess(r, a.sweep, k + 1)
            for (_, a), r, k in zip(arcs, radii, counts)
        ]
        gains = [g if not math.isnan(g) else math.inf for g in gains]
        counts[int(np.argmax(gains))] += 1
    pieces = sorted(zip(arcs, radii, counts), key=lambda x: x[0][0])
    return np.vstack([
        route.discs.centres[a.disc] + _arc_vertices(a, r, k) for (_, a), r, k in pieces
    ])


_ARC_STEP = 0.15
"""Radians of arc per candidate vertex when following a disc closely."""
_APEX_SPAN = 4
"""A candidate vertex may cut across up to this many consecutive arcs of the route."""


def _motion(angle: float, sweep: float) -> np.ndarray:
    """Direction of travel on a circle at ``angle`` when sweeping with ``sweep``'s sign."""
    sign = 1.0 if sweep > 0 else -1.0
    return sign * np.array([-math.sin(angle), math.cos(angle)])


def _candidates(route: Route, margin: float) -> tuple[np.ndarray, np.ndarray]:
    """Candidate polygon vertices around ``route`` and their position along it.

    Start and goal; for every arc, vertices of polygons circumscribed about the disc
    widened by ``margin`` (one per ``_ARC_STEP`` radians, and with one or two vertices for
    the whole arc), so that following them stays clear; and "apexes": where the line
    entering one arc meets the line leaving an arc up to ``_APEX_SPAN`` arcs later, one
    vertex that cuts several bends when the gap allows.
    Returns points ``(P, 2)`` and keys ``(P,)`` (metres along the route).
    """
    points, keys = [route.nodes[0]], [-1.0]
    ends = []  # per arc: entry point/direction, exit point/direction, keys
    along = 0.0
    for i, arc in enumerate(route.arcs):
        a, b = route.nodes[i], route.nodes[i + 1]
        if arc is None:
            along += float(np.hypot(*(b - a)))
            continue
        c = route.discs.centres[arc.disc]
        r = float(route.discs.radii[arc.disc])
        big = r + margin
        dense = max(1, math.ceil(abs(arc.sweep) / _ARC_STEP))
        for count in sorted({1, 2, dense}):  # coarse polygons too: fewer vertices per arc
            if abs(arc.sweep) / (2 * count) < 0.5 * math.pi - 1e-3:
                points.extend(c + _arc_vertices(arc, big, count))
                keys.extend(
                    along + r * abs(arc.sweep) * (2 * np.arange(count) + 1) / (2 * count))
        end_angle = arc.start + arc.sweep
        ends.append((c + big * np.array([math.cos(arc.start), math.sin(arc.start)]),
                     _motion(arc.start, arc.sweep),
                     c + big * np.array([math.cos(end_angle), math.sin(end_angle)]),
                     _motion(end_angle, arc.sweep), along, along + r * abs(arc.sweep)))
        along += r * abs(arc.sweep)
    for i in range(len(ends)):
        p_in, d_in = ends[i][0], ends[i][1]
        for j in range(i + 1, min(i + _APEX_SPAN, len(ends))):
            p_out, d_out = ends[j][2], ends[j][3]
            # p_in + t d_in = p_out - u d_out, with t, u >= 0
            matrix = np.column_stack([d_in, d_out])
            if abs(np.linalg.det(matrix)) < 1e-9:
                continue
            t, u = np.linalg.solve(matrix, p_out - p_in)
            if t >= 0 and u >= 0:
                points.append(p_in + t * d_in)
                keys.append(0.5 * (ends[i][4] + ends[j][5]))
    points.append(route.nodes[-1])
    keys.append(along + 1.0)
    return np.array(points), np.array(keys)


class _Layers:
    """Shortest chains from point 0 to the last over ``clear`` forward links ``(P, P)``,
    one layer per number of links, extended on demand (a dynamic programme over links:
    layer ``L`` holds the shortest chain of exactly ``L`` links to every point)."""

    def __init__(self, points: np.ndarray, clear: np.ndarray) -> None:
        P = len(points)
        length = np.hypot(*(points[None, :, :] - points[:, None, :]).transpose(2, 0, 1))
        self.weight = np.where(clear, length, np.inf)
        self.best = np.full(P, np.inf)
        self.best[0] = 0.0
        self.parents: list[np.ndarray] = []
        self.finals: list[float] = []  # length of the shortest chain of L + 1 links

    def extend(self, links: int) -> None:
        """Compute the layers up to ``links`` links."""
        P = len(self.best)
        while len(self.finals) < links:
            total = self.best[:, None] + self.weight
            parent = np.argmin(total, axis=0)
            self.best = total[parent, np.arange(P)]
            self.parents.append(parent)
            self.finals.append(float(self.best[-1]))

    def chain(self, max_links: int) -> list[int] | None:
        """Indices of the shortest chain of at most ``max_links`` links, or ``None``."""
        self.extend(max_links)
        finals = self.finals[:max_links]
        links = int(np.argmin(finals))
        if not np.isfinite(finals[links]):
            return None
        P = len(self.best)
        chain = [P - 1]
        for layer in range(links, -1, -1):
            chain.append(int(self.parents[layer][chain[-1]]))
        return chain[::-1]


def _fewest_metres_polygon(points, clear, max_links: int) -> list[int] | None:
    """Indices of the shortest chain from point 0 to the last over ``clear`` forward
    links ``(P, P)`` with at most ``max_links`` links; ``None`` when there is none."""
    return _Layers(points, clear).chain(max_links)


def _pad(vertices: np.ndarray, count: int) -> np.ndarray:
    """``count`` interior vertices: the chain's own plus points spread evenly along its
    longest legs (collinear, so the length and the clearance do not change)."""
    legs = np.diff(vertices, axis=0)
    lengths = np.hypot(*legs.T)
    extra = np.zeros(len(legs), int)
    for _ in range(count - (len(vertices) - 2)):
        extra[int(np.argmax(lengths / (extra + 1)))] += 1
    out = []
    for k, leg in enumerate(legs):
        if k:
            out.append(vertices[k])
        for q in range(1, extra[k] + 1):
            out.append(vertices[k] + leg * q / (extra[k] + 1))
    return np.array(out).reshape(-1, 2)


def route_waypoints(problem: PlanningProblem, route: Route, waypoints: int, *,
                    margin: float | None = None) -> np.ndarray:
    """See :func:`_route_polygon` (which also says whether the polygon is clear)."""
    return _route_polygon(problem, route, waypoints, margin=margin)[0]


def _route_polygon(problem: PlanningProblem, route: Route, waypoints: int, *,
                   margin: float | None = None) -> tuple[np.ndarray, bool]:
    """``route`` as ``waypoints`` centroid waypoints ``(m, 3)``: a clear polygon near it.

    The shortest chain of at most ``m`` vertices, from start to goal, over candidate
    vertices around the route (:func:`_candidates`) whose every leg stays clear of the
    discs widened by ``margin / 2`` and inside the area: with as many waypoints as the
    route has bends it hugs the route (within ``margin``); with fewer it cuts across
    bends where the gaps allow, still clear. Unused waypoints are spread along the
    longest legs. When no such chain exists the arcs' corners are cut
    (:func:`_allocated_polygon`) and the optimizer is left to repair the seed
    (:func:`seed_waypoints` then also tries routes with fewer legs).
    Altitudes go linearly from start to goal along the polygon, inside the bounds.
    Returns the waypoints ``(m, 3)`` and whether the clear chain was found.
    """
    return RouteChains(problem, route, margin=margin).polygon(waypoints)


class RouteChains:
    """The clear polygons near one route, for any number of waypoints (see
    :func:`_route_polygon`): the candidate vertices and their clear links are computed
    once; :meth:`polygon` and :meth:`lengths` extend one dynamic programme over the
    number of links as far as they are asked."""

    def __init__(self, problem: PlanningProblem, route: Route, *,
                 margin: float | None = None) -> None:
        self.problem, self.route = problem, route
        self.margin = seed_margin(problem) if margin is None else margin
        points, keys = _candidates(route, self.margin)
        points = points[np.argsort(keys, kind="stable")]
        rect_lo, rect_hi = centroid_rectangle(problem)
        widened = Discs(route.discs.centres, route.discs.radii + 0.5 * self.margin,
                        route.discs.cylinder, route.discs.uav)
        # A vertex beyond the area's side (a route along the side) is moved onto it; the
        # legs' clearance decides whether it is usable.
        self.points = np.clip(points, rect_lo, rect_hi)
        P = len(self.points)
        i, j = np.triu_indices(P, 1)
        clear = np.zeros((P, P), bool)
        clear[i, j] = segments_clear(self.points[i], self.points[j], widened)
        self._layers = _Layers(self.points, clear)

    @property
    def candidates(self) -> int:
        return len(self.points)

    def lengths(self, waypoints: int) -> np.ndarray:
        """``(waypoints,)``: entry ``m - 1`` is the 3D length (metres, altitude linear from
        start to goal) of the shortest clear chain with at most ``m`` waypoints, ``inf``
        where there is none."""
        self._layers.extend(waypoints + 1)
        flat = np.minimum.accumulate(np.array(self._layers.finals[: waypoints + 1]))[1:]
        dz = float(self.problem.goal[2] - self.problem.start[2])
        return np.hypot(flat, dz)

    def polygon(self, waypoints: int) -> tuple[np.ndarray, bool]:
        """Waypoints ``(m, 3)`` and whether they follow a clear chain (see
        :func:`_route_polygon`)."""
        m = waypoints
        problem, start, goal = self.problem, self.problem.start, self.problem.goal
        lower, upper = _bounds(problem, m)
        chain = self._layers.chain(m + 1)
        if chain is None:
            xy = _allocated_polygon(self.route, m, self.margin)
        else:
            xy = _pad(self.points[chain], m)
        full = np.vstack([start[:2], xy, goal[:2]])
        along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(full, axis=0).T))])
        frac = along[1:-1] / max(along[-1], 1e-12)
        z = start[2] + frac * (goal[2] - start[2])
        return np.clip(np.column_stack([xy, z]), lower, upper), chain is not None


def _bounds(problem: PlanningProblem, waypoints: int) -> tuple[np.ndarray, np.ndarray]:
    """The problem's bounds ``(m, 3)`` for ``waypoints`` waypoints (the same per row)."""
    lower, upper = problem.bounds()
    return (np.broadcast_to(lower[:1], (waypoints, 3)),
            np.broadcast_to(upper[:1], (waypoints, 3)))


def _resample(line: np.ndarray, count: int) -> np.ndarray:
    """``count`` points evenly spaced strictly inside the polyline ``(P, 2)``."""
    along = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(line, axis=0).T))])
    s = along[-1] * np.arange(1, count + 1) / (count + 1)
    return np.column_stack([np.interp(s, along, line[:, 0]), np.interp(s, along, line[:, 1])])


STRAIGHTER_SHARES = (0.02, 0.05, 0.1, 0.2, 0.5)
"""Extra metres per straight leg, as shares of the shortest route's length, tried in turn
when no route has a clear ``m``-waypoint polygon (it bends too often)."""


def _straighter_polygon(problem: PlanningProblem, length: float) -> np.ndarray | None:
    """A clear ``m``-waypoint polygon near a route with fewer legs, or ``None``.

    The routes here run around discs already widened by :func:`seed_margin`, so their
    long legs, which graze other discs, stay clear when followed exactly; each straight leg
    costs ``share * length`` extra, the smallest share that gives a clear polygon wins.
    """
    margin = seed_margin(problem)
    for route in straighter_routes(problem, [s * length for s in STRAIGHTER_SHARES],
                                   margin=margin):
        polygon, clear = _route_polygon(problem, route, problem.waypoints, margin=1e-6)
        if clear:
            return polygon
    return None


def seed_margin(problem: PlanningProblem) -> float:
    """Radius margin for seed routes (metres): feasibility needs *more* than the radius."""
    scale = float(problem.radii.max()) if len(problem.radii) else 1.0
    return 1e-3 * scale + 1e-3


def seed_waypoints(
    problem: PlanningProblem, *, count: int = 4, routes: list[Route] | None = None,
    chains: list[RouteChains] | None = None,
) -> np.ndarray:
    """Waypoints ``(R, m, 3)`` near up to ``count`` short routes (or the given
    ``routes``, or the routes of the given ``chains``), kept :func:`seed_margin` off the
    discs (:func:`route_waypoints`): the clear ones first, shortest route first among
    equals; ``(0, m, 3)`` when no route exists."""
    m = problem.waypoints
    if chains is None:
        if routes is None:
            routes = shortest_routes(problem, count=count)
        chains = [RouteChains(problem, r) for r in routes]
    if not chains:
        return np.zeros((0, m, 3))
    polygons = [c.polygon(m) for c in chains]
    if not any(clear for _, clear in polygons):
        polygon = _straighter_polygon(problem, chains[0].route.length)
        if polygon is not None:
            polygons.insert(0, (polygon, True))
    # clear polygons first (stable: shortest route first among them)
    order = sorted(range(len(polygons)), key=lambda i: not polygons[i][1])
    return np.stack([polygons[i][0] for i in order])
