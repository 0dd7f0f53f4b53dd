"""How close a sampled path comes to many points, without measuring every sample
against every point.

A predicted flight is tens of thousands of samples, an orchard thousands of trees: the
full ``(samples x trees)`` distance array of a survey would be gigabytes. The samples are
cut into runs of about ``sqrt(T)`` consecutive samples, each with its bounding box; a
point's nearest sample lies in a run whose box is no further than the nearest sample found
so far, so only those runs are measured (one pass over the boxes finds the run nearest
by its box and measures it, a second measures the runs whose boxes are nearer than
that). Exact: the same distances and the same (first) nearest sample as the full array.

Pure computation (numba-compiled loops).
"""

from __future__ import annotations

import math

import numpy as np

from ..ardupilot.compiled import njit


@njit(cache=True)
def _boxes(xy, run):
    T = xy.shape[0]
    C = (T + run - 1) // run
    box = np.empty((C, 4))
    for c in range(C):
        lo, hi = c * run, min((c + 1) * run, T)
        x0 = x1 = xy[lo, 0]
        y0 = y1 = xy[lo, 1]
        for t in range(lo + 1, hi):
            x, y = xy[t, 0], xy[t, 1]
            x0, x1 = min(x0, x), max(x1, x)
            y0, y1 = min(y0, y), max(y1, y)
        box[c, 0], box[c, 1], box[c, 2], box[c, 3] = x0, y0, x1, y1
    return box


@njit(cache=True)
def _nearest(xy, centres, run):
    T, M = xy.shape[0], centres.shape[0]
    box = _boxes(xy, run)
    C = box.shape[0]
    dist = np.empty(M)
    index = np.empty(M, np.int64)
    bound = np.empty(C)
    for m in range(M):
        cx, cy = centres[m, 0], centres[m, 1]
        first, first_lb = 0, math.inf
        for c in range(C):
            dx = max(box[c, 0] - cx, 0.0, cx - box[c, 2])
            dy = max(box[c, 1] - cy, 0.0, cy - box[c, 3])
            lb = math.sqrt(dx * dx + dy * dy)
            bound[c] = lb
            if lb < first_lb:
                first, first_lb = c, lb
        best, best_t = math.inf, T
        for sweep in range(2):
            for c in range(C):
                if sweep == 0 and c != first:
                    continue
                if sweep == 1 and (c == first or bound[c] > best):
                    continue
                for t in range(c * run, min((c + 1) * run, T)):
                    dx, dy = xy[t, 0] - cx, xy[t, 1] - cy
                    d = math.sqrt(dx * dx + dy * dy)
                    if d < best or (d == best and t < best_t):
                        best, best_t = d, t
        dist[m], index[m] = best, best_t
    return dist, index


def nearest_samples(xy: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For every point of ``centres`` ``(M, 2)``: the horizontal distance to the nearest
    of the samples ``xy`` ``(T, 2)`` (T >= 1) and that sample's index (the first, on a
    tie), each ``(M,)``."""
    xy = np.ascontiguousarray(xy, float)
    centres = np.ascontiguousarray(np.asarray(centres, float).reshape(-1, 2))
    if len(xy) == 0:
        raise ValueError("no samples")
    run = max(int(math.sqrt(len(xy))), 8)
    return _nearest(xy, centres, run)
