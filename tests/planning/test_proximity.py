"""The nearest sample of a path to each of many points: the compiled runs-and-boxes search
gives the full array's distances and (first, on a tie) indices."""

import numpy as np
import pytest

from ftlbo_mav.planning import proximity


@pytest.mark.parametrize("seed", [0, 1])
def test_the_compiled_search_is_the_full_array(monkeypatch, seed):
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 4 * np.pi, 3000)
    xy = np.column_stack([40 * np.cos(t) + t, 25 * np.sin(2 * t)])  # a path that loops back
    xy[1500:1600] = xy[1400:1500]  # flown twice: ties, the first sample wins
    centres = np.concatenate([rng.uniform(-60, 60, (400, 2)), xy[1450:1460]])
    full_d, full_i = proximity.nearest_samples(xy, centres)
    monkeypatch.setattr(proximity, "FULL_ARRAY_LIMIT", 0)
    d, i = proximity.nearest_samples(xy, centres)
    np.testing.assert_array_equal(d, full_d)
    np.testing.assert_array_equal(i, full_i)
    assert (full_i[-10:] < 1500).all()


def test_once_numba_is_loaded_and_cached_the_compiled_search_runs_at_smaller_sizes(monkeypatch):
    calls = []
    from ftlbo_mav import compiling
    from ftlbo_mav.planning import _proximity_jit

    real = _proximity_jit._nearest
    monkeypatch.setattr(_proximity_jit, "_nearest", lambda *a: calls.append(1) or real(*a))
    xy = np.column_stack([np.arange(300.0), np.zeros(300)])
    centres = np.column_stack([np.arange(100.0), np.ones(100)])
    monkeypatch.setattr(compiling, "loaded", lambda: False)
    proximity.nearest_samples(xy, centres)
    assert not calls
    monkeypatch.setattr(compiling, "loaded", lambda: True)
    monkeypatch.setattr(compiling, "ready", lambda *f: False)  # cache cold
    proximity.nearest_samples(xy, centres)
    assert not calls  # compiling would cost more than the arrays
    monkeypatch.setattr(compiling, "ready", lambda *f: True)
    d, _ = proximity.nearest_samples(xy, centres)
    assert calls and np.allclose(d, 1.0)
