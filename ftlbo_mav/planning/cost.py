"""The paper's cost (eqs. 5-11), vectorized over a whole population.

All functions take centroid waypoints ``(S, m, 3)`` metres ENU (S students, m waypoints)
and return per-student arrays ``(S,)``. The path of student s is ``P_s, W_1..W_m, P_f``
(eq. 6 runs j = 0..m+1, NOTES 4); UAV n flies the same path shifted by its offset (eq. 4).

Terms:

- length (eq. 6): the centroid path's length; every UAV's path has the same length.
- safety (eqs. 7-9): for every UAV n, every segment j of its own path and every cylinder
  k, ``V = R_k / d`` with ``d`` the horizontal distance from the cylinder axis to the
  segment (NOTES 3), infinite when ``d <= R_k`` (``R_k`` includes the clearance). The sum
  over n, j, k is divided by ``m * K`` as in eq. 9; the UAVs are summed, not averaged,
  like the task term of eq. 11.
- task (eqs. 10-11): for every UAV and every waypoint W_1..W_m, the distance of its
  altitude outside ``[h_min, h_max]``, infinite at or below the ground (NOTES 5).

A UAV's segment against a cylinder is the centroid's segment against the cylinder moved
by minus the UAV's offset, so the distances are computed once for N*K shifted axes.
"""

from __future__ import annotations

import os
import time
from contextlib import contextmanager
from typing import NamedTuple

import numpy as np

from .problem import PlanningProblem


class CostTerms(NamedTuple):
    """The three cost terms and their weighted sum, each ``(S,)``."""

    total: np.ndarray
    length: np.ndarray
    safety: np.ndarray
    task: np.ndarray


def path_length(paths: np.ndarray) -> np.ndarray:
    """Length of paths ``(S, P, 3)`` -> ``(S,)`` metres."""
    seg = np.diff(paths, axis=1)
    return np.sqrt(np.einsum("spi,spi->sp", seg, seg)).sum(axis=1)


_CHUNK_ELEMENTS = 1 << 16
"""Largest ``(N*K, S*J)`` distance block computed at once (512 KiB of float64 per array):
big populations are evaluated in chunks of students, so memory stays bounded and the
temporaries stay in cache (measured: ~1.8x more evaluations/s than 2 MiB blocks with 100
cylinders or 30 UAVs, the same with the example's 21 shifted axes)."""


def _axes(problem: PlanningProblem) -> np.ndarray:
    """Cylinder axes seen from the centroid, ``c_k - offset_n``: ``(N*K, 2)`` metres."""
    N, K = problem.uav_count, len(problem.radii)
    return (problem.centres[None, :, :] - problem.offsets[:, None, :2]).reshape(N * K, 2)


def _axis_distances(problem: PlanningProblem, paths: np.ndarray) -> np.ndarray:
    """Distances ``(N*K, S*J)``: row ``n*K + k``, column ``s*J + j`` (J = P-1 segments).

    The shifted axes run down the rows and the segments along the columns, so every
    numpy loop is a long contiguous one over the segments (the hot path of the planner;
    with axes last, each loop would be only N*K elements long). Temporaries are reused.
    """
    axes = _axes(problem)
    a = paths[:, :-1, :2].reshape(-1, 2)
    b = paths[:, 1:, :2].reshape(-1, 2) - a
    ax, ay = a[:, 0], a[:, 1]
    bx, by = b[:, 0].copy(), b[:, 1].copy()
    seg2 = bx * bx + by * by
    np.maximum(seg2, 1e-12, out=seg2)
    cx = np.subtract(axes[:, 0, None], ax)  # (NK, SJ): axis minus segment start
    cy = np.subtract(axes[:, 1, None], ay)
    t = cx * bx
    tmp = cy * by
    t += tmp
    t /= seg2  # position of the closest point along the segment, clipped to it
    np.clip(t, 0.0, 1.0, out=t)
    np.multiply(t, bx, out=tmp)
    cx -= tmp
    np.multiply(t, by, out=tmp)
    cy -= tmp
    cx *= cx
    cy *= cy
    cx += cy
    return np.sqrt(cx, out=cx)


def segment_axis_distances(problem: PlanningProblem, paths: np.ndarray) -> np.ndarray:
    """Horizontal distance of every UAV segment to every cylinder axis.

    ``paths``: centroid paths ``(S, P, 3)``. Returns ``(S, P-1, N, K)`` metres.
    """
    paths = np.asarray(paths, float)
    S, P, _ = paths.shape
    N, K = problem.uav_count, len(problem.radii)
    d = _axis_distances(problem, paths)
    return d.reshape(N, K, S, P - 1).transpose(2, 3, 0, 1)


COMPILED_FROM = 400
"""UAVs x cylinders from which the safety term runs compiled (:mod:`._cost_jit`, some 25
times faster per distance, no temporaries); below, numpy's arrays (numba's start-up, 0.3 s
in a new process, costs more than such problems save)."""
COMPILED_SEGMENTS_FROM = 3000
"""UAVs x cylinders x segments per student from which the safety term runs compiled
however few the cylinders (3 UAVs among 100 trees with 10 to 18 waypoints: 3,300 to
5,700; an evaluation of a class then costs some 0.4-0.7 ms in numpy's arrays, 0.03 ms
compiled). Ten UAVs among 20 trees with 10 waypoints (2,200) stay in numpy: their plan
evaluates some 100 classes, less than numba's start-up."""


def _compiled(problem: PlanningProblem) -> bool:
    """Whether the safety term of ``problem`` runs compiled (:data:`COMPILED_FROM`,
    :data:`COMPILED_SEGMENTS_FROM`)."""
    pairs = problem.uav_count * len(problem.radii)
    return pairs >= COMPILED_FROM or pairs * (problem.waypoints + 1) >= COMPILED_SEGMENTS_FROM


PARALLEL_FROM = 2_000_000
"""UAV-segment-axis distances in one call of the compiled safety term from which it runs
on every core even on a busy machine; below, on the calling thread alone when the
machine is busy (:func:`_busy`). A parallel call waits for its slowest thread: where
other processes keep the cores busy, one of them may wait a time slice of several
milliseconds, where the call's work is a fraction of one. The orchard survey of issue 51
evaluates 100 students x 2 segments x 960 axes (0.2 ms of work) some 23,000 times: 20 s
of its plan with two threads at load 3, 5 s with one; on a quiet machine two threads
are faster (the whole plan 7.7 s against 9.1 s with one, the dense 100-tree field's
plan() 0.53 s against 0.68 s; 2026-12-07, ``python benchmarks/goals.py``). Bit for bit
the same: each student's sums run in the same order either way."""

_LOAD_SEEN: list[float] = [-1.0, 0.0]  # when (time.monotonic) and the answer, 1 s old at most


def _busy() -> bool:
    """Whether the machine's other processes keep its cores busy: the 1-minute load
    average (this process counts one) at least the cores less a half, read at most once
    a second."""
    now = time.monotonic()
    if now - _LOAD_SEEN[0] > 1.0:
        try:
            load = os.getloadavg()[0]
        except OSError:  # not every system has one
            load = 0.0
        _LOAD_SEEN[:] = [now, float(load >= (os.cpu_count() or 1) - 0.5)]
    return bool(_LOAD_SEEN[1])


@contextmanager
def _threads_for(distances: int):
    """numba's threads for the calls inside: all of them from :data:`PARALLEL_FROM`
    distances or on a machine not :func:`_busy`, else one (the calling thread)."""
    if distances >= PARALLEL_FROM or not _busy():
        yield
        return
    import numba

    before = numba.get_num_threads()
    numba.set_num_threads(1)
    try:
        yield
    finally:
        numba.set_num_threads(before)


_ARRAYS: dict[int, tuple[PlanningProblem, np.ndarray, np.ndarray]] = {}


def _compiled_arrays(problem: PlanningProblem) -> tuple[np.ndarray, np.ndarray]:
    """The shifted axes ``(N*K, 2)`` and their radii ``(N*K,)`` of ``problem`` for the
    compiled loop, made once per problem (an optimizer evaluates one problem thousands of
    times; the last few problems are kept, held by identity: problems are frozen)."""
    held = _ARRAYS.get(id(problem))
    if held is None or held[0] is not problem:
        if len(_ARRAYS) >= 8:
            _ARRAYS.pop(next(iter(_ARRAYS)))
        held = (problem, np.ascontiguousarray(_axes(problem)),
                np.ascontiguousarray(np.tile(problem.radii, problem.uav_count), float))
        _ARRAYS[id(problem)] = held
    return held[1], held[2]


def _safety(problem: PlanningProblem, paths: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 9 and the total depth of the violations (0 when clear), each ``(S,)``."""
    S, P, _ = paths.shape
    K = len(problem.radii)
    if K == 0:
        return np.zeros(S), np.zeros(S)
    J = P - 1
    if _compiled(problem):
        from ._cost_jit import safety

        axes, tiled = _compiled_arrays(problem)
        with _threads_for(S * J * len(tiled)):
            return safety(np.ascontiguousarray(paths), axes, tiled,
                          1.0 / (problem.waypoints * K))
    radii = np.tile(problem.radii, problem.uav_count)[:, None]  # (NK, 1)
    d = _axis_distances(problem, paths)  # (NK, S*J)
    # Sum of R/d over n, j, k; where some d is 0 the student is inside (infinite) anyway.
    with np.errstate(divide="ignore"):
        ratio = np.divide(radii, d)
    v = ratio.sum(axis=0).reshape(S, J).sum(axis=1) / (problem.waypoints * K)
    # r - d >= 0 exactly when d <= r (IEEE subtraction keeps the sign).
    np.subtract(radii, d, out=d)
    deepest = d.max(axis=0).reshape(S, J).max(axis=1)
    inside = deepest >= 0.0
    v[inside] = np.inf
    depth = np.zeros(S)
    if inside.any():
        over = d.reshape(-1, S, J)[:, inside, :]
        depth[inside] = np.maximum(over, 0.0).sum(axis=(0, 2))
    return v, depth


def safety_cost(problem: PlanningProblem, paths: np.ndarray) -> np.ndarray:
    """Eq. 9 for centroid paths ``(S, P, 3)`` -> ``(S,)`` (infinite on any violation)."""
    return _safety(problem, paths)[0]


def task_cost(problem: PlanningProblem, waypoints: np.ndarray) -> np.ndarray:
    """Eqs. 10-11 for waypoints ``(S, m, 3)`` -> ``(S,)``."""
    h = waypoints[:, :, 2, None] + problem.offsets[:, 2]  # (S, m, N)
    out = np.maximum(problem.h_min - h, 0.0) + np.maximum(h - problem.h_max, 0.0)
    cost = out.sum(axis=(1, 2))
    cost[(h <= 0.0).any(axis=(1, 2))] = np.inf
    return cost


def _terms(problem: PlanningProblem, waypoints: np.ndarray) -> tuple[CostTerms, np.ndarray]:
    waypoints = np.asarray(waypoints, float)
    S = waypoints.shape[0]
    per_student = (waypoints.shape[1] + 1) * max(problem.uav_count * len(problem.radii), 1)
    step = max(_CHUNK_ELEMENTS // per_student, 1)
    if _compiled(problem):
        step = S  # compiled: no temporaries to bound
    if S > step:  # bounded memory for big classes, many UAVs, obstacles or waypoints
        parts = [_terms(problem, waypoints[i : i + step]) for i in range(0, S, step)]
        terms = CostTerms(*(np.concatenate([p[0][i] for p in parts]) for i in range(4)))
        return terms, np.concatenate([p[1] for p in parts])
    paths = problem.full_paths(waypoints)
    length = path_length(paths)
    safety, depth = _safety(problem, paths)
    task = task_cost(problem, waypoints)
    a, b, g = problem.weights
    with np.errstate(invalid="ignore"):  # 0 * inf when a weight is zero: the term is off
        total = a * length + np.where(b == 0, 0.0, b * safety) + np.where(g == 0, 0.0, g * task)
    if b != 0:
        depth = depth + np.maximum(-waypoints[:, :, 2, None] - problem.offsets[:, 2], 0).sum(
            axis=(1, 2)
        )
    return CostTerms(total, length, safety, task), depth


def cost_terms(problem: PlanningProblem, waypoints: np.ndarray) -> CostTerms:
    """All terms for waypoints ``(S, m, 3)`` metres ENU."""
    return _terms(problem, waypoints)[0]


INFEASIBLE = 1e9
"""Search costs at or above this stand for the paper's infinite cost."""


def search_cost(problem: PlanningProblem, waypoints: np.ndarray) -> np.ndarray:
    """The cost the optimizers minimize, ``(S, m, 3) -> (S,)``.

    Equal to the paper's total cost wherever that is finite. Where the paper's cost is
    infinite (a UAV segment inside a cylinder, a UAV at or below the ground), it is
    ``INFEASIBLE + depth``, with depth the summed metres by which the violations go in:
    every violating path still ranks after every clear one, as with an infinite cost, but
    among violating paths the shallower ranks first, so a class that starts with no clear
    path at all (likely among many trees) still has a direction to improve in. The
    paper's random initial class relies on some students being clear; ours need not.
    """
    terms, depth = _terms(problem, waypoints)
    return np.where(np.isfinite(terms.total), terms.total, INFEASIBLE + depth)


def total_cost(problem: PlanningProblem, waypoints: np.ndarray) -> np.ndarray:
    """Weighted sum (eq. 5) for waypoints ``(S, m, 3)`` -> ``(S,)``."""
    return cost_terms(problem, waypoints).total
