"""Plan, predict, repair, until kept (planning/repair.py): a survey's lanes laid further
in before the first plan by the swing its straight route is predicted to make."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ftlbo_mav.planning import planner as planner_module
from ftlbo_mav.planning import repair as R
from ftlbo_mav.scenario import load_scenario, parse_scenario

FIELD = Path(__file__).resolve().parents[2] / "missions" / "field-survey.toml"


def test_the_straight_routes_swing_is_found_before_planning_and_the_survey_planned_once(
        monkeypatch):
    scenario = load_scenario(FIELD)
    low, high = R._straight_excursion(scenario)
    assert max(low.max(), high.max()) > 0.1  # the field's triangle swings out turning
    calls = []
    real = planner_module._plan_legs
    monkeypatch.setattr(planner_module, "_plan_legs",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    plan = planner_module.plan(scenario)
    assert len(calls) == 1  # laid in before the first plan: not planned again for it
    assert plan.feasible and plan.lanes_inset_m > 0.1
    inset = max(low.max(), high.max()) + R.SURVEY_RELAY_MARGIN_M
    assert np.isclose(plan.lanes_inset_m, inset)


def test_no_guess_when_a_straight_leg_is_blocked():
    text = FIELD.read_text()
    # a tree on the first lane's line: that leg's plan bends, its swing is not guessed
    scenario = load_scenario(FIELD)
    a, b = scenario.route_enu()[1:3]
    middle = scenario.frame.to_lla((a + b) / 2)
    tree = f"\n[[obstacles]]\nlat = {middle[0]:.8f}\nlon = {middle[1]:.8f}\nradius = 1.0\n"
    blocked = parse_scenario(text.replace("[survey]", tree + "\n[survey]", 1),
                             base_dir=FIELD.parent)
    assert R._straight_excursion(blocked) is None
