"""Tangent visibility graph: exact lengths by hand, formation inflation, area, no route."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftlbo_mav.planning.discs import formation_discs
from ftlbo_mav.planning.feasibility import violations
from ftlbo_mav.planning.geometric import lower_bound, shortest_route, shortest_routes
from ftlbo_mav.planning.problem import PlanningProblem, problem_from_scenario
from ftlbo_mav.planning.seeds import route_waypoints, seed_waypoints
from ftlbo_mav.scenario import load_scenario

from ..conftest import EXAMPLE


def field(**overrides) -> PlanningProblem:
    values = dict(
        start=np.array([-20.0, 0.0, 4.0]),
        goal=np.array([20.0, 0.0, 4.0]),
        offsets=np.zeros((1, 3)),
        centres=np.array([[0.0, 0.0]]),
        radii=np.array([5.0]),
        h_min=2.0,
        h_max=7.0,
        area_lower=np.array([-30.0, -30.0]),
        area_upper=np.array([30.0, 30.0]),
        waypoints=6,
        weights=np.ones(3),
    )
    values.update(overrides)
    return PlanningProblem(**values)


def around_one_disc(a: float, r: float) -> float:
    """Start and goal at distance a on either side of a disc of radius r."""
    return 2 * math.sqrt(a * a - r * r) + r * (math.pi - 2 * math.acos(r / a))


def outside_all(problem: PlanningProblem, points: np.ndarray) -> bool:
    discs = formation_discs(problem)
    d = np.hypot(*(points[:, None, :] - discs.centres[None]).transpose(2, 0, 1))
    return bool(np.all(d >= discs.radii - 1e-6))


def test_around_one_disc_by_hand():
    problem = field()
    route = shortest_route(problem)
    assert route.length == pytest.approx(around_one_disc(20.0, 5.0), rel=1e-12)
    assert outside_all(problem, route.polyline())


def test_straight_when_nothing_is_in_the_way():
    problem = field(centres=np.array([[0.0, 15.0]]))
    assert lower_bound(problem) == pytest.approx(40.0)
    problem = field(centres=np.zeros((0, 2)), radii=np.zeros(0))
    assert lower_bound(problem) == pytest.approx(40.0)


def test_the_altitude_difference_lifts_the_bound():
    problem = field(goal=np.array([20.0, 0.0, 7.0]))
    assert lower_bound(problem) == pytest.approx(math.hypot(around_one_disc(20.0, 5.0), 3.0))


def test_every_uavs_offset_inflates_the_obstacle():
    # Two UAVs 2 m north and south of the centroid: the centroid must clear a capsule of
    # two discs centred 2 m south and north of the axis. Going north around it is the
    # one-disc detour around the northern disc seen from points 2 m south of its centre.
    offsets = np.array([[0.0, 2.0, 0.0], [0.0, -2.0, 0.0]])
    problem = field(offsets=offsets)
    discs = formation_discs(problem)
    assert sorted(map(tuple, discs.centres)) == [(0.0, -2.0), (0.0, 2.0)]
    route = shortest_route(problem)
    assert route.length > around_one_disc(20.0, 5.0) + 1.0
    assert outside_all(problem, route.polyline())
    # brute-force check of the length: the detour over the top disc
    a = math.hypot(20.0, 2.0)
    tangent = math.sqrt(a * a - 25.0)
    phi = math.atan2(2.0, 20.0)  # start and goal lie phi below the top disc's centre
    arc = math.pi + 2 * phi - 2 * math.acos(5.0 / a)
    assert route.length == pytest.approx(2 * tangent + 5.0 * arc, rel=1e-12)


def test_the_area_keeps_every_uav_inside():
    # A corridor 12 m high; the disc leaves 7 m to the south wall, less north: with UAVs
    # 3 m north and south of the centroid only the south side fits (7 - 3 > 0).
    problem = field(
        centres=np.array([[0.0, 1.0]]), radii=np.array([4.0]),
        area_lower=np.array([-30.0, -10.0]), area_upper=np.array([30.0, 6.0]),
        offsets=np.array([[0.0, 3.0, 0.0], [0.0, -3.0, 0.0]]),
    )
    route = shortest_route(problem)
    assert route is not None
    poly = route.polyline()
    lower, upper = problem.bounds()
    assert np.all(poly >= lower[0, :2] - 1e-9) and np.all(poly <= upper[0, :2] + 1e-9)
    assert poly[:, 1].min() < -1.0  # went south
    # Shrink the corridor: no side fits, no route.
    blocked = field(
        centres=np.array([[0.0, 1.0]]), radii=np.array([4.0]),
        area_lower=np.array([-30.0, -5.0]), area_upper=np.array([30.0, 6.0]),
        offsets=np.array([[0.0, 3.0, 0.0], [0.0, -3.0, 0.0]]),
    )
    assert shortest_route(blocked) is None
    assert lower_bound(blocked) is None


def test_a_row_of_touching_discs_blocks_and_a_gap_lets_through():
    xs = np.arange(-30.0, 31.0, 6.0)
    wall = np.column_stack([np.zeros_like(xs), xs])  # a north-south wall at east = 0
    closed = field(centres=wall, radii=np.full(len(xs), 3.2))
    assert shortest_route(closed) is None
    gap = field(centres=wall[np.abs(xs - 6.0) > 1], radii=np.full(len(xs) - 1, 3.2))
    route = shortest_route(gap)
    assert route is not None and outside_all(gap, route.polyline())


def test_example_bound_routes_and_seeds():
    problem = problem_from_scenario(load_scenario(EXAMPLE), waypoints=10)  # the paper's
    routes = shortest_routes(problem, count=4)
    bound = lower_bound(problem, routes[0])
    straight = float(np.linalg.norm(problem.goal - problem.start))
    assert straight < bound < 1.1 * straight
    assert [r.length for r in routes] == sorted(r.length for r in routes)
    for route in routes:
        assert outside_all(problem, route.polyline())
    seeds = seed_waypoints(problem)
    assert seeds.shape[1:] == (problem.waypoints, 3)
    best = problem.full_paths(seeds[:1])[0]
    assert violations(problem, best) == []  # the shortest seed route is flyable
    length = np.linalg.norm(np.diff(best, axis=0), axis=1).sum()
    assert bound < length < 1.001 * bound


def test_fewer_waypoints_than_bends_still_give_a_clear_seed():
    # Three discs on the straight line: the route bends around each of them, but one
    # waypoint above them all is enough to pass clear.
    problem = field(centres=np.array([[-8.0, 0.0], [0.0, 0.0], [8.0, 0.0]]),
                    radii=np.array([2.0, 2.5, 2.0]), waypoints=1)
    route = shortest_route(problem)
    assert sum(a is not None for a in route.arcs) >= 2
    w = route_waypoints(problem, route, 1)
    path = problem.full_paths(w[None])[0]
    assert violations(problem, path) == []
    length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
    assert route.length < length < 1.05 * route.length
    # with enough waypoints the polygon hugs the route
    many = route_waypoints(problem, route, 12)
    path = problem.full_paths(many[None])[0]
    assert violations(problem, path) == []
    assert np.linalg.norm(np.diff(path, axis=0), axis=1).sum() < 1.002 * route.length


def test_a_route_that_bends_too_often_falls_back_to_a_straighter_one():
    # The shortest route weaves over, under and over three discs: one waypoint cannot
    # follow it, but going under all three with one waypoint is clear.
    problem = field(centres=np.array([[-8.0, 2.5], [0.0, -2.5], [8.0, 2.5]]),
                    radii=np.full(3, 2.8), waypoints=1)
    route = shortest_route(problem)
    weaving = problem.full_paths(route_waypoints(problem, route, 1)[None])[0]
    assert violations(problem, weaving) != []
    seeds = seed_waypoints(problem)
    assert violations(problem, problem.full_paths(seeds[:1])[0]) == []


def grid_shortest(problem: PlanningProblem, step: float) -> float:
    """Length of the shortest path on a grid (16 neighbours) whose every edge is clear and
    inside the area: a feasible path, so never shorter than the true shortest route."""
    import heapq

    from ftlbo_mav.planning.discs import centroid_rectangle
    from ftlbo_mav.planning.tangents import segments_clear

    lo, hi = centroid_rectangle(problem)
    xs = np.arange(lo[0], hi[0] + 1e-9, step)
    ys = np.arange(lo[1], hi[1] + 1e-9, step)
    nodes = np.array([(x, y) for x in xs for y in ys] + [problem.start[:2], problem.goal[:2]])
    start, goal = len(nodes) - 2, len(nodes) - 1
    moves = [(dx, dy) for dx in range(-2, 3) for dy in range(-2, 3)
             if (dx, dy) != (0, 0) and math.gcd(abs(dx), abs(dy)) == 1]
    index = {(i, j): i * len(ys) + j for i in range(len(xs)) for j in range(len(ys))}
    p, q = [], []
    for (i, j), a in index.items():
        for dx, dy in moves:
            b = index.get((i + dx, j + dy))
            if b is not None and a < b:
                p.append(a), q.append(b)
    near = np.hypot(*(nodes[:-2] - problem.start[:2]).T).argsort()[:9]
    near_goal = np.hypot(*(nodes[:-2] - problem.goal[:2]).T).argsort()[:9]
    p += [start] * 9 + [goal] * 9
    q += list(near) + list(near_goal)
    p, q = np.array(p), np.array(q)
    ok = segments_clear(nodes[p], nodes[q], formation_discs(problem))
    edges = [[] for _ in nodes]
    for a, b in zip(p[ok], q[ok]):
        w = float(np.hypot(*(nodes[a] - nodes[b])))
        edges[a].append((b, w))
        edges[b].append((a, w))
    dist = {start: 0.0}
    heap = [(0.0, start)]
    while heap:
        d, u = heapq.heappop(heap)
        if u == goal:
            return d
        if d > dist[u]:
            continue
        for v, w in edges[u]:
            if d + w < dist.get(v, math.inf):
                dist[v] = d + w
                heapq.heappush(heap, (d + w, v))
    return math.inf


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(8))
def test_no_clear_grid_path_is_shorter_than_the_bound(seed):
    rng = np.random.default_rng(seed)
    problem = field(
        centres=rng.uniform([-15, -12], [15, 12], size=(12, 2)),
        radii=rng.uniform(1.0, 3.0, size=12),
        offsets=np.array([[0.0, 1.5, 0.0], [0.0, -1.5, 0.0], [1.0, 0.0, 0.0]]),
        area_lower=np.array([-25.0, -16.0]), area_upper=np.array([25.0, 16.0]),
    )
    discs = formation_discs(problem)
    for end in (problem.start, problem.goal):
        if np.any(np.hypot(*(discs.centres - end[:2]).T) <= discs.radii):
            pytest.skip("a disc covers the start or the goal")
    bound = lower_bound(problem)
    grid = grid_shortest(problem, 0.5)
    if bound is None:
        assert grid == math.inf
    else:
        assert bound <= grid + 1e-9  # a clear path shorter than the bound: a missed gap
        assert grid < 1.05 * bound  # and the bound is not far too low


def triangle_among_trees(seed: int, *, trees: int) -> PlanningProblem:
    """A 100 m x 60 m field of random trees (radius + clearance 1-3 m), none near start
    or goal, three UAVs in a triangle crossing it from west to east."""
    rng = np.random.default_rng(seed)
    centres = rng.uniform([5.0, 5.0], [95.0, 55.0], (trees, 2))
    far = np.minimum(np.hypot(*(centres - [2.0, 30.0]).T), np.hypot(*(centres - [98.0, 30.0]).T))
    return field(start=np.array([2.0, 30.0, 4.0]), goal=np.array([98.0, 30.0, 4.0]),
                 offsets=np.array([[0.0, 1.0, 0.0], [-1.0, -1.0, 0.0], [1.0, -1.0, 0.0]]),
                 centres=centres[far > 8.0], radii=rng.uniform(1.0, 3.0, (far > 8.0).sum()),
                 area_lower=np.array([0.0, 0.0]), area_upper=np.array([100.0, 60.0]))


@pytest.mark.parametrize("penalty", [0.0, 5.0])
def test_the_graph_in_arrays_is_searched_as_the_lists_are(monkeypatch, penalty):
    from ftlbo_mav.planning import geometric as G

    problem = triangle_among_trees(7, trees=45)
    discs = formation_discs(problem)
    monkeypatch.setattr(G, "ARRAY_GRAPH_LOADED_FROM", 10**9)  # lists even with numba loaded
    lists = G._Graph(problem, discs)
    monkeypatch.setattr(G, "ARRAY_GRAPH_FROM", 1)
    arrays = G._Graph(problem, discs)
    assert lists._csr is None and arrays._csr is not None
    assert len(arrays._csr[1]) == sum(map(len, lists.edges))
    for source in (0, 1):
        d1, p1, v1 = lists.dijkstra(source, leg_penalty=penalty)
        d2, p2, v2 = arrays.dijkstra(source, leg_penalty=penalty)
        np.testing.assert_array_equal(d1, d2)
        np.testing.assert_array_equal(p1, p2)
        assert [v1[n] for n in range(len(d1))] == [v2[n] for n in range(len(d2))]
    assert G.shortest_routes(problem, count=4)[0].length > 0
