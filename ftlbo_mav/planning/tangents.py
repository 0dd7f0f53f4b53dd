"""The tangent graph's candidate segments and which of them are clear.

The shortest centroid path among the discs (:mod:`.discs`) is a taut string of straight
segments tangent to the discs and arcs along them (:mod:`.geometric`). Its candidate
segments are the start/goal-to-disc tangents and the inner and outer bitangents of every
two discs; a segment is kept when neither end lies deep inside another disc
(:func:`_buried`), both ends lie in the centroid's rectangle and it enters no disc
(:func:`segments_clear`). :func:`tangent_segments` gives the clear ones, all candidates
made at once (:func:`_all_segments`) or, among many discs, a chunk of disc pairs at a
time through a grid, compiled (:func:`_clear_segments`), the clear bitangents of the
last set of discs kept for the next graph among them (:func:`_known_bitangents`).

All arrays are metres ENU; angles in radians, counter-clockwise from east.
"""

from __future__ import annotations

import math

import numpy as np

from .discs import TOL, TWO_PI, Discs, _covered_arcs, _in_rectangle, _neighbours

_EDGE_CHUNK = 1 << 16  # segments checked against all discs at once (bounded memory)


def tangent_segments(discs: Discs, start: np.ndarray, goal: np.ndarray, lower, upper):
    """The clear candidate segments of the tangent graph from ``start (2,)`` to
    ``goal (2,)`` among ``discs`` in the rectangle ``lower``..``upper``: tangent points
    ``t_disc``, ``t_angle`` and ``t_point (T, 2)``, the segments' keys ``seg_p``,
    ``seg_q`` (-1 start, -2 goal, else an index into the tangent points) and their ends
    ``p``, ``q`` ``(E, 2)``; made a chunk at a time from :data:`CHUNKED_GRAPH_FROM`
    discs (then only the tangent points of clear segments), else all at once."""
    if len(discs.radii) >= CHUNKED_GRAPH_FROM:
        t_disc, t_angle, seg_p, seg_q, p, q = _clear_segments(discs, start, goal, lower,
                                                              upper)
        return t_disc, t_angle, _on_circle(discs, t_disc, t_angle), seg_p, seg_q, p, q
    t_disc, t_angle, seg_p, seg_q, p, q, t_point = _all_segments(discs, start, goal, lower,
                                                                upper)
    return t_disc, t_angle, t_point, seg_p, seg_q, p, q


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
            clear[has[d < discs.radii[k] * (1 - TOL) - TOL]] = False
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
        return (d >= discs.radii * (1 - TOL) - TOL).all(axis=1)
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
        blocked = near[d < r * (1 - TOL) - TOL]
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
                              discs.centres, discs.radii, *grid, TOL)


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
    their ends ``p``, ``q``. The segments :func:`_all_segments` keeps from all candidates
    at once (the same tests), in another order."""
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

    The same discs grown by a few millimetres (the seed routes' margin,
    :func:`.geometric.straighter_routes`) test only the bitangents clear among the discs
    themselves, again at the grown radii
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
                                *grid, TOL)
        i, j, kind = i[ok], j[ok], kind[ok]
        angle_i, angle_j = bitangent_angles(i, j, kind, discs.centres, discs.radii, TOL)
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
                                *grid, TOL)
        for a in range(0, end - begin, _PAIR_CHUNK):
            part = ok[:, a:a + _PAIR_CHUNK]
            kind, at = np.nonzero(part)  # kind-major, pairs in order: _bitangents' order
            k = begin + a + at
            i = np.searchsorted(before, k, side="right") - 1
            j = k - before[i] + i + 1
            angle_i, angle_j = bitangent_angles(i, j, kind, discs.centres, discs.radii, TOL)
            yield i, angle_i, j, angle_j, kind



def _buried(discs: Discs, disc: np.ndarray, angle: np.ndarray, *, bins: int = 64,
            margin: float = 1e-3, marked: np.ndarray | None = None) -> np.ndarray:
    """Which tangent points ``(disc, angle)`` (T,) lie well inside another disc: those in
    an angular bin (``bins`` per circle) wholly inside a covered arc shrunk by ``margin``
    radians at both ends. Every segment from such a point enters that disc; a quick
    first cut before :func:`segments_clear`, never a verdict on a point near an edge.
    ``marked``: :func:`_buried_bins`, when already known."""
    if marked is None:
        marked = _buried_bins(discs, bins=bins, margin=margin)
    width = TWO_PI / bins
    k = np.floor((angle % TWO_PI) / width).astype(int) % bins
    return marked[disc, k]


def _buried_bins(discs: Discs, *, bins: int = 64, margin: float = 1e-3) -> np.ndarray:
    """``(C, bins)``: the angular bins of each circle wholly inside a covered arc shrunk by
    ``margin`` (see :func:`_buried`)."""
    C = len(discs.radii)
    idx, centre, half = _covered_arcs(discs)
    width = TWO_PI / bins
    begin = (centre - half + margin) % TWO_PI
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
    outer = d > np.abs(ri - rj) + TOL
    a = np.arccos(np.clip((ri - rj) / np.where(outer, d, 1.0), -1, 1))
    for sign in (1.0, -1.0):
        ang = phi + sign * a
        parts.append((i[outer], ang[outer], j[outer], ang[outer]))
    inner = d > ri + rj + TOL
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
