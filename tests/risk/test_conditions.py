"""A risk flight's conditions follow from its seed alone, within the ranges given."""

from __future__ import annotations

import pytest

from ftlbo_mav.errors import BadInput
from ftlbo_mav.risk.conditions import R95_PER_SIGMA, Ranges, draw


def test_a_seed_gives_the_same_conditions_and_another_seed_others():
    ranges = Ranges(gps_wander_m=0.1)
    assert draw(ranges, 7, 3) == draw(ranges, 7, 3)
    drawn = [draw(ranges, s, 3) for s in range(200)]
    assert len({c.wind for c in drawn}) == 200
    assert len({c.gps_seeds for c in drawn}) == 200
    assert all(len(c.gps_seeds) == 3 and c.seed == s for s, c in enumerate(drawn))


def test_the_wind_stays_in_its_ranges_and_fills_them():
    ranges = Ranges(wind_max_m_s=6.0, turbulence_max_m_s=1.5, gps_wander_m=0.0)
    winds = [draw(ranges, s, 3).wind for s in range(500)]
    speeds, froms, turbs = zip(*winds)
    assert 0 <= min(speeds) < 0.5 and 5.5 < max(speeds) <= 6.0
    assert 0 <= min(froms) < 10 and 350 < max(froms) <= 360
    assert 0 <= min(turbs) and max(turbs) <= 1.5
    calm = [draw(Ranges(wind_max_m_s=0, turbulence_max_m_s=0), s, 3).wind for s in range(5)]
    assert all(spd == 0 and turb == 0 for spd, _frm, turb in calm)


def test_a_copter_is_lost_at_the_rate_asked_within_its_window():
    never = [draw(Ranges(lost_rate=0.0), s, 3).lost for s in range(100)]
    assert never == [None] * 100
    always = [draw(Ranges(lost_rate=1.0, lost_window_s=(4.0, 9.0)), s, 3).lost
              for s in range(100)]
    assert {who for who, _at in always} == {0, 1, 2}
    assert all(4.0 <= at <= 9.0 for _who, at in always)
    some = sum(draw(Ranges(lost_rate=0.3), s, 3).lost is not None for s in range(1000))
    assert 240 < some < 360


def test_a_mode_is_taken_over_at_its_rate_without_changing_the_other_conditions():
    plain = [draw(Ranges(lost_rate=0.3), s, 3) for s in range(300)]
    taken = [draw(Ranges(lost_rate=0.3, takeover_rate=0.5), s, 3) for s in range(300)]
    assert all(p.takeover is None for p in plain)
    assert [(p.wind, p.gps_seeds, p.lost) for p in plain] == \
        [(t.wind, t.gps_seeds, t.lost) for t in taken]
    assert 110 < sum(t.takeover is not None for t in taken) < 190
    assert {t.takeover[0] for t in taken if t.takeover} == {0, 1, 2}
    assert "uav" in next(t for t in taken if t.takeover).describe()


def test_the_gps_wander_defaults_to_the_plans_navigation_budget():
    assert Ranges().with_budget(0.49).gps_wander_m == pytest.approx(0.49 / R95_PER_SIGMA, abs=1e-4)
    assert Ranges(gps_wander_m=0.3).with_budget(0.49).gps_wander_m == 0.3  # given: kept
    assert Ranges().with_budget(float("inf")).gps_wander_m == 0.0  # no budget


@pytest.mark.parametrize("kw, problem", [
    ({"wind_max_m_s": -1.0}, "wind-max-m-s"), ({"turbulence_max_m_s": float("nan")}, "turb"),
    ({"lost_rate": 1.5}, "probability"), ({"takeover_rate": -0.1}, "takeover rate"),
    ({"gps_wander_m": -0.1}, "gps wander"),
    ({"lost_window_s": (9.0, 4.0)}, "lost window"), ({"gps_correlation_s": 0.0}, "correlation")])
def test_bad_ranges_are_refused_with_what_is_wrong(kw, problem):
    with pytest.raises(BadInput, match=problem):
        Ranges(**kw)
