"""The safety term's loop (:func:`.cost._safety`), compiled: every UAV segment against
every shifted cylinder axis without the ``(N*K, S*J)`` temporaries. The same arithmetic
per distance as :func:`.cost._axis_distances` (so the same distances, bit for bit); the
sums run in another order (differences of ~1e-15 relative). Imported only for problems
large enough to pay for numba's start-up (:data:`.cost.COMPILED_FROM`).

The inner loop is written so that LLVM vectorizes it: no branch per distance (``r / d``
is already infinite at ``d = 0``; a violation is counted in an integer, its depth summed
as ``max(r - d, 0)``) and ``fastmath`` limited to reassociating the sums (``reassoc``,
``nsz``: no approximate division or square root, no fused multiply-add, so every
distance keeps its bits). Measured on this machine: 4.4 times faster than a loop that
branches (100 students x 2 segments x 510 axes: 0.34 ms -> 0.077 ms)."""

from __future__ import annotations

import math

import numpy as np
from numba import prange

from ..compiling import njit


@njit(cache=True, parallel=True, fastmath={"reassoc", "nsz"})
def safety(paths, axes, radii, scale):
    """``paths`` ``(S, P, 3)`` centroid paths, ``axes`` ``(NK, 2)`` the shifted cylinder
    axes, ``radii`` ``(NK,)`` theirs: per student eq. 9's sum times ``scale`` (inf where
    a segment is inside a cylinder, ``d <= r``) and the summed depth of the violations."""
    S, P = paths.shape[0], paths.shape[1]
    NK = axes.shape[0]
    east = np.ascontiguousarray(axes[:, 0])
    north = np.ascontiguousarray(axes[:, 1])
    v = np.zeros(S)
    depth = np.zeros(S)
    for s in prange(S):  # students in parallel: numba threads over the cores
        total = 0.0
        deep = 0.0
        hits = 0
        for j in range(P - 1):
            ax, ay = paths[s, j, 0], paths[s, j, 1]
            bx, by = paths[s, j + 1, 0] - ax, paths[s, j + 1, 1] - ay
            seg2 = max(bx * bx + by * by, 1e-12)
            for i in range(NK):
                cx = east[i] - ax
                cy = north[i] - ay
                t = cx * bx
                t += cy * by
                t /= seg2
                t = min(max(t, 0.0), 1.0)
                cx -= t * bx
                cy -= t * by
                d = math.sqrt(cx * cx + cy * cy)
                r = radii[i]
                total += r / d
                deep += max(r - d, 0.0)
                hits += r >= d
        v[s] = math.inf if hits else total * scale
        depth[s] = deep
    return v, depth
