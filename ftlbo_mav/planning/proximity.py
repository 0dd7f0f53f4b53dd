"""How close a sampled path comes to many points, without measuring every sample
against every point.

A predicted flight is tens of thousands of samples, an orchard thousands of trees: the
full ``(samples x trees)`` distance array of a survey would be gigabytes. The samples are
cut into runs of about ``sqrt(T)`` consecutive samples, each with its bounding box; a
point's nearest sample lies in a run whose box is no further than the nearest sample found
so far, so only those runs are measured (one pass over the boxes finds the run nearest
by its box and measures it, a second measures the runs whose boxes are nearer than
that). Exact: the same distances and the same (first) nearest sample as the full array,
which is what small cases use (below :data:`FULL_ARRAY_LIMIT` elements, where numba's
start-up would cost more than the array).

Pure computation (numba-compiled loops in :mod:`._proximity_jit`).
"""

from __future__ import annotations

import math

import numpy as np

from ..compiling import cheap

FULL_ARRAY_LIMIT = 2_000_000
"""Samples x points up to which the full distance array is computed (16 MB), unless numba
is loaded already and the loop cached (:func:`..compiling.cheap`) and there are more than
:data:`COMPILED_LOADED_FROM`: the same distances and indices, compiled (the dense 100-tree
field's 18 predictions: 0.47 s in arrays)."""
COMPILED_LOADED_FROM = 20_000


def nearest_samples(xy: np.ndarray, centres: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For every point of ``centres`` ``(M, 2)``: the horizontal distance to the nearest
    of the samples ``xy`` ``(T, 2)`` (T >= 1) and that sample's index (the first, on a
    tie), each ``(M,)``."""
    xy = np.ascontiguousarray(xy, float)
    centres = np.ascontiguousarray(np.asarray(centres, float).reshape(-1, 2))
    if len(xy) == 0:
        raise ValueError("no samples")
    size = len(xy) * len(centres)
    if size <= FULL_ARRAY_LIMIT and not (size > COMPILED_LOADED_FROM
                                         and cheap(_compiled_nearest)):
        d = np.sqrt(((xy[None, :, :] - centres[:, None, :]) ** 2).sum(axis=-1))  # (M, T)
        index = d.argmin(axis=1)
        return d[np.arange(len(centres)), index], index
    run = max(int(math.sqrt(len(xy))), 8)
    return _compiled_nearest()(xy, centres, run)


def _compiled_nearest():
    from ._proximity_jit import _nearest

    return _nearest
