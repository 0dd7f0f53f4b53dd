"""Shortest horizontal routes around the formation-inflated obstacles: bound and seeds.

The centroid's obstacles are one disc per UAV and cylinder in the area shrunk by the
formation (:mod:`.discs`). The shortest centroid path in that free space (a rectangle
minus discs) is a taut string: straight segments tangent to the discs and arcs along
them, never bending at the rectangle's sides or where two discs cross (those corners
point away from the free space). It is found exactly by Dijkstra on the tangent
visibility graph: start, goal, the tangent points of every start/goal-to-disc tangent
and of every inner and outer bitangent between two discs, joined by the tangent segments
that enter no disc and stay in the rectangle (:mod:`.tangents`), and by the arcs between
neighbouring tangent points on a disc that enter no other disc and stay in the rectangle.

- :func:`shortest_route` -> :class:`Route` or ``None`` when the formation cannot pass;
- :func:`shortest_routes` -> the shortest and a few alternative routes;
- :func:`lower_bound` -> the shortest length any feasible centroid path can have.

:mod:`.seeds` turns routes into waypoints for the seeded planner.

All arrays are metres ENU; angles in radians, counter-clockwise from east.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from ..compiling import cheap
from .discs import (
    TWO_PI,
    Discs,
    _forbidden_arrays,
    _forbidden_intervals,
    centroid_rectangle,
    formation_discs,
)
from .problem import PlanningProblem
from .tangents import tangent_segments

_ALTERNATIVE_TRIES = 400  # graph nodes tried for alternative routes


@dataclass(frozen=True)
class Arc:
    """An arc of disc ``disc`` from angle ``start`` sweeping ``sweep`` (signed, ccw > 0)."""

    disc: int
    start: float
    sweep: float


@dataclass(frozen=True)
class Route:
    """A horizontal centroid route from start to goal.

    ``length``: metres. ``nodes``: ``(Q, 2)`` the graph nodes passed (start, tangent
    points, goal). ``arcs``: for each of the ``Q-1`` legs, the :class:`Arc` followed or
    ``None`` for a straight segment. ``discs``: the discs the route was computed for.
    """

    length: float
    nodes: np.ndarray
    arcs: tuple[Arc | None, ...]
    discs: Discs

    def polyline(self, *, step_rad: float = 0.05) -> np.ndarray:
        """The route as a dense polyline ``(P, 2)``, arcs sampled every ``step_rad``."""
        points = [self.nodes[0]]
        for i, arc in enumerate(self.arcs):
            if arc is not None:
                c, r = self.discs.centres[arc.disc], self.discs.radii[arc.disc]
                count = max(int(abs(arc.sweep) / step_rad), 1)
                angles = arc.start + arc.sweep * np.arange(1, count) / count
                points.extend(c + r * np.column_stack([np.cos(angles), np.sin(angles)]))
            points.append(self.nodes[i + 1])
        return np.array(points)



ARRAY_GRAPH_FROM = 20_000
"""Graph nodes from which the tangent graph is held in arrays and searched compiled
(:mod:`._geometric_jit`: the same edges in the same order, the same heap), not in lists
of Python tuples (an orchard's way back across its rows: 100,000 nodes, 4.7 million heap
operations)."""
ARRAY_GRAPH_LOADED_FROM = 500
"""Graph nodes from which the graph is held in arrays and searched compiled when numba is
loaded already and the search cached (:func:`..compiling.cheap`): the same search, so the
same routes."""



def _graph_loops():
    from ._geometric_jit import arcs_free, dijkstra

    return arcs_free, dijkstra



def _arc_free(start: float, sweep: float, intervals) -> bool:
    """Whether the ccw arc ``(start, start + sweep)`` misses every forbidden interval."""
    for centre, half in intervals:
        if half >= math.pi:
            return False
        s = (centre - half - start) % TWO_PI
        if s < sweep - 1e-9 or s + 2 * half > TWO_PI + 1e-9:
            return False
    return True



class _Graph:
    """The tangent visibility graph of one problem (built once, searched twice)."""

    def __init__(self, problem: PlanningProblem, discs: Discs) -> None:
        lower, upper = centroid_rectangle(problem)
        self.discs = discs
        start, goal = problem.start[:2].astype(float), problem.goal[:2].astype(float)
        t_disc, t_angle, t_point, seg_p, seg_q, p, q = tangent_segments(discs, start, goal,
                                                                        lower, upper)
        self._build(start, goal, discs, lower, upper, t_disc, t_angle, seg_p, seg_q, p, q,
                    t_point)

    def _build(self, start, goal, discs, lower, upper, t_disc, t_angle, seg_p, seg_q, p, q,
               t_point) -> None:
        """The graph from the clear segments (keys into the tangent points ``t_disc``,
        ``t_angle``, ``t_point``; -1 start, -2 goal) and the arcs between their ends."""
        # Nodes: 0 start, 1 goal, then every tangent point used by a valid segment.
        mark = np.zeros(len(t_disc), bool)  # the keys used, sorted (np.unique: slower)
        mark[seg_p[seg_p >= 0]] = True
        mark[seg_q[seg_q >= 0]] = True
        used = np.flatnonzero(mark)
        node_of = np.full(len(t_disc) + 2, -1)
        node_of[used] = 2 + np.arange(len(used))
        node_of[-1], node_of[-2] = 0, 1  # keys -1 and -2 index the end of the array
        self.points = np.vstack([start, goal, t_point[used]]) if len(used) else np.vstack(
            [start, goal])
        self.node_disc = np.concatenate([[-1, -1], t_disc[used]]).astype(int)
        self.node_angle = np.concatenate([[0.0, 0.0], t_angle[used] % TWO_PI])
        lengths = np.hypot(*(q - p).T)
        a_seg, b_seg = node_of[seg_p], node_of[seg_q]
        # Arcs between neighbouring tangent points on each disc: the nodes of each disc in
        # angle order, each to the next and the last to the first
        order = np.lexsort((self.node_angle, self.node_disc))
        order = order[self.node_disc[order] >= 0]
        groups = np.flatnonzero(np.diff(self.node_disc[order])) + 1
        self._csr = None
        if len(self.points) >= ARRAY_GRAPH_FROM or (
                len(self.points) >= ARRAY_GRAPH_LOADED_FROM and cheap(_graph_loops)):
            self.edges = None
            self._arrays(a_seg, b_seg, lengths, order, groups,
                         _forbidden_arrays(discs, lower, upper), discs)
            return
        forbidden = _forbidden_intervals(discs, lower, upper)
        edges: list[list[tuple[int, float, Arc | None]]] = [[] for _ in range(len(self.points))]
        for a, b, w in zip(a_seg, b_seg, lengths):
            edges[a].append((b, float(w), None))
            edges[b].append((a, float(w), None))
        for on in np.split(order, groups):
            if len(on) < 2:
                continue
            disc = int(self.node_disc[on[0]])
            r = float(discs.radii[disc])
            for a, b in zip(on, np.roll(on, -1)):
                sweep = (self.node_angle[b] - self.node_angle[a]) % TWO_PI
                if sweep <= 1e-12:  # the same point twice: a zero-length link
                    edges[a].append((int(b), 0.0, None))
                    edges[b].append((int(a), 0.0, None))
                    continue
                if not _arc_free(float(self.node_angle[a]), sweep, forbidden[disc]):
                    continue
                start_a = float(self.node_angle[a])
                edges[a].append((int(b), r * sweep, Arc(int(disc), start_a, sweep)))
                edges[b].append((int(a), r * sweep, Arc(int(disc), start_a + sweep, -sweep)))
        self.edges = edges

    def _arrays(self, a_seg, b_seg, lengths, order, groups, forbidden, discs) -> None:
        """The same edges as the lists of :meth:`_build`, in the same order per node, as
        arrays (CSR) for the compiled search (:data:`ARRAY_GRAPH_FROM`); ``forbidden``:
        :func:`_forbidden_arrays`."""
        from ._geometric_jit import arcs_free

        # each node's neighbour in angle order on its disc (groups of 2 or more)
        nxt = np.roll(order, -1)
        begin = np.concatenate([[0], groups])
        end = np.concatenate([groups, [len(order)]])
        nxt[end - 1] = order[begin]  # the last of a disc to its first
        size = np.repeat(end - begin, end - begin)
        a_arc, b_arc = order[size >= 2], nxt[size >= 2]
        disc = self.node_disc[a_arc]
        start_a = self.node_angle[a_arc]
        sweep = (self.node_angle[b_arc] - start_a) % TWO_PI
        zero = sweep <= 1e-12
        first, iv_centre, iv_half = forbidden
        free = arcs_free(start_a, sweep, first[disc], first[disc + 1], iv_centre, iv_half)
        keep = zero | free
        a_arc, b_arc, disc, start_a = a_arc[keep], b_arc[keep], disc[keep], start_a[keep]
        sweep, zero = sweep[keep], zero[keep]
        weight_arc = np.where(zero, 0.0, discs.radii[disc] * sweep)
        # directed edges in the lists' order: a->b then b->a, the segments, then the arcs
        src = np.column_stack([np.concatenate([a_seg, a_arc]),
                               np.concatenate([b_seg, b_arc])]).ravel()
        dst = np.column_stack([np.concatenate([b_seg, b_arc]),
                               np.concatenate([a_seg, a_arc])]).ravel()
        w = np.repeat(np.concatenate([lengths, weight_arc]), 2)
        is_arc = np.repeat(np.concatenate([np.zeros(len(a_seg), bool), ~zero]), 2)
        arc_disc = np.repeat(np.concatenate([np.full(len(a_seg), -1), disc]), 2)
        arc_start = np.column_stack([np.concatenate([np.zeros(len(a_seg)), start_a]),
                                     np.concatenate([np.zeros(len(a_seg)), start_a + sweep])
                                     ]).ravel()
        arc_sweep = np.column_stack([np.concatenate([np.zeros(len(a_seg)), sweep]),
                                     np.concatenate([np.zeros(len(a_seg)), -sweep])]).ravel()
        by = np.argsort(src, kind="stable")
        indptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=len(self.points)))])
        self._csr = (indptr.astype(np.int64), dst[by].astype(np.int64), w[by], ~is_arc[by])
        self._arc = (is_arc[by], arc_disc[by], arc_start[by], arc_sweep[by])

    def dijkstra(self, source: int, *, leg_penalty: float = 0.0
                 ) -> tuple[np.ndarray, np.ndarray, list]:
        """Distances, predecessors and arcs from ``source``; ``leg_penalty`` metres are
        added to every straight segment (routes with fewer legs)."""
        if self._csr is not None:
            from ._geometric_jit import dijkstra

            dist, prev, edge = dijkstra(*self._csr, source, float(leg_penalty))
            return dist, prev, _Via(edge, *self._arc)
        n = len(self.points)
        dist = np.full(n, np.inf)
        prev = np.full(n, -1)
        via: list[Arc | None] = [None] * n
        dist[source] = 0.0
        heap = [(0.0, source)]
        done = np.zeros(n, bool)
        while heap:
            d, u = heapq.heappop(heap)
            if done[u]:
                continue
            done[u] = True
            for v, w, arc in self.edges[u]:
                nd = d + w + (leg_penalty if arc is None else 0.0)
                if nd < dist[v] - 1e-12:
                    dist[v], prev[v], via[v] = nd, u, arc
                    heapq.heappush(heap, (nd, v))
        return dist, prev, via

    def route(self, nodes: list[int], arcs: list[Arc | None], length: float) -> Route:
        return Route(float(length), self.points[nodes], tuple(arcs), self.discs)


class _Via:
    """Per node, the :class:`Arc` it was reached along, or None (a straight segment): the
    compiled search's edges (:meth:`_Graph.dijkstra`) read as the lists' ``via``."""

    def __init__(self, edge, is_arc, disc, start, sweep) -> None:
        self.edge, self.is_arc, self.disc, self.start, self.sweep = (edge, is_arc, disc, start,
                                                                     sweep)

    def __getitem__(self, node: int) -> Arc | None:
        e = self.edge[node]
        if e < 0 or not self.is_arc[e]:
            return None
        return Arc(int(self.disc[e]), float(self.start[e]), float(self.sweep[e]))


def _walk(prev, via, end: int) -> tuple[list[int], list[Arc | None]]:
    """Nodes from the search's source to ``end`` and the arcs of the legs."""
    nodes, arcs = [end], []
    while prev[nodes[-1]] >= 0:
        arcs.append(via[nodes[-1]])
        nodes.append(int(prev[nodes[-1]]))
    return nodes[::-1], arcs[::-1]


def _reverse(arc: Arc | None) -> Arc | None:
    return None if arc is None else Arc(arc.disc, arc.start + arc.sweep, -arc.sweep)


def shortest_routes(
    problem: PlanningProblem, *, count: int = 1, margin: float = 0.0, spread: float = 0.25
) -> list[Route]:
    """Up to ``count`` short routes, the shortest first; ``[]`` when no route exists.

    The first is the exact shortest route. The others are the shortest routes through
    other graph nodes (start->node->goal, from one search from each end), kept when they
    pass a different sequence of discs and are at most ``1 + spread`` times longer:
    alternatives around the trees for seeding, not a ranked list of all routes.
    """
    graph = _Graph(problem, formation_discs(problem, margin=margin))
    from_start, prev_s, via_s = graph.dijkstra(0)
    if not np.isfinite(from_start[1]):
        return []
    nodes, arcs = _walk(prev_s, via_s, 1)
    routes = [graph.route(nodes, arcs, from_start[1])]
    if count <= 1:
        return routes
    from_goal, prev_g, via_g = graph.dijkstra(1)
    through = from_start + from_goal
    seen = {tuple(graph.node_disc[nodes])}
    for v in np.argsort(through)[:_ALTERNATIVE_TRIES]:
        if len(routes) >= count or through[v] > (1 + spread) * from_start[1]:
            break
        head_nodes, head_arcs = _walk(prev_s, via_s, int(v))
        tail_nodes, tail_arcs = _walk(prev_g, via_g, int(v))
        all_nodes = head_nodes + tail_nodes[::-1][1:]
        key = tuple(graph.node_disc[all_nodes])
        if key in seen:
            continue
        seen.add(key)
        all_arcs = head_arcs + [_reverse(a) for a in tail_arcs[::-1]]
        routes.append(graph.route(all_nodes, all_arcs, through[v]))
    return routes


def straighter_routes(problem: PlanningProblem, penalties, *, margin: float = 0.0):
    """For each penalty (metres), the shortest route when every straight leg costs that
    much more: routes with fewer, longer legs (for seeds with few waypoints). Yields
    :class:`Route` objects (true lengths), or nothing when no route exists."""
    graph = _Graph(problem, formation_discs(problem, margin=margin))
    for penalty in penalties:
        dist, prev, via = graph.dijkstra(0, leg_penalty=penalty)
        if not np.isfinite(dist[1]):
            return
        nodes, arcs = _walk(prev, via, 1)
        points = graph.points[nodes]
        length = sum(
            float(np.hypot(*(points[i + 1] - points[i]))) if arc is None
            else float(graph.discs.radii[arc.disc]) * abs(arc.sweep)
            for i, arc in enumerate(arcs)
        )
        yield graph.route(nodes, arcs, length)


def shortest_route(problem: PlanningProblem, *, margin: float = 0.0) -> Route | None:
    """The shortest horizontal centroid route, or ``None`` when the formation cannot pass."""
    routes = shortest_routes(problem, margin=margin)
    return routes[0] if routes else None


def lower_bound(problem: PlanningProblem, route: Route | None = None) -> float | None:
    """No feasible centroid path is shorter than this (metres); ``None``: no route exists.

    The shortest horizontal route, lifted by the start-goal altitude difference
    (``sqrt(L^2 + dz^2)``, the shortest 3D curve over it; equal to ``L`` when start and
    goal are at one altitude). Feasible paths keep a clearance strictly greater than the
    radii, so they are strictly longer; a plan can only approach the bound.
    """
    route = route if route is not None else shortest_route(problem)
    if route is None:
        return None
    dz = float(problem.goal[2] - problem.start[2])
    return math.hypot(route.length, dz)
