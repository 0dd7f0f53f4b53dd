"""The rally search's compiled tests (:mod:`ftlbo_mav.mission._rally_jit`) and its own
numpy arithmetic answer as numpy's distances do, and the search chooses the same points
compiled as in numpy."""

from __future__ import annotations

import numpy as np
import pytest

from ftlbo_mav.geo import segment_distance
from ftlbo_mav.mission import rally
from ftlbo_mav.mission._rally_jit import clear_of_segments
from ftlbo_mav.mission.fence import FenceSettings


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


def test_the_searchs_distances_are_numpys_to_the_bit():
    rng = np.random.default_rng(5)
    p, q = rng.uniform(-300.0, 300.0, (50, 2)), rng.uniform(-300.0, 300.0, (70, 2))
    a, b = rng.uniform(-300.0, 300.0, (1, 70, 2)), rng.uniform(-300.0, 300.0, (50, 1, 2))
    b[0, 0] = a[0, 0]  # a segment of zero length
    np.testing.assert_array_equal(rally._norm(p - q[0]), np.linalg.norm(p - q[0], axis=1))
    np.testing.assert_array_equal(rally._distances(p, q),
                                  np.linalg.norm(p[:, None] - q[None], axis=2))
    np.testing.assert_array_equal(rally._grid_distance(p[:, 0], q[:, 1], q[0]), np.linalg.norm(
        np.stack(np.meshgrid(p[:, 0], q[:, 1]), axis=-1) - q[0], axis=-1))
    np.testing.assert_array_equal(rally._segment_distance(p[:, None], a, b),
                                  segment_distance(p[:, None], a, b))
    np.testing.assert_array_equal(rally._segment_distance(q[3], a, b),
                                  segment_distance(q[3], a, b))


def _crowd(rng, n):
    """``n`` UAVs in a formation flying across a 60 m field among a few trees to goals
    close together (their rally points crowd one another, some find none)."""
    home = rng.uniform(2, 8, 2) + 3.0 * np.column_stack([np.arange(n) % 5, np.arange(n) // 5])
    goal = home + rng.uniform(25, 35, 2) + rng.normal(0, 1.0, (n, 2))
    middle = (home + goal) / 2 + rng.normal(0, 3.0, (n, 2))
    paths = np.stack([home, middle, goal], axis=1)
    return dict(paths=np.concatenate([paths, np.full((n, 3, 1), 4.0)], axis=2),
                centres=rng.uniform(5, 55, (6, 2)), radii=rng.uniform(0.5, 1.5, 6),
                clearance_m=0.5, area_min=np.zeros(2), area_max=np.array([64.0, 60.0]))


def test_the_compiled_candidate_test_is_numpys():
    rng = np.random.default_rng(7)
    case = _crowd(rng, 12)
    own = rally._densify(case["paths"][0, :, :2], 1.0)
    own_home = np.linalg.norm(own - own[0], axis=1)
    places = np.concatenate([case["paths"][1:, 0, :2], rng.uniform(20, 50, (8, 2))])
    others = [rally._densify(p[:, :2], 1.0) for p in case["paths"][1:4]]
    line_a = np.concatenate(others)
    line_b = np.repeat(rng.uniform(30, 50, (3, 2)), [len(o) for o in others], axis=0)
    line_a[:3] = line_b[:3]  # segments of zero length too
    sep = 2.5
    lines = dict(line_a=line_a, line_b=line_b, line_lo=np.minimum(line_a, line_b) - sep,
                 line_hi=np.maximum(line_a, line_b) + sep)
    answers = set()
    for _ in range(60):
        chunk = rng.uniform(0.0, 64.0, (rng.integers(1, 40), 2))
        kw = dict(own=own, own_home=own_home, places=places, sep=sep, **lines)
        numpy = rally._first_clear(chunk, **kw)[0]
        assert rally._first_clear(chunk, **kw, compiled=True)[0] == numpy
        answers.add(numpy if numpy is None else min(numpy, 1))
    assert answers == {None, 0, 1}  # none passes, the first does, a later one does


@pytest.mark.parametrize("n, sep", [(9, 2.0), (16, 4.0), (24, 6.0)])
def test_the_compiled_search_chooses_the_numpy_searchs_points(monkeypatch, n, sep):
    case = _crowd(np.random.default_rng(n), n)
    settings = FenceSettings(rally_separation_m=sep, grid_m=0.5)
    monkeypatch.setattr(rally, "COMPILED_UAVS_FROM", 10**9)
    numpy = rally.rally_points_enu(**case, settings=settings)
    monkeypatch.setattr(rally, "COMPILED_UAVS_FROM", 1)
    compiled = rally.rally_points_enu(**case, settings=settings)
    assert len(compiled) == n
    for x, y in zip(numpy, compiled):
        assert (x is None) == (y is None)
        if x is not None:
            np.testing.assert_array_equal(x, y)
    if sep == 6.0:
        assert any(x is None for x in numpy)  # the crowd leaves some without one
