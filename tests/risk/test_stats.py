"""Exact intervals for what a number of flights shows."""

from __future__ import annotations

import math

import pytest

from ftlbo_mav.risk.stats import clopper_pearson, ecdf, probability, spread


@pytest.mark.parametrize("k, n, low, high", [
    # textbook Clopper-Pearson 95 % values
    (3, 100, 0.0062, 0.0852), (5, 10, 0.1871, 0.8129), (1, 20, 0.0013, 0.2487),
    (50, 1000, 0.0373, 0.0654)])
def test_clopper_pearson_matches_the_exact_interval(k, n, low, high):
    lo, hi = clopper_pearson(k, n)
    assert lo == pytest.approx(low, abs=1e-4) and hi == pytest.approx(high, abs=1e-4)


@pytest.mark.parametrize("n", [1, 10, 100, 1000])
def test_with_no_event_the_bound_is_what_n_flights_can_show(n):
    lo, hi = clopper_pearson(0, n)
    assert lo == 0.0 and hi == pytest.approx(1 - 0.025 ** (1 / n), rel=1e-6)
    lo, hi = clopper_pearson(n, n)
    assert hi == 1.0 and lo == pytest.approx(0.025 ** (1 / n), rel=1e-6)


def test_a_probability_says_its_events_and_interval():
    p = probability("clearance below 0", [False] * 97 + [True] * 3)
    assert (p.events, p.flights, p.estimate) == (3, 100, 0.03)
    assert "3 of 100 flights" in p.describe() and "0.62%-8.52%" in p.describe()
    with pytest.raises(ValueError):
        clopper_pearson(5, 3)


def test_spread_and_ecdf_skip_flights_without_the_figure():
    s = spread([1.0, None, 3.0, float("nan"), 2.0])
    assert s["n"] == 3 and s["min"] == 1.0 and s["median"] == 2.0 and s["max"] == 3.0
    assert spread([None]) == {"n": 0}
    x, y = ecdf([3.0, None, 1.0, 2.0])
    assert list(x) == [1.0, 2.0, 3.0] and list(y) == pytest.approx([1 / 3, 2 / 3, 1.0])
    assert not math.isnan(y[-1])
