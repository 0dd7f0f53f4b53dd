"""Formation offsets: each UAV's position relative to the group's centroid (paper eqs. 2-4).

A formation is an array of offsets, shape ``(N, 3)`` metres ``[east, north, up]``; UAV n
flies ``P_n = P_F + offset_n`` (eq. 4). The paper's experiment gives explicit offsets that
do not satisfy its own equal-radius rule (NOTES 2), so both kinds are supported.
"""

from __future__ import annotations

import numpy as np

PLANES = ("horizontal", "vertical")


def regular_formation(*, count: int, radius_m: float, plane: str = "horizontal") -> np.ndarray:
    """N UAVs evenly spaced on a circle of radius ``radius_m`` around the centroid.

    Every UAV is ``radius_m`` from the centroid (eq. 2) and equally far from both its
    neighbours on the circle (eq. 3); the offsets sum to zero, so the centroid of the
    UAVs is the planned centroid (eq. 1).

    ``plane="horizontal"``: the circle lies in the east-north plane, UAV 1 due north.
    ``plane="vertical"``: the circle lies in the east-up plane, UAV 1 on top, like the
    experiment's triangle.

    Returns shape ``(count, 3)`` metres ENU.
    """
    if count < 1:
        raise ValueError("a formation needs at least one UAV")
    if radius_m < 0:
        raise ValueError("the formation radius must not be negative")
    if plane not in PLANES:
        raise ValueError(f"plane must be one of {', '.join(PLANES)}")
    if count == 1:
        return np.zeros((1, 3))
    angle = 2.0 * np.pi * np.arange(count) / count
    along, across = radius_m * np.sin(angle), radius_m * np.cos(angle)
    zeros = np.zeros(count)
    if plane == "horizontal":
        offsets = np.stack([along, across, zeros], axis=1)
    else:
        offsets = np.stack([along, zeros, across], axis=1)
    offsets[np.abs(offsets) < 1e-12] = 0.0
    return offsets


def closest_pair(offsets: np.ndarray) -> tuple[int, int, float] | None:
    """The two UAVs of the formation closest to each other: ``(i, j, metres)`` (3D, i < j,
    0-based); ``None`` for one UAV. ``offsets``: ``(N, 3)`` metres ENU."""
    offsets = np.asarray(offsets, float).reshape(-1, 3)
    if len(offsets) < 2:
        return None
    dist = np.linalg.norm(offsets[:, None, :] - offsets[None, :, :], axis=-1)
    i, j = np.triu_indices(len(offsets), 1)
    k = int(np.argmin(dist[i, j]))
    return int(i[k]), int(j[k]), float(dist[i[k], j[k]])


def min_separation(offsets: np.ndarray) -> float:
    """Smallest 3D distance between two UAVs of the formation, metres (inf for one UAV)."""
    pair = closest_pair(offsets)
    return float("inf") if pair is None else pair[2]


def slot_errors(positions: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """Each UAV's distance from its slot: the group's centroid plus its planned offset.

    The slot is taken from the flown centroid, so a formation that holds its shape but
    lags the plan has zero error. Returns ``(..., N)`` metres.
    """
    positions = np.asarray(positions, float)
    offsets = np.asarray(offsets, float)
    rel = positions - positions.mean(axis=-2, keepdims=True)
    target = offsets - offsets.mean(axis=0)
    return np.linalg.norm(rel - target, axis=-1)
