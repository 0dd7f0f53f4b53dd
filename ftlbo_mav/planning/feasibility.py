"""Is a planned centroid path flyable? Clearance, altitude band and area, per UAV.

A plan is feasible when every UAV segment keeps the clearance from every cylinder (its
horizontal distance to the axis exceeds radius + clearance), every UAV waypoint is inside
the altitude band and every UAV waypoint is inside the area. The result is a list of
sentences a person can act on; empty means feasible.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .cost import segment_axis_distances
from .problem import PlanningProblem

_TOL = 1e-9


def violations(problem: PlanningProblem, path: np.ndarray, *, limit: int = 20) -> list[str]:
    """Violations of the centroid path ``(m+2, 3)`` metres ENU (start, waypoints, goal).

    At most ``limit`` messages, the last one counting what was left out.
    """
    path = np.asarray(path, float)
    messages: list[str] = []
    uavs = path[None, :, :] + problem.offsets[:, None, :]  # (N, P, 3)

    if len(problem.radii):
        # only the cylinders within their radius of the box around every UAV's points can
        # be entered (a leg among thousands of trees passes a few hundred)
        lo, hi = uavs[:, :, :2].min(axis=(0, 1)), uavs[:, :, :2].max(axis=(0, 1))
        gap = np.maximum(np.maximum(lo - problem.centres, problem.centres - hi), 0.0)
        near = np.flatnonzero(np.hypot(gap[:, 0], gap[:, 1]) <= problem.radii * (1 + 1e-9))
        sub = replace(problem, centres=problem.centres[near], radii=problem.radii[near])
        d = segment_axis_distances(sub, path[None])[0]  # (J, N, K')
        for j, n, i in zip(*np.nonzero(d <= sub.radii)):
            k = near[i]
            messages.append(
                f"UAV {n + 1} segment {j}-{j + 1} passes {d[j, n, i]:.2f} m from the axis of "
                f"obstacle {k + 1} (needs more than {problem.radii[k]:.2f} m: radius + clearance)"
            )
    h = uavs[:, 1:-1, 2]
    for n, j in zip(*np.nonzero((h < problem.h_min - _TOL) | (h > problem.h_max + _TOL))):
        messages.append(
            f"UAV {n + 1} waypoint {j + 1} at {h[n, j]:.2f} m is outside the altitude band "
            f"[{problem.h_min:g}, {problem.h_max:g}] m"
        )
    xy = uavs[:, :, :2]
    outside = ((xy < problem.area_lower - _TOL) | (xy > problem.area_upper + _TOL)).any(axis=2)
    for n, j in zip(*np.nonzero(outside)):
        messages.append(f"UAV {n + 1} point {j} is outside the area")
    if len(messages) > limit:
        messages = messages[: limit - 1] + [f"... and {len(messages) - limit + 1} more"]
    return messages
