"""The vectorized cost against a plain scalar reference written from the paper."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ftlbo_mav.planning.cost import INFEASIBLE, cost_terms, search_cost
from ftlbo_mav.planning.problem import PlanningProblem, problem_from_scenario
from ftlbo_mav.scenario import load_scenario

from ..conftest import EXAMPLE


def reference_cost(problem: PlanningProblem, waypoints) -> tuple[float, float, float, float]:
    """Eqs. 5-11, one UAV, one segment, one cylinder at a time."""
    path = [list(problem.start)] + [list(w) for w in waypoints] + [list(problem.goal)]
    m, K = len(waypoints), len(problem.radii)
    length = sum(math.dist(path[j], path[j + 1]) for j in range(len(path) - 1))

    safety = 0.0
    for offset in problem.offsets:
        for j in range(len(path) - 1):
            a = (path[j][0] + offset[0], path[j][1] + offset[1])
            b = (path[j + 1][0] + offset[0], path[j + 1][1] + offset[1])
            for (cx, cy), r in zip(problem.centres, problem.radii):
                abx, aby = b[0] - a[0], b[1] - a[1]
                denom = abx * abx + aby * aby
                t = 0.0 if denom == 0 else ((cx - a[0]) * abx + (cy - a[1]) * aby) / denom
                t = min(1.0, max(0.0, t))
                d = math.hypot(a[0] + t * abx - cx, a[1] + t * aby - cy)
                safety += math.inf if d <= r else r / d
    safety = safety / (m * K) if K else 0.0

    task = 0.0
    for offset in problem.offsets:
        for w in waypoints:
            h = w[2] + offset[2]
            if h <= 0:
                task += math.inf
            elif h < problem.h_min:
                task += problem.h_min - h
            elif h > problem.h_max:
                task += h - problem.h_max
    a, b, g = problem.weights
    return a * length + b * safety + g * task, length, safety, task


EXAMPLE_PROBLEM = problem_from_scenario(load_scenario(EXAMPLE), waypoints=4)
LOWER, UPPER = EXAMPLE_PROBLEM.bounds()


@settings(max_examples=150, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-10, 100), st.floats(-10, 60), st.floats(-3, 12)),
        min_size=4,
        max_size=4,
    ),
)
def test_vectorized_cost_equals_the_scalar_reference(waypoints):
    w = np.array(waypoints, float)
    terms = cost_terms(EXAMPLE_PROBLEM, w[None])
    expected = reference_cost(EXAMPLE_PROBLEM, waypoints)
    for got, want in zip((terms.total, terms.length, terms.safety, terms.task), expected):
        if math.isinf(want):
            assert np.isinf(got[0])
        else:
            assert got[0] == pytest.approx(want, rel=1e-9, abs=1e-9)


def test_population_shape_and_independence():
    rng = np.random.default_rng(1)
    pop = LOWER + rng.random((50, 4, 3)) * (UPPER - LOWER)
    batch = cost_terms(EXAMPLE_PROBLEM, pop).total
    assert batch.shape == (50,)
    one_by_one = [cost_terms(EXAMPLE_PROBLEM, pop[i : i + 1]).total[0] for i in range(50)]
    assert np.array_equal(batch, one_by_one)


def _open_field(**overrides) -> PlanningProblem:
    values = dict(
        start=np.array([0.0, 0.0, 4.0]),
        goal=np.array([30.0, 0.0, 4.0]),
        offsets=np.array([[0.0, 0.0, 0.0], [0.0, 3.0, 0.0]]),
        centres=np.array([[15.0, 10.0]]),
        radii=np.array([2.0]),
        h_min=2.0,
        h_max=7.0,
        area_lower=np.array([-5.0, -5.0]),
        area_upper=np.array([35.0, 20.0]),
        waypoints=2,
        weights=np.ones(3),
    )
    values.update(overrides)
    return PlanningProblem(**values)


def test_straight_path_values_by_hand():
    problem = _open_field()
    w = np.array([[[10.0, 0.0, 4.0], [20.0, 0.0, 4.0]]])
    terms = cost_terms(problem, w)
    assert terms.length[0] == pytest.approx(30.0)
    # UAV 1 passes 10 m from the axis on the middle segment; the outer segments end 5 m
    # short of the axis's abscissa. UAV 2 flies 3 m closer.
    d_outer = math.hypot(5.0, 10.0)
    uav1 = 2 / d_outer + 2 / 10 + 2 / d_outer
    uav2 = 2 / math.hypot(5.0, 7.0) + 2 / 7 + 2 / math.hypot(5.0, 7.0)
    assert terms.safety[0] == pytest.approx((uav1 + uav2) / (2 * 1))
    assert terms.task[0] == 0.0


def test_a_uav_offset_into_an_obstacle_makes_the_cost_infinite():
    # The centroid passes 4 m from the axis (radius 2), but UAV 2 (3 m north) passes 1 m.
    problem = _open_field(centres=np.array([[15.0, 4.0]]))
    w = np.array([[[10.0, 0.0, 4.0], [20.0, 0.0, 4.0]]])
    assert np.isinf(cost_terms(problem, w).safety[0])
    assert INFEASIBLE < search_cost(problem, w)[0] < INFEASIBLE + 10


def test_task_cost_below_above_and_under_ground():
    problem = _open_field(centres=np.zeros((0, 2)), radii=np.zeros(0))
    w = np.array(
        [
            [[10.0, 0.0, 1.5], [20.0, 0.0, 4.0]],  # both UAVs 0.5 m low at waypoint 1
            [[10.0, 0.0, 8.0], [20.0, 0.0, 4.0]],  # both 1 m high
            [[10.0, 0.0, 0.0], [20.0, 0.0, 4.0]],  # on the ground
        ]
    )
    task = cost_terms(problem, w).task
    assert task[0] == pytest.approx(1.0) and task[1] == pytest.approx(2.0)
    assert np.isinf(task[2])
    assert cost_terms(problem, w).safety[0] == 0.0  # no obstacles: no violation cost


def test_search_cost_ranks_shallower_violations_first_and_equals_cost_when_clear():
    problem = _open_field(
        offsets=np.zeros((1, 3)), centres=np.array([[15.0, 0.5]]), radii=np.array([2.0])
    )
    deep = np.array([[[10.0, 0.5, 4.0], [20.0, 0.5, 4.0]]])
    shallow = np.array([[[10.0, -1.2, 4.0], [20.0, -1.2, 4.0]]])
    clear = np.array([[[10.0, -3.0, 4.0], [20.0, -3.0, 4.0]]])
    s_deep, s_shallow, s_clear = (search_cost(problem, w)[0] for w in (deep, shallow, clear))
    assert s_clear < s_shallow < s_deep
    assert s_clear == pytest.approx(cost_terms(problem, clear).total[0])


def test_the_compiled_safety_term_is_numpys(monkeypatch):
    """From COMPILED_FROM UAVs x cylinders the safety term runs compiled: the same costs
    (to summation order) and the same depths as numpy's arrays, feasible or not."""
    from ftlbo_mav.planning import cost as cost_module

    rng = np.random.default_rng(3)
    offsets = np.column_stack([rng.uniform(-2, 2, (40, 2)), np.zeros(40)])
    problem = PlanningProblem(
        start=np.array([5.0, 5.0, 4.0]), goal=np.array([195.0, 195.0, 4.0]), offsets=offsets,
        centres=rng.uniform(20, 180, (12, 2)), radii=rng.uniform(0.5, 1.5, 12), h_min=2.0,
        h_max=7.0, area_lower=np.zeros(2), area_upper=np.full(2, 200.0), waypoints=6,
        weights=np.array([1.0, 1.0, 1.0]))
    line = np.linspace(problem.start, problem.goal, 8)[1:-1]
    waypoints = line[None] + rng.normal(0, 15, (40, 6, 3)) * [1, 1, 0]
    compiled = cost_module.search_cost(problem, waypoints)
    monkeypatch.setattr(cost_module, "COMPILED_FROM", 10**9)
    monkeypatch.setattr(cost_module, "COMPILED_SEGMENTS_FROM", 10**9)
    arrays = cost_module.search_cost(problem, waypoints)
    assert 0 < np.isfinite(cost_module.cost_terms(problem, waypoints).safety).sum() < 40
    assert np.allclose(compiled, arrays, rtol=1e-12, atol=0)


@pytest.mark.parametrize("compiled", [True, False])
def test_a_segment_touching_a_cylinder_is_inside_compiled_or_not(monkeypatch, compiled):
    """``d <= R`` is inside (infinite safety) in both forms of the safety term, also at
    ``d == R`` exactly, where the depth is 0 (the compiled loop counts hits, it does not
    read them from the depth)."""
    from ftlbo_mav.planning import cost as cost_module

    monkeypatch.setattr(cost_module, "COMPILED_FROM", 1 if compiled else 10**9)
    monkeypatch.setattr(cost_module, "COMPILED_SEGMENTS_FROM", 1 if compiled else 10**9)
    problem = PlanningProblem(
        start=np.array([0.0, 1.0, 4.0]), goal=np.array([20.0, 1.0, 4.0]),
        offsets=np.zeros((1, 3)), centres=np.array([[10.0, 0.0]]), radii=np.array([1.0]),
        h_min=2.0, h_max=7.0, area_lower=np.full(2, -50.0), area_upper=np.full(2, 50.0),
        waypoints=1, weights=np.array([1.0, 1.0, 1.0]))
    touching = np.array([[[10.0, 1.0, 4.0]]])
    apart = np.array([[[10.0, 1.5, 4.0]]])
    assert np.isinf(cost_module.safety_cost(problem, problem.full_paths(touching))[0])
    assert cost_module.search_cost(problem, touching)[0] == cost_module.INFEASIBLE
    assert np.isfinite(cost_module.safety_cost(problem, problem.full_paths(apart))[0])


def test_the_compiled_safety_term_is_the_same_on_one_thread_or_all(monkeypatch):
    """Below PARALLEL_FROM distances a call on a busy machine runs on the calling thread
    alone (a parallel call waits for its slowest thread): the same costs bit for bit,
    and numba's thread count is given back after the call."""
    import numba

    from ftlbo_mav.planning import cost as cost_module

    rng = np.random.default_rng(5)
    problem = PlanningProblem(
        start=np.array([5.0, 5.0, 4.0]), goal=np.array([195.0, 195.0, 4.0]),
        offsets=np.array([[0.0, 4.0, 0.0], [0.0, 0.0, 0.0], [0.0, -4.0, 0.0]]),
        centres=rng.uniform(20, 180, (150, 2)), radii=rng.uniform(0.1, 0.3, 150), h_min=2.0,
        h_max=7.0, area_lower=np.zeros(2), area_upper=np.full(2, 200.0), waypoints=2,
        weights=np.array([1.0, 1.0, 1.0]))
    waypoints = np.linspace(problem.start, problem.goal, 4)[1:-1][None] \
        + rng.normal(0, 20, (100, 2, 3)) * [1, 1, 0]
    before = numba.get_num_threads()
    monkeypatch.setattr(cost_module, "_busy", lambda: True)
    monkeypatch.setattr(cost_module, "PARALLEL_FROM", 10**12)
    alone = cost_module.cost_terms(problem, waypoints)
    assert numba.get_num_threads() == before
    monkeypatch.setattr(cost_module, "PARALLEL_FROM", 0)
    every = cost_module.cost_terms(problem, waypoints)
    assert np.array_equal(alone.safety, every.safety) and np.isfinite(alone.safety).any()


def test_the_machine_is_busy_when_its_load_fills_its_cores_but_one_half(monkeypatch):
    """_busy: the 1-minute load average against the cores, read at most once a second."""
    from ftlbo_mav.planning import cost as cost_module

    load = [1.2]
    monkeypatch.setattr(cost_module.os, "cpu_count", lambda: 2)
    monkeypatch.setattr(cost_module.os, "getloadavg", lambda: (load[0], 0.0, 0.0))
    monkeypatch.setattr(cost_module, "_LOAD_SEEN", [-1.0, 0.0])
    clock = [100.0]
    monkeypatch.setattr(cost_module.time, "monotonic", lambda: clock[0])
    assert not cost_module._busy()  # this plan alone: 1.2 < 1.5
    load[0] = 3.0
    assert not cost_module._busy()  # read less than a second ago
    clock[0] += 1.5
    assert cost_module._busy()
