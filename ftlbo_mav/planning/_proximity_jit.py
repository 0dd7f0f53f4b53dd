"""The compiled loops of :mod:`.proximity` (numba; imported only for large cases, so that
a small plan does not pay numba's start-up)."""

from __future__ import annotations

import math

import numpy as np

from ..compiling import njit


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
