"""The centroid's free space: the area shrunk by the formation, minus one disc per UAV
and cylinder, and what those discs cover of each other.

A formation whose centroid follows a path keeps UAV ``n`` at ``centroid + offset_n``.
UAV ``n`` clears cylinder ``k`` when its horizontal distance to the axis exceeds
``R_k + clearance``; in centroid coordinates that is the centroid staying outside the disc
of radius ``R_k + clearance`` centred at ``c_k - offset_n``. The obstacle the *centroid*
must avoid is therefore, for every cylinder, the union of N such discs (one per UAV), and
every UAV stays inside the area when the centroid stays inside the area shrunk by the
formation's extent (:func:`centroid_rectangle`, :meth:`PlanningProblem.bounds`).

- :func:`formation_discs` -> :class:`Discs`, those on the rim of each cylinder's blob;
- which discs touch (:func:`_touching_pairs`: a sort, a grid, or compiled);
- which arcs of each circle lie inside another disc or outside the rectangle
  (:func:`_covered_arcs`, :func:`_forbidden_intervals`), on which the tangent graph's
  arcs are judged (:mod:`.geometric`) and its tangent points cut (:mod:`.tangents`).

All arrays are metres ENU; angles in radians, counter-clockwise from east.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..compiling import cheap
from .problem import PlanningProblem

TOL = 1e-9
"""The geometric tests' tolerance (metres; relative where it scales a radius)."""
TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class Discs:
    """The centroid's obstacles: ``centres (C, 2)``, ``radii (C,)``, ``cylinder (C,)`` and
    ``uav (C,)`` (which cylinder and which UAV each disc stands for, 0-based)."""

    centres: np.ndarray
    radii: np.ndarray
    cylinder: np.ndarray
    uav: np.ndarray



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
                              2.0 * float(radii.max()) + 1e-6, TOL)
        rim = rim if rim.any() else keep  # every circle covered: none dropped (as below)
        return Discs(centres[rim], radii[rim], cylinder[rim], uav[rim])
    i, j = _touching_pairs(centres, radii)
    dist = np.hypot(*(centres[j] - centres[i]).T)
    # disc i inside disc j (for equal discs keep the first one)
    inside = dist + radii[i] <= radii[j] + TOL
    both = dist + radii[j] <= radii[i] + TOL  # and j inside i: equal discs
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
test_discs.py), and a plan whose first tangent graph loaded numba finds the seed
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
        a = (centre - half) % TWO_PI
        spans.append((a, a + 2 * half))
    spans.sort()
    # walk once around from the first span's start, unwrapping the spans that wrap
    begin, reach = spans[0][0], spans[0][1]
    for a, b in spans[1:] + [(a + TWO_PI, b + TWO_PI) for a, b in spans]:
        if a >= reach - 1e-9:
            return False
        reach = max(reach, b)
        if reach > begin + TWO_PI + 1e-9:
            return True
    return False


def centroid_rectangle(problem: PlanningProblem) -> tuple[np.ndarray, np.ndarray]:
    """Where the centroid may go so every UAV stays in the area: ``(lower (2,), upper (2,))``."""
    lower, upper = problem.bounds()
    return lower[0, :2], upper[0, :2]



def _in_rectangle(points: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    tol = TOL * (1 + np.abs(upper - lower))
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

