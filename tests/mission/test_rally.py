"""The rally search's compiled line test (:mod:`ftlbo_mav.mission._rally_jit`) answers as
numpy's distances do."""

from __future__ import annotations

import numpy as np

from ftlbo_mav.geo import segment_distance
from ftlbo_mav.mission._rally_jit import clear_of_segments


def test_the_compiled_line_test_is_numpys():
    rng = np.random.default_rng(3)
    q = rng.uniform(0.0, 60.0, (400, 2))
    a = rng.uniform(0.0, 60.0, (300, 2))
    b = np.broadcast_to(rng.uniform(0.0, 60.0, 2), a.shape).copy()  # a fan, as RTL's lines
    a[:5] = b[:5]  # segments of zero length too
    for sep in (0.5, 3.0, 10.0):
        numpy = segment_distance(q[:, None], a[None], b[None]).min(axis=1) >= sep
        compiled = clear_of_segments(q, a, b, sep)
        assert compiled.dtype == bool
        np.testing.assert_array_equal(compiled, numpy)
        assert 0 < numpy.sum() < len(q) or sep == 10.0  # both answers occur
