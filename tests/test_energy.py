"""The battery model (ftlbo_mav/energy.py): currents, a mission's charge as ArduCopter
flies it, the reserve, and the [battery] table."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftlbo_mav.ardupilot.navigation import Navigation
from ftlbo_mav.energy import (
    BATTERY_VIOLATION,
    SOLO,
    Battery,
    battery_from_document,
    charge_problem,
    end_charge,
)
from ftlbo_mav.errors import ScenarioError
from ftlbo_mav.mission.export import plan_document, plan_missions
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.scenario import load_scenario

from .conftest import EXAMPLE

SOLO_BATTERY = Battery.from_endurance(SOLO["capacity_mah"], SOLO["endurance_min"],
                                      reserve_pct=SOLO["reserve_pct"])


def test_the_endurance_is_the_hover_current_that_empties_the_battery():
    assert SOLO_BATTERY.hover_current_a == pytest.approx(5.2 / (20 / 60))  # 15.6 A
    assert SOLO_BATTERY.mah(20 * 60) == pytest.approx(5200)
    assert SOLO_BATTERY.usable_mah == pytest.approx(3900)


def test_climbs_cost_more_and_descents_less_as_momentum_theory_says():
    b = Battery(capacity_mah=1000, hover_current_a=10.0, induced_velocity_m_s=5.0)
    assert float(b.current_a(0.0, 0.0)) == 10.0
    # w = vz / (2 v_h) = 0.5: w + sqrt(w^2 + 1) = 1.618
    assert float(b.current_a(0.0, 5.0)) == pytest.approx(10.0 * (0.5 + np.sqrt(1.25)))
    assert float(b.current_a(0.0, -1.5)) < 10.0
    # faster descents than v_h / 2 are counted at its ratio, never less
    assert float(b.current_a(0.0, -10.0)) == pytest.approx(float(b.current_a(0.0, -2.5)))


def test_forward_flight_goes_to_the_cruise_current_with_the_square_of_the_speed():
    b = Battery(capacity_mah=1000, hover_current_a=10.0, cruise_current_a=14.0,
                cruise_speed_m_s=10.0)
    amps = b.current_a(np.array([0.0, 5.0, 10.0, 20.0]), np.zeros(4))
    assert amps.tolist() == pytest.approx([10.0, 11.0, 14.0, 14.0])


def test_a_landing_descends_fast_then_at_land_speed_and_rtl_flies_home_first():
    b, nav = SOLO_BATTERY, Navigation()
    mah, s = end_charge(b, nav, end_action="land", goal=np.array([0.0, 0.0, 30.0]),
                        home=np.zeros(3))
    assert s == pytest.approx(20.0 / 1.5 + 10.0 / 0.5)  # WPNAV_SPEED_DN, then LAND_SPEED
    assert mah == pytest.approx(b.mah(20 / 1.5, 0, -1.5) + b.mah(20.0, 0, -0.5))
    rtl, rtl_s = end_charge(b, nav, end_action="rtl", goal=np.array([100.0, 0.0, 10.0]),
                            home=np.zeros(3))
    # climb to RTL_ALT 15 m, 100 m at WPNAV_SPEED, RTL_LOIT_TIME, then down from 15 m
    assert rtl_s == pytest.approx(5 / 2.5 + 100 / 10 + 5 + 5 / 1.5 + 10 / 0.5)
    assert rtl > mah * 0.5 and end_charge(b, nav, end_action="loiter", goal=np.zeros(3),
                                          home=np.zeros(3)) == (0.0, 0.0)


def _example(tmp_path, table: str):
    scenario = tmp_path / "example.toml"
    scenario.write_text(EXAMPLE.read_text() + "\n[battery]\n" + table)
    return load_scenario(scenario)


@pytest.fixture(scope="module")
def solo_plan(tmp_path_factory):
    return plan(_example(tmp_path_factory.mktemp("solo"),
                         "capacity = 5200\nendurance = 20\nreserve = 25\n"))


def test_the_example_s_charge_follows_its_predicted_flight(solo_plan):
    p = solo_plan
    assert p.feasible and len(p.charges) == 3
    b = p.scenario.battery
    for n, c in enumerate(p.charges):
        assert np.all(np.diff(c.to_end_mah) <= 1e-9) and c.to_end_mah[-1] == c.end_mah
        assert c.to_end_mah[0] == pytest.approx(c.legs_mah + c.end_mah)
        alt = p.prediction.positions[n, 0, 2]
        assert c.takeoff_mah == pytest.approx(b.mah(alt / 2.5, 0.0, 2.5))
        # the legs at about the hover current over the predicted seconds
        legs_s = p.prediction.seconds[n]
        assert c.legs_mah == pytest.approx(b.mah(legs_s), rel=0.05)
    assert charge_problem("uav1", p.charges[0], b) is None


def test_plan_json_gives_each_uav_s_charge_and_reads_the_battery_back(solo_plan):
    doc = plan_document(solo_plan, plan_missions(solo_plan), written=True)
    doc = json.loads(json.dumps(doc))
    assert battery_from_document(doc["battery"]) == solo_plan.scenario.battery
    first = doc["uavs"][0]["battery"]
    assert first["mah"] == pytest.approx(solo_plan.charges[0].total_mah, abs=0.1)
    assert first["lands_with_pct"] > 90 and len(first["to_end_mah"]) == len(
        doc["uavs"][0]["waypoints"])


def test_a_mission_that_would_land_below_the_reserve_is_infeasible_with_its_figures(tmp_path):
    p = plan(_example(tmp_path, "capacity = 180\nhover_current = 15.6\nreserve = 25\n"))
    assert not p.feasible
    (why,) = [v for v in p.violations if v.startswith(BATTERY_VIOLATION)]
    assert "uav1's mission uses" in why and "below the 25 % reserve" in why


@pytest.mark.parametrize("table, field", [
    ("capacity = 5200\n", "battery.hover_current"),
    ("capacity = 5200\nendurance = 20\nhover_current = 15\n", "battery.hover_current"),
    ("capacity = 5200\nendurance = 20\nreserve = 100\n", "battery.reserve"),
    ("capacity = 0\nendurance = 20\n", "battery.capacity"),
    ("capacity = 5200\nendurance = 20\nvoltage = 14.8\n", "battery"),
])
def test_a_battery_table_that_cannot_be_used_names_its_field(tmp_path, table, field):
    with pytest.raises(ScenarioError, match=field.replace(".", r"\.")):
        _example(tmp_path, table)


def test_the_current_at_two_speeds_is_the_arrays_to_the_last_bit():
    """The emulator asks for the current at every step with two floats: plain floats,
    the same numbers as the array path."""
    rng = np.random.default_rng(3)
    battery = Battery(5200.0, 14.0, cruise_current_a=17.0, cruise_speed_m_s=8.0)
    for h, v in zip(rng.uniform(-12, 12, 500), rng.uniform(-6, 6, 500)):
        assert battery.current_a(float(h), float(v)) == float(
            battery.current_a(np.array([h]), np.array([v]))[0])
