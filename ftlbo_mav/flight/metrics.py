"""How well a flown formation holds: pure functions on ENU positions.

``positions``: ``(N, 3)`` metres ENU, one row per UAV at one instant (or ``(T, N, 3)``
over time); ``offsets``: ``(N, 3)`` the planned offsets from the centroid.
"""

from __future__ import annotations

import numpy as np

from ..formation import slot_errors


def formation_error(positions: np.ndarray, offsets: np.ndarray) -> np.ndarray:
    """RMS over the UAVs of :func:`slot_errors`, ``(...)`` metres."""
    return np.sqrt(np.mean(slot_errors(positions, offsets) ** 2, axis=-1))


def min_separation(positions: np.ndarray) -> np.ndarray:
    """Smallest 3D distance between any two UAVs, ``(...)`` metres (inf for one UAV)."""
    positions = np.asarray(positions, float)
    n = positions.shape[-2]
    if n < 2:
        return np.full(positions.shape[:-2], np.inf)
    diff = positions[..., :, None, :] - positions[..., None, :, :]
    dist = np.linalg.norm(diff, axis=-1)
    i, j = np.triu_indices(n, 1)
    return dist[..., i, j].min(axis=-1)


def min_clearance(positions: np.ndarray, centres: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Smallest horizontal distance from any UAV to any cylinder's surface, ``(...)`` metres.

    ``centres``: ``(K, 2)`` axes; ``radii``: ``(K,)`` the cylinders' own radii. Negative
    inside a cylinder; inf without obstacles.
    """
    positions = np.asarray(positions, float)
    if len(radii) == 0:
        return np.full(positions.shape[:-2], np.inf)
    d = np.linalg.norm(positions[..., :, None, :2] - np.asarray(centres, float), axis=-1)
    return (d - np.asarray(radii, float)).min(axis=(-1, -2))
