"""The navigation budget (pure): the classes and their figures, the combined error of
two copters, how close two copters can truly be, and the budget that keeps a promise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftlbo_mav.gnss import (
    CLASSES,
    DEFAULT_CLASS,
    NO_BUDGET,
    R95_PER_CEP,
    budget,
    budget_from_document,
    classes_within,
    largest_error_for,
    pair_error_m,
    true_distance,
    would_do,
)


def test_the_95_percent_radius_of_a_circular_normal_is_2_08_cep():
    rng = np.random.default_rng(1)
    r = np.hypot(*rng.normal(0, 1, (2, 200_000)))
    assert R95_PER_CEP == pytest.approx(np.quantile(r, 0.95) / np.quantile(r, 0.5), rel=0.01)


def test_the_default_is_an_uncorrected_gps_and_the_classes_tighten():
    assert DEFAULT_CLASS == "gps" and budget() is CLASSES["gps"]
    figures = [CLASSES[n].horizontal_m for n in ("gps", "sbas", "rtk-float", "rtk-fixed")]
    assert figures == sorted(figures, reverse=True)
    assert CLASSES["gps"].horizontal_m == pytest.approx(5.2, abs=0.01)
    assert [CLASSES[n].min_fix_type for n in ("gps", "sbas", "rtk-float", "rtk-fixed")] == [
        3, 4, 5, 6]
    assert all(c.source for c in CLASSES.values())


def test_a_figure_replaces_the_class_figure_but_keeps_its_fix_type():
    b = budget("rtk-float", 0.3)
    assert (b.name, b.horizontal_m, b.min_fix_type) == ("rtk-float", 0.3, 5)
    custom = budget(None, 1.2)
    assert (custom.name, custom.min_fix_type) == ("custom", 3)


def test_two_independent_errors_combine_as_sqrt_2():
    rng = np.random.default_rng(2)
    sigma = 1.0
    one = np.quantile(np.hypot(*rng.normal(0, sigma, (2, 100_000))), 0.95)
    diff = rng.normal(0, sigma, (2, 100_000)) - rng.normal(0, sigma, (2, 100_000))
    assert np.quantile(np.hypot(*diff), 0.95) == pytest.approx(pair_error_m(one), rel=0.02)


def test_a_horizontal_error_cannot_close_a_vertical_gap():
    assert true_distance(3.0, 3.0, 1.0) == pytest.approx(math.hypot(2.0, 3.0))
    assert true_distance(3.0, 3.0, 5.0) == pytest.approx(3.0)
    assert true_distance(6.0, 0.0, 7.0) == 0.0


def test_the_largest_error_that_keeps_a_separation():
    h, v = np.array([6.0, 3.0]), np.array([0.0, 3.0])
    e = largest_error_for(h, v, 2.0)
    assert e == pytest.approx(6.0 - 2.0)  # the pair 3 m apart in height keeps 2 m whatever
    assert true_distance(h, v, e).min() == pytest.approx(2.0)
    assert largest_error_for([1.0], [0.0], 2.0) == 0.0
    assert largest_error_for([0.0], [3.0], 2.0) == math.inf


def test_the_budget_that_would_do_names_the_loosest_class_that_fits():
    assert [c.name for c in classes_within(0.5)] == ["rtk-float", "rtk-fixed"]
    assert "rtk-float" in would_do(2.83) and "2.83 m" in would_do(2.83)
    assert "no class" in would_do(0.001)


def test_a_plan_json_budget_reads_back_and_an_old_plan_has_none():
    b = CLASSES["sbas"]
    assert budget_from_document(b.document()) == b
    assert budget_from_document(None) is NO_BUDGET and NO_BUDGET.horizontal_m == 0
    with pytest.raises(ValueError):
        budget_from_document({"horizontal_error_m": -1})
