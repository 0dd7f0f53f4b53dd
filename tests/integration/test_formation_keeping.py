"""Issue 11's ordering on the emulator with per-vehicle variation (``sim --vary``: start
latencies up to 0.3 s, WPNAV_JERK within 5%): the example flown on fresh vehicles the
naive way (one by one) and by ``fly`` with its formation keeper, as
``benchmarks/flight.py --vary`` flies it. The same comparison on ArduCopter SITL is that
benchmark's table in docs/flight.md."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from ftlbo_mav.mission.export import write_plan
from ftlbo_mav.planning.planner import plan
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes

from .fleet import BACKEND

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "missions" / "nha-trang-orchard.toml"

pytestmark = pytest.mark.skipif(BACKEND == "sitl", reason="the emulator's --vary; on SITL "
                                "this is benchmarks/flight.py")


@pytest.fixture(scope="module")
def flights(tmp_path_factory):
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from flight import fly_fresh

    scenario = load_scenario(EXAMPLE)
    plan_dir = tmp_path_factory.mktemp("keeping") / "plan"
    write_plan(plan(scenario), plan_dir)
    homes = scenario_homes(scenario)
    # on a virtual clock (the copters in this process): what is compared is the ordering
    # and the keeper's pacing in the copters' seconds, not the wall clock's
    return {strategy: fly_fresh(plan_dir, homes, strategy, seed=0, vary=True, virtual=True)
            for strategy in ("naive", "fly")}


def test_fly_holds_the_formation_within_the_targets(flights):
    fly = flights["fly"]
    assert fly["formation_error_rms_legs_m"] <= 0.15
    # the emulator shares one process (and the machine) with the ground side: in CI a
    # worst of 0.46 m was seen once, the RMS within 0.15 m (0.08-0.17 m worst otherwise;
    # the 0.3 m of the goal is ArduPilot's, docs/flight.md)
    assert fly["formation_error_max_legs_m"] <= 0.5
    assert max(fly["final_distance_to_goal_m"]) <= 0.5
    assert fly["min_clearance_m"] >= 1.0 - 0.05  # the plan keeps 1.0 m
    assert sum(v["pauses"] for v in fly["keeper"]["vehicles"].values()) > 0


def test_a_naive_start_is_clearly_worse(flights):
    naive, fly = flights["naive"], flights["fly"]
    assert naive["formation_error_rms_legs_m"] > 3 * fly["formation_error_rms_legs_m"]
    assert naive["formation_error_max_legs_m"] > 0.3
