"""The rally search's costly test compiled (numba): candidates against the return lines of
a long survey (tens of thousands of segments). Imported only for large cases
(:data:`.rally.COMPILED_FROM`), so that a small plan does not pay numba's start-up."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..ardupilot.compiled import njit


@njit(cache=True, parallel=True)
def clear_of_segments(q, a, b, sep):
    """``(C,)`` whether each point ``q (C, 2)`` is at least ``sep`` from every segment
    ``a``-``b`` (each ``(S, 2)``): the arithmetic of :func:`ftlbo_mav.geo.segment_distance`,
    a candidate given up at its first segment nearer than ``sep``."""
    C, S = q.shape[0], a.shape[0]
    ok = np.ones(C, np.bool_)
    for c in prange(C):
        qx, qy = q[c, 0], q[c, 1]
        for s in range(S):
            abx, aby = b[s, 0] - a[s, 0], b[s, 1] - a[s, 1]
            denom = max(abx * abx + aby * aby, 1e-12)
            t = ((qx - a[s, 0]) * abx + (qy - a[s, 1]) * aby) / denom
            t = min(max(t, 0.0), 1.0)
            dx = a[s, 0] + t * abx - qx
            dy = a[s, 1] + t * aby - qy
            if math.sqrt(dx * dx + dy * dy) < sep:
                ok[c] = False
                break
    return ok
