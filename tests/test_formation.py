import itertools

import numpy as np
import pytest

from ftlbo_mav.formation import min_separation, regular_formation


@pytest.mark.parametrize("count", [2, 3, 4, 5, 7])
@pytest.mark.parametrize("plane", ["horizontal", "vertical"])
def test_regular_formation_satisfies_the_papers_rules(count, plane):
    offsets = regular_formation(count=count, radius_m=4.0, plane=plane)
    assert offsets.shape == (count, 3)
    # eq. 1: the UAVs' centroid is the planned centroid.
    assert np.allclose(offsets.mean(axis=0), 0, atol=1e-12)
    # eq. 2: every UAV at r_F from the centroid.
    assert np.allclose(np.linalg.norm(offsets, axis=1), 4.0)
    # eq. 3: equal distance to both neighbours on the ring.
    nxt = np.roll(offsets, -1, axis=0)
    prv = np.roll(offsets, 1, axis=0)
    assert np.allclose(np.linalg.norm(offsets - nxt, axis=1), np.linalg.norm(offsets - prv, axis=1))
    flat_axis = 2 if plane == "horizontal" else 1
    assert np.allclose(offsets[:, flat_axis], 0)


def test_vertical_triangle_has_uav1_on_top():
    offsets = regular_formation(count=3, radius_m=2.0, plane="vertical")
    assert np.allclose(offsets[0], [0, 0, 2])
    assert offsets[1, 2] < 0 and offsets[2, 2] < 0


def test_min_separation():
    offsets = np.array([[0, 0, 2], [3, 0, -1], [-3, 0, -1]], float)
    expected = min(np.linalg.norm(a - b) for a, b in itertools.combinations(offsets, 2))
    assert min_separation(offsets) == pytest.approx(expected)
    assert min_separation(offsets[:1]) == float("inf")


def test_bad_arguments():
    with pytest.raises(ValueError):
        regular_formation(count=0, radius_m=1)
    with pytest.raises(ValueError):
        regular_formation(count=3, radius_m=1, plane="diagonal")
