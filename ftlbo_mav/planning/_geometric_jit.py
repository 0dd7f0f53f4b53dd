"""The tangent graph's loops compiled (numba), each the same arithmetic as its numpy twin,
for problems of thousands of discs and millions of candidate segments. Imported only for
such problems (or when numba is loaded and the loop cached: :func:`..compiling.cheap`), so
that a small plan does not pay numba's start-up.

- the discs (:mod:`.discs`): which touch (:func:`touching_pairs`), which lie on the rim
  of a cylinder's blob (:func:`rim_discs`);
- the candidate segments (:mod:`.tangents`): the discs in a grid (:func:`disc_grid`),
  segments walked through it (:func:`clear_through_grid`, from
  :data:`.tangents.GRID_CLEAR_FROM`), every disc pair's bitangents judged in one pass
  (:func:`bitangent_verdicts`, :func:`candidate_verdicts`, :func:`bitangent_angles`);
- the graph (:mod:`.geometric`): its arcs judged (:func:`arcs_free`) and searched
  (:func:`dijkstra`).

Kept whole: to numba and to the user a module of compiled loops is one unit, and these
are the one tangent graph's: :mod:`..compiling` names this module ("the tangent graph's
loops") and says so on stderr, once per module, before its first compile after an
install; three modules would say three lines, and nothing for a module its table does
not name. Its three parts follow the three modules whose twins they are.
"""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..compiling import njit

# -- the discs (.discs) ----------------------------------------------------------------


@njit(cache=True)
def _spans_cover(centre, half, n):
    """Whether the open intervals ``(centre[:n], half[:n])`` of one circle cover the whole
    of it (:func:`.discs._circle_covered`, the same walk); ``centre`` is reused."""
    two_pi = 2.0 * math.pi
    if n == 0:
        return False
    a = np.empty(n)
    b = np.empty(n)
    for m in range(n):
        h = half[m]
        if h >= math.pi:
            return True
        a[m] = (centre[m] - h) % two_pi
        b[m] = a[m] + 2 * h
    for m in range(1, n):  # sort the spans as Python sorts its tuples (a, then b)
        x, y = a[m], b[m]
        k = m - 1
        while k >= 0 and (a[k] > x or (a[k] == x and b[k] > y)):
            a[k + 1], b[k + 1] = a[k], b[k]
            k -= 1
        a[k + 1], b[k + 1] = x, y
    begin, reach = a[0], b[0]
    for step in range(1, 2 * n):  # spans[1:], then every span a turn later
        if step < n:
            x, y = a[step], b[step]
        else:
            x, y = a[step - n] + two_pi, b[step - n] + two_pi
        if x >= reach - 1e-9:
            return False
        reach = max(reach, y)
        if reach > begin + two_pi + 1e-9:
            return True
    return False


@njit(cache=True)
def _touch(xi, yi, ri, xj, yj, rj):
    """:func:`.discs._touching`'s test, ``hypot(dx, dy) <= ri + rj + 1e-6``, decided
    on the squares where they are clear of round-off by far, by ``hypot`` itself near the
    edge."""
    dx, dy = xj - xi, yj - yi
    d2 = dx * dx + dy * dy
    reach = ri + rj + 1e-6
    if d2 < reach * reach * (1.0 - 1e-9):
        return True
    if d2 > reach * reach * (1.0 + 1e-9):
        return False
    return math.hypot(dx, dy) <= reach


@njit(cache=True)
def _partners(i, centres, radii, gx, gy, nx, ny, starts, items, out_j, at):
    """The discs touching disc ``i`` among the 3 x 3 cells around its own, written to
    ``out_j[at:]`` when ``at >= 0``; their count."""
    n = 0
    for yy in range(max(gy[i] - 1, 0), min(gy[i] + 2, ny)):
        for xx in range(max(gx[i] - 1, 0), min(gx[i] + 2, nx)):
            c = yy * nx + xx
            for m in range(starts[c], starts[c + 1]):
                j = items[m]
                if j != i and _touch(centres[i, 0], centres[i, 1], radii[i], centres[j, 0],
                                     centres[j, 1], radii[j]):
                    if at >= 0:
                        out_j[at + n] = j
                    n += 1
    return n


@njit(cache=True)
def _centre_grid(centres, cell):
    """Each disc in the square cell of side ``cell`` holding its centre: its cell
    ``gx``, ``gy``, the grid's ``nx``, ``ny`` and the discs of each cell, ascending, as
    ``starts (nx*ny + 1,)`` and ``items``."""
    C = centres.shape[0]
    lo0, lo1 = centres[:, 0].min(), centres[:, 1].min()
    gx = np.empty(C, np.int64)
    gy = np.empty(C, np.int64)
    for k in range(C):
        gx[k] = int((centres[k, 0] - lo0) / cell)
        gy[k] = int((centres[k, 1] - lo1) / cell)
    nx, ny = gx.max() + 1, gy.max() + 1
    counts = np.zeros(nx * ny + 1, np.int64)
    for k in range(C):
        counts[gy[k] * nx + gx[k] + 1] += 1
    starts = np.cumsum(counts)
    items = np.empty(C, np.int64)
    fill = starts[:-1].copy()
    for k in range(C):
        c = gy[k] * nx + gx[k]
        items[fill[c]] = k
        fill[c] += 1
    return gx, gy, nx, ny, starts, items


@njit(cache=True, parallel=True)
def touching_pairs(centres, radii, cell):
    """Every ordered pair ``(i, j)``, ``i != j``, of discs that touch or overlap
    (:func:`_touch`), ordered by ``i`` then ``j``: each disc in the square cell of side
    ``cell`` (at least twice the largest radius) holding its centre, its partners among
    the discs of the 3 x 3 cells around. Two passes over the discs in parallel (count,
    then fill), no candidate arrays."""
    C = centres.shape[0]
    gx, gy, nx, ny, starts, items = _centre_grid(centres, cell)
    found = np.zeros(C + 1, np.int64)
    none = np.empty(0, np.int64)
    for i in prange(C):
        found[i + 1] = _partners(i, centres, radii, gx, gy, nx, ny, starts, items, none, -1)
    first = np.cumsum(found)
    pair_i = np.empty(first[-1], np.int64)
    pair_j = np.empty(first[-1], np.int64)
    for i in prange(C):
        n = _partners(i, centres, radii, gx, gy, nx, ny, starts, items, pair_j, first[i])
        pair_i[first[i]:first[i] + n] = i
        pair_j[first[i]:first[i] + n].sort()
    return pair_i, pair_j


@njit(cache=True, parallel=True)
def rim_discs(centres, radii, lower, upper, cell, tol):
    """``keep (C,)``, ``rim (C,)``: the discs :func:`.discs.formation_discs` keeps,
    found without pair arrays. ``keep``: a disc inside another is dropped (of equal ones
    the first is kept); ``rim``: then a kept disc whose circle the other kept discs and
    the rectangle ``lower``..``upper`` cover wholly (:func:`.discs._covered_arcs`,
    :func:`.discs._forbidden_arrays`, :func:`_spans_cover`: the same arithmetic).
    Each disc's partners come from the 3 x 3 cells of side ``cell`` (at least twice the
    largest radius) around its own."""
    C = centres.shape[0]
    gx, gy, nx, ny, starts, items = _centre_grid(centres, cell)
    keep = np.ones(C, np.bool_)
    for i in prange(C):
        xi, yi, ri = centres[i, 0], centres[i, 1], radii[i]
        for yy in range(max(gy[i] - 1, 0), min(gy[i] + 2, ny)):
            for xx in range(max(gx[i] - 1, 0), min(gx[i] + 2, nx)):
                c = yy * nx + xx
                for m in range(starts[c], starts[c + 1]):
                    j = items[m]
                    if j == i or not _touch(xi, yi, ri, centres[j, 0], centres[j, 1],
                                            radii[j]):
                        continue
                    d = math.hypot(centres[j, 0] - xi, centres[j, 1] - yi)
                    if d + ri <= radii[j] + tol and (d + radii[j] > ri + tol or i > j):
                        keep[i] = False
    out = keep.copy()
    for i in prange(C):
        if not keep[i]:
            continue
        xi, yi, ri = centres[i, 0], centres[i, 1], radii[i]
        n = 0
        for yy in range(max(gy[i] - 1, 0), min(gy[i] + 2, ny)):
            for xx in range(max(gx[i] - 1, 0), min(gx[i] + 2, nx)):
                c = yy * nx + xx
                n += starts[c + 1] - starts[c]
        centre = np.empty(n + 4)
        half = np.empty(n + 4)
        n = 0
        for yy in range(max(gy[i] - 1, 0), min(gy[i] + 2, ny)):
            for xx in range(max(gx[i] - 1, 0), min(gx[i] + 2, nx)):
                c = yy * nx + xx
                for m in range(starts[c], starts[c + 1]):
                    j = items[m]
                    if j == i or not keep[j]:
                        continue
                    vx, vy = centres[j, 0] - xi, centres[j, 1] - yi
                    d = math.hypot(vx, vy)
                    rj = radii[j]
                    if d >= ri + rj or d + rj <= ri:  # apart, or j inside i
                        continue
                    if d + ri <= rj:  # i's whole circle inside j
                        centre[n], half[n] = 0.0, math.pi
                    else:
                        cos_a = (ri * ri + d * d - rj * rj) / (2 * ri * d)
                        centre[n] = math.atan2(vy, vx)
                        half[n] = math.acos(min(max(cos_a, -1.0), 1.0))
                    n += 1
        for side in range(4):  # west, east, south, north
            if side == 0:
                normal, h = math.pi, xi - lower[0]
            elif side == 1:
                normal, h = 0.0, upper[0] - xi
            elif side == 2:
                normal, h = -0.5 * math.pi, yi - lower[1]
            else:
                normal, h = 0.5 * math.pi, upper[1] - yi
            if h <= -ri:  # the whole circle beyond the side
                centre[n], half[n] = 0.0, math.pi
                n += 1
            elif h < ri:
                centre[n], half[n] = normal, math.acos(h / ri)
                n += 1
        out[i] = not _spans_cover(centre, half, n)
    return keep, out


# -- the candidate segments (.tangents) ------------------------------------------------


@njit(cache=True)
def _cells(x, y, r, lo0, lo1, cell, nx, ny):
    """The cells ``(x0, x1, y0, y1)``, inclusive, that the bounding box of the disc at
    ``(x, y)`` of radius ``r`` meets."""
    return (max(int((x - r - lo0) / cell), 0), min(int((x + r - lo0) / cell), nx - 1),
            max(int((y - r - lo1) / cell), 0), min(int((y + r - lo1) / cell), ny - 1))


@njit(cache=True)
def disc_grid(centres, radii, lo0, lo1, cell, nx, ny):
    """Square cells of side ``cell`` from ``(lo0, lo1)``, ``nx`` by ``ny``: the discs whose
    bounding box meets each cell, as ``starts (nx*ny + 1,)`` and ``items``."""
    C = centres.shape[0]
    counts = np.zeros(nx * ny + 1, np.int64)
    for k in range(C):
        x0, x1, y0, y1 = _cells(centres[k, 0], centres[k, 1], radii[k], lo0, lo1, cell, nx, ny)
        for gy in range(y0, y1 + 1):
            for gx in range(x0, x1 + 1):
                counts[gy * nx + gx + 1] += 1
    starts = np.cumsum(counts)
    items = np.empty(starts[-1], np.int64)
    fill = starts[:-1].copy()
    for k in range(C):
        x0, x1, y0, y1 = _cells(centres[k, 0], centres[k, 1], radii[k], lo0, lo1, cell, nx, ny)
        for gy in range(y0, y1 + 1):
            for gx in range(x0, x1 + 1):
                items[fill[gy * nx + gx]] = k
                fill[gy * nx + gx] += 1
    return starts, items


@njit(cache=True)
def _walk_clear(ax, ay, qx, qy, centres, radii, starts, items, lo0, lo1, cell, nx, ny, tol):
    """Whether the segment ``(ax, ay) -> (qx, qy)`` enters no disc's interior: the discs of
    every cell the segment crosses are tested (a disc in two such cells twice: cheaper
    than a shared record of the discs tested, which the threads would write to in
    turn), the cells visited in the segment's order
    (Amanatides and Woo's traversal, clipped to the grid). A disc the segment enters
    holds a point of it in its bounding box, so it is listed in a cell the segment
    crosses (:func:`disc_grid`)."""
    bx, by = qx - ax, qy - ay
    seg2 = max(bx * bx + by * by, 1e-18)
    # the segment in cell units, clipped to the grid's box [0, nx] x [0, ny]
    x0, y0 = (ax - lo0) / cell, (ay - lo1) / cell
    dx, dy = bx / cell, by / cell
    t0, t1 = 0.0, 1.0
    for p, q in ((-dx, x0), (dx, nx - x0), (-dy, y0), (dy, ny - y0)):
        if p == 0.0:
            if q < 0.0:
                return True  # parallel to a side and outside: no disc there
        elif p < 0.0:
            t0 = max(t0, q / p)
        else:
            t1 = min(t1, q / p)
    if t0 > t1:
        return True
    gx = min(max(int(math.floor(x0 + t0 * dx)), 0), nx - 1)
    gy = min(max(int(math.floor(y0 + t0 * dy)), 0), ny - 1)
    ex = min(max(int(math.floor(x0 + t1 * dx)), 0), nx - 1)
    ey = min(max(int(math.floor(y0 + t1 * dy)), 0), ny - 1)
    step_x = 1 if ex > gx else -1
    step_y = 1 if ey > gy else -1
    # the segment's parameter where it crosses the next cell side in x and in y
    if dx > 0.0:
        next_x, delta_x = (gx + 1 - x0) / dx, 1.0 / dx
    elif dx < 0.0:
        next_x, delta_x = (gx - x0) / dx, -1.0 / dx
    else:
        next_x, delta_x = math.inf, math.inf
    if dy > 0.0:
        next_y, delta_y = (gy + 1 - y0) / dy, 1.0 / dy
    elif dy < 0.0:
        next_y, delta_y = (gy - y0) / dy, -1.0 / dy
    else:
        next_y, delta_y = math.inf, math.inf
    left_x, left_y = abs(ex - gx), abs(ey - gy)
    while True:
        c = gy * nx + gx
        for m in range(starts[c], starts[c + 1]):
            k = items[m]
            cx, cy = centres[k, 0] - ax, centres[k, 1] - ay
            t = min(max((cx * bx + cy * by) / seg2, 0.0), 1.0)
            d = math.hypot(cx - t * bx, cy - t * by)
            if d < radii[k] * (1 - tol) - tol:
                return False
        if left_x == 0 and left_y == 0:
            return True
        # one cell on, to the end cell by a staircase whatever the round-off
        if left_y == 0 or (left_x > 0 and next_x < next_y):
            gx += step_x
            next_x += delta_x
            left_x -= 1
        else:
            gy += step_y
            next_y += delta_y
            left_y -= 1


@njit(cache=True, parallel=True)
def clear_through_grid(p, q, centres, radii, starts, items, lo0, lo1, cell, nx, ny, tol):
    """``(E,)``: True where the segment ``p[e] -> q[e]`` enters no disc's interior (the
    test of :func:`.tangents.segments_clear`, the same arithmetic), each segment walked
    through the grid (:func:`_walk_clear`)."""
    E = p.shape[0]
    clear = np.ones(E, np.bool_)
    for e in prange(E):
        clear[e] = _walk_clear(p[e, 0], p[e, 1], q[e, 0], q[e, 1], centres, radii, starts,
                               items, lo0, lo1, cell, nx, ny, tol)
    return clear


@njit(cache=True)
def _pair_tangents(xa, ya, ra, xb, yb, rb, tol):
    """What the bitangents of discs ``a`` and ``b`` share: ``phi`` (the direction from
    ``a`` to ``b``), whether the outer and the inner pair exist and their half-angles
    (:func:`.tangents._bitangents`, the same arithmetic)."""
    vx, vy = xb - xa, yb - ya
    d = math.hypot(vx, vy)
    phi = math.atan2(vy, vx)
    outer = d > abs(ra - rb) + tol
    inner = d > ra + rb + tol
    alpha_outer = math.acos(min(max((ra - rb) / d, -1.0), 1.0)) if outer else 0.0
    alpha_inner = math.acos(min(max((ra + rb) / d, -1.0), 1.0)) if inner else 0.0
    return phi, outer, inner, alpha_outer, alpha_inner


@njit(cache=True)
def _kind_angles(phi, alpha_outer, alpha_inner, kind):
    """The tangent angles on ``a`` and on ``b`` of bitangent ``kind``: 0, 1 the outer (+,
    -), 2, 3 the inner (+, -) as :func:`.tangents._bitangents` makes them."""
    alpha = alpha_outer if kind < 2 else alpha_inner
    ai = phi + alpha if kind % 2 == 0 else phi + -1.0 * alpha
    aj = ai if kind < 2 else ai + math.pi
    return ai, aj


@njit(cache=True)
def pair_rows(C):
    """``(C,)``: the index of pair ``(a, a + 1)`` in ``np.triu_indices(C, 1)``'s order:
    the pairs of the rows above ``a``."""
    rows = np.arange(C)
    return rows * C - rows * (rows + 1) // 2


_PAIR_BLOCK = 4096  # pairs a thread takes at a time (walked row by row, no pair arrays)


@njit(cache=True, parallel=True)
def bitangent_verdicts(begin, end, centres, radii, marked, lower, upper, starts, items, lo0,
                       lo1, cell, nx, ny, tol):
    """``ok (4, end - begin)``: for the disc pairs ``begin`` to ``end`` (exclusive) of
    ``np.triu_indices(C, 1)``'s order, which of their four bitangents (rows as
    :func:`_kind_angles`) exist, have neither end in a ``marked`` bin
    (:func:`.tangents._buried_bins`), have both ends in the rectangle ``lower``..``upper``
    (:func:`.discs._in_rectangle`) and enter no disc (:func:`_walk_clear`). Only the
    verdicts are written (a byte a candidate, not two angles of eight): the pairs are
    walked in blocks, row by row, with no pair arrays; :func:`bitangent_angles` gives the
    angles of the clear ones."""
    C = centres.shape[0]
    before = pair_rows(C)
    bins = marked.shape[1]
    two_pi = 2.0 * math.pi
    width = two_pi / bins
    tol0 = tol * (1 + abs(upper[0] - lower[0]))
    tol1 = tol * (1 + abs(upper[1] - lower[1]))
    M = end - begin
    ok = np.zeros((4, M), np.bool_)
    for block in prange((M + _PAIR_BLOCK - 1) // _PAIR_BLOCK):
        first = begin + block * _PAIR_BLOCK
        a = np.searchsorted(before, first, side="right") - 1
        b = first - before[a] + a + 1
        for m in range(first - begin, min(first - begin + _PAIR_BLOCK, M)):
            xa, ya, ra = centres[a, 0], centres[a, 1], radii[a]
            xb, yb, rb = centres[b, 0], centres[b, 1], radii[b]
            phi, outer, inner, alpha_outer, alpha_inner = _pair_tangents(xa, ya, ra, xb, yb,
                                                                         rb, tol)
            for kind in range(4):
                if not (outer if kind < 2 else inner):
                    continue
                ai, aj = _kind_angles(phi, alpha_outer, alpha_inner, kind)
                if marked[a, int(math.floor((ai % two_pi) / width)) % bins]:
                    continue
                if marked[b, int(math.floor((aj % two_pi) / width)) % bins]:
                    continue
                px, py = xa + ra * math.cos(ai), ya + ra * math.sin(ai)
                qx, qy = xb + rb * math.cos(aj), yb + rb * math.sin(aj)
                if not (lower[0] - tol0 <= px <= upper[0] + tol0
                        and lower[1] - tol1 <= py <= upper[1] + tol1
                        and lower[0] - tol0 <= qx <= upper[0] + tol0
                        and lower[1] - tol1 <= qy <= upper[1] + tol1):
                    continue
                ok[kind, m] = _walk_clear(px, py, qx, qy, centres, radii, starts, items, lo0,
                                          lo1, cell, nx, ny, tol)
            b += 1
            if b == C:
                a += 1
                b = a + 1
    return ok


@njit(cache=True, parallel=True)
def candidate_verdicts(i, j, kind, centres, radii, marked, lower, upper, starts, items, lo0,
                       lo1, cell, nx, ny, tol):
    """``ok (K,)``: :func:`bitangent_verdicts`' tests for the bitangents ``kind[k]`` of the
    pairs ``(i[k], j[k])`` alone (the ones clear among the same discs a little smaller:
    :func:`.tangents._known_bitangents`)."""
    bins = marked.shape[1]
    two_pi = 2.0 * math.pi
    width = two_pi / bins
    tol0 = tol * (1 + abs(upper[0] - lower[0]))
    tol1 = tol * (1 + abs(upper[1] - lower[1]))
    K = len(i)
    ok = np.zeros(K, np.bool_)
    for k in prange(K):
        a, b = i[k], j[k]
        xa, ya, ra = centres[a, 0], centres[a, 1], radii[a]
        xb, yb, rb = centres[b, 0], centres[b, 1], radii[b]
        phi, outer, inner, alpha_outer, alpha_inner = _pair_tangents(xa, ya, ra, xb, yb, rb,
                                                                     tol)
        if not (outer if kind[k] < 2 else inner):
            continue
        ai, aj = _kind_angles(phi, alpha_outer, alpha_inner, kind[k])
        if marked[a, int(math.floor((ai % two_pi) / width)) % bins]:
            continue
        if marked[b, int(math.floor((aj % two_pi) / width)) % bins]:
            continue
        px, py = xa + ra * math.cos(ai), ya + ra * math.sin(ai)
        qx, qy = xb + rb * math.cos(aj), yb + rb * math.sin(aj)
        if not (lower[0] - tol0 <= px <= upper[0] + tol0
                and lower[1] - tol1 <= py <= upper[1] + tol1
                and lower[0] - tol0 <= qx <= upper[0] + tol0
                and lower[1] - tol1 <= qy <= upper[1] + tol1):
            continue
        ok[k] = _walk_clear(px, py, qx, qy, centres, radii, starts, items, lo0, lo1, cell,
                            nx, ny, tol)
    return ok


@njit(cache=True)
def bitangent_angles(i, j, kind, centres, radii, tol):
    """``angle_i``, ``angle_j`` ``(K,)``: the tangent angles of bitangent ``kind[k]`` of
    the pair ``(i[k], j[k])``, ``i < j``, as :func:`bitangent_verdicts` made them."""
    K = len(i)
    angle_i = np.empty(K)
    angle_j = np.empty(K)
    for k in range(K):
        a, b = i[k], j[k]
        phi, _, _, alpha_outer, alpha_inner = _pair_tangents(
            centres[a, 0], centres[a, 1], radii[a], centres[b, 0], centres[b, 1], radii[b],
            tol)
        angle_i[k], angle_j[k] = _kind_angles(phi, alpha_outer, alpha_inner, kind[k])
    return angle_i, angle_j


# -- the graph (.geometric) ------------------------------------------------------------


@njit(cache=True)
def arcs_free(start, sweep, lo, hi, centres, halves):
    """``(A,)``: whether each ccw arc ``(start, start + sweep)`` of a circle misses every
    forbidden interval of that circle, ``centres[lo[a]:hi[a]]`` and ``halves`` likewise
    (:func:`.geometric._arc_free`, the same arithmetic)."""
    two_pi = 2.0 * math.pi
    free = np.ones(len(start), np.bool_)
    for a in range(len(start)):
        for m in range(lo[a], hi[a]):
            half = halves[m]
            if half >= math.pi:
                free[a] = False
                break
            s = (centres[m] - half - start[a]) % two_pi
            if s < sweep[a] - 1e-9 or s + 2 * half > two_pi + 1e-9:
                free[a] = False
                break
    return free


@njit(cache=True)
def _less(d1, n1, d2, n2):
    return d1 < d2 or (d1 == d2 and n1 < n2)


@njit(cache=True)
def dijkstra(indptr, indices, weights, straight, source, leg_penalty):
    """Dijkstra over a graph in CSR form, as :meth:`.geometric._Graph.dijkstra` runs it
    over its lists (the same relaxation, and a binary heap of ``(distance, node)`` that
    sifts as Python's heapq does, so ties fall alike): distances, predecessors and the
    edge each node was reached by (-1: none)."""
    n = len(indptr) - 1
    dist = np.full(n, np.inf)
    prev = np.full(n, -1, np.int64)
    via = np.full(n, -1, np.int64)
    done = np.zeros(n, np.bool_)
    hd = np.empty(len(indices) + 1)
    hn = np.empty(len(indices) + 1, np.int64)
    size = 0
    dist[source] = 0.0
    hd[0], hn[0] = 0.0, source
    size = 1
    while size:
        # heappop: the last item replaces the root, then _siftup (to a leaf, then down)
        d, u = hd[0], hn[0]
        size -= 1
        if size:
            ld, ln = hd[size], hn[size]
            pos, end = 0, size
            child = 1
            while child < end:
                right = child + 1
                if right < end and not _less(hd[child], hn[child], hd[right], hn[right]):
                    child = right
                hd[pos], hn[pos] = hd[child], hn[child]
                pos = child
                child = 2 * pos + 1
            hd[pos], hn[pos] = ld, ln
            while pos > 0:  # _siftdown(heap, 0, pos)
                parent = (pos - 1) >> 1
                if _less(ld, ln, hd[parent], hn[parent]):
                    hd[pos], hn[pos] = hd[parent], hn[parent]
                    pos = parent
                    continue
                break
            hd[pos], hn[pos] = ld, ln
        if done[u]:
            continue
        done[u] = True
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            nd = d + weights[e] + (leg_penalty if straight[e] else 0.0)
            if nd < dist[v] - 1e-12:
                dist[v], prev[v], via[v] = nd, u, e
                # heappush: append, then _siftdown(heap, 0, size)
                pos = size
                size += 1
                while pos > 0:
                    parent = (pos - 1) >> 1
                    if _less(nd, v, hd[parent], hn[parent]):
                        hd[pos], hn[pos] = hd[parent], hn[parent]
                        pos = parent
                        continue
                    break
                hd[pos], hn[pos] = nd, v
    return dist, prev, via
