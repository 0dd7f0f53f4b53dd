"""The tangent graph's candidate segments: made a chunk at a time, from the last discs'
clear bitangents, walked through a grid compiled: the same as all at once."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.planning.discs import formation_discs

from .test_geometric import triangle_among_trees


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
