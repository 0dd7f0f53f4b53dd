"""The rally search's return lines kept as fans (pure): each chosen UAV's lines all end at
its rally point and lie in the convex hull of it and the path points they start from, so
a candidate, or a batch of them, farther than the separation beyond one edge of that hull
is farther than that from every one of them, and none of them need be measured
(:func:`.rally.search_rally_points`, :func:`._rally_jit.first_clear`)."""

from __future__ import annotations

import numpy as np


def convex_hull(points: np.ndarray) -> np.ndarray:
    """The convex hull of ``points`` (n, 2), counter-clockwise (Andrew's monotone chain)."""
    pts = np.unique(points, axis=0)  # sorted by east, then north
    if len(pts) < 3:
        return pts

    def half(seq):
        out: list[np.ndarray] = []
        for p in seq:
            while len(out) >= 2 and ((out[-1][0] - out[-2][0]) * (p[1] - out[-2][1])
                                     - (out[-1][1] - out[-2][1]) * (p[0] - out[-2][0])) <= 0:
                out.pop()
            out.append(p)
        return out

    lower, upper = half(pts), half(pts[::-1])
    return np.array(lower[:-1] + upper[:-1])


def outward_edges(hull: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges of a counter-clockwise ``hull`` (h, 2) of three corners or more (as
    :func:`convex_hull` gives it): their starts (h, 2) and outward unit normals (h, 2).
    A point ``q`` is ``(q - start) . normal`` beyond an edge's line."""
    edge = np.roll(hull, -1, axis=0) - hull
    normal = np.column_stack([edge[:, 1], -edge[:, 0]])  # outward for a ccw hull
    normal /= np.maximum(np.hypot(normal[:, 0], normal[:, 1]), 1e-300)[:, None]
    return hull, normal


class Fans:
    """The chosen UAVs' return lines as fans: each UAV's lines (contiguous in the line
    arrays, ``start`` (F+1,) their bounds) run from path points to its rally point
    ``rally`` (F, 2), sorted by their direction from it (``angle`` (S,), radians in
    [-pi, pi], ascending within a fan), and lie in the convex hull of those points and
    the rally point, kept as its edges' starts ``edge_a`` (E, 2) and outward unit normals
    ``edge_n`` (E, 2), ``edge_start`` (F+1,) each fan's. A point farther than the
    separation beyond one edge of a fan's hull is farther than that from each of its
    lines (a fan of fewer than three distinct corners has no edges: never skipped); a
    point at ``d`` > sep from the rally point is within sep of a line only if the line's
    direction is within ``asin(sep / d)`` of the point's."""

    def __init__(self, *, reach: float = np.inf, lo: np.ndarray | None = None,
                 hi: np.ndarray | None = None, bucket_m: float = 8.0) -> None:
        self.start, self.edge_start = [0], [0]
        self.edge_a, self.edge_n = np.zeros((0, 2)), np.zeros((0, 2))
        self.rally, self.angle = np.zeros((0, 2)), np.zeros(0)
        # buckets: square cells of bucket_m over lo..hi, each listing the fans that may
        # come within reach of a point in it (one bucket of every fan without lo/hi)
        self.reach = reach
        self.origin = np.zeros(2) if lo is None else np.asarray(lo, float)
        span = np.zeros(2) if lo is None or hi is None else np.asarray(hi, float) - self.origin
        self.bucket_m = bucket_m if lo is not None and hi is not None else np.inf
        self.shape = (1, 1) if lo is None or hi is None else tuple(
            int(v) for v in np.floor(span / bucket_m).astype(int)[::-1] + 1)  # (ny, nx)
        self._pairs: list[np.ndarray] = []  # (bucket, fan) rows, per fan
        self._csr: tuple[np.ndarray, np.ndarray] | None = None

    @classmethod
    def each_line(cls, line_a: np.ndarray, line_b: np.ndarray) -> Fans:
        """The lines ``line_a``-``line_b`` (S, 2) as they come, each its own fan ending at
        its ``line_b``: no hull, one bucket of them all."""
        fans = cls()
        fans.start = list(range(len(line_a) + 1))
        fans.edge_start = [0] * (len(line_a) + 1)
        fans.rally = np.ascontiguousarray(line_b, float).reshape(-1, 2)
        fans.angle = np.arctan2(line_a[:, 1] - line_b[:, 1], line_a[:, 0] - line_b[:, 0])
        fans._pairs = [np.column_stack([np.zeros(len(line_a), np.int64),
                                        np.arange(len(line_a), dtype=np.int64)])]
        return fans

    def add(self, starts: np.ndarray, rally: np.ndarray) -> np.ndarray:
        """The fan of the lines from ``starts`` (m, 2) to ``rally`` (2,). Returns the
        order (m,) in which its lines must be appended to the line arrays."""
        hull = convex_hull(np.concatenate([starts, rally[None]]))
        a, n = outward_edges(hull) if len(hull) >= 3 else (np.zeros((0, 2)), np.zeros((0, 2)))
        self.edge_a = np.concatenate([self.edge_a, a])
        self.edge_n = np.concatenate([self.edge_n, n])
        angle = np.arctan2(starts[:, 1] - rally[1], starts[:, 0] - rally[0])
        order = np.argsort(angle, kind="stable")
        self.angle = np.concatenate([self.angle, angle[order]])
        self.rally = np.concatenate([self.rally, rally[None]])
        self.start.append(self.start[-1] + len(starts))
        self.edge_start.append(self.edge_start[-1] + len(a))
        self._bucket(len(self.start) - 2, np.concatenate([starts, rally[None]]), a, n)
        return order

    def _bucket(self, f: int, corners: np.ndarray, a: np.ndarray, n: np.ndarray) -> None:
        """List fan ``f`` (its lines within the hull of ``corners`` (m, 2), edges ``a``,
        ``n``) in every bucket within ``reach`` of its box that no edge has wholly beyond
        ``reach``."""
        ny, nx = self.shape
        if not np.isfinite(self.bucket_m):
            self._pairs.append(np.array([[0, f]], np.int64))
            self._csr = None
            return
        size = self.bucket_m
        lo = np.floor((corners.min(axis=0) - self.reach - self.origin) / size).astype(int)
        hi = np.floor((corners.max(axis=0) + self.reach - self.origin) / size).astype(int)
        lo, hi = np.maximum(lo, 0), np.minimum(hi, [nx - 1, ny - 1])
        if np.any(hi < lo):
            return
        ix, iy = np.meshgrid(np.arange(lo[0], hi[0] + 1), np.arange(lo[1], hi[1] + 1))
        ix, iy = ix.ravel(), iy.ravel()
        keep = np.ones(len(ix), bool)
        if len(a):  # a bucket wholly beyond an edge by more than reach: none of its lines
            x0, y0 = self.origin[0] + ix * size, self.origin[1] + iy * size
            for ea, en in zip(a, n):
                beyond = np.full(len(ix), np.inf)
                for cx in (x0, x0 + size):
                    for cy in (y0, y0 + size):
                        beyond = np.minimum(beyond, (cx - ea[0]) * en[0] + (cy - ea[1]) * en[1])
                keep &= beyond <= self.reach
        self._pairs.append(np.column_stack([iy[keep] * nx + ix[keep],
                                            np.full(int(keep.sum()), f)]).astype(np.int64))
        self._csr = None

    def buckets(self) -> tuple[np.ndarray, np.ndarray]:
        """``bucket_start`` (ny*nx+1,) and ``bucket_fans``: the fans of bucket ``b`` are
        ``bucket_fans[bucket_start[b]:bucket_start[b + 1]]``, ascending."""
        if self._csr is None:
            ny, nx = self.shape
            pairs = (np.concatenate(self._pairs) if self._pairs
                     else np.zeros((0, 2), np.int64))
            pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
            start = np.searchsorted(pairs[:, 0], np.arange(ny * nx + 1)).astype(np.int64)
            self._csr = start, np.ascontiguousarray(pairs[:, 1])
        return self._csr

    def arrays(self) -> tuple:
        """``start``, ``edge_start`` (int64), ``edge_a``, ``edge_n``, ``rally``, ``angle``,
        then the buckets: ``bucket_start``, ``bucket_fans``, ``origin`` (2,), the bucket's
        side (inf: one bucket), ``nx``, ``ny``: for the compiled test."""
        ny, nx = self.shape
        return (np.asarray(self.start, np.int64), np.asarray(self.edge_start, np.int64),
                self.edge_a, self.edge_n, self.rally, self.angle, *self.buckets(),
                self.origin, float(self.bucket_m), nx, ny)

    def far(self, lo: np.ndarray, hi: np.ndarray, sep: float) -> np.ndarray:
        """(F,) whether each fan's hull has an edge with the box ``lo``..``hi`` (2,)
        wholly beyond it by more than ``sep`` (a hair more): no line of it comes within
        ``sep`` of a point in the box."""
        if not len(self.edge_a):
            return np.zeros(len(self.start) - 1, bool)
        corners = np.array([lo, [lo[0], hi[1]], hi, [hi[0], lo[1]]])
        d = ((corners[None] - self.edge_a[:, None]) * self.edge_n[:, None]).sum(-1).min(axis=1)
        beyond = (d > sep + 1e-6).astype(np.int64)  # (E,): the box is wholly beyond the edge
        ends = np.asarray(self.edge_start, np.int64)
        return (np.add.reduceat(np.append(beyond, 0), ends[:-1]) * (np.diff(ends) > 0)) > 0

    def reaching(self, chunk: np.ndarray, line_lo: np.ndarray, line_hi: np.ndarray,
                 sep: float) -> np.ndarray:
        """(S,) mask of the lines that may come within ``sep`` of a candidate of ``chunk``
        (C, 2): their box grown by ``sep`` (``line_lo``, ``line_hi``) holds part of the
        chunk's box, and their fan's hull is not beyond ``sep`` from it."""
        lo, hi = chunk.min(axis=0), chunk.max(axis=0)
        hit = np.all((line_lo <= hi) & (line_hi >= lo), axis=1)
        if not len(self.edge_a) or not hit.any():
            return hit
        return hit & ~np.repeat(self.far(lo, hi, sep), np.diff(self.start))
