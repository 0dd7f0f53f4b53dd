"""The centroid's discs: the rim kept, the same route; touching pairs by sort, grid and
compiled; the compiled rim the same as the arrays'."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.planning.discs import formation_discs
from ftlbo_mav.planning.geometric import shortest_route
from ftlbo_mav.planning.problem import PlanningProblem

from .test_geometric import field


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
