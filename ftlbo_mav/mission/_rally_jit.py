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


NEIGHBOURS = 8
"""Lines or path points either side of the last that ruled out a candidate, tried first."""


@njit(cache=True)
def _directions(dx, dy, reach, angle, ranges):
    """The index ranges (into ``ranges (2, 2)``, returned how many) of the sorted
    directions ``angle (m,)`` (radians, [-pi, pi]) of a fan's segments from its rally
    point that may pass within ``reach`` of a point at ``(dx, dy)`` from it: those within
    ``asin(reach / d)`` (and 1e-9) of the point's direction; every one when ``d`` is not
    more than ``reach``. A segment from the rally point in a direction ``D`` radians
    from the point's is at least ``d sin D`` from it (``d`` when ``D`` > pi/2)."""
    d = math.sqrt(dx * dx + dy * dy)
    m = angle.shape[0]
    if d <= reach:
        ranges[0, 0], ranges[0, 1] = 0, m
        return 1
    theta = math.atan2(dy, dx)
    half = math.asin(reach / d) + 1e-9
    lo, hi = theta - half, theta + half
    if lo < -math.pi:
        ranges[0, 0], ranges[0, 1] = 0, np.searchsorted(angle, hi, side="right")
        ranges[1, 0], ranges[1, 1] = np.searchsorted(angle, lo + 2.0 * math.pi), m
        return 2
    if hi > math.pi:
        ranges[0, 0], ranges[0, 1] = 0, np.searchsorted(angle, hi - 2.0 * math.pi,
                                                        side="right")
        ranges[1, 0], ranges[1, 1] = np.searchsorted(angle, lo), m
        return 2
    ranges[0, 0] = np.searchsorted(angle, lo)
    ranges[0, 1] = np.searchsorted(angle, hi, side="right")
    return 1


@njit(cache=True)
def first_clear(chunk, line_a, line_b, line_lo, line_hi, fan_start, edge_start, edge_a,
                edge_n, fan_rally, fan_angle, bucket_start, bucket_fans, origin, bucket_m,
                nx, ny, own, own_home, places, sep, budget):
    """The index of the first of the candidates ``chunk (C, 2)`` at least ``sep`` from
    every segment ``line_a``-``line_b`` (each ``(S, 2)``) whose own return lines (from
    the points of ``own (P, 2)`` nearer to it than ``own_home (P,)``) keep ``sep`` from
    every one of ``places (Q, 2)``; -1 if none is. The tests and arithmetic of
    :func:`.rally._first_clear`, a candidate at a time in order, each given up at its
    first line or place too near. Only the lines that can be too near are measured: the
    segments are in fans (``fan_start (F+1,)``), each in a convex hull of edges
    ``edge_a``/``edge_n`` (``edge_start (F+1,)``; :class:`.rally_fans.Fans`), and a fan whose
    hull the candidate is farther than ``sep`` beyond is skipped (only the fans listed in
    the candidate's bucket are looked at, ``bucket_fans[bucket_start[b]:bucket_start[b +
    1]]`` for the square of side ``bucket_m`` from ``origin (2,)`` that holds it, ``nx``
    by ``ny`` of them: the others' hulls are beyond the whole bucket; every fan outside
    them), as a segment whose box
    grown by ``sep`` (``line_lo``, ``line_hi``) does not hold it; of a fan's segments
    (all ending at its ``fan_rally (F, 2)``, sorted by their direction ``fan_angle (S,)``
    from it) only those whose direction is within ``asin(sep / d)`` (a hair more) of the
    candidate's, ``d`` from the rally point, are measured; of the places only
    those within ``sep`` (a hair more) of the box of its return lines are measured.
    The line, or the place and path point, that ruled out a candidate is tried first on
    the next, with the :data:`NEIGHBOURS` lines or path points either side of it (the
    next candidate, a neighbour, is mostly ruled out by the same or the next): a
    candidate too near one fails at once, which the full tests would also find, so the
    choice is the same.
    Returns the index and the work done: hull edges, segments and places measured, path
    points looked at (:data:`.rally.WORK_PER_UAV`); -1 as soon as the work passes
    ``budget`` (not when it is negative)."""
    used = np.empty(own.shape[0], np.int64)
    ranges = np.empty((2, 2), np.int64)
    reach = sep + 1e-6
    work = 0
    last_line, last_place, last_point = -1, -1, -1  # what ruled out the last candidate
    for c in range(chunk.shape[0]):
        if 0 <= budget <= work:
            return -1, work
        cx, cy = chunk[c, 0], chunk[c, 1]
        work += 1
        ok = True
        if last_line >= 0:
            for s in range(max(0, last_line - NEIGHBOURS),
                           min(line_a.shape[0], last_line + NEIGHBOURS + 1)):
                work += 1
                if _segment_distance(cx, cy, line_a[s, 0], line_a[s, 1],
                                     line_b[s, 0], line_b[s, 1]) < sep:
                    ok = False
                    break
        if ok and last_place >= 0:
            qx, qy = places[last_place, 0], places[last_place, 1]
            for p in range(max(0, last_point - NEIGHBOURS),
                           min(own.shape[0], last_point + NEIGHBOURS + 1)):
                work += 1
                dx, dy = own[p, 0] - cx, own[p, 1] - cy
                if math.sqrt(dx * dx + dy * dy) < own_home[p] and _segment_distance(
                        qx, qy, own[p, 0], own[p, 1], cx, cy) < sep:
                    ok = False
                    break
        if not ok:
            continue
        bx = math.floor((cx - origin[0]) / bucket_m) if bucket_m < np.inf else 0
        by = math.floor((cy - origin[1]) / bucket_m) if bucket_m < np.inf else 0
        if 0 <= bx < nx and 0 <= by < ny:
            b = by * nx + bx
            listed = bucket_fans[bucket_start[b]:bucket_start[b + 1]]
        else:
            listed = np.arange(fan_start.shape[0] - 1)
        for f in listed:
            work += 1
            far = False
            for e in range(edge_start[f], edge_start[f + 1]):
                work += 1
                if ((cx - edge_a[e, 0]) * edge_n[e, 0]
                        + (cy - edge_a[e, 1]) * edge_n[e, 1]) > reach:
                    far = True
                    break
            if far:
                continue
            f0, f1 = fan_start[f], fan_start[f + 1]
            n_ranges = _directions(cx - fan_rally[f, 0], cy - fan_rally[f, 1], reach,
                                   fan_angle[f0:f1], ranges)
            work += 1
            for r in range(n_ranges):
                for s in range(f0 + ranges[r, 0], f0 + ranges[r, 1]):
                    work += 1
                    if (cx < line_lo[s, 0] or cx > line_hi[s, 0]
                            or cy < line_lo[s, 1] or cy > line_hi[s, 1]):
                        continue
                    if _segment_distance(cx, cy, line_a[s, 0], line_a[s, 1],
                                         line_b[s, 0], line_b[s, 1]) < sep:
                        ok = False
                        last_line, last_place = s, -1
                        break
                if not ok:
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
        first_place = max(last_place, 0)  # the last one too near first, then in order
        for jj in range(places.shape[0] if m else 0):
            j = (first_place + jj) % places.shape[0]
            qx, qy = places[j, 0], places[j, 1]
            if qx < lo0 - reach or qx > hi0 + reach or qy < lo1 - reach or qy > hi1 + reach:
                continue
            work += m
            for i in range(m):
                p = used[i]
                if _segment_distance(qx, qy, own[p, 0], own[p, 1], cx, cy) < sep:
                    ok = False
                    last_line, last_place, last_point = -1, j, p
                    break
            if not ok:
                break
        if ok:
            return c, work
    return -1, work
