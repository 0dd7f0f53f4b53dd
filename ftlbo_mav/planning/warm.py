"""The planner's loops that run compiled only once cached, compiled into numba's cache in
the background (:data:`..compiling.LATER`, :func:`..compiling.cheap`).

A plan of a hundred trees finds the tangent graph's search, the discs' rim and the
nearest-sample search worth running compiled once they are cached, but not worth
compiling in the foreground (seconds, where the plan takes one). Without this the cache
would fill only when a plan large enough to compile them in the foreground came along;
with it, the first such plan starts :func:`compile_loops` in the background and the next
ones run compiled (the dense 100-tree field's ``plan()``: 1.3 s in numpy, 0.5 s
compiled).
"""

from __future__ import annotations


def compile_loops() -> None:
    """Compile the loops into numba's cache through the calls a plan makes (so with the
    argument types a plan gives them): the tangent graph of three UAVs among 60 seeded
    trees with every threshold at 0, and the nearest-sample search."""
    import numpy as np

    from . import discs, geometric, proximity
    from .problem import PlanningProblem

    rng = np.random.default_rng(0)
    problem = PlanningProblem(
        start=np.array([5.0, 5.0, 4.0]), goal=np.array([195.0, 195.0, 4.0]),
        offsets=np.array([[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, -4.0, 0.0]]),
        centres=rng.uniform(20, 180, (60, 2)), radii=rng.uniform(1.0, 2.0, 60), h_min=2.0,
        h_max=7.0, area_lower=np.zeros(2), area_upper=np.full(2, 200.0), waypoints=2,
        weights=np.ones(3))
    saved = (geometric.ARRAY_GRAPH_FROM, discs.COMPILED_RIM_FROM, proximity.FULL_ARRAY_LIMIT)
    geometric.ARRAY_GRAPH_FROM = discs.COMPILED_RIM_FROM = proximity.FULL_ARRAY_LIMIT = 0
    try:
        geometric.shortest_routes(problem, count=2)
        proximity.nearest_samples(rng.uniform(0, 200, (50, 2)), problem.centres)
    finally:
        geometric.ARRAY_GRAPH_FROM, discs.COMPILED_RIM_FROM, proximity.FULL_ARRAY_LIMIT = saved
