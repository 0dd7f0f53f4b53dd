"""The rally-point search: one rally point per UAV, where RTL goes when it is nearer
than home (pure; the rules are in :mod:`.fence`'s notes and :func:`search_rally_points`).

Bounded (issue 51): each UAV's search stops after :data:`WORK_PER_UAV` elementary tests;
a UAV whose search stops there has no rally point (RTL goes home), which
:attr:`RallySearch.stopped` says, :mod:`.fence` writes in its notes (plan.json) and
``plan`` says on stderr. A search that ends within the bound chooses as the unbounded
one (docs/outputs.md, "The search is bounded")."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .rally_fans import Fans, outward_edges
from .rally_fans import convex_hull as _hull


class RallySettings(Protocol):
    """What the search reads of :class:`~.fence.FenceSettings` (metres)."""

    corner_cut_m: float
    margin_m: float
    rally_separation_m: float
    grid_m: float


def _norm(v: np.ndarray) -> np.ndarray:
    """The lengths of the vectors ``v`` (..., 2): the arithmetic of ``np.linalg.norm(v,
    axis=-1)`` (the squares summed in order, the square root), without its cost of a
    reduction over an axis of two."""
    x, y = v[..., 0], v[..., 1]
    return np.sqrt(x * x + y * y)


def _distances(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(n, m) distances between the points ``p`` (n, 2) and ``q`` (m, 2): :func:`_norm` of
    ``p[:, None] - q[None]``, from the coordinates' columns (no (n, m, 2) array)."""
    dx, dy = p[:, 0, None] - q[None, :, 0], p[:, 1, None] - q[None, :, 1]
    return np.sqrt(dx * dx + dy * dy)


def _segment_distance(q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distances from points ``q`` (..., 2) to segments ``a``-``b`` (..., 2), broadcast:
    the arithmetic of :func:`ftlbo_mav.geo.segment_distance`, a coordinate at a time
    (the same numbers, in half the time or less: no (..., 2) temporaries, no norm)."""
    abx, aby = b[..., 0] - a[..., 0], b[..., 1] - a[..., 1]
    denom = np.maximum(abx * abx + aby * aby, 1e-12)
    t = np.clip(((q[..., 0] - a[..., 0]) * abx + (q[..., 1] - a[..., 1]) * aby) / denom,
                0.0, 1.0)
    dx, dy = a[..., 0] + t * abx - q[..., 0], a[..., 1] + t * aby - q[..., 1]
    return np.sqrt(dx * dx + dy * dy)


def _densify(path: np.ndarray, step_m: float) -> np.ndarray:
    """Points along a polyline ``(n, 2)`` at most ``step_m`` apart, ends included."""
    out = [path[:1]]
    for a, b in zip(path[:-1], path[1:]):
        k = max(1, math.ceil(float(np.linalg.norm(b - a)) / step_m))
        out.append(a + (b - a) * (np.arange(1, k + 1) / k)[:, None])
    return np.concatenate(out)


def _near_box(points: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Mask of ``points`` (n, 2) inside the box ``lo``..``hi`` (2,), edges included."""
    return np.all((points >= lo) & (points <= hi), axis=1)


def _near_hull(queries: np.ndarray, points: np.ndarray, reach: float) -> np.ndarray:
    """Mask of ``queries`` (Q, 2) not farther than ``reach`` (a hair more) from the convex
    hull of ``points`` (n, 2): no query outside it is within ``reach`` of a segment
    between two of the points."""
    lo, hi = points.min(axis=0) - reach - 1e-6, points.max(axis=0) + reach + 1e-6
    near = _near_box(queries, lo, hi)
    hull = _hull(points)
    if len(hull) < 3 or not near.any():
        return near
    a, normal = outward_edges(hull)
    q = queries[near]
    beyond = ((q[:, None, :] - a[None]) * normal[None]).sum(-1) > reach + 1e-6
    near[np.flatnonzero(near)[beyond.any(axis=1)]] = False
    return near


def _box(axis: np.ndarray, centre: float, half: float) -> slice:
    """The indices of the sorted ``axis`` within ``half`` of ``centre`` (a hair wider)."""
    lo, hi = np.searchsorted(axis, [centre - half - 1e-6, centre + half + 1e-6])
    return slice(int(lo), int(hi) + 1)


def _grid_distance(xs: np.ndarray, ys: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(len(ys), len(xs)) distances from ``q`` (2,) to the cells of the grid ``xs`` by
    ``ys`` (as :func:`_norm` of each cell less ``q``, broadcast rather than meshed)."""
    dx, dy = xs - q[0], ys - q[1]
    return np.sqrt((dx * dx)[None, :] + (dy * dy)[:, None])


class _RallyGrid:
    """The rally search's candidates: a regular grid over the area (inset), those clear of
    the obstacles, served nearest-first around a goal in growing rings so that a search
    that stops early never sorts the whole field. The order is that of a stable sort of
    the whole grid by distance (ties in row-major order)."""

    def __init__(self, *, xs: np.ndarray, ys: np.ndarray, centres: np.ndarray,
                 radii: np.ndarray, clearance_m: float, step_m: float) -> None:
        self.xs, self.ys, self.step = xs, ys, step_m
        clear = np.ones((len(ys), len(xs)), bool)
        for c, r in zip(centres, radii):  # each obstacle blanks the cells of its box only
            reach = r + clearance_m
            ix, iy = _box(xs, c[0], reach), _box(ys, c[1], reach)
            clear[iy, ix] &= _grid_distance(xs[ix], ys[iy], c) >= reach
        self.clear = clear

    def stamp(self, count: np.ndarray, q: np.ndarray, radius_m: float, add: int) -> None:
        """Add ``add`` to ``count`` (ny, nx) at the cells closer than ``radius_m`` to
        ``q`` (2,)."""
        ix, iy = _box(self.xs, q[0], radius_m), _box(self.ys, q[1], radius_m)
        count[iy, ix] += add * (_grid_distance(self.xs[ix], self.ys[iy], q) < radius_m)

    def outside_discs(self, centres: np.ndarray, radii: np.ndarray,
                      tile: int = 16) -> np.ndarray:
        """(ny, nx) mask: False on the tiles of ``tile`` x ``tile`` cells wholly inside
        one of the discs ``centres`` (B, 2), ``radii`` (B,) (a hair inside), True
        elsewhere. A coarse cover of the discs, for a fast first cut; each disc looks
        only at the tiles that start within its box."""
        ny, nx = self.clear.shape
        x0 = self.xs[::tile]
        x1 = self.xs[np.minimum(np.arange(tile - 1, nx + tile - 1, tile), nx - 1)]
        y0 = self.ys[::tile]
        y1 = self.ys[np.minimum(np.arange(tile - 1, ny + tile - 1, tile), ny - 1)]
        inside = np.zeros((len(y0), len(x0)), bool)
        r = radii - 1e-6
        for c, rr in zip(centres, r):
            ix, iy = _box(x0, c[0], rr), _box(y0, c[1], rr)
            corner_in = np.ones((len(y0[iy]), len(x0[ix])), bool)
            for cx in (x0[ix], x1[ix]):
                for cy in (y0[iy], y1[iy]):
                    corner_in &= (np.hypot(cx[None] - c[0], cy[:, None] - c[1]) < rr)
            inside[iy, ix] |= corner_in
        return ~np.repeat(np.repeat(inside, tile, axis=0), tile, axis=1)[:ny, :nx]

    def nearest_first(self, goal: np.ndarray, allowed: np.ndarray):
        """Yield the cells of ``allowed`` (ny, nx) as arrays (C, 2), together
        nearest-first from ``goal`` (2,), each ring with the number of cells looked at
        to find it (its window's)."""
        xs, ys = self.xs, self.ys
        if not len(xs) or not len(ys):
            return
        far = float(np.hypot(max(abs(xs[0] - goal[0]), abs(xs[-1] - goal[0])),
                             max(abs(ys[0] - goal[1]), abs(ys[-1] - goal[1])))) + 1.0
        inner, outer = -1.0, 8.0 * self.step
        while inner <= far:
            ix, iy = _box(xs, goal[0], outer), _box(ys, goal[1], outer)
            window = allowed[iy, ix]  # its cells row-major, as the whole grid's order
            jy, jx = np.divmod(np.flatnonzero(window), window.shape[1])  # np.nonzero's, faster
            wx, wy = xs[ix][jx], ys[iy][jy]
            dx, dy = wx - goal[0], wy - goal[1]
            d = np.sqrt(dx * dx + dy * dy)  # _norm of the cells less the goal
            ring = np.flatnonzero((d > inner) & (d <= outer) if inner >= 0 else d <= outer)
            if len(ring):
                ring = ring[np.argsort(d[ring], kind="stable")]
            yield np.column_stack([wx[ring], wy[ring]]), window.size
            inner, outer = outer, 1.5 * outer  # a search stopped early sorts little


WORK_PER_UAV = 20_000_000
"""The rally search's bound per UAV, in elementary tests: grid cells looked at in its
rings, candidates measured against a blocked path point, and hull edges, line segments,
path points and places the candidate tests measure. A UAV that reaches it without a
point has none (:attr:`RallySearch.stopped`): 0.1-0.2 s of one core, so that a 200-UAV
circle crossing a 1 km field (issue 51: over 300 s before) searches in about 10 s."""


@dataclass(frozen=True)
class RallySearch:
    """The rally search's outcome: ``points`` one (east, north) metres or None per UAV;
    ``stopped`` True where the UAV has none because its search reached
    :data:`WORK_PER_UAV` first (rather than because no place in the area qualifies)."""

    points: tuple[np.ndarray | None, ...]
    stopped: tuple[bool, ...]


def rally_points_enu(*, paths: np.ndarray, centres: np.ndarray, radii: np.ndarray,
                     clearance_m: float, area_min: np.ndarray, area_max: np.ndarray,
                     settings: RallySettings) -> list[np.ndarray | None]:
    """One rally point (east, north) per UAV, or None where none fits or the search
    reached its bound: :func:`search_rally_points`'s points."""
    return list(search_rally_points(paths=paths, centres=centres, radii=radii,
                                    clearance_m=clearance_m, area_min=area_min,
                                    area_max=area_max, settings=settings).points)


def search_rally_points(*, paths: np.ndarray, centres: np.ndarray, radii: np.ndarray,
                        clearance_m: float, area_min: np.ndarray, area_max: np.ndarray,
                        settings: RallySettings,
                        work_per_uav: int | None = None) -> RallySearch:
    """One rally point (east, north) per UAV, or None where none fits (module notes).

    Chosen in UAV order, each the candidate nearest its goal that is clear of the
    obstacles, inside the area, ``rally_separation_m`` from the homes and rally points
    of the others, from the others' return lines to their rally points, and whose own
    return lines keep that distance from the others' homes and rally points. A return
    line to a rally point: from each point of the UAV's path nearer to its rally point
    than to its home (RTL flies to the nearer, RALLY_INCL_HOME 1), straight to it.
    ``paths`` (N, n, 3) ENU metres, row 0 each UAV's home; ``centres`` (K, 2), ``radii``
    (K,); ``area_min``/``area_max`` (2,) the area's ENU bounding box.

    The search: the homes and chosen rally points are stamped on the grid (a count of
    the places each cell is too near), so a cell too near one costs a look-up; a cell
    nearer than home to a path point already too near a place fails at once; the rest
    come nearest-first in rings (:class:`_RallyGrid`) and are tested exactly in growing
    batches, each against only what can reach it (the places and line segments whose
    bounding box, grown by the separation, holds the batch's box). The result is the
    first candidate in distance order that passes every test, as a search of the whole
    grid would find it. From :data:`COMPILED_UAVS_FROM` UAVs (or a batch of
    :data:`COMPILED_FROM` candidate x line pairs) the exact tests run compiled, a candidate
    at a time (:func:`._rally_jit.first_clear`), to the same choice. Each chosen UAV's
    return lines are kept with their convex hull: a batch, or a candidate, farther than
    the separation beyond one of its edges skips them all.

    Bounded: each UAV's search stops after ``work_per_uav`` elementary tests (default
    :data:`WORK_PER_UAV`); that UAV then has no rally point and ``stopped`` says so."""
    if work_per_uav is None:
        work_per_uav = WORK_PER_UAV
    inset = settings.corner_cut_m + settings.margin_m
    sep = settings.rally_separation_m
    xs = np.arange(area_min[0] + inset, area_max[0] - inset + 1e-9, settings.grid_m)
    ys = np.arange(area_min[1] + inset, area_max[1] - inset + 1e-9, settings.grid_m)
    grid = _RallyGrid(xs=xs, ys=ys, centres=np.asarray(centres, float).reshape(-1, 2),
                      radii=np.asarray(radii, float).reshape(-1), clearance_m=clearance_m,
                      step_m=settings.grid_m)
    flat = [_densify(p[:, :2], 1.0) for p in paths]
    homes = paths[:, 0, :2]
    n = len(paths)
    compiled = n >= COMPILED_UAVS_FROM
    chosen: list[np.ndarray | None] = [None] * n
    stopped = [False] * n
    rally, placed = np.zeros((n, 2)), np.zeros(n, bool)  # chosen as an array, and which
    # how many homes and rally points each cell is closer than sep to
    crowd = np.zeros(grid.clear.shape, np.int32)
    for h in homes:
        grid.stamp(crowd, h, sep, 1)
    # the chosen UAVs' return lines so far: segment starts (S, 2), ends (S, 2), boxes
    line_a, line_b = np.zeros((0, 2)), np.zeros((0, 2))
    line_lo, line_hi = np.zeros((0, 2)), np.zeros((0, 2))
    # which lines are whose, the convex hull of each UAV's lines, which may reach a cell
    fans = Fans(reach=sep + 1e-6, lo=np.asarray(area_min, float) - 1.0,
                hi=np.asarray(area_max, float) + 1.0)
    for k in range(n):
        own = flat[k]
        own_home = _norm(own - homes[k])  # (P,)
        others = np.arange(n) != k
        places = np.concatenate([homes[others], rally[placed & others]])
        blocked, blocked_reach = _blocked_starts(own, own_home, places, sep)
        grid.stamp(crowd, homes[k], sep, -1)  # its own home is no obstacle to it
        allowed = grid.clear & (crowd == 0)
        if len(blocked):
            allowed &= grid.outside_discs(blocked, blocked_reach)
        grid.stamp(crowd, homes[k], sep, 1)
        batch, work = 32, 0
        own_box = (own.min(axis=0), own.max(axis=0))
        for ring, looked in grid.nearest_first(paths[k, -1, :2], allowed):
            work += looked
            i = 0
            while i < len(ring) and chosen[k] is None and work < work_per_uav:
                chunk = ring[i:i + batch]
                i += len(chunk)
                batch = min(4 * batch, 4096 if compiled else 1024)
                if len(blocked):  # a return line that starts within sep of a place fails
                    work += len(chunk) * len(blocked)
                    chunk = chunk[_clear_of_blocked(chunk, blocked, blocked_reach)]
                    if not len(chunk):
                        continue
                hit = None if compiled else fans.reaching(chunk, line_lo, line_hi, sep)
                first, done = _first_clear(chunk, own=own, own_home=own_home, places=places,
                                           line_a=line_a, line_b=line_b, line_lo=line_lo,
                                           line_hi=line_hi, sep=sep, compiled=compiled,
                                           hit=hit, fans=fans, own_box=own_box,
                                           budget=work_per_uav - work)
                work += done
                if first is not None:
                    chosen[k] = chunk[first]
            if chosen[k] is not None or work >= work_per_uav:
                stopped[k] = chosen[k] is None
                break
        if chosen[k] is not None:
            grid.stamp(crowd, chosen[k], sep, 1)
            rally[k], placed[k] = chosen[k], True
            use = _norm(own - chosen[k]) < own_home
            a = own[use]
            a = a[fans.add(a, chosen[k])]  # a fan's lines in the order of their direction
            b = np.broadcast_to(chosen[k], a.shape)
            line_a, line_b = np.concatenate([line_a, a]), np.concatenate([line_b, b])
            line_lo = np.concatenate([line_lo, np.minimum(a, b) - sep])
            line_hi = np.concatenate([line_hi, np.maximum(a, b) + sep])
    return RallySearch(tuple(chosen), tuple(stopped))


def _blocked_starts(own: np.ndarray, own_home: np.ndarray, places: np.ndarray,
                    sep: float) -> tuple[np.ndarray, np.ndarray]:
    """The points of the UAV's path ``own`` (P, 2) already within ``sep`` of one of the
    ``places`` (Q, 2) (a little inside, so that the exact test decides every case at the
    boundary), with their distances from home ``own_home`` (P,): a candidate nearer to
    one of them than home is has a return line that starts there, and fails. Only the
    discs (point, distance) that no other disc kept holds are returned. Only the places
    within ``sep`` of the path's box are measured: no other is near a point of it."""
    q = places[_near_box(places, own.min(axis=0) - sep, own.max(axis=0) + sep)]
    near = (_distances(own, q) < sep - 1e-6).any(axis=1)
    pts, reach = own[near], own_home[near]
    order = np.argsort(-reach, kind="stable")
    kept: list[int] = []
    for i in order:  # the widest first; a disc inside one kept adds nothing
        if kept and np.any(_norm(pts[kept] - pts[i]) + reach[i] <= reach[kept]):
            continue
        kept.append(int(i))
    return pts[kept], reach[kept]


def _clear_of_blocked(cand: np.ndarray, blocked: np.ndarray, reach: np.ndarray) -> np.ndarray:
    """Mask of ``cand`` (C, 2) farther than ``reach`` (B,) from every ``blocked`` (B, 2):
    from no such point would RTL fly to the candidate (it is not nearer than home)."""
    keep = np.ones(len(cand), bool)
    step = max(1, 2_000_000 // max(1, len(blocked)))
    for i in range(0, len(cand), step):
        part = cand[i:i + step]
        d = _distances(part, blocked)
        keep[i:i + step] = ~np.any(d < reach[None] - 1e-6, axis=1)
    return keep


def _first_clear(chunk: np.ndarray, *, own: np.ndarray, own_home: np.ndarray,
                 places: np.ndarray, line_a: np.ndarray, line_b: np.ndarray,
                 line_lo: np.ndarray, line_hi: np.ndarray, sep: float,
                 compiled: bool = False, hit: np.ndarray | None = None,
                 fans: Fans | None = None, own_box: tuple | None = None,
                 budget: int | None = None) -> tuple[int | None, int]:
    """The index of the first of the candidates ``chunk`` (C, 2) that keeps ``sep``
    between itself and the others' return lines ``line_a``-``line_b`` (S, 2) (their boxes
    grown by ``sep``: ``line_lo``, ``line_hi``) and between the others' places ``places``
    (Q, 2) and its own return lines (from the points of ``own`` (P, 2) nearer to it than
    ``own_home`` (P,), their distances from the UAV's home); None if none does. The
    second test, the costly one, runs on a few candidates at a time, in order; or, when
    ``compiled``, both run compiled a candidate at a time (:func:`._rally_jit.first_clear`:
    the same tests, without numpy's cost per call on small arrays), as they also do when
    the candidates x lines that can reach them (``hit`` (S,), else found here from the
    boxes) are :data:`COMPILED_FROM` or more. ``fans`` (:class:`.rally_fans.Fans`) says whose the
    lines are, for the compiled test to skip a fan's lines at once; ``own_box`` the box
    (lo, hi) of ``own``. Returns the index and the work done: compiled, what it measured,
    given up (None) once a ``budget`` of work (:data:`WORK_PER_UAV`; None: no budget) is
    spent; in numpy, at most candidates x (lines reaching them + path points + places),
    the batch tested whole."""
    if hit is None and not compiled:
        lo, hi = chunk.min(axis=0), chunk.max(axis=0)
        hit = np.all((line_lo <= hi) & (line_hi >= lo), axis=1)
    if compiled or len(chunk) * int(hit.sum()) >= COMPILED_FROM:
        from ._rally_jit import first_clear

        if fans is None:  # the lines as they come, each its own fan
            fans = Fans.each_line(line_a, line_b)
        chunk = np.ascontiguousarray(chunk, float)
        # only the places within sep of the box of the path and the candidates can be
        # too near a return line (the compiled test looks at the box of each's lines)
        reach = sep + 1e-6
        own_lo, own_hi = own_box if own_box is not None else (own.min(axis=0), own.max(axis=0))
        box_lo = np.minimum(own_lo, chunk.min(axis=0)) - reach
        box_hi = np.maximum(own_hi, chunk.max(axis=0)) + reach
        first, done = first_clear(chunk, line_a, line_b, line_lo, line_hi, *fans.arrays(),
                                  own, own_home,
                                  places[_near_box(places, box_lo, box_hi)], float(sep),
                                  -1 if budget is None else max(int(budget), 1))
        return (None if first < 0 else int(first)), int(done)
    found = _first_clear_numpy(chunk, own=own, own_home=own_home, places=places,
                               line_a=line_a[hit], line_b=line_b[hit], sep=sep)
    return found, len(chunk) * (int(hit.sum()) + len(own) + len(places))


def _first_clear_numpy(chunk: np.ndarray, *, own: np.ndarray, own_home: np.ndarray,
                       places: np.ndarray, line_a: np.ndarray, line_b: np.ndarray,
                       sep: float) -> int | None:
    """:func:`_first_clear` in numpy, the lines ``line_a``-``line_b`` those that can
    reach the candidates."""
    ok = np.ones(len(chunk), bool)
    if len(line_a):
        ok &= _clear_of_lines(chunk, line_a, line_b, sep)
    live = np.flatnonzero(ok)
    i, step = 0, 4
    while i < len(live):
        sub = chunk[live[i:i + step]]
        good = _own_lines_clear(sub, own=own, own_home=own_home, places=places, sep=sep)
        if good.any():
            return int(live[i + int(np.argmax(good))])
        i, step = i + len(sub), 2 * step
    return None


COMPILED_FROM = 1_000_000
"""Candidate x line pairs from which :func:`_clear_of_lines` runs compiled (a survey's
return lines are tens of thousands of segments; numba's start-up, 0.3 s, costs more
than smaller searches take)."""

COMPILED_UAVS_FROM = 100
"""UAVs from which :func:`_first_clear` runs compiled: each UAV tests its candidates
against the others' homes, rally points and lines in many calls on small arrays, whose
cost in numpy outgrows numba's start-up (0.3 s in a fresh process; a large plan has
already paid it): 100 UAVs among 320 trees search in 0.40 s in numpy, 0.44 s compiled in
a fresh process and 0.17 s once numba is loaded; 200 in 1.14 s, 0.76 s and 0.44 s."""


def _clear_of_lines(q: np.ndarray, a: np.ndarray, b: np.ndarray, sep: float) -> np.ndarray:
    """``(C,)`` whether each of the points ``q (C, 2)`` keeps ``sep`` from every segment
    ``a``-``b`` ``(S, 2)``."""
    if len(q) * len(a) >= COMPILED_FROM:
        from ._rally_jit import clear_of_segments

        return clear_of_segments(np.ascontiguousarray(q, float), np.ascontiguousarray(a, float),
                                 np.ascontiguousarray(b, float), float(sep))
    return _segment_distance(q[:, None], a[None], b[None]).min(axis=1) >= sep


def _own_lines_clear(cand: np.ndarray, *, own: np.ndarray, own_home: np.ndarray,
                     places: np.ndarray, sep: float) -> np.ndarray:
    """Which candidates ``cand`` (C, 2) have return lines (from the points of ``own``
    (P, 2) nearer to them than ``own_home`` (P,)) that keep ``sep`` from every one of
    ``places`` (Q, 2). Returns (C,) bool."""
    ok = np.ones(len(cand), bool)
    to_cand = _distances(cand, own) < own_home[None]  # (C, P)
    used = to_cand.any(axis=0)
    if not used.any():
        return ok
    pts, to_cand = own[used], to_cand[:, used]
    near = places[_near_hull(places, np.concatenate([pts, cand]), sep)]
    # the places nearest the candidates first: those most likely to rule them out
    near = near[np.argsort(_norm(near - cand.mean(axis=0)))]
    for q in near:
        live = np.flatnonzero(ok)
        if not len(live):
            break
        d = _segment_distance(q, pts[None], cand[live, None])  # (C', P')
        ok[live] &= np.where(to_cand[live], d, np.inf).min(axis=1) >= sep
    return ok
