"""The rally search's costly tests compiled (numba): candidates against the return lines of
a long survey (tens of thousands of segments), and a large swarm's candidates against the
others' lines and places one at a time. Imported only for large cases
(:data:`.rally.COMPILED_FROM`, :data:`.rally.COMPILED_UAVS_FROM`), so that a small plan
does not pay numba's start-up."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..compiling import njit


@njit(cache=True)
def _segment_distance(qx, qy, ax, ay, bx, by):
    """The distance from ``(qx, qy)`` to the segment ``(ax, ay)``-``(bx, by)``: the
    arithmetic of :func:`ftlbo_mav.geo.segment_distance`, in its order."""
    abx, aby = bx - ax, by - ay
    denom = max(abx * abx + aby * aby, 1e-12)
    t = ((qx - ax) * abx + (qy - ay) * aby) / denom
    t = min(max(t, 0.0), 1.0)
    dx = ax + t * abx - qx
    dy = ay + t * aby - qy
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, parallel=True)
def clear_of_segments(q, a, b, sep):
    """``(C,)`` whether each point ``q (C, 2)`` is at least ``sep`` from every segment
    ``a``-``b`` (each ``(S, 2)``), a candidate given up at its first segment nearer than
    ``sep``."""
    C, S = q.shape[0], a.shape[0]
    ok = np.ones(C, np.bool_)
    for c in prange(C):
        for s in range(S):
            if _segment_distance(q[c, 0], q[c, 1], a[s, 0], a[s, 1], b[s, 0], b[s, 1]) < sep:
                ok[c] = False
                break
    return ok


@njit(cache=True)
def first_clear(chunk, line_a, line_b, line_lo, line_hi, fan_start, edge_start, edge_a,
                edge_n, own, own_home, places, sep):
    """The index of the first of the candidates ``chunk (C, 2)`` at least ``sep`` from
    every segment ``line_a``-``line_b`` (each ``(S, 2)``) whose own return lines (from
    the points of ``own (P, 2)`` nearer to it than ``own_home (P,)``) keep ``sep`` from
    every one of ``places (Q, 2)``; -1 if none is. The tests and arithmetic of
    :func:`.rally._first_clear`, a candidate at a time in order, each given up at its
    first line or place too near. Only the lines that can be too near are measured: the
    segments are in fans (``fan_start (F+1,)``), each in a convex hull of edges
    ``edge_a``/``edge_n`` (``edge_start (F+1,)``; :class:`.rally_fans.Fans`), and a fan whose
    hull the candidate is farther than ``sep`` beyond is skipped, as a segment whose box
    grown by ``sep`` (``line_lo``, ``line_hi``) does not hold it; of the places only
    those within ``sep`` (a hair more) of the box of its return lines are measured.
    Returns the index and the work done: hull edges, segments and places measured, path
    points looked at (:data:`.rally.WORK_PER_UAV`)."""
    used = np.empty(own.shape[0], np.int64)
    reach = sep + 1e-6
    work = 0
    for c in range(chunk.shape[0]):
        cx, cy = chunk[c, 0], chunk[c, 1]
        ok = True
        for f in range(fan_start.shape[0] - 1):
            far = False
            for e in range(edge_start[f], edge_start[f + 1]):
                work += 1
                if ((cx - edge_a[e, 0]) * edge_n[e, 0]
                        + (cy - edge_a[e, 1]) * edge_n[e, 1]) > reach:
                    far = True
                    break
            if far:
                continue
            work += fan_start[f + 1] - fan_start[f]
            for s in range(fan_start[f], fan_start[f + 1]):
                if (cx < line_lo[s, 0] or cx > line_hi[s, 0]
                        or cy < line_lo[s, 1] or cy > line_hi[s, 1]):
                    continue
                if _segment_distance(cx, cy, line_a[s, 0], line_a[s, 1],
                                     line_b[s, 0], line_b[s, 1]) < sep:
                    ok = False
                    break
            if not ok:
                break
        if not ok:
            continue
        m = 0
        lo0, lo1, hi0, hi1 = cx, cy, cx, cy
        work += own.shape[0] + places.shape[0]
        for p in range(own.shape[0]):
            dx, dy = own[p, 0] - cx, own[p, 1] - cy
            if math.sqrt(dx * dx + dy * dy) < own_home[p]:
                used[m] = p
                m += 1
                lo0, hi0 = min(lo0, own[p, 0]), max(hi0, own[p, 0])
                lo1, hi1 = min(lo1, own[p, 1]), max(hi1, own[p, 1])
        for j in range(places.shape[0] if m else 0):
            qx, qy = places[j, 0], places[j, 1]
            if qx < lo0 - reach or qx > hi0 + reach or qy < lo1 - reach or qy > hi1 + reach:
                continue
            work += m
            for i in range(m):
                p = used[i]
                if _segment_distance(qx, qy, own[p, 0], own[p, 1], cx, cy) < sep:
                    ok = False
                    break
            if not ok:
                break
        if ok:
            return c, work
    return -1, work
