"""The shipped survey (missions/orchard-survey.toml), end to end: its plan (the shipped
folder, which tests/test_survey_scenario.py holds to what ``plan`` writes), upload the
missions, fly them on the emulator (or ArduPilot SITL when ARDUPILOT_SITL is set) and
check on what the vehicles reported that every UAV flew every lane and landed at the goal."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest
from click.testing import CliRunner

from ftlbo_mav.cli import main
from ftlbo_mav.flight.record import FlightRecord
from ftlbo_mav.scenario import load_scenario
from ftlbo_mav.sim.homes import scenario_homes
from ftlbo_mav.sim.vehicle import VehicleOptions

from ..conftest import ROOT
from .fleet import BACKEND, vehicles

pytestmark = [pytest.mark.sitl, pytest.mark.slow]

SURVEY = ROOT / "missions" / "orchard-survey.toml"
SPEEDUP = 12.0  # SITL's; the emulator flies it on a virtual clock (fleet.vehicles)
PASS_M = 3.0
"""How near each UAV must come to each of its lane ends: ArduCopter's waypoint radius
(WPNAV_RADIUS, 2 m) plus a margin for corner cutting at the turns."""


def test_the_survey_plans_uploads_and_flies_every_lane(tmp_path):
    scenario = load_scenario(SURVEY)
    out = tmp_path / "survey"
    # the shipped plan folder: tests/test_survey_scenario.py holds it to what `plan` writes
    shutil.copytree(SURVEY.with_suffix(""), out)
    options = {} if BACKEND == "sitl" else {"options": VehicleOptions(heartbeat_s=0.25)}
    with vehicles(3, homes=scenario_homes(scenario), speedup=SPEEDUP, virtual=True,
                  **options) as fleet:
        urls = " ".join(fleet.urls)
        uploaded = CliRunner().invoke(main, ["upload", str(out), "--sysid", "1..3",
                                             "--connect", urls])
        assert uploaded.exit_code == 0, uploaded.output
        # with the keeper and the plan's own formation bound: on the virtual clock the
        # ground's timing is the copters' (at 12x on the wall clock it was 12 times coarser
        # and both were off)
        flown = CliRunner().invoke(main, ["fly", str(out), "--sysid", "1..3",
                                          "--control-port", "0", "--connect", urls])
        assert flown.exit_code == 0, flown.output
    assert "all vehicles finished their missions" in flown.stdout
    summary = json.loads((out / "flight" / "summary.json").read_text())
    # the promised clearance less a stated corner tolerance, as in test_fly
    assert summary["inside_obstacle"] is False
    assert summary["min_clearance_m"] >= scenario.clearance_m - 0.05, summary["min_clearance_m"]
    assert max(summary["final_distance_to_goal_m"]) < 1.0  # landed at the goal
    # every UAV passed each of its lane ends (via point + its offset), in order
    record = FlightRecord.from_csv((out / "flight" / "flight.csv").read_text())
    via = scenario.route_enu()[1:-1]
    for n in range(3):
        samples = record.of(n + 1)
        track = scenario.frame.to_enu(lat_deg=[s.lat_deg for s in samples],
                                      lon_deg=[s.lon_deg for s in samples])[:, :2]
        targets = via[:, :2] + scenario.offsets_m[n, :2]
        distance = np.hypot(*(track[None, :, :] - targets[:, None, :]).transpose(2, 0, 1))
        assert distance.min(axis=1).max() < PASS_M, distance.min(axis=1)
        after = 0  # lane after lane, in the planned order: each end reached after the last
        for k, row in enumerate(distance):
            near = np.flatnonzero(row[after:] < PASS_M)
            assert len(near), f"uav{n + 1} did not reach {scenario.via[k].name} in order"
            after += int(near[0])
