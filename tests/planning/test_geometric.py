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


def _all_discs(problem: PlanningProblem):
    """Every (UAV, cylinder) disc, none dropped."""
    from ftlbo_mav.planning.discs import Discs

    N, K = problem.uav_count, len(problem.radii)
    centres = (problem.centres[None, :, :] - problem.offsets[:, None, :2]).reshape(-1, 2)
    return Discs(centres, np.tile(problem.radii, N), np.tile(np.arange(K), N),
                 np.repeat(np.arange(N), K))


def test_a_large_formation_keeps_only_the_rim_of_each_blob_and_the_same_route():
    """Issue 21: discs whose circle lies inside other discs change nothing; dropping them
    keeps 200-UAV graphs small. The route is the one over every disc."""
    from ftlbo_mav.planning.discs import centroid_rectangle
    from ftlbo_mav.planning.geometric import _Graph

    i = np.arange(24)
    offsets = np.column_stack([(i % 6) * 2.0 - 5.0, (i // 6) * 2.0 - 3.0, np.zeros(24)])
    rng = np.random.default_rng(5)
    problem = field(offsets=offsets, centres=rng.uniform(-12, 12, (3, 2)),
                    radii=rng.uniform(1.5, 2.5, 3), start=np.array([-22.0, -1.0, 4.0]),
                    goal=np.array([22.0, 1.0, 4.0]))
    kept, every = formation_discs(problem), _all_discs(problem)
    assert len(kept.radii) < 0.75 * len(every.radii)  # the inner discs went
    lower, upper = centroid_rectangle(problem)
    angles = np.linspace(0, 2 * np.pi, 720, endpoint=False)
    ring = np.column_stack([np.cos(angles), np.sin(angles)])
    kept_set = {(round(c[0], 9), round(c[1], 9)) for c in kept.centres}
    for c, r in zip(every.centres, every.radii):
        pts = c + r * ring
        others = np.hypot(*(pts[:, None] - every.centres[None]).transpose(2, 0, 1))
        inside = (others < every.radii[None] - 1e-9).sum(axis=1)  # its own: on, not in
        outside = ~np.all((pts >= lower) & (pts <= upper), axis=1)
        covered = np.all((inside > 0) | outside)
        assert ((round(c[0], 9), round(c[1], 9)) not in kept_set) == covered
    graph = _Graph(problem, every)
    dist, _, _ = graph.dijkstra(0)
    route = shortest_route(problem)
    assert route is not None and route.length == pytest.approx(dist[1], rel=1e-9)


def test_the_grid_finds_the_same_touching_pairs_as_the_sort():
    from ftlbo_mav.planning import discs as D

    rng = np.random.default_rng(5)
    for count, side in ((1500, 300.0), (1000, 40.0)):  # sparse, and piled on each other
        centres = rng.uniform(0.0, side, (count, 2))
        radii = rng.uniform(0.5, 5.0, count)
        i, j = D._touching_pairs_grid(centres, radii)
        order = np.argsort(centres[:, 0], kind="stable")  # the sort by east, as below
        xs = centres[order, 0]
        reach = radii[order] + radii.max() + 1e-6
        a, b = D._ranges(np.searchsorted(xs, xs - reach), np.searchsorted(xs, xs + reach,
                                                                          side="right"))
        si, sj = D._touching(centres, radii, order[a], order[b])
        assert set(zip(i.tolist(), j.tolist())) == set(zip(si.tolist(), sj.tolist()))
        assert len(i) == len(si) and np.all(np.diff(i) >= 0)
        from ftlbo_mav.planning._geometric_jit import touching_pairs

        ci, cj = touching_pairs(centres, radii, 2.0 * radii.max() + 1e-6)  # compiled
        np.testing.assert_array_equal(ci, i)
        np.testing.assert_array_equal(cj, j)


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


@pytest.mark.parametrize("seed", [0, 1])
def test_the_graph_made_a_chunk_at_a_time_is_the_same_graph(monkeypatch, seed):
    from ftlbo_mav.planning import geometric as G
    from ftlbo_mav.planning import tangents as T

    problem = triangle_among_trees(seed, trees=60)
    monkeypatch.setattr(G, "ARRAY_GRAPH_LOADED_FROM", 10**9)  # lists, to count the edges
    monkeypatch.setattr(T, "CHUNKED_GRAPH_FROM", 10**9)
    whole = G.shortest_routes(problem, count=4)
    graph = G._Graph(problem, formation_discs(problem))
    monkeypatch.setattr(T, "CHUNKED_GRAPH_FROM", 1)
    monkeypatch.setattr(T, "_PAIR_CHUNK", 97)  # many chunks
    chunked = G.shortest_routes(problem, count=4)
    again = G._Graph(problem, formation_discs(problem))
    assert len(again.points) == len(graph.points)
    assert sum(map(len, again.edges)) == sum(map(len, graph.edges))
    assert [r.length for r in chunked] == pytest.approx([r.length for r in whole], rel=1e-12)
    np.testing.assert_allclose(chunked[0].nodes, whole[0].nodes, atol=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_seed_margins_graph_from_the_discs_own_bitangents_is_the_same(monkeypatch, seed):
    """The discs grown by the seed routes' margin test only the bitangents clear among the
    discs themselves (tangents._known_bitangents): the same clear bitangents as testing
    every pair among the grown discs, on random fields of 150 trees."""
    from ftlbo_mav.planning import tangents as T
    from ftlbo_mav.planning.discs import centroid_rectangle
    from ftlbo_mav.planning.seeds import seed_margin

    problem = triangle_among_trees(seed, trees=150)
    monkeypatch.setattr(T, "CHUNKED_GRAPH_FROM", 1)
    lower, upper = centroid_rectangle(problem)
    own = formation_discs(problem)
    grown = formation_discs(problem, margin=seed_margin(problem))

    def clear(discs) -> set:
        chunks = T._known_bitangents(discs, T._buried_bins(discs), T._grid(discs), lower,
                                     upper)
        return {(int(a), int(b), int(k)) for i, _ai, j, _aj, kind in chunks
                for a, b, k in zip(i, j, kind)}

    T._LAST_BITANGENTS.clear()
    exact = clear(grown)  # every pair tested
    T._LAST_BITANGENTS.clear()
    clear(own)
    reused = clear(grown)  # only the own discs' clear ones tested again
    assert reused == exact and len(exact) > 1000
    # (the growth can merge blobs and keep another set of rim discs: then all are tested)
    if np.array_equal(own.centres, grown.centres):
        assert T._LAST_BITANGENTS[0][0][1] == own.radii.tobytes()  # tested again, not kept


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


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_compiled_rim_is_the_discs_the_arrays_keep(monkeypatch, seed):
    """From COMPILED_RIM_FROM discs formation_discs keeps its discs compiled, with no pair
    arrays: the same discs, in the same order, as the arrays of every touching pair and
    the walks around each circle; with UAVs stacked on one offset (equal discs), trees of
    every size (discs inside others) and trees cut by the area's sides."""
    from ftlbo_mav.planning import discs as D

    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(np.arange(6) * 2.0, np.arange(4) * 2.0), -1).reshape(-1, 2)
    offsets = np.column_stack([np.concatenate([grid, grid[:5]]), np.zeros(len(grid) + 5)])
    problem = field(offsets=offsets, centres=rng.uniform(-35.0, 35.0, (60, 2)),
                    radii=rng.uniform(0.3, 6.0, 60))
    monkeypatch.setattr(D, "COMPILED_RIM_FROM", 10**9)
    arrays = D.formation_discs(problem)
    monkeypatch.setattr(D, "COMPILED_RIM_FROM", 1)
    compiled = D.formation_discs(problem)
    assert 0 < len(arrays.radii) < problem.uav_count * 60
    for name in ("centres", "radii", "cylinder", "uav"):
        np.testing.assert_array_equal(getattr(compiled, name), getattr(arrays, name))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_compiled_walk_through_the_grid_tests_as_every_disc_does(seed):
    """The compiled test of segments against discs through the grid (each segment's cells
    in turn) says what testing every segment against every disc says: random segments,
    many tangent to a disc, some beyond the grid, some along a cell side, some a point."""
    from ftlbo_mav.planning import tangents as T
    from ftlbo_mav.planning.discs import Discs

    rng = np.random.default_rng(seed)
    C = 300
    centres = rng.uniform(0.0, 100.0, (C, 2))
    radii = rng.uniform(0.5, 4.0, C)
    discs = Discs(centres, radii, np.arange(C), np.zeros(C, int))
    k = rng.integers(0, C, 3000)
    angle = rng.uniform(0, 2 * np.pi, 3000)
    on_circle = centres[k] + radii[k, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    p = np.concatenate([on_circle[:1000], rng.uniform(-30.0, 130.0, (1500, 2)),
                        np.repeat([[0.0, 50.0], [-20.0, -20.0]], 250, axis=0)])
    q = np.concatenate([on_circle[1000:2000], rng.uniform(-30.0, 130.0, (1500, 2)),
                        np.column_stack([rng.uniform(0.0, 100.0, 250), np.full(250, 50.0)]),
                        np.full((250, 2), -20.0)])
    p[-10:] = q[-10:] = on_circle[-10:]  # segments of no length on a circle
    compiled = T._clear_through_grid(p, q, discs)
    every = np.array([T.segments_clear(p[a:a + 1], q[a:a + 1], discs)[0]
                      for a in range(len(p))])
    assert 0 < every.sum() < len(p)
    np.testing.assert_array_equal(compiled, every)
