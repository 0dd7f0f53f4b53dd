"""Shortest horizontal routes around the formation-inflated obstacles: bound and seeds.

A formation whose centroid follows a path keeps UAV ``n`` at ``centroid + offset_n``.
UAV ``n`` clears cylinder ``k`` when its horizontal distance to the axis exceeds
``R_k + clearance``; in centroid coordinates that is the centroid staying outside the disc
of radius ``R_k + clearance`` centred at ``c_k - offset_n``. The obstacle the *centroid*
must avoid is therefore, for every cylinder, the union of N such discs (one per UAV), and
every UAV stays inside the area when the centroid stays inside the area shrunk by the
formation's extent (:meth:`PlanningProblem.bounds`).

The shortest centroid path in that free space (a rectangle minus discs) is a taut string:
straight segments tangent to the discs and arcs along them, never bending at the
rectangle's sides or where two discs cross (those corners point away from the free
space). It is found exactly by Dijkstra on the tangent visibility graph: start, goal, the
tangent points of every start/goal-to-disc tangent and of every inner and outer
bitangent between two discs, joined by the tangent segments that enter no disc and stay
in the rectangle, and by the arcs between neighbouring tangent points on a disc that
enter no other disc and stay in the rectangle.

- :func:`shortest_route` -> :class:`Route` or ``None`` when the formation cannot pass;
- :func:`shortest_routes` -> the shortest and a few alternative routes;
- :func:`lower_bound` -> the shortest length any feasible centroid path can have.

:mod:`.seeds` turns routes into waypoints for the seeded planner.

All arrays are metres ENU; angles in radians, counter-clockwise from east.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass

import numpy as np

from ..compiling import cheap
from .problem import PlanningProblem

_TOL = 1e-9
_TWO_PI = 2.0 * math.pi
_EDGE_CHUNK = 1 << 16  # segments checked against all discs at once (bounded memory)
_ALTERNATIVE_TRIES = 400  # graph nodes tried for alternative routes


@dataclass(frozen=True)
class Discs:
    """The centroid's obstacles: ``centres (C, 2)``, ``radii (C,)``, ``cylinder (C,)`` and
    ``uav (C,)`` (which cylinder and which UAV each disc stands for, 0-based)."""

    centres: np.ndarray
    radii: np.ndarray
    cylinder: np.ndarray
    uav: np.ndarray


@dataclass(frozen=True)
class Arc:
    """An arc of disc ``disc`` from angle ``start`` sweeping ``sweep`` (signed, ccw > 0)."""

    disc: int
    start: float
    sweep: float


@dataclass(frozen=True)
class Route:
    """A horizontal centroid route from start to goal.

    ``length``: metres. ``nodes``: ``(Q, 2)`` the graph nodes passed (start, tangent
    points, goal). ``arcs``: for each of the ``Q-1`` legs, the :class:`Arc` followed or
    ``None`` for a straight segment. ``discs``: the discs the route was computed for.
    """

    length: float
    nodes: np.ndarray
    arcs: tuple[Arc | None, ...]
    discs: Discs

    def polyline(self, *, step_rad: float = 0.05) -> np.ndarray:
        """The route as a dense polyline ``(P, 2)``, arcs sampled every ``step_rad``."""
        points = [self.nodes[0]]
        for i, arc in enumerate(self.arcs):
            if arc is not None:
                c, r = self.discs.centres[arc.disc], self.discs.radii[arc.disc]
                count = max(int(abs(arc.sweep) / step_rad), 1)
                angles = arc.start + arc.sweep * np.arange(1, count) / count
                points.extend(c + r * np.column_stack([np.cos(angles), np.sin(angles)]))
            points.append(self.nodes[i + 1])
        return np.array(points)


def formation_discs(problem: PlanningProblem, *, margin: float = 0.0) -> Discs:
    """One disc per (UAV, cylinder): centre ``c_k - offset_n``, radius ``R_k + clearance``.

    ``margin`` (metres) is added to every radius. Duplicates (UAVs stacked at one
    horizontal offset), discs inside another disc and discs whose whole circle lies inside
    other discs or outside the centroid's rectangle are dropped: they change nothing (a
    path from outside can enter such a disc only across its circle, through another
    disc). In a formation of many UAVs that leaves the discs on the rim of each
    cylinder's blob, which keeps the graph's bitangents few.
    """
    N, K = problem.uav_count, len(problem.radii)
    if K == 0:
        empty = np.zeros(0, int)
        return Discs(np.zeros((0, 2)), np.zeros(0), empty, empty)
    centres = (problem.centres[None, :, :] - problem.offsets[:, None, :2]).reshape(-1, 2)
    radii = np.tile(problem.radii + margin, N)
    cylinder = np.tile(np.arange(K), N)
    uav = np.repeat(np.arange(N), K)
    lower, upper = centroid_rectangle(problem)
    if len(radii) >= COMPILED_RIM_FROM or (len(radii) >= COMPILED_RIM_LOADED_FROM
                                           and cheap(_rim_discs)):
        from ._geometric_jit import rim_discs

        keep, rim = rim_discs(np.ascontiguousarray(centres, float), radii,
                              np.asarray(lower, float), np.asarray(upper, float),
                              2.0 * float(radii.max()) + 1e-6, _TOL)
        rim = rim if rim.any() else keep  # every circle covered: none dropped (as below)
        return Discs(centres[rim], radii[rim], cylinder[rim], uav[rim])
    i, j = _touching_pairs(centres, radii)
    dist = np.hypot(*(centres[j] - centres[i]).T)
    # disc i inside disc j (for equal discs keep the first one)
    inside = dist + radii[i] <= radii[j] + _TOL
    both = dist + radii[j] <= radii[i] + _TOL  # and j inside i: equal discs
    drop = np.zeros(len(radii), bool)
    drop[i[inside & ~both]] = True
    drop[i[inside & both & (i > j)]] = True
    keep = ~drop
    discs = Discs(centres[keep], radii[keep], cylinder[keep], uav[keep])
    # the kept discs' touching pairs are the kept pairs (renumbered), not a second search
    both_kept = keep[i] & keep[j]
    number = np.cumsum(keep) - 1
    pairs = number[i[both_kept]], number[j[both_kept]]
    covered = np.array([_circle_covered(iv) for iv in _forbidden_intervals(
        discs, lower, upper, pairs=pairs)], bool)
    if covered.any() and not covered.all():
        discs = Discs(discs.centres[~covered], discs.radii[~covered],
                      discs.cylinder[~covered], discs.uav[~covered])
    return discs


def _rim_discs():
    from ._geometric_jit import rim_discs

    return rim_discs


COMPILED_RIM_FROM = 5000
"""Discs (UAVs x cylinders) from which :func:`formation_discs` finds the discs it keeps
compiled (:func:`._geometric_jit.rim_discs`), not through arrays of every touching pair
(200 UAVs among 320 trees: 64,000 discs, 10.8 million pairs: 4.8 s in numpy, 0.7 s
compiled; 50 UAVs among 320 trees, 16,000 discs: 0.35 s and 0.06 s)."""
COMPILED_RIM_LOADED_FROM = 500
"""Discs from which :func:`formation_discs` keeps its discs compiled when numba is loaded
already and the loop cached (:func:`..compiling.cheap`): the same discs (tests/planning/
test_geometric.py), and a plan whose first tangent graph loaded numba finds the seed
routes' discs without a Python walk around each circle (10 UAVs among 320 trees: 3,200
discs, 0.06 s in numpy, some 5 ms compiled)."""

GRID_PAIRS_FROM = 2000
"""Discs from which :func:`_touching_pairs` finds its candidates in a grid, not a sort
by east (a formation of 200 UAVs turns 320 trees into 64,000 discs: the east sort's
windows hold 160 million candidates, 14 GB; the grid's neighbourhoods 15 million)."""


COMPILED_PAIRS_FROM = 20_000
"""Discs from which :func:`_touching_pairs` runs compiled (:func:`._geometric_jit.
touching_pairs`: the grid's pairs without its candidate arrays; 200 UAVs among 320 trees,
64,000 discs: 6.6 s in numpy's arrays)."""


def _touching_pairs(centres: np.ndarray, radii: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every ordered pair ``(i, j)``, ``i != j``, of discs ``centres (C, 2)``, ``radii (C,)``
    that touch or overlap (``d <= r_i + r_j``, a hair wider), found through a sort by
    east, or a grid from :data:`GRID_PAIRS_FROM` discs, not a ``(C, C)`` matrix."""
    C = len(radii)
    if C < 2:
        return np.zeros(0, int), np.zeros(0, int)
    if C >= COMPILED_PAIRS_FROM:
        from ._geometric_jit import touching_pairs

        return touching_pairs(np.ascontiguousarray(centres, float),
                              np.ascontiguousarray(radii, float), 2.0 * float(radii.max()) + 1e-6)
    if C >= GRID_PAIRS_FROM:
        return _touching_pairs_grid(centres, radii)
    order = np.argsort(centres[:, 0], kind="stable")
    xs = centres[order, 0]
    reach = radii[order] + radii.max() + 1e-6
    lo = np.searchsorted(xs, xs - reach, side="left")
    hi = np.searchsorted(xs, xs + reach, side="right")
    a, b = _ranges(lo, hi)
    i, j = order[a], order[b]
    return _touching(centres, radii, i, j)


def _ranges(lo: np.ndarray, hi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each ``k``, every ``m`` in ``[lo[k], hi[k])``: the pairs ``(k, m)`` as two arrays."""
    counts = hi - lo
    a = np.repeat(np.arange(len(lo)), counts)
    b = lo[a] + (np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts))
    return a, b


def _touching(centres, radii, i, j) -> tuple[np.ndarray, np.ndarray]:
    keep = i != j
    i, j = i[keep], j[keep]
    d = np.hypot(*(centres[j] - centres[i]).T)
    near = d <= radii[i] + radii[j] + 1e-6
    return i[near], j[near]


def _touching_pairs_grid(centres: np.ndarray, radii: np.ndarray
                         ) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_touching_pairs` through square cells of twice the largest radius: two discs
    that touch lie in the same or neighbouring cells. The same pairs, ordered by ``i``
    then ``j``."""
    cell = 2.0 * float(radii.max()) + 1e-6
    ij = np.floor((centres - centres.min(axis=0)) / cell).astype(np.int64)
    width = int(ij[:, 0].max()) + 3  # a column of empty cells on either side
    key = (ij[:, 1] + 1) * width + (ij[:, 0] + 1)
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    pairs_i, pairs_j = [], []
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            target = sorted_key + dy * width + dx  # the neighbour cell of each disc
            lo = np.searchsorted(sorted_key, target, side="left")
            hi = np.searchsorted(sorted_key, target, side="right")
            step = max(1, int(len(lo) * 2e7 // max(int((hi - lo).sum()), 1)))
            for start in range(0, len(lo), step):  # bounded memory
                a, b = _ranges(lo[start:start + step], hi[start:start + step])
                i, j = _touching(centres, radii, order[a + start], order[b])
                pairs_i.append(i)
                pairs_j.append(j)
    i, j = np.concatenate(pairs_i), np.concatenate(pairs_j)
    by = np.lexsort((j, i))
    return i[by], j[by]


def _neighbours(discs: Discs, count: int = 6) -> np.ndarray:
    """Per disc, up to ``count`` of the discs that touch it, nearest first, then -1:
    ``(C + 1, count)``, the last row (index -1) all -1."""
    C = len(discs.radii)
    out = np.full((C + 1, count), -1)
    i, j = _touching_pairs(discs.centres, discs.radii)
    if not len(i):
        return out
    d = np.hypot(*(discs.centres[j] - discs.centres[i]).T)
    order = np.lexsort((d, i))
    i, j = i[order], j[order]
    start = np.searchsorted(i, i, side="left")
    rank = np.arange(len(i)) - start
    keep = rank < count
    out[i[keep], rank[keep]] = j[keep]
    return out


def _circle_covered(intervals) -> bool:
    """Whether the open angular intervals ``(centre, half_width)`` cover the whole
    circle, each point strictly inside one (overlaps of more than 1e-9 rad)."""
    if not intervals:
        return False
    spans = []
    for centre, half in intervals:
        if half >= math.pi:
            return True
        a = (centre - half) % _TWO_PI
        spans.append((a, a + 2 * half))
    spans.sort()
    # walk once around from the first span's start, unwrapping the spans that wrap
    begin, reach = spans[0][0], spans[0][1]
    for a, b in spans[1:] + [(a + _TWO_PI, b + _TWO_PI) for a, b in spans]:
        if a >= reach - 1e-9:
            return False
        reach = max(reach, b)
        if reach > begin + _TWO_PI + 1e-9:
            return True
    return False


def centroid_rectangle(problem: PlanningProblem) -> tuple[np.ndarray, np.ndarray]:
    """Where the centroid may go so every UAV stays in the area: ``(lower (2,), upper (2,))``."""
    lower, upper = problem.bounds()
    return lower[0, :2], upper[0, :2]


def segments_clear(p: np.ndarray, q: np.ndarray, discs: Discs, *,
                   first: np.ndarray | None = None) -> np.ndarray:
    """For segments ``p -> q`` (each ``(E, 2)``): True where no disc interior is entered.

    ``first`` (E, m), optional: per segment the discs most likely to block it (-1 for
    none), tested before the others; the same test, so the same answer, sooner."""
    clear = np.ones(len(p), bool)
    C = len(discs.radii)
    if C == 0 or len(p) == 0:
        return clear
    if len(p) * C >= GRID_CLEAR_FROM:  # the same test, walked through a grid, compiled
        return _clear_through_grid(p, q, discs)
    if first is not None and first.size and len(p) * C > _EDGE_CHUNK:
        for col in first.T:  # one candidate blocker per segment at a time
            has = np.flatnonzero(clear & (col >= 0))
            if not len(has):
                continue
            k = col[has]
            a, ab = p[has], q[has] - p[has]
            ac = discs.centres[k] - a
            seg2 = np.maximum((ab * ab).sum(-1), 1e-18)
            t = np.clip((ac * ab).sum(-1) / seg2, 0.0, 1.0)
            d = np.hypot(*(ac - t[:, None] * ab).T)
            clear[has[d < discs.radii[k] * (1 - _TOL) - _TOL]] = False
        rest = np.flatnonzero(clear)
        clear[rest] = segments_clear(p[rest], q[rest], discs)
        return clear
    if len(p) * C <= _EDGE_CHUNK:  # small: every segment against every disc at once
        a, b = p[:, None, :], q[:, None, :]
        ab = b - a
        ac = discs.centres[None, :, :] - a
        seg2 = np.maximum((ab * ab).sum(-1), 1e-18)
        t = np.clip((ac * ab).sum(-1) / seg2, 0.0, 1.0)
        d = np.hypot(*(ac - t[..., None] * ab).transpose(2, 0, 1))
        return (d >= discs.radii * (1 - _TOL) - _TOL).all(axis=1)
    # Many: one disc at a time against the segments still clear, after a bounding-box
    # test. Most candidate segments (bitangents of far-apart discs) are blocked by some
    # disc early, so the work shrinks quickly and memory stays O(segments).
    alive = np.arange(len(p))
    lo, hi = np.minimum(p, q), np.maximum(p, q)
    for k in np.random.default_rng(0).permutation(C):  # fixed order: deterministic
        c, r = discs.centres[k], discs.radii[k]
        near = alive[((lo[alive] < c + r) & (hi[alive] > c - r)).all(axis=1)]
        if not len(near):
            continue
        a, ab = p[near], q[near] - p[near]
        ac = c - a
        seg2 = np.maximum((ab * ab).sum(-1), 1e-18)
        t = np.clip((ac * ab).sum(-1) / seg2, 0.0, 1.0)
        d = np.hypot(*(ac - t[:, None] * ab).T)
        blocked = near[d < r * (1 - _TOL) - _TOL]
        if len(blocked):
            clear[blocked] = False
            alive = alive[clear[alive]]
    return clear


GRID_CLEAR_FROM = 2e6
"""Segments x discs from which :func:`segments_clear` walks each segment through a grid
of the discs, compiled (:mod:`._geometric_jit`; the tangent graph of 10 UAVs among 320
trees: 12 million candidate bitangents, 2,500 discs; the seeds' candidate links of the
dense 100-tree field). Below, numba's start-up costs more than the test."""


def _clear_through_grid(p: np.ndarray, q: np.ndarray, discs: Discs, grid=None) -> np.ndarray:
    from ._geometric_jit import clear_through_grid

    grid = _grid(discs) if grid is None else grid
    return clear_through_grid(np.ascontiguousarray(p, float), np.ascontiguousarray(q, float),
                              discs.centres, discs.radii, *grid, _TOL)


def _grid(discs: Discs):
    """The discs in square cells of twice their median radius (:mod:`._geometric_jit`):
    ``(starts, items, lo_east, lo_north, cell, nx, ny)``."""
    from ._geometric_jit import disc_grid

    centres, radii = discs.centres, discs.radii
    lo, hi = (centres - radii[:, None]).min(axis=0), (centres + radii[:, None]).max(axis=0)
    cell = max(2.0 * float(np.median(radii)), float((hi - lo).max()) / 2048.0)
    nx, ny = (int((hi - lo)[i] // cell) + 1 for i in range(2))
    starts, items = disc_grid(centres, radii, lo[0], lo[1], cell, nx, ny)
    return starts, items, float(lo[0]), float(lo[1]), cell, nx, ny


ARRAY_GRAPH_FROM = 20_000
"""Graph nodes from which the tangent graph is held in arrays and searched compiled
(:mod:`._geometric_jit`: the same edges in the same order, the same heap), not in lists
of Python tuples (an orchard's way back across its rows: 100,000 nodes, 4.7 million heap
operations)."""
ARRAY_GRAPH_LOADED_FROM = 500
"""Graph nodes from which the graph is held in arrays and searched compiled when numba is
loaded already and the search cached (:func:`..compiling.cheap`): the same search, so the
same routes."""



def _graph_loops():
    from ._geometric_jit import arcs_free, dijkstra

    return arcs_free, dijkstra


CHUNKED_GRAPH_FROM = 250
"""Discs from which the tangent graph's candidate segments are made and tested compiled, a
chunk of disc pairs at a time (:func:`_clear_segments`), keeping only the clear ones:
2,500 discs make 12 million candidate bitangents, 2 GB at once; 300 discs (3 UAVs among
100 trees) 0.1 s a graph in arrays, some 10 ms compiled."""
_PAIR_CHUNK = 1 << 18
_VERDICT_CHUNKS = 64
"""Chunks of pairs judged in one compiled call: 16.8 million pairs, 67 MB of verdicts."""


def _clear_segments(discs: Discs, start: np.ndarray, goal: np.ndarray, lower, upper):
    """The clear candidate segments of the tangent graph, made a chunk at a time: tangent
    points ``t_disc``, ``t_angle`` (only those of clear segments), the segments' keys
    ``seg_p``, ``seg_q`` (-1 start, -2 goal, else an index into the tangent points) and
    their ends ``p``, ``q``. The segments :class:`_Graph` keeps from all candidates at once
    (the same tests), in another order."""
    grid = _grid(discs)
    marked = _buried_bins(discs)
    t_disc, t_angle, keys_p, keys_q, ps, qs = [], [], [], [], [], []
    count = 0

    def keep(pk, pq, disc_p, ang_p, disc_q, ang_q, fixed_p, fixed_q, *, tested=False):
        """Candidates from ``pk`` keys (-1, -2; or 0: the tangent ``disc_p``, ``ang_p``)
        to ``pq`` likewise; ``fixed_*``: the start's or goal's point where the key is < 0.
        ``tested``: the candidates are the clear ones already (:func:`_clear_bitangents`)."""
        nonlocal count
        if not tested:
            alive = np.ones(len(pk), bool)
            for keys, disc, ang in ((pk, disc_p, ang_p), (pq, disc_q, ang_q)):
                on = keys >= 0
                alive[on] &= ~_buried(discs, disc[on], ang[on], marked=marked)
            pk, pq = pk[alive], pq[alive]
            disc_p, ang_p = disc_p[alive], ang_p[alive]
            disc_q, ang_q = disc_q[alive], ang_q[alive]
        p = np.where((pk >= 0)[:, None], _on_circle(discs, disc_p, ang_p), fixed_p)
        q = np.where((pq >= 0)[:, None], _on_circle(discs, disc_q, ang_q), fixed_q)
        if tested:
            ok = np.ones(len(pk), bool)
        else:
            ok = _in_rectangle(p, lower, upper) & _in_rectangle(q, lower, upper)
            ok[ok] = _clear_through_grid(p[ok], q[ok], discs, grid)
        for keys, disc, ang in ((pk, disc_p, ang_p), (pq, disc_q, ang_q)):
            on = ok & (keys >= 0)
            keys[on] = count + np.arange(on.sum())
            count += int(on.sum())
            t_disc.append(disc[on])
            t_angle.append(ang[on])
        keys_p.append(pk[ok])
        keys_q.append(pq[ok])
        ps.append(p[ok])
        qs.append(q[ok])

    for key, point in ((-1, start), (-2, goal)):
        disc, angle = _point_tangents(point, discs)
        n = len(disc)
        keep(np.full(n, key), np.zeros(n, int), disc, angle, disc, angle, point, point)
    for di, ai, dj, aj, _kind in _known_bitangents(discs, marked, grid, lower, upper):
        n = len(di)
        keep(np.zeros(n, int), np.zeros(n, int), di, ai, dj, aj, start, goal, tested=True)
    none = np.zeros(1, int)
    keep(np.array([-1]), np.array([-2]), none, np.zeros(1), none, np.zeros(1), start, goal)
    return (np.concatenate(t_disc), np.concatenate(t_angle), np.concatenate(keys_p),
            np.concatenate(keys_q), np.concatenate(ps), np.concatenate(qs))


_LAST_BITANGENTS: list = []  # [(key, chunks)]: the last disc set's clear bitangents
GROWN_REUSE_M = 0.05
"""Discs grown by at most this much (the seed routes' margin, :func:`.seeds.seed_margin`)
have their tangent graph made from the clear bitangents of the discs themselves."""


def _known_bitangents(discs: Discs, marked, grid, lower, upper) -> list:
    """:func:`_clear_bitangents` as a list, kept for the last set of discs and rectangle:
    the tangent graphs of one problem with other starts and goals (every copter's way home
    among the same trees, ``planning/homeward.py``) share them.

    The same discs grown by a few millimetres (:func:`straighter_routes`' seed margin)
    test only the bitangents clear among the discs themselves, again at the grown radii
    (:func:`._geometric_jit.candidate_verdicts`): growing every disc clears no bitangent
    that was blocked by more than the growth, so the graph misses only those that grazed a
    third disc within it, and it serves seed routes, never the bound. The 10-UAV formation
    among 320 trees: 0.26 s -> some 10 ms for that graph."""
    rect = (np.asarray(lower, float).tobytes(), np.asarray(upper, float).tobytes())
    key = (discs.centres.tobytes(), discs.radii.tobytes(), *rect)
    if _LAST_BITANGENTS and _LAST_BITANGENTS[0][0] == key:
        return _LAST_BITANGENTS[0][1]
    if _LAST_BITANGENTS and _LAST_BITANGENTS[0][0][0] == key[0] \
            and _LAST_BITANGENTS[0][0][2:] == key[2:]:
        before = np.frombuffer(_LAST_BITANGENTS[0][0][1], float)
        growth = discs.radii - before if len(before) == len(discs.radii) else None
        if (growth is not None and len(growth) and np.all(growth >= 0)
                and np.ptp(growth) <= 1e-12 and growth.max() <= GROWN_REUSE_M):
            return list(_regrown(discs, marked, grid, lower, upper,
                                 _LAST_BITANGENTS[0][1]))  # (the smaller discs' kept)
    chunks = list(_clear_bitangents(discs, marked, grid, lower, upper))
    _LAST_BITANGENTS[:] = [(key, chunks)]
    return chunks


def _regrown(discs: Discs, marked, grid, lower, upper, chunks):
    """The bitangents of ``chunks`` (clear among the same discs a little smaller) that
    are clear among ``discs``, in their order, as :func:`_clear_bitangents` gives them."""
    from ._geometric_jit import bitangent_angles, candidate_verdicts

    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    for i, _ai, j, _aj, kind in chunks:
        ok = candidate_verdicts(i, j, kind, discs.centres, discs.radii, marked, lower, upper,
                                *grid, _TOL)
        i, j, kind = i[ok], j[ok], kind[ok]
        angle_i, angle_j = bitangent_angles(i, j, kind, discs.centres, discs.radii, _TOL)
        yield i, angle_i, j, angle_j, kind


def _clear_bitangents(discs: Discs, marked, grid, lower, upper):
    """The clear bitangents of every disc pair, a chunk of :data:`_PAIR_CHUNK` pairs of
    ``np.triu_indices(C, 1)``'s order at a time, each as (disc_i, angle_i, disc_j,
    angle_j, kind) in :func:`_bitangents`' order: the tests of :func:`_clear_segments`' ``keep``
    (ends not buried, in the rectangle, the segment clear) made compiled in one pass over
    :data:`_VERDICT_CHUNKS` chunks (:func:`._geometric_jit.bitangent_verdicts`), and the
    angles made again for the clear ones only (:func:`._geometric_jit.bitangent_angles`):
    no array of every candidate."""
    from ._geometric_jit import bitangent_angles, bitangent_verdicts, pair_rows

    C = len(discs.radii)
    before = pair_rows(C)
    pairs = C * (C - 1) // 2
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    span = _PAIR_CHUNK * _VERDICT_CHUNKS
    for begin in range(0, pairs, span):
        end = min(begin + span, pairs)
        ok = bitangent_verdicts(begin, end, discs.centres, discs.radii, marked, lower, upper,
                                *grid, _TOL)
        for a in range(0, end - begin, _PAIR_CHUNK):
            part = ok[:, a:a + _PAIR_CHUNK]
            kind, at = np.nonzero(part)  # kind-major, pairs in order: _bitangents' order
            k = begin + a + at
            i = np.searchsorted(before, k, side="right") - 1
            j = k - before[i] + i + 1
            angle_i, angle_j = bitangent_angles(i, j, kind, discs.centres, discs.radii, _TOL)
            yield i, angle_i, j, angle_j, kind


def _in_rectangle(points: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    tol = _TOL * (1 + np.abs(upper - lower))
    return ((points >= lower - tol) & (points <= upper + tol)).all(axis=-1)


def _forbidden_intervals(discs: Discs, lower, upper, *, pairs=None
                         ) -> list[list[tuple[float, float]]]:
    """Per disc, angular intervals ``(centre, half_width)`` of its circle that lie inside
    another disc or outside the rectangle (open intervals); ``pairs``: the discs'
    touching pairs when known (:func:`_touching_pairs`)."""
    first, centre, half = _forbidden_arrays(discs, lower, upper, pairs=pairs)
    return [[(float(c), float(h)) for c, h in zip(centre[a:b], half[a:b])]
            for a, b in zip(first[:-1], first[1:])]


def _forbidden_arrays(discs: Discs, lower, upper, *, pairs=None
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_forbidden_intervals` as arrays: disc ``c``'s intervals are
    ``centre[first[c]:first[c + 1]]`` and ``half`` likewise (``first (C + 1,)``), the
    arcs inside other discs first, then the rectangle's sides west, east, south, north."""
    C = len(discs.radii)
    idx, centre, half = _covered_arcs(discs, pairs=pairs)
    parts_i, parts_c, parts_h = [idx], [centre], [half]
    r = discs.radii
    for normal_angle, h in ((math.pi, discs.centres[:, 0] - lower[0]),
                            (0.0, upper[0] - discs.centres[:, 0]),
                            (-0.5 * math.pi, discs.centres[:, 1] - lower[1]),
                            (0.5 * math.pi, upper[1] - discs.centres[:, 1])):
        beyond = np.flatnonzero(h <= -r)  # the whole circle beyond the side
        cut = np.flatnonzero((h < r) & (h > -r))
        k = np.concatenate([beyond, cut])
        parts_i.append(k)
        parts_c.append(np.concatenate([np.zeros(len(beyond)), np.full(len(cut), normal_angle)]))
        # math.acos, one by one: the few discs a side cuts
        parts_h.append(np.array([math.pi] * len(beyond)
                                + [math.acos(x) for x in (h[cut] / r[cut]).tolist()], float))
    i, c, hw = (np.concatenate(x) for x in (parts_i, parts_c, parts_h))
    by = np.argsort(i, kind="stable")
    first = np.concatenate([[0], np.cumsum(np.bincount(i, minlength=C))]).astype(np.int64)
    return first, c[by].astype(float), hw[by].astype(float)


def _covered_arcs(discs: Discs, *, pairs=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The arcs of each disc's circle inside another disc (open): ``disc (A,)``,
    ``centre (A,)`` angle and ``half (A,)`` width, ``half = pi`` for a whole circle
    (``pairs``: the touching pairs, when known)."""
    i, j = _touching_pairs(discs.centres, discs.radii) if pairs is None else pairs
    v = discs.centres[j] - discs.centres[i]
    d = np.hypot(v[:, 0], v[:, 1])
    ri, rj = discs.radii[i], discs.radii[j]
    # apart, or j inside i: j does not cover i's circle
    cover = ~((d >= ri + rj) | (d + rj <= ri))
    whole = cover & (d + ri <= rj)  # i's whole circle inside j
    part = cover & ~whole
    with np.errstate(divide="ignore", invalid="ignore"):
        cos_a = (ri * ri + d * d - rj * rj) / (2 * ri * d)
    half = np.arccos(np.clip(np.where(part, cos_a, 1.0), -1.0, 1.0))
    centre = np.where(whole, 0.0, np.arctan2(v[:, 1], v[:, 0]))
    half = np.where(whole, math.pi, half)
    return i[cover], centre[cover], half[cover]


def _buried(discs: Discs, disc: np.ndarray, angle: np.ndarray, *, bins: int = 64,
            margin: float = 1e-3, marked: np.ndarray | None = None) -> np.ndarray:
    """Which tangent points ``(disc, angle)`` (T,) lie well inside another disc: those in
    an angular bin (``bins`` per circle) wholly inside a covered arc shrunk by ``margin``
    radians at both ends. Every segment from such a point enters that disc; a quick
    first cut before :func:`segments_clear`, never a verdict on a point near an edge.
    ``marked``: :func:`_buried_bins`, when already known."""
    if marked is None:
        marked = _buried_bins(discs, bins=bins, margin=margin)
    width = _TWO_PI / bins
    k = np.floor((angle % _TWO_PI) / width).astype(int) % bins
    return marked[disc, k]


def _buried_bins(discs: Discs, *, bins: int = 64, margin: float = 1e-3) -> np.ndarray:
    """``(C, bins)``: the angular bins of each circle wholly inside a covered arc shrunk by
    ``margin`` (see :func:`_buried`)."""
    C = len(discs.radii)
    idx, centre, half = _covered_arcs(discs)
    width = _TWO_PI / bins
    begin = (centre - half + margin) % _TWO_PI
    first = np.ceil(begin / width).astype(int)
    last = np.floor((begin + 2 * (half - margin)) / width).astype(int) - 1  # inclusive
    whole = half >= math.pi
    first[whole], last[whole] = 0, bins - 1
    ok = last >= first
    diff = np.zeros((C, 2 * bins + 1), int)
    np.add.at(diff, (idx[ok], first[ok]), 1)
    np.add.at(diff, (idx[ok], np.minimum(last[ok] + 1, 2 * bins)), -1)
    run = np.cumsum(diff, axis=1)
    return (run[:, :bins] + run[:, bins:2 * bins]) > 0


def _arc_free(start: float, sweep: float, intervals) -> bool:
    """Whether the ccw arc ``(start, start + sweep)`` misses every forbidden interval."""
    for centre, half in intervals:
        if half >= math.pi:
            return False
        s = (centre - half - start) % _TWO_PI
        if s < sweep - 1e-9 or s + 2 * half > _TWO_PI + 1e-9:
            return False
    return True


def _point_tangents(p: np.ndarray, discs: Discs):
    """Tangent points from ``p (2,)`` to every disc it is outside of: (disc, angle) pairs."""
    v = p - discs.centres
    d = np.hypot(v[:, 0], v[:, 1])
    ok = d > discs.radii
    phi = np.arctan2(v[:, 1], v[:, 0])
    alpha = np.arccos(np.clip(discs.radii / np.where(ok, d, 1.0), -1, 1))
    idx = np.nonzero(ok)[0]
    angles = np.concatenate([phi[idx] + alpha[idx], phi[idx] - alpha[idx]])
    return np.concatenate([idx, idx]), angles


def _bitangents(discs: Discs, pairs: tuple[np.ndarray, np.ndarray] | None = None):
    """Inner and outer bitangents of every disc pair (or of the ``pairs`` ``(i, j)``
    given): (disc_i, angle_i, disc_j, angle_j)."""
    C = len(discs.radii)
    i, j = np.triu_indices(C, 1) if pairs is None else pairs
    v = discs.centres[j] - discs.centres[i]
    d = np.hypot(v[:, 0], v[:, 1])
    phi = np.arctan2(v[:, 1], v[:, 0])
    ri, rj = discs.radii[i], discs.radii[j]
    parts = []
    outer = d > np.abs(ri - rj) + _TOL
    a = np.arccos(np.clip((ri - rj) / np.where(outer, d, 1.0), -1, 1))
    for sign in (1.0, -1.0):
        ang = phi + sign * a
        parts.append((i[outer], ang[outer], j[outer], ang[outer]))
    inner = d > ri + rj + _TOL
    a = np.arccos(np.clip((ri + rj) / np.where(inner, d, 1.0), -1, 1))
    for sign in (1.0, -1.0):
        ang = phi + sign * a
        parts.append((i[inner], ang[inner], j[inner], ang[inner] + math.pi))
    return tuple(np.concatenate(p) for p in zip(*parts))


def _on_circle(discs: Discs, disc: np.ndarray, angle: np.ndarray) -> np.ndarray:
    return discs.centres[disc] + discs.radii[disc, None] * np.column_stack(
        [np.cos(angle), np.sin(angle)]
    )


def _all_segments(discs: Discs, start: np.ndarray, goal: np.ndarray, lower, upper):
    """The clear candidate segments of the tangent graph, all candidates made at once:
    ``t_disc``, ``t_angle`` (every candidate's tangent points), ``seg_p``, ``seg_q`` (-1
    start, -2 goal, else an index into them), the ends ``p``, ``q`` and ``t_point``."""
    seg_p, seg_q = [], []  # node keys: -1 start, -2 goal, else index into tangent list
    t_disc, t_angle = [], []

    def add_tangents(disc, angle):
        base = sum(len(a) for a in t_angle)
        t_disc.append(np.asarray(disc, int))
        t_angle.append(np.asarray(angle, float))
        return base + np.arange(len(disc))

    for key, p in ((-1, start), (-2, goal)):
        disc, angle = _point_tangents(p, discs)
        ids = add_tangents(disc, angle)
        seg_p.append(np.full(len(ids), key))
        seg_q.append(ids)
    if len(discs.radii) > 1:
        di, ai, dj, aj = _bitangents(discs)
        seg_p.append(add_tangents(di, ai))
        seg_q.append(add_tangents(dj, aj))
    seg_p.append(np.array([-1]))
    seg_q.append(np.array([-2]))
    t_disc = np.concatenate(t_disc) if t_disc else np.zeros(0, int)
    t_angle = np.concatenate(t_angle) if t_angle else np.zeros(0)
    seg_p, seg_q = np.concatenate(seg_p), np.concatenate(seg_q)
    if len(t_disc):  # ends deep inside another disc: no segment from them is clear
        buried = np.append(_buried(discs, t_disc, t_angle), [False, False])
        alive = ~buried[seg_p] & ~buried[seg_q]  # keys -1, -2: start and goal
        seg_p, seg_q = seg_p[alive], seg_q[alive]
    # the points of the tangents still in question only (the rest stay at 0, unused)
    t_point = np.zeros((len(t_disc), 2))
    if len(t_disc):
        mark = np.zeros(len(t_disc), bool)  # (a mask: np.unique of millions is slow)
        mark[seg_p[seg_p >= 0]] = True
        mark[seg_q[seg_q >= 0]] = True
        wanted = np.flatnonzero(mark)
        t_point[wanted] = _on_circle(discs, t_disc[wanted], t_angle[wanted])

    def coords(keys):
        out = t_point[np.maximum(keys, 0)] if len(t_point) else np.zeros((len(keys), 2))
        out = out.copy()
        out[keys == -1] = start
        out[keys == -2] = goal
        return out

    p, q = coords(seg_p), coords(seg_q)
    ok = _in_rectangle(p, lower, upper) & _in_rectangle(q, lower, upper)
    # a segment from a disc's circle is most often blocked by that disc's neighbours
    near = _neighbours(discs)
    ends = np.concatenate([t_disc, [-1, -1]])  # keys -1, -2: start and goal
    first = np.concatenate([near[ends[seg_p]], near[ends[seg_q]]], axis=1)
    ok[ok] = segments_clear(p[ok], q[ok], discs, first=first[ok])
    seg_p, seg_q, p, q = seg_p[ok], seg_q[ok], p[ok], q[ok]
    return t_disc, t_angle, seg_p, seg_q, p, q, t_point


class _Graph:
    """The tangent visibility graph of one problem (built once, searched twice)."""

    def __init__(self, problem: PlanningProblem, discs: Discs) -> None:
        lower, upper = centroid_rectangle(problem)
        self.discs = discs
        start, goal = problem.start[:2].astype(float), problem.goal[:2].astype(float)
        if len(discs.radii) >= CHUNKED_GRAPH_FROM:
            t_disc, t_angle, seg_p, seg_q, p, q = _clear_segments(discs, start, goal, lower,
                                                                  upper)
            t_point = np.zeros((0, 2))
        else:
            t_disc, t_angle, seg_p, seg_q, p, q, t_point = _all_segments(discs, start, goal,
                                                                        lower, upper)
        self._build(start, goal, discs, lower, upper, t_disc, t_angle, seg_p, seg_q, p, q,
                    t_point)

    def _build(self, start, goal, discs, lower, upper, t_disc, t_angle, seg_p, seg_q, p, q,
               t_point) -> None:
        """The graph from the clear segments (keys into the tangent points ``t_disc``,
        ``t_angle``; -1 start, -2 goal) and the arcs between their ends."""
        if len(t_point) < len(t_disc):  # made a chunk at a time: only the kept tangents
            t_point = _on_circle(discs, t_disc, t_angle)
        # Nodes: 0 start, 1 goal, then every tangent point used by a valid segment.
        mark = np.zeros(len(t_disc), bool)  # the keys used, sorted (np.unique: slower)
        mark[seg_p[seg_p >= 0]] = True
        mark[seg_q[seg_q >= 0]] = True
        used = np.flatnonzero(mark)
        node_of = np.full(len(t_disc) + 2, -1)
        node_of[used] = 2 + np.arange(len(used))
        node_of[-1], node_of[-2] = 0, 1  # keys -1 and -2 index the end of the array
        self.points = np.vstack([start, goal, t_point[used]]) if len(used) else np.vstack(
            [start, goal])
        self.node_disc = np.concatenate([[-1, -1], t_disc[used]]).astype(int)
        self.node_angle = np.concatenate([[0.0, 0.0], t_angle[used] % _TWO_PI])
        lengths = np.hypot(*(q - p).T)
        a_seg, b_seg = node_of[seg_p], node_of[seg_q]
        # Arcs between neighbouring tangent points on each disc: the nodes of each disc in
        # angle order, each to the next and the last to the first
        order = np.lexsort((self.node_angle, self.node_disc))
        order = order[self.node_disc[order] >= 0]
        groups = np.flatnonzero(np.diff(self.node_disc[order])) + 1
        self._csr = None
        if len(self.points) >= ARRAY_GRAPH_FROM or (
                len(self.points) >= ARRAY_GRAPH_LOADED_FROM and cheap(_graph_loops)):
            self.edges = None
            self._arrays(a_seg, b_seg, lengths, order, groups,
                         _forbidden_arrays(discs, lower, upper), discs)
            return
        forbidden = _forbidden_intervals(discs, lower, upper)
        edges: list[list[tuple[int, float, Arc | None]]] = [[] for _ in range(len(self.points))]
        for a, b, w in zip(a_seg, b_seg, lengths):
            edges[a].append((b, float(w), None))
            edges[b].append((a, float(w), None))
        for on in np.split(order, groups):
            if len(on) < 2:
                continue
            disc = int(self.node_disc[on[0]])
            r = float(discs.radii[disc])
            for a, b in zip(on, np.roll(on, -1)):
                sweep = (self.node_angle[b] - self.node_angle[a]) % _TWO_PI
                if sweep <= 1e-12:  # the same point twice: a zero-length link
                    edges[a].append((int(b), 0.0, None))
                    edges[b].append((int(a), 0.0, None))
                    continue
                if not _arc_free(float(self.node_angle[a]), sweep, forbidden[disc]):
                    continue
                start_a = float(self.node_angle[a])
                edges[a].append((int(b), r * sweep, Arc(int(disc), start_a, sweep)))
                edges[b].append((int(a), r * sweep, Arc(int(disc), start_a + sweep, -sweep)))
        self.edges = edges

    def _arrays(self, a_seg, b_seg, lengths, order, groups, forbidden, discs) -> None:
        """The same edges as the lists of :meth:`_build`, in the same order per node, as
        arrays (CSR) for the compiled search (:data:`ARRAY_GRAPH_FROM`); ``forbidden``:
        :func:`_forbidden_arrays`."""
        from ._geometric_jit import arcs_free

        # each node's neighbour in angle order on its disc (groups of 2 or more)
        nxt = np.roll(order, -1)
        begin = np.concatenate([[0], groups])
        end = np.concatenate([groups, [len(order)]])
        nxt[end - 1] = order[begin]  # the last of a disc to its first
        size = np.repeat(end - begin, end - begin)
        a_arc, b_arc = order[size >= 2], nxt[size >= 2]
        disc = self.node_disc[a_arc]
        start_a = self.node_angle[a_arc]
        sweep = (self.node_angle[b_arc] - start_a) % _TWO_PI
        zero = sweep <= 1e-12
        first, iv_centre, iv_half = forbidden
        free = arcs_free(start_a, sweep, first[disc], first[disc + 1], iv_centre, iv_half)
        keep = zero | free
        a_arc, b_arc, disc, start_a = a_arc[keep], b_arc[keep], disc[keep], start_a[keep]
        sweep, zero = sweep[keep], zero[keep]
        weight_arc = np.where(zero, 0.0, discs.radii[disc] * sweep)
        # directed edges in the lists' order: a->b then b->a, the segments, then the arcs
        src = np.column_stack([np.concatenate([a_seg, a_arc]),
                               np.concatenate([b_seg, b_arc])]).ravel()
        dst = np.column_stack([np.concatenate([b_seg, b_arc]),
                               np.concatenate([a_seg, a_arc])]).ravel()
        w = np.repeat(np.concatenate([lengths, weight_arc]), 2)
        is_arc = np.repeat(np.concatenate([np.zeros(len(a_seg), bool), ~zero]), 2)
        arc_disc = np.repeat(np.concatenate([np.full(len(a_seg), -1), disc]), 2)
        arc_start = np.column_stack([np.concatenate([np.zeros(len(a_seg)), start_a]),
                                     np.concatenate([np.zeros(len(a_seg)), start_a + sweep])
                                     ]).ravel()
        arc_sweep = np.column_stack([np.concatenate([np.zeros(len(a_seg)), sweep]),
                                     np.concatenate([np.zeros(len(a_seg)), -sweep])]).ravel()
        by = np.argsort(src, kind="stable")
        indptr = np.concatenate([[0], np.cumsum(np.bincount(src, minlength=len(self.points)))])
        self._csr = (indptr.astype(np.int64), dst[by].astype(np.int64), w[by], ~is_arc[by])
        self._arc = (is_arc[by], arc_disc[by], arc_start[by], arc_sweep[by])

    def dijkstra(self, source: int, *, leg_penalty: float = 0.0
                 ) -> tuple[np.ndarray, np.ndarray, list]:
        """Distances, predecessors and arcs from ``source``; ``leg_penalty`` metres are
        added to every straight segment (routes with fewer legs)."""
        if self._csr is not None:
            from ._geometric_jit import dijkstra

            dist, prev, edge = dijkstra(*self._csr, source, float(leg_penalty))
            return dist, prev, _Via(edge, *self._arc)
        n = len(self.points)
        dist = np.full(n, np.inf)
        prev = np.full(n, -1)
        via: list[Arc | None] = [None] * n
        dist[source] = 0.0
        heap = [(0.0, source)]
        done = np.zeros(n, bool)
        while heap:
            d, u = heapq.heappop(heap)
            if done[u]:
                continue
            done[u] = True
            for v, w, arc in self.edges[u]:
                nd = d + w + (leg_penalty if arc is None else 0.0)
                if nd < dist[v] - 1e-12:
                    dist[v], prev[v], via[v] = nd, u, arc
                    heapq.heappush(heap, (nd, v))
        return dist, prev, via

    def route(self, nodes: list[int], arcs: list[Arc | None], length: float) -> Route:
        return Route(float(length), self.points[nodes], tuple(arcs), self.discs)


class _Via:
    """Per node, the :class:`Arc` it was reached along, or None (a straight segment): the
    compiled search's edges (:meth:`_Graph.dijkstra`) read as the lists' ``via``."""

    def __init__(self, edge, is_arc, disc, start, sweep) -> None:
        self.edge, self.is_arc, self.disc, self.start, self.sweep = (edge, is_arc, disc, start,
                                                                     sweep)

    def __getitem__(self, node: int) -> Arc | None:
        e = self.edge[node]
        if e < 0 or not self.is_arc[e]:
            return None
        return Arc(int(self.disc[e]), float(self.start[e]), float(self.sweep[e]))


def _walk(prev, via, end: int) -> tuple[list[int], list[Arc | None]]:
    """Nodes from the search's source to ``end`` and the arcs of the legs."""
    nodes, arcs = [end], []
    while prev[nodes[-1]] >= 0:
        arcs.append(via[nodes[-1]])
        nodes.append(int(prev[nodes[-1]]))
    return nodes[::-1], arcs[::-1]


def _reverse(arc: Arc | None) -> Arc | None:
    return None if arc is None else Arc(arc.disc, arc.start + arc.sweep, -arc.sweep)


def shortest_routes(
    problem: PlanningProblem, *, count: int = 1, margin: float = 0.0, spread: float = 0.25
) -> list[Route]:
    """Up to ``count`` short routes, the shortest first; ``[]`` when no route exists.

    The first is the exact shortest route. The others are the shortest routes through
    other graph nodes (start->node->goal, from one search from each end), kept when they
    pass a different sequence of discs and are at most ``1 + spread`` times longer:
    alternatives around the trees for seeding, not a ranked list of all routes.
    """
    graph = _Graph(problem, formation_discs(problem, margin=margin))
    from_start, prev_s, via_s = graph.dijkstra(0)
    if not np.isfinite(from_start[1]):
        return []
    nodes, arcs = _walk(prev_s, via_s, 1)
    routes = [graph.route(nodes, arcs, from_start[1])]
    if count <= 1:
        return routes
    from_goal, prev_g, via_g = graph.dijkstra(1)
    through = from_start + from_goal
    seen = {tuple(graph.node_disc[nodes])}
    for v in np.argsort(through)[:_ALTERNATIVE_TRIES]:
        if len(routes) >= count or through[v] > (1 + spread) * from_start[1]:
            break
        head_nodes, head_arcs = _walk(prev_s, via_s, int(v))
        tail_nodes, tail_arcs = _walk(prev_g, via_g, int(v))
        all_nodes = head_nodes + tail_nodes[::-1][1:]
        key = tuple(graph.node_disc[all_nodes])
        if key in seen:
            continue
        seen.add(key)
        all_arcs = head_arcs + [_reverse(a) for a in tail_arcs[::-1]]
        routes.append(graph.route(all_nodes, all_arcs, through[v]))
    return routes


def straighter_routes(problem: PlanningProblem, penalties, *, margin: float = 0.0):
    """For each penalty (metres), the shortest route when every straight leg costs that
    much more: routes with fewer, longer legs (for seeds with few waypoints). Yields
    :class:`Route` objects (true lengths), or nothing when no route exists."""
    graph = _Graph(problem, formation_discs(problem, margin=margin))
    for penalty in penalties:
        dist, prev, via = graph.dijkstra(0, leg_penalty=penalty)
        if not np.isfinite(dist[1]):
            return
        nodes, arcs = _walk(prev, via, 1)
        points = graph.points[nodes]
        length = sum(
            float(np.hypot(*(points[i + 1] - points[i]))) if arc is None
            else float(graph.discs.radii[arc.disc]) * abs(arc.sweep)
            for i, arc in enumerate(arcs)
        )
        yield graph.route(nodes, arcs, length)


def shortest_route(problem: PlanningProblem, *, margin: float = 0.0) -> Route | None:
    """The shortest horizontal centroid route, or ``None`` when the formation cannot pass."""
    routes = shortest_routes(problem, margin=margin)
    return routes[0] if routes else None


def lower_bound(problem: PlanningProblem, route: Route | None = None) -> float | None:
    """No feasible centroid path is shorter than this (metres); ``None``: no route exists.

    The shortest horizontal route, lifted by the start-goal altitude difference
    (``sqrt(L^2 + dz^2)``, the shortest 3D curve over it; equal to ``L`` when start and
    goal are at one altitude). Feasible paths keep a clearance strictly greater than the
    radii, so they are strictly longer; a plan can only approach the bound.
    """
    route = route if route is not None else shortest_route(problem)
    if route is None:
        return None
    dz = float(problem.goal[2] - problem.start[2])
    return math.hypot(route.length, dz)
