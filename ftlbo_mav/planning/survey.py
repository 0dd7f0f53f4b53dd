"""Survey lanes: parallel centre lines across a rectangle, in boustrophedon order.

Pure geometry on plain arrays (metres east/north), no scenario, no geodesy: the scenario
reader (:mod:`ftlbo_mav.scenario`) turns a ``[survey]`` table into lanes with
:func:`lay_lanes` and makes each lane's two ends via points.

Conventions: ``heading_deg`` is the lanes' direction in degrees clockwise from north (a
compass heading; 0 and 180 give the same lanes). "Across" is the direction 90 degrees
clockwise from the heading.

Coverage (as Mission Planner's grid and QGroundControl's survey lay transects): the first
lane runs on the rectangle's one side and the last on the other, the lanes in between
evenly spread, as many as it takes for the spacing to be no wider than asked. So every
point of the rectangle is within half the (actual) spacing of a lane's line. With an
oblique heading the two outer "sides" are corners: the outer lanes are the first ones
:data:`MIN_LANE_M` long, a corner triangle less than that wide beyond them.
"""

from __future__ import annotations

import math

import numpy as np

END_CLEARANCE_M = 0.01
"""A lane end moved off an obstacle stops this far outside its disc (the disc's radius
already holds the clearance; a via point must be strictly outside)."""

SPACING_TOLERANCE = 1e-3
"""A rectangle a hair wider than a whole number of spacings (by less than this share of
one spacing: a millimetre in 7 m, what a corner's lat/lon rounding or the frame's
curvature adds) gets no lane more: its lanes are that share further apart than asked."""

MIN_LANE_M = 1.0
"""Lanes shorter than this (a corner of an oblique rectangle, a lane blocked to its
ends) are dropped."""


def directions(heading_deg: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit vectors ``(2,)`` along the lanes and across them (90 degrees clockwise)."""
    h = math.radians(heading_deg)
    along = np.array([math.sin(h), math.cos(h)])
    across = np.array([math.cos(h), -math.sin(h)])
    return along, across


def _clip_line(point: np.ndarray, along: np.ndarray, lower: np.ndarray,
               upper: np.ndarray) -> tuple[float, float] | None:
    """Parameter interval ``[t0, t1]`` of ``point + t along`` inside the rectangle."""
    t0, t1 = -math.inf, math.inf
    for axis in range(2):
        if abs(along[axis]) < 1e-12:
            if not lower[axis] - 1e-9 <= point[axis] <= upper[axis] + 1e-9:
                return None
            continue
        a = (lower[axis] - point[axis]) / along[axis]
        b = (upper[axis] - point[axis]) / along[axis]
        t0, t1 = max(t0, min(a, b)), min(t1, max(a, b))
    return (t0, t1) if t0 <= t1 else None


def _off_discs(t0: float, t1: float, offset: float, along: np.ndarray, across: np.ndarray,
               centres: np.ndarray, radii: np.ndarray) -> tuple[float, float] | None:
    """Move the ends of the lane ``[t0, t1]`` (at ``offset`` across) inward until neither
    is inside a disc; ``None`` when they meet."""
    if not len(radii):
        return t0, t1
    c_along, c_across = centres @ along, centres @ across
    gap = radii + END_CLEARANCE_M
    half2 = gap**2 - (c_across - offset) ** 2
    hit = half2 > 0
    lo = c_along[hit] - np.sqrt(half2[hit])
    hi = c_along[hit] + np.sqrt(half2[hit])
    moved = True
    while moved:  # an end pushed out of one disc may land in the next one
        moved = False
        inside = (lo < t0) & (t0 < hi)
        if inside.any():
            t0, moved = float(hi[inside].max()), True
        inside = (lo < t1) & (t1 < hi)
        if inside.any():
            t1, moved = float(lo[inside].min()), True
        if t0 >= t1:
            return None
    return t0, t1


def lay_lanes(*, lower: np.ndarray, upper: np.ndarray, spacing_m: float, heading_deg: float,
              begin: np.ndarray, centres: np.ndarray | None = None,
              radii: np.ndarray | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
    """Lanes inside the rectangle ``lower (2,)``..``upper (2,)``, in flight order.

    Parallel centre lines along ``heading_deg``, clipped to the rectangle: the first and
    last on its two sides across (see the module), :func:`lane_offsets` between them, at
    most ``spacing_m`` apart. A lane end inside one of the discs ``centres (C, 2)``, ``radii (C,)``
    (the obstacles as the centroid sees them: one disc per UAV and cylinder, radius +
    clearance) is moved inward along the lane until it is outside every disc; the
    obstacles in a lane's middle are left to the planner's detours. Lanes shorter than
    :data:`MIN_LANE_M` are dropped.

    Order (boustrophedon): the survey starts at whichever outer lane (first or last
    across) is nearer to ``begin (2,)``, enters it at its end nearer to ``begin``, then
    takes the lanes across in turn, entering each at the end nearer to where the
    previous one was left. Returns ``(entry (2,), exit (2,))`` per lane.
    """
    if spacing_m <= 0:
        raise ValueError("spacing must be > 0")
    along, across = directions(heading_deg)
    centres = np.zeros((0, 2)) if centres is None else np.asarray(centres, float)
    radii = np.zeros(0) if radii is None else np.asarray(radii, float)
    lanes = []
    for offset in lane_offsets(lower=lower, upper=upper, spacing_m=spacing_m,
                               heading_deg=heading_deg):
        point = offset * across
        span = _clip_line(point, along, lower, upper)
        if span is None:
            continue
        span = _off_discs(*span, offset, along, across, centres, radii)
        if span is None or span[1] - span[0] < MIN_LANE_M:
            continue
        lanes.append((point + span[0] * along, point + span[1] * along))
    if not lanes:
        return []
    begin = np.asarray(begin, float)[:2]
    if _distance(begin, lanes[-1]) < _distance(begin, lanes[0]):
        lanes.reverse()
    ordered, here = [], begin
    for a, b in lanes:
        if np.hypot(*(b - here)) < np.hypot(*(a - here)):
            a, b = b, a
        ordered.append((a, b))
        here = b
    return ordered


def across_extent(*, lower: np.ndarray, upper: np.ndarray,
                  heading_deg: float) -> tuple[float, float]:
    """The smallest and largest across coordinate a lane of the rectangle can have: its
    sides, or for an oblique heading the offsets where a lane is :data:`MIN_LANE_M` long
    (a lane ``u`` inside a corner is ``u / |sin h cos h|`` long)."""
    along, across = directions(heading_deg)
    corners = np.array([[lower[0], lower[1]], [upper[0], lower[1]],
                        [lower[0], upper[1]], [upper[0], upper[1]]])
    first, last = float((corners @ across).min()), float((corners @ across).max())
    skew = abs(along[0] * along[1])
    inset = MIN_LANE_M * skew * (1 + 1e-6) if skew > 1e-12 else 0.0
    if last - first <= 2 * inset:
        middle = (first + last) / 2
        return middle, middle
    return first + inset, last - inset


def lane_offsets(*, lower: np.ndarray, upper: np.ndarray, spacing_m: float,
                 heading_deg: float) -> np.ndarray:
    """The lanes' across coordinates ``(K,)``: ``K = ceil(width / spacing) + 1`` evenly
    from one side (:func:`across_extent`) to the other, so never more than ``spacing_m``
    apart (within :data:`SPACING_TOLERANCE`); one lane when the rectangle is no wider
    than a lane."""
    first, last = across_extent(lower=lower, upper=upper, heading_deg=heading_deg)
    width = last - first
    if width <= 1e-9:
        return np.array([first])
    gaps = max(int(math.ceil(width / spacing_m - SPACING_TOLERANCE)), 1)
    return first + np.arange(gaps + 1) * (width / gaps)


def lane_spacing(offsets: np.ndarray) -> float:
    """The actual spacing of lanes at ``offsets`` (0 for one lane)."""
    return float(np.diff(np.sort(offsets)).max()) if len(offsets) > 1 else 0.0


def _distance(point: np.ndarray, lane: tuple[np.ndarray, np.ndarray]) -> float:
    """Distance from ``point (2,)`` to the segment ``lane``."""
    a, b = lane
    ab = b - a
    t = float(np.clip((point - a) @ ab / max(ab @ ab, 1e-18), 0.0, 1.0))
    return float(np.hypot(*(point - a - t * ab)))


def formation_width(offsets: np.ndarray, heading_deg: float) -> float:
    """How wide the formation ``offsets (N, 3)`` is across lanes of ``heading_deg``
    (metres, between its outermost UAVs)."""
    _, across = directions(heading_deg)
    side = np.asarray(offsets, float)[:, :2] @ across
    return float(side.max() - side.min())
